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

**Method.** The stretch over which the hand is closed on the object is read off the **summed finger
flexion** (every ``…flex…`` DoF but the wrist's) by a two-threshold (hysteresis) detector: a closing must
rise :data:`CLOSING_FRACTION` of the recording's range above the open hand to start and fall halfway back
to end, so noise near one threshold cannot split or start an episode. :mod:`handsim.glove.grasp_hysteresis`
gives the steps, the phases they mark and the reasons for every parameter.

**Partial closings are not grasps.** A rise of less than two fifths of the range does not start an
episode: a hand that closes on an object reaches about the same closed flexion every time it grasps it,
and a closing that stops far short of that is an adjustment or a finger moving on its own. An episode is
**truncated** when the file starts with the hand already closed or closing (no frame shows it open before
the closure) or ends before the release.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from handsim.datatypes.trajectory import Phase, Trajectory
from handsim.errors import TrajectoryError
from handsim.glove.calibration_sequence import CalibrationSequence, recognise_calibration_sequence
from handsim.glove.grasp_episode import (
    ANNOTATION,
    AUTOMATIC,
    CALIBRATION,
    GRASP_PHASE,
    PHASE_NAMES,
    REACH_PHASE,
    RETRACT_PHASE,
    GraspEpisode,
)
from handsim.glove.grasp_hysteresis import (
    APPROACH_S,
    CLOSING_FRACTION,
    HOLD_FRACTION,
    MIN_CLOSED_S,
    MIN_OPENING_S,
    MIN_RANGE_RAD,
    MOVE_FRACTION,
    PARTIAL_FRACTION,
    RANGE_PERCENTILES,
    RELEASE_FRACTION,
    RELEASE_S,
    SMOOTHING_S,
    automatic_episodes,
)


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
    episodes, lo, hi = automatic_episodes(flexion, times)
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
    return automatic_episodes(f, t)[0]


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
