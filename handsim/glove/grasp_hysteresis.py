"""The hysteresis that finds grasp episodes in a recording's summed finger flexion, and its parameters.

Temporal segmentation of hand motion has been done on self-similarity matrices of the poses
(Stollenwerk et al. 2016, "Automatic temporal segmentation of articulated hand motion", ICCSA 2016 Part
II, Springer, pp. 433–449, doi:10.1007/978-3-319-42108-7_33; surveyed in spec 003 §2.3),
which splits motion into recurring primitives. A replay needs something plainer: the stretch over which
the hand is closed on the object. That is read off the **summed finger flexion** F (every ``…flex…`` DoF
but the wrist's, the signal the replay's grasp frame uses) by a two-threshold (hysteresis) detector, as
in Canny's hysteresis thresholding (Canny 1986, IEEE TPAMI 8(6):679–698): a closing must cross a high
threshold to start and a lower one to end, so noise near one threshold cannot split or start an episode.

1. F is smoothed (Gaussian, :data:`SMOOTHING_S`) and scaled by its robust range R, the spread between its
   :data:`RANGE_PERCENTILES` (a recording whose R is under :data:`MIN_RANGE_RAD` holds no closing).
2. A **closing** starts when F has risen :data:`CLOSING_FRACTION` · R above its least value since the
   hand last opened (the *open level* of that closing). Thresholds are measured from that open level,
   not from the recording's minimum, so a glove whose readings drift over minutes (the shared session's
   closings start from 4.6 rad in its first minute, from 5.0 rad in its last, medians) still has every
   closing measured against the hand just before it.
3. It ends (the hand **releases**) when F falls back below the open level plus :data:`RELEASE_FRACTION` of
   the closing's rise so far: halfway back. An opening that stays above :data:`PARTIAL_FRACTION` of the
   rise and lasts less than :data:`MIN_OPENING_S` is a regrip inside the episode, not a release.
4. A closing whose flexion stays past halfway from the open level to its peak for less than
   :data:`MIN_CLOSED_S` is a twitch, not a grasp.
5. Phases, from the episode's open level L and its typical closed flexion C (the median of F over the
   closed stretch): ``hold``, the frames from the first to the last at or above L +
   :data:`HOLD_FRACTION` · (C − L); ``closure``, from the last frame before the hold within
   :data:`MOVE_FRACTION` of the way from L (the hand starts closing) to the hold; ``release``, from the hold
   to the first frame back within :data:`MOVE_FRACTION` of the open level after it (the least flexion
   within :data:`RELEASE_S`); ``approach``, up to :data:`APPROACH_S` before the closure, after the
   previous episode's release.

A closing that rises less than :data:`CLOSING_FRACTION` of the range is partial, not a grasp
(:mod:`handsim.glove.segmentation` explains why).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from handsim.datatypes.trajectory import Phase
from handsim.glove.grasp_episode import AUTOMATIC, GraspEpisode

SMOOTHING_S = 0.05
"""Standard deviation of the Gaussian that smooths the summed flexion, s (3 samples at 60 Hz; the gain
falls to −3 dB at 2.6 Hz). It removes the glove's quantisation steps and single-sample jitter, which
could otherwise cross a threshold, and moves a closing's threshold crossing by well under its duration
(a closing takes at least 0.09 s, Cole & Abbs 1986, J Neurophysiol 55(6):1407–1423)."""

RANGE_PERCENTILES = (1.0, 99.0)
"""The percentiles of the smoothed flexion whose spread is the recording's range R. A long closure leaves
only a few percent of the frames open (GraspDB14's pen interaction trial is open for 2.2 s of its 35.5 s),
a rare grasp in a long rest only a few percent closed: the 1st and 99th percentiles still fall on the
open and the closed hand, and ignore the most extreme 1 % (a flexion spike)."""

MIN_RANGE_RAD = 2.0
"""A recording whose range R is below this holds no closing, rad. A resting hand's summed flexion moves
by 0.2–0.63 rad in the shared recordings (1st–99th percentile over a rest of 1–2 s) and by about 1 rad
over a 12 s rest in another session of the same glove data; a grasp closes by several radians (the shared
GraspDB14 trials' ranges are 6.1–9.9 rad)."""

CLOSING_FRACTION = 0.4
"""A closing starts when the flexion has risen this fraction of the range R above its open level. Two
fifths, not one half: the repeated closings of one recording differ in depth (in another session of 49
tennis-ball grasps from the same source as the shared data the shallowest rises 0.69 R, the others
0.85–1.0 R; the shared session's task cycles stand 0.38–1.38 R above the valleys beside them, 47 of its 50
at least 0.4 R), and a closing that covers less of the way is partial. The bumps between the shared
session's cycles, mostly the index finger flexing ahead of the others, reach up to 0.43 R: no fraction
separates the two completely there (at 0.4 it has 51 episodes for its 50 cycles)."""

RELEASE_FRACTION = 0.5
"""The hold ends when the flexion falls back below the open level plus this fraction of the closing's rise
(halfway back). Measured on the closing's own rise, not on R: a hand that was not wide open before a grasp
need not open wide after it, and a GraspDB14 trial's hand opens more in the reach ("overopen") than it
rests after the release."""

PARTIAL_FRACTION = 0.25
"""An opening whose flexion stays above the open level plus this fraction of the closing's rise is
partial; a partial opening shorter than :data:`MIN_OPENING_S` is a regrip inside the episode."""

MIN_OPENING_S = 0.3
"""A partial opening shorter than this does not end an episode, s: letting go of an object and closing on
it again takes an opening and a closing, each at least 0.09 s even in the fastest finger–thumb pinches
(Cole & Abbs 1986); a loosening of the grip for under 0.3 s is an adjustment within one grasp
(GraspDB14's pen trial loosens its grip below halfway for 0.2 s at 3.1 s)."""

MIN_CLOSED_S = 0.2
"""A closing that stays past halfway to its peak for less than this is a twitch, not a grasp, s (its width
at half height, which does not depend on where the closing threshold lies): about the closing and the
opening of the fastest voluntary finger movements (≈ 0.09 s each, Cole & Abbs 1986)."""

HOLD_FRACTION = 0.8
"""The hold is the frames at or above the open level plus this fraction of the way to the episode's
typical closed flexion (the median over its closed stretch): the hand within a fifth of its grip."""

MOVE_FRACTION = 0.1
"""The closure starts, and the release ends, where the flexion is within this fraction of the way from
the open level to the closed flexion (the hand has started to close, or is open again)."""

APPROACH_S = 1.0
"""The approach is at most this long before the closure starts, s: a reach-to-grasp movement, with the
hand opening and then closing on the object in its last part, lasts under a second (Jeannerod 1984, "The
timing of natural prehension movements", J Motor Behav 16(3):235–254)."""

RELEASE_S = 1.0
"""The open level after an episode is the least flexion within this long after the hold, s: GraspDB14's
annotated sample retracts the arm and opens the hand in 1.1 s (its ``retract-opening`` phase), and a later,
deeper opening belongs to the next reach, not to this release."""


@dataclass(frozen=True)
class _Stretch:
    """A closed stretch ``[start, stop)``, its open level (units of R) and frame, and how the file cuts it."""

    start: int
    stop: int
    anchor: float
    anchor_frame: int
    peak: float
    cut_start: bool
    cut_end: bool


def automatic_episodes(f: np.ndarray, t: np.ndarray) -> tuple[tuple[GraspEpisode, ...], float, float]:
    """The episodes of a summed flexion signal, and the open and closed flexion its thresholds are scaled by.

    Args:
        f: Summed finger flexion per frame, rad (T,), finite.
        t: Sample times, s (T,), strictly increasing.

    Returns:
        The episodes (source :data:`~handsim.glove.grasp_episode.AUTOMATIC`), and the open and closed
        flexion (rad); no episodes when their spread is under :data:`MIN_RANGE_RAD`.
    """
    smooth = _smooth(f, t)
    lo, hi = (float(v) for v in np.percentile(smooth, RANGE_PERCENTILES))
    if hi - lo < MIN_RANGE_RAD:
        return (), lo, hi
    scaled = (smooth - lo) / (hi - lo)
    stretches = [s for s in _closed_stretches(scaled, t) if _lasts(s, scaled, t)]
    episodes: list[GraspEpisode] = []
    for k, stretch in enumerate(stretches):
        previous_stop = episodes[-1].stop if episodes else 0
        next_open = stretches[k + 1].anchor_frame + 1 if k + 1 < len(stretches) else f.shape[0]
        anchor = lo + stretch.anchor * (hi - lo)
        episodes.append(_episode(k + 1, stretch, anchor, smooth, f, t, previous_stop, next_open))
    return tuple(episodes), lo, hi


def _smooth(flexion: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Gaussian smoothing with :data:`SMOOTHING_S` (in samples of the median interval), edges held."""
    if flexion.shape[0] < 2:
        return flexion.copy()
    sigma = SMOOTHING_S / float(np.median(np.diff(times)))
    radius = math.ceil(3 * sigma)
    kernel = np.exp(-0.5 * (np.arange(-radius, radius + 1) / sigma) ** 2)
    return np.convolve(np.pad(flexion, radius, mode="edge"), kernel / kernel.sum(), mode="valid")


def _closed_stretches(s: np.ndarray, t: np.ndarray) -> list[_Stretch]:
    """The hysteresis on the flexion in units of the range (0 open, 1 closed)."""
    n = s.shape[0]
    stretches: list[_Stretch] = []
    closed = bool(s[0] >= CLOSING_FRACTION)  # closed at the first frame: measured from the open hand
    start, anchor, anchor_frame, peak, cut_start = 0, 0.0, 0, float(s[0]), closed
    low, low_frame = float(s[0]), 0
    dip: int | None = None  # first frame of an opening not yet confirmed
    deepest = 0.0
    for i in range(n):
        v = float(s[i])
        if not closed:
            if v <= low:  # the last frame at the least flexion: where the closing starts from
                low, low_frame = v, i
            if v - low >= CLOSING_FRACTION:
                closed, start, anchor, anchor_frame, peak, cut_start = True, i, low, low_frame, v, False
                dip = None
            continue
        if dip is None:
            peak = max(peak, v)
        if v >= anchor + RELEASE_FRACTION * (peak - anchor):
            dip = None
            continue
        if dip is None:
            dip, deepest = i, v
        deepest = min(deepest, v)
        if deepest < anchor + PARTIAL_FRACTION * (peak - anchor) or t[i] - t[dip] >= MIN_OPENING_S:
            stretches.append(_Stretch(start, dip, anchor, anchor_frame, peak, cut_start, False))
            opening = s[dip : i + 1]
            low_frame = dip + int(opening.shape[0] - 1 - np.argmin(opening[::-1]))
            closed, low = False, float(s[low_frame])
    if closed:  # an opening under way at the last frame is a release seen
        stop = n if dip is None else dip
        stretches.append(_Stretch(start, stop, anchor, anchor_frame, peak, cut_start, dip is None))
    return stretches


def _lasts(stretch: _Stretch, s: np.ndarray, t: np.ndarray) -> bool:
    """Whether the flexion stays past halfway from the open level to the peak for :data:`MIN_CLOSED_S`."""
    level = stretch.anchor + RELEASE_FRACTION * (stretch.peak - stretch.anchor)
    below = np.flatnonzero(s[stretch.anchor_frame : stretch.start] < level)
    first = stretch.anchor_frame + int(below[-1]) + 1 if below.size else stretch.anchor_frame
    return t[stretch.stop - 1] - t[first] >= MIN_CLOSED_S


def _episode(
    index: int,
    stretch: _Stretch,
    anchor: float,
    smooth: np.ndarray,
    flexion: np.ndarray,
    t: np.ndarray,
    previous_stop: int,
    next_open: int,
) -> GraspEpisode:
    """Phases, peak and truncation of one closed stretch.

    ``anchor`` is its open level (rad); ``next_open`` one past the next episode's open frame (or the frame
    count): the release ends before it.
    """
    n = flexion.shape[0]
    closed = float(np.median(smooth[stretch.start : stretch.stop]))
    first = max(previous_stop, stretch.anchor_frame)
    above = np.flatnonzero(smooth[first : stretch.stop] >= anchor + HOLD_FRACTION * (closed - anchor)) + first
    hold_start, hold_stop = int(above[0]), int(above[-1]) + 1
    if stretch.cut_start:
        closure_start = first
    else:
        opening = np.flatnonzero(smooth[first : hold_start + 1] <= anchor + MOVE_FRACTION * (closed - anchor))
        closure_start = first + int(opening[-1]) if opening.size else first
    if stretch.cut_end:
        hold_stop = release_stop = n
    else:
        within = int(np.searchsorted(t, t[hold_stop] + RELEASE_S + 1e-9))
        after = smooth[hold_stop : max(min(next_open, within), hold_stop + 1)]
        reopened = float(after.min())
        release_stop = hold_stop + int(np.argmax(after <= reopened + MOVE_FRACTION * (closed - reopened))) + 1
    approach_start = max(previous_stop, int(np.searchsorted(t, t[closure_start] - APPROACH_S - 1e-9)))
    intervals = (
        ("approach", approach_start, closure_start),
        ("closure", closure_start, hold_start),
        ("hold", hold_start, hold_stop),
        ("release", hold_stop, release_stop),
    )
    phases = tuple(Phase(name, a, b) for name, a, b in intervals if b > a)
    cut_start = stretch.cut_start or closure_start == 0
    notes = []
    if cut_start:
        notes.append("the file starts with the hand closed or closing")
    if stretch.cut_end:
        notes.append("the file ends before the release")
    peak = hold_start + int(np.argmax(flexion[hold_start:hold_stop]))
    return GraspEpisode(
        index=index,
        start=phases[0].start,
        stop=phases[-1].stop,
        phases=phases,
        peak_flexion=float(flexion[peak]),
        peak_frame=peak,
        truncated=cut_start or stretch.cut_end,
        source=AUTOMATIC,
        note="; ".join(notes),
    )
