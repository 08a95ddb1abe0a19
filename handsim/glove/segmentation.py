"""Grasp episodes of a glove recording: each closing of the hand with its approach, closure, hold and release.

A GraspDB14 trial holds one grasp, but a session, an object-interaction trial or a user's own recording
holds many, or one that lasts half a minute. :func:`segment_grasps` turns a recording into
:class:`GraspEpisode` s, each a frame interval with its phases (``approach``, ``closure``, ``hold``,
``release``), its peak flexion, whether the file cuts it off (``truncated``: never judged) and how it was
found (``source``):

* ``"annotation"``: the recording carries annotated phases (a GraspDB14 ``_annot-`` file matched to it
  by :func:`handsim.io.graspdb.annotations.match_annotation` and attached by
  :func:`handsim.glove.checks.check_recording`): each ``grasp`` phase is the hold of one episode.
* ``"automatic"``: otherwise, the hysteresis below on the summed finger flexion.

A calibration sequence (:mod:`handsim.glove.calibration_sequence`) has no episodes; the segmentation says
so (:data:`~handsim.glove.calibration_sequence.CALIBRATE_HINT`).

**Method.** Temporal segmentation of hand motion has been done on self-similarity matrices of the poses
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

**Partial closings are not grasps.** A rise of less than two fifths of the range does not start an
episode: a hand that closes on an object reaches about the same closed flexion every time it grasps it,
and a closing that stops far short of that is an adjustment or a finger moving on its own. An episode is
**truncated** when the file starts with the hand already closed or closing (no frame shows it open before
the closure) or ends before the release.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from handsim.datatypes.trajectory import Phase, Trajectory
from handsim.errors import TrajectoryError
from handsim.glove.calibration_sequence import CalibrationSequence, recognise_calibration_sequence

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

PHASE_NAMES = ("approach", "closure", "hold", "release")
"""The phases of an episode, in time order."""

AUTOMATIC = "automatic"
"""Source of episodes found by the hysteresis on the summed flexion."""

ANNOTATION = "annotation"
"""Source of episodes taken from annotated ``grasp`` phases."""

CALIBRATION = "calibration sequence"
"""Source of a segmentation of a recognised calibration sequence (no episodes)."""

GRASP_PHASE = "grasp"
"""The annotated phase that is an episode's hold (GraspDB14 ``.grasp``)."""

REACH_PHASE = "reach"
"""The annotated phase before it (approach and closure; GraspDB14 ``reach-overopen-closing``)."""

RETRACT_PHASE = "retract"
"""The annotated phase after it (the release; GraspDB14 ``retract-opening``)."""


@dataclass(frozen=True)
class GraspEpisode:
    """One grasp of a recording.

    Attributes:
        index: 1-based position in the recording.
        start: First frame (0-based).
        stop: One past the last frame.
        phases: The episode's non-empty phases among :data:`PHASE_NAMES`, in time order; frame intervals
            (``stop`` exclusive) that tile ``[start, stop)``. A truncated episode may lack the approach and
            closure (cut at the start) or the release (cut at the end); every episode has a hold.
        peak_flexion: Largest summed finger flexion of the hold, rad.
        peak_frame: The frame of :attr:`peak_flexion`.
        truncated: The file starts or ends inside the episode (a hand already closed or closing at the
            first frame, or not yet released at the last): never judged.
        source: :data:`AUTOMATIC` or :data:`ANNOTATION`.
        note: For people: why it is truncated; empty otherwise.
    """

    index: int
    start: int
    stop: int
    phases: tuple[Phase, ...]
    peak_flexion: float
    peak_frame: int
    truncated: bool
    source: str
    note: str = ""

    def phase(self, name: str) -> Phase | None:
        """The phase of this name, or None when the episode lacks it.

        Raises:
            TrajectoryError: ``name`` is not one of :data:`PHASE_NAMES`.
        """
        if name not in PHASE_NAMES:
            raise TrajectoryError(f"no episode phase {name!r}; phases are {list(PHASE_NAMES)}")
        return next((p for p in self.phases if p.name == name), None)

    @property
    def hold(self) -> Phase:
        """The hold (or manipulation) phase: what a replay judges."""
        return next(p for p in self.phases if p.name == "hold")

    def to_dict(self) -> dict:
        """JSON-ready fields: phases as ``{name: [start, stop]}``."""
        return {
            "index": self.index,
            "start": self.start,
            "stop": self.stop,
            "phases": {p.name: [p.start, p.stop] for p in self.phases},
            "peak_flexion_rad": self.peak_flexion,
            "peak_frame": self.peak_frame,
            "truncated": self.truncated,
            "source": self.source,
            "note": self.note,
        }


@dataclass(frozen=True)
class GraspSegmentation:
    """A recording's grasp episodes, and how they were found.

    Attributes:
        episodes: In time order.
        source: :data:`AUTOMATIC`, :data:`ANNOTATION` or :data:`CALIBRATION`.
        times: The recording's sample times, s (T,).
        flexion: Its summed finger flexion, rad (T,) (:func:`summed_flexion`).
        open_closed: The recording's open and closed flexion (the :data:`RANGE_PERCENTILES` of the smoothed
            flexion), rad; for the automatic segmentation, else None.
        calibration: Why the recording is a calibration sequence, if it is one.
        note: For people: how the episodes were found.
    """

    episodes: tuple[GraspEpisode, ...]
    source: str
    times: np.ndarray = field(repr=False, compare=False)
    flexion: np.ndarray = field(repr=False, compare=False)
    open_closed: tuple[float, float] | None = None
    calibration: CalibrationSequence | None = None
    note: str = ""

    @property
    def complete(self) -> tuple[GraspEpisode, ...]:
        """The episodes the file does not cut off: those a replay judges."""
        return tuple(e for e in self.episodes if not e.truncated)

    def lines(self) -> list[str]:
        """Human-readable lines: a summary, then one line per episode (times in s, flexion in rad)."""
        if self.calibration is not None:
            return [f"episodes   none: {self.calibration.text()}"]
        n, k = len(self.episodes), len(self.complete)
        head = f"episodes   {n} ({k} complete, {n - k} truncated), {self.source}: {self.note}"
        out = [head]
        t = self.times
        for e in self.episodes:
            hold = e.hold
            state = "truncated" if e.truncated else "complete"
            span = f"frames {e.start}–{e.stop - 1} ({t[e.start]:.2f}–{t[e.stop - 1]:.2f} s)"
            held = f"hold {t[hold.start]:.2f}–{t[hold.stop - 1]:.2f} s"
            out.append(
                f"episode {e.index:3d} {span}, {held}, peak flexion {e.peak_flexion:.2f} rad, {state}, "
                f"{e.source}" + (f" ({e.note})" if e.note else "")
            )
        return out

    def to_dict(self) -> dict:
        """JSON-ready: ``source``, ``note``, ``calibration`` (its text or None), ``episodes``."""
        return {
            "source": self.source,
            "note": self.note,
            "calibration": None if self.calibration is None else self.calibration.text(),
            "episodes": [e.to_dict() for e in self.episodes],
        }


def flexion_columns(dof_names: tuple[str, ...] | list[str]) -> list[int]:
    """The finger flexion DoFs: names containing ``flex``, except the wrist's (``root_…``)."""
    return [i for i, name in enumerate(dof_names) if "flex" in name and not name.startswith("root")]


def summed_flexion(trajectory: Trajectory) -> np.ndarray:
    """Sum of the finger flexion targets per frame, rad (T,).

    Raises:
        TrajectoryError: The trajectory has no finger flexion DoF, or a non-finite flexion target (the
            message names the recording, the DoF and the frame).
    """
    what = trajectory.source or "the trajectory"
    cols = flexion_columns(trajectory.dof_names)
    if not cols:
        raise TrajectoryError(
            f"{what}: no finger flexion DoFs (names containing 'flex', not the wrist's 'root_…') to find "
            f"grasps from; its DoFs are {list(trajectory.dof_names)}"
        )
    values = np.asarray(trajectory.targets, dtype=float)[:, cols]
    bad = ~np.isfinite(values)
    if bad.any():
        frame, col = (int(v[0]) for v in np.nonzero(bad))
        raise TrajectoryError(
            f"{what}: DoF {trajectory.dof_names[cols[col]]!r} is not finite at frame {frame} "
            f"({float(values[frame, col])}); fill the gaps first (handsim.glove.fill_gaps)"
        )
    return values.sum(axis=1)


def segment_grasps(trajectory: Trajectory) -> GraspSegmentation:
    """The grasp episodes of a glove recording.

    A calibration sequence (:func:`~handsim.glove.calibration_sequence.recognise_calibration_sequence`)
    has none; a recording with annotated ``grasp`` phases has one episode per phase (source
    :data:`ANNOTATION`); any other is segmented by :func:`find_grasp_episodes` (source :data:`AUTOMATIC`).

    Args:
        trajectory: The recording, radians; with the phases of its annotation when one matched it
            (:func:`handsim.glove.checks.check_recording`).

    Returns:
        The segmentation.

    Raises:
        TrajectoryError: No finger flexion DoFs or a non-finite flexion target (:func:`summed_flexion`).
    """
    flexion = summed_flexion(trajectory)
    times = np.asarray(trajectory.times, dtype=float)
    calibration = recognise_calibration_sequence(trajectory)
    if calibration is not None:
        return GraspSegmentation(
            (), CALIBRATION, times, flexion, calibration=calibration, note=calibration.text()
        )
    grasps = [p for p in trajectory.phases if p.name.strip(".") == GRASP_PHASE and p.stop > p.start]
    if grasps:
        episodes = _annotated_episodes(trajectory.phases, grasps, flexion)
        note = f"the recording's annotated '{GRASP_PHASE}' phases (each the hold of one episode)"
        return GraspSegmentation(episodes, ANNOTATION, times, flexion, note=note)
    episodes, lo, hi = _automatic(flexion, times)
    if hi - lo < MIN_RANGE_RAD:
        note = (
            f"the summed finger flexion spans {hi - lo:.2f} rad ({lo:.2f}–{hi:.2f} rad), under the "
            f"{MIN_RANGE_RAD:g} rad a closing needs: the fingers barely move"
        )
    else:
        note = (
            f"hysteresis on the summed finger flexion (open {lo:.2f} rad, closed {hi:.2f} rad; a closing "
            f"rises {CLOSING_FRACTION:g} of the range, {CLOSING_FRACTION * (hi - lo):.2f} rad, above the "
            "open hand)"
        )
    return GraspSegmentation(episodes, AUTOMATIC, times, flexion, (lo, hi), note=note)


def find_grasp_episodes(flexion: npt.ArrayLike, times: npt.ArrayLike) -> tuple[GraspEpisode, ...]:
    """Grasp episodes from a summed finger flexion signal, by the hysteresis of this module's docstring.

    Args:
        flexion: Summed finger flexion per frame, rad (T,).
        times: Sample times, s (T,), strictly increasing.

    Returns:
        The episodes (source :data:`AUTOMATIC`), in time order; none when the flexion's range is under
        :data:`MIN_RANGE_RAD`.

    Raises:
        TrajectoryError: The arrays are not 1-D of one length, hold non-finite values, or the times do not
            strictly increase.
    """
    f = np.asarray(flexion, dtype=float)
    t = np.asarray(times, dtype=float)
    if f.ndim != 1 or t.shape != f.shape or f.shape[0] == 0:
        raise TrajectoryError(
            f"flexion and times must be 1-D arrays of one non-zero length, got shapes {f.shape} and {t.shape}"
        )
    for name, values in (("flexion", f), ("times", t)):
        if not np.all(np.isfinite(values)):
            raise TrajectoryError(f"{name} is not finite at frame {int(np.argmax(~np.isfinite(values)))}")
    if np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0)) + 1
        raise TrajectoryError(f"times must strictly increase; sample {k} is not after sample {k - 1}")
    return _automatic(f, t)[0]


# --------------------------------------------------------------------------------------------------
# The hysteresis


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


def _automatic(f: np.ndarray, t: np.ndarray) -> tuple[tuple[GraspEpisode, ...], float, float]:
    """The episodes, and the open and closed flexion the thresholds are scaled by (rad)."""
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


# --------------------------------------------------------------------------------------------------
# Annotated episodes


def _annotated_episodes(
    phases: tuple[Phase, ...], grasps: list[Phase], flexion: np.ndarray
) -> tuple[GraspEpisode, ...]:
    """One episode per annotated grasp phase.

    The reach before it is split at its most open frame into approach and closure; the retract after it is
    the release.
    """
    n = flexion.shape[0]
    episodes = []
    for k, grasp in enumerate(grasps):
        reach = next((p for p in phases if p.name.strip(".") == REACH_PHASE and p.stop == grasp.start), None)
        retract = next(
            (p for p in phases if p.name.strip(".") == RETRACT_PHASE and p.start == grasp.stop), None
        )
        intervals = []
        if reach is not None:
            segment = flexion[reach.start : reach.stop]
            most_open = reach.start + int(segment.shape[0] - 1 - np.argmin(segment[::-1]))
            intervals += [("approach", reach.start, most_open), ("closure", most_open, reach.stop)]
        intervals.append(("hold", grasp.start, grasp.stop))
        if retract is not None:
            intervals.append(("release", retract.start, retract.stop))
        episode_phases = tuple(Phase(name, a, b) for name, a, b in intervals if b > a)
        start, stop = episode_phases[0].start, episode_phases[-1].stop
        notes = []
        if grasp.start == 0:
            notes.append("the annotated grasp starts at the first frame")
        if grasp.stop == n:
            notes.append("the annotated grasp ends at the last frame")
        peak = grasp.start + int(np.argmax(flexion[grasp.start : grasp.stop]))
        episodes.append(
            GraspEpisode(
                index=k + 1,
                start=start,
                stop=stop,
                phases=episode_phases,
                peak_flexion=float(flexion[peak]),
                peak_frame=peak,
                truncated=bool(notes),
                source=ANNOTATION,
                note="; ".join(notes),
            )
        )
    return tuple(episodes)


__all__ = [
    "ANNOTATION",
    "APPROACH_S",
    "AUTOMATIC",
    "CALIBRATION",
    "CLOSING_FRACTION",
    "HOLD_FRACTION",
    "MIN_CLOSED_S",
    "MIN_OPENING_S",
    "MIN_RANGE_RAD",
    "MOVE_FRACTION",
    "PARTIAL_FRACTION",
    "PHASE_NAMES",
    "RANGE_PERCENTILES",
    "RELEASE_FRACTION",
    "RELEASE_S",
    "SMOOTHING_S",
    "GraspEpisode",
    "GraspSegmentation",
    "find_grasp_episodes",
    "flexion_columns",
    "segment_grasps",
    "summed_flexion",
]
