"""When a glove recording's grasp closes: the closing ramp, the closed frame and the hold window.

A glove records the hand alone. What the recording says about the grasp is its finger flexion over time:
the sum of the flexion targets (every DoF named ``…flex…`` except the wrist's ``root_…``;
:func:`handsim.glove.segmentation.summed_flexion`). From it:

* the **closed** frame: the first frame of the hold window whose flexion has risen :data:`CLOSED_FRACTION`
  of the way from the window's first frame to its peak;
* the **open** frame: the most open frame (least flexion) of the reach before it, within
  :data:`OPEN_SEARCH_S` seconds: where the closing that grips the object starts;
* the **closing ramp** ``open … closed`` and its **flexion fraction** ``φ(f) = (F(f) − F(open)) /
  (F(closed) − F(open))``: 0 at the open hand, 1 at the closed grasp. The placement search looks for the
  object at the ramp frames of given fractions (:func:`closing_frames`).

The hold window is, in order of preference: the annotated ``grasp`` phase, a grasp episode's closure and
hold (a recording cut to one episode by :func:`handsim.trials.episodes.episode_trajectory`, whose phases
``closure`` and ``hold`` the segmentation found; closed where the hold starts), or the frames above
:data:`PEAK_WINDOW` of the flexion range around its peak.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handsim.datatypes.trajectory import Trajectory
from handsim.glove.segmentation import summed_flexion

GRASP_PHASE = "grasp"
EPISODE_PHASES = ("closure", "hold")
"""The phases of a grasp episode (:data:`handsim.glove.segmentation.PHASE_NAMES`) the window is read from."""
PEAK_WINDOW = 0.8
"""Without a ``grasp`` phase, the hold window is the frames around peak flexion above this fraction of
the flexion range."""
CLOSED_FRACTION = 0.98
"""The grasp has closed at the first frame of the window whose flexion has risen this fraction of the way
from the window's first frame to its peak."""
OPEN_SEARCH_S = 2.0
"""The open frame is searched this long before the closed frame, s: a reach-to-grasp movement, with the
hand opening to its maximum grip aperture and closing on the object, lasts under a second (Jeannerod 1984,
"The timing of natural prehension movements", J Motor Behav 16(3):235–254), so 2 s covers the whole
closing of one grasp; GraspDB14's annotated sample reaches and closes in 0.95 s (frames 25–81 at 60 Hz)."""


@dataclass(frozen=True)
class GraspFrame:
    """The frames a glove trial's grasp closes over, and the frames holding is judged over.

    Attributes:
        frame: Trajectory frame index where the grasp phase starts (first contact in the annotation).
        closed: Frame at which the grasp has closed: the object's support is released from there.
        window: First and last frame of the hold window (inclusive).
        source: ``"episode"`` (a grasp episode's closure and hold), ``"phase"`` (the annotated ``grasp``
            phase) or ``"peak flexion"``.
        note: For people.
        open: The most open frame of the reach before ``closed`` (start of the closing ramp).
    """

    frame: int
    closed: int
    window: tuple[int, int]
    source: str
    note: str
    open: int = 0

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {
            "frame": self.frame,
            "open": self.open,
            "closed": self.closed,
            "window": list(self.window),
            "source": self.source,
        }


def grasp_frame(trajectory: Trajectory) -> GraspFrame:
    """The grasp frame, the closing ramp and the hold window of a glove recording.

    With an annotated ``grasp`` phase: its first frame (the hand reaches the object), closed at
    :data:`CLOSED_FRACTION` of the flexion rise within the phase; the window is the phase. Else a grasp
    episode (phases ``closure`` and ``hold``): the grasp frame is the closure's first, closed at the hold's
    first; the window runs from the closure to the hold's last frame, so a long hold is judged whole.
    Without either:
    the frames above :data:`PEAK_WINDOW` of the flexion range around the peak; the grasp frame is their
    first, closed at the same fraction of the rise to the peak. The open frame is the least flexed frame
    within :data:`OPEN_SEARCH_S` before the closed frame.

    Raises:
        TrajectoryError: No finger flexion DoFs (names containing ``flex``, not the wrist's ``root_…``), or
            a non-finite flexion target (:func:`~handsim.glove.segmentation.summed_flexion`).
    """
    flex = summed_flexion(trajectory)
    times = np.asarray(trajectory.times, dtype=float)
    for phase in trajectory.phases:
        if phase.name.strip(".") == GRASP_PHASE and phase.stop > phase.start:
            lo, hi = phase.start, phase.stop - 1
            why = f"grasp frame {lo} = start of the annotated 'grasp' phase (frames {lo}–{hi}, 0-based)"
            return _grasp_frame(flex, times, lo, hi, "phase", why)
    named = {p.name: p for p in trajectory.phases if p.stop > p.start}
    if all(name in named for name in EPISODE_PHASES):
        closure, hold = (named[name] for name in EPISODE_PHASES)
        lo, closed, hi = closure.start, hold.start, hold.stop - 1
        opened = _open(flex, times, closed)
        note = (
            f"grasp episode: closure from frame {lo}, hold frames {closed}–{hi} (0-based); closing from "
            f"frame {opened}, closed at frame {closed}"
        )
        return GraspFrame(frame=lo, closed=closed, window=(lo, hi), source="episode", note=note, open=opened)
    peak = int(np.argmax(flex))
    level = flex.min() + PEAK_WINDOW * (flex[peak] - flex.min())
    lo = peak
    while lo > 0 and flex[lo - 1] >= level:
        lo -= 1
    hi = peak
    while hi + 1 < flex.shape[0] and flex[hi + 1] >= level:
        hi += 1
    why = (
        f"no 'grasp' phase: grasp frame {lo} = first of frames {lo}–{hi} above {PEAK_WINDOW:.0%} of the "
        f"flexion range (peak at {peak})"
    )
    return _grasp_frame(flex, times, lo, hi, "peak flexion", why)


def _grasp_frame(flex: np.ndarray, times: np.ndarray, lo: int, hi: int, source: str, why: str) -> GraspFrame:
    """The grasp frame of the window ``lo..hi`` (inclusive) with its closed and open frames."""
    closed = _closed(flex, lo, hi)
    opened = _open(flex, times, closed)
    note = f"{why}; closing from frame {opened}, closed at frame {closed}"
    return GraspFrame(frame=lo, closed=closed, window=(lo, hi), source=source, note=note, open=opened)


def _closed(flex: np.ndarray, lo: int, hi: int) -> int:
    window = flex[lo : hi + 1]
    level = window[0] + CLOSED_FRACTION * (window.max() - window[0])
    return lo + int(np.argmax(window >= level))


def _open(flex: np.ndarray, times: np.ndarray, closed: int) -> int:
    first = int(np.searchsorted(times, times[closed] - OPEN_SEARCH_S - 1e-9))
    return first + int(np.argmin(flex[first : closed + 1]))


def flexion_fraction(trajectory: Trajectory, grasp: GraspFrame, frame: int) -> float:
    """How far the closing has come at ``frame``: 0 at the open frame, 1 at the closed frame.

    Returns 1.0 for a grasp without a rise (the open frame is the closed frame).
    """
    flex = summed_flexion(trajectory)
    rise = flex[grasp.closed] - flex[grasp.open]
    return 1.0 if rise <= 0 else float((flex[frame] - flex[grasp.open]) / rise)


def closing_frames(trajectory: Trajectory, grasp: GraspFrame, fractions: tuple[float, ...]) -> list[int]:
    """The first frame of the closing ramp at or past each flexion fraction (distinct, most closed first).

    Args:
        trajectory: The glove trajectory.
        grasp: Its grasp frames (:func:`grasp_frame`).
        fractions: Flexion fractions in [0, 1].

    Returns:
        Frames in ``[grasp.open, grasp.closed]``, each the first whose fraction reaches one of
        ``fractions``, without repeats, the most closed first.
    """
    flex = summed_flexion(trajectory)[grasp.open : grasp.closed + 1]
    rise = flex[-1] - flex[0]
    frames = set()
    for s in fractions:
        if rise <= 0:
            frames.add(grasp.closed)
            continue
        frames.add(grasp.open + int(np.argmax(flex >= flex[0] + s * rise - 1e-12)))
    return sorted(frames, reverse=True)
