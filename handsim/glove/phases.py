"""Trial phases of CyberGlove recordings on plain data: switch segments, annotated intervals, cutting.

Two sources name frame intervals of a recording:

* The glove's **switch** (spec §3.5–3.7): the actors toggled it to mark poses of the calibration
  sequence and the start and end of each task. :func:`switch_segments` / :func:`split_by_switch` turn
  the switch state into ``on``/``off`` :class:`~handsim.datatypes.trajectory.Phase` intervals.
* **Phase annotation files** (``<motion name>_annot-.txt``), read by
  :mod:`handsim.io.graspdb.annotations` into :class:`PhaseAnnotation` intervals (label, 0-based start,
  exclusive stop); :class:`AnnotationMatch` says which annotation a recording uses, and why.

Phases become named frame intervals of a :class:`~handsim.datatypes.trajectory.Trajectory` (``start`` 0-based,
``stop`` exclusive) with :func:`with_phases`; :func:`cut` slices a trajectory to one phase.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from handsim.datatypes.trajectory import ObjectTrack, Phase, Trajectory
from handsim.errors import TrajectoryError

SWITCH_ON = "on"
"""Name of a phase during which the glove switch is ON."""

SWITCH_OFF = "off"
"""Name of a phase during which the glove switch is OFF."""


# --------------------------------------------------------------------------------------------------
# Switch segments


def switch_segments(switch: npt.ArrayLike) -> tuple[Phase, ...]:
    """Split a switch-state series into maximal runs of equal state.

    Args:
        switch: Switch state per frame, shape (T,): booleans or 0/1 numbers.

    Returns:
        The runs in frame order, named :data:`SWITCH_ON` or :data:`SWITCH_OFF`; they tile ``[0, T)``.

    Raises:
        TrajectoryError: ``switch`` is not a non-empty 1-D array of booleans or 0/1 values.
    """
    s = np.asarray(switch)
    if s.ndim != 1 or s.shape[0] == 0:
        raise TrajectoryError(f"switch must be a non-empty 1-D array, got shape {s.shape}")
    if s.dtype != bool:
        if not np.issubdtype(s.dtype, np.number) or not np.all((s == 0) | (s == 1)):
            bad = int(np.argmax(~((s == 0) | (s == 1)))) if np.issubdtype(s.dtype, np.number) else 0
            raise TrajectoryError(
                f"switch must hold booleans or 0/1 values; frame {bad} holds {s[bad].item()!r}"
            )
        s = s == 1
    edges = (np.flatnonzero(s[1:] != s[:-1]) + 1).tolist()
    starts = [0, *edges]
    stops = [*edges, s.shape[0]]
    return tuple(
        Phase(SWITCH_ON if s[a] else SWITCH_OFF, int(a), int(b)) for a, b in zip(starts, stops, strict=True)
    )


def split_by_switch(trajectory: Trajectory, *, state: bool | None = None) -> tuple[Phase, ...]:
    """The switch segments of a CyberGlove recording as phases.

    In the GraspDB14 scenarios the switch is ON while a task is executed (spec §3.6), so
    ``split_by_switch(traj, state=True)`` gives the motion trials of an uncut recording.

    Args:
        trajectory: A recording with a switch state (:attr:`Trajectory.switch`).
        state: Keep only the ON (True) or OFF (False) segments; None keeps all.

    Returns:
        Phases named ``"on"``/``"off"`` in frame order.

    Raises:
        TrajectoryError: The trajectory has no switch state.
    """
    if trajectory.switch is None:
        what = trajectory.source or "the trajectory"
        raise TrajectoryError(f"{what} has no switch state (only CyberGlove recordings carry one)")
    segments = switch_segments(trajectory.switch)
    if state is None:
        return segments
    wanted = SWITCH_ON if state else SWITCH_OFF
    return tuple(p for p in segments if p.name == wanted)


# --------------------------------------------------------------------------------------------------
# Annotated intervals


@dataclass(frozen=True)
class PhaseAnnotation:
    """One interval of a GraspDB14 phase annotation file.

    Attributes:
        label: The label as written, e.g. ``".rest"`` or ``"reach-overopen-closing"``.
        start: First frame, 0-based (the file's first frame minus 1).
        stop: One past the last frame (the file's last frame, which is 1-based and inclusive).
        line: 1-based line of the file it was read from (0 when not read from a file).
    """

    label: str
    start: int
    stop: int
    line: int = 0

    @property
    def name(self) -> str:
        """Phase name: the label without its leading ``.`` and qualifiers (``"reach"``)."""
        return self.label.lstrip(".").split("-")[0]

    @property
    def static(self) -> bool:
        """True for a static phase (label starts with ``.``: the hand holds a pose)."""
        return self.label.startswith(".")

    @property
    def qualifiers(self) -> tuple[str, ...]:
        """The ``-``-separated words after the name (``("overopen", "closing")``)."""
        return tuple(self.label.lstrip(".").split("-")[1:])

    def to_phase(self) -> Phase:
        """The interval as a trajectory :class:`~handsim.datatypes.trajectory.Phase` named :attr:`name`."""
        return Phase(self.name, self.start, self.stop)


@dataclass(frozen=True)
class AnnotationMatch:
    """Which phase annotation a recording uses, and why (or why none).

    Made by :func:`handsim.io.graspdb.annotations.match_annotation` (or ``check_annotation``).

    Attributes:
        path: The annotation file used, or None.
        note: For people: the file and the frames it covers, or why no annotation is used. A file that lies
            beside the recording but is not used gives a note starting with ``warning:``.
        intervals: The intervals of :attr:`path` as read when it was matched (empty when none is used). Not
            compared: the file names them.
    """

    path: Path | None
    note: str
    intervals: tuple[PhaseAnnotation, ...] = field(default=(), compare=False, repr=False)

    @property
    def warning(self) -> bool:
        """An annotation lies beside the recording but is not used."""
        return self.note.startswith("warning:")


# --------------------------------------------------------------------------------------------------
# Phases on trajectories


def with_phases(
    trajectory: Trajectory, items: Sequence[Phase | PhaseAnnotation], source: str = "given intervals"
) -> Trajectory:
    """Set a trajectory's phases from given intervals.

    From an annotation file: :func:`handsim.io.graspdb.annotations.attach_phases`.

    Args:
        trajectory: The recording the phases belong to.
        items: Phases or annotated intervals (frame numbers 0-based, stop exclusive).
        source: Where the intervals come from (an annotation file's path), for the note and messages.

    Returns:
        A copy of the trajectory with :attr:`~Trajectory.phases` replaced (annotations become phases named
        :attr:`PhaseAnnotation.name`) and a note naming the source, each interval's label, and frames no
        phase covers.

    Raises:
        TrajectoryError: An interval ends after the trajectory's last frame (the message names the
            source and the annotation's line).
    """
    n = trajectory.nframes
    phases: list[Phase] = []
    labels: list[str] = []
    for item in items:
        if isinstance(item, PhaseAnnotation):
            if item.stop > n:
                where = f"{source}:{item.line}" if item.line else source
                raise TrajectoryError(
                    f"{where}: interval {item.start + 1}-{item.stop} ({item.label}) ends after the last "
                    f"frame {n} of {trajectory.source or 'the trajectory'}; is it the annotation of another "
                    "motion?"
                )
            phases.append(item.to_phase())
            labels.append(f"{item.label} [{item.start}, {item.stop})")
        else:
            phases.append(item)
            labels.append(f"{item.name} [{item.start}, {item.stop})")
    covered = np.zeros(n, dtype=bool)
    for phase in phases:
        covered[max(phase.start, 0) : max(phase.stop, 0)] = True
    note = f"phases from {source} (frames 0-based, stop exclusive): {', '.join(labels)}"
    if not covered.all():
        note += f"; {int((~covered).sum())} of {n} frames are in no phase"
    return dataclasses.replace(trajectory, phases=tuple(phases), notes=(*trajectory.notes, note))


def cut(trajectory: Trajectory, phase: Phase | str) -> Trajectory:
    """The part of a trajectory inside one phase, as a trajectory of its own.

    Every per-frame array (targets, validity, switch, root pose, channels, filled mask, object tracks) is
    sliced to ``[phase.start, phase.stop)``; times restart at 0; phases overlapping the interval are
    clipped to it and shifted. A note records the cut.

    Args:
        trajectory: The recording.
        phase: A :class:`~handsim.datatypes.trajectory.Phase`, or the name of one of the trajectory's phases
        (the
            first with that name).

    Returns:
        The cut trajectory.

    Raises:
        TrajectoryError: No phase has that name, or the phase lies outside the trajectory's frames.
    """
    p = trajectory.phase(phase) if isinstance(phase, str) else phase
    n = trajectory.nframes
    if not 0 <= p.start < p.stop <= n:
        raise TrajectoryError(f"phase {p.name!r} spans frames [{p.start}, {p.stop}), outside [0, {n})")
    sl = slice(p.start, p.stop)

    def part(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else np.asarray(a)[sl].copy()

    phases = tuple(
        Phase(q.name, max(q.start, p.start) - p.start, min(q.stop, p.stop) - p.start)
        for q in trajectory.phases
        if q.start < p.stop and q.stop > p.start
    )
    t0 = float(trajectory.times[p.start])
    return dataclasses.replace(
        trajectory,
        times=trajectory.times[sl] - t0,
        targets=trajectory.targets[sl].copy(),
        valid=trajectory.valid[sl].copy(),
        switch=part(trajectory.switch),
        root_pose=part(trajectory.root_pose),
        hand_roots={k: np.asarray(v)[sl].copy() for k, v in trajectory.hand_roots.items()},
        channels={k: np.asarray(v)[sl].copy() for k, v in trajectory.channels.items()},
        filled=part(trajectory.filled),
        phases=phases,
        objects={
            k: ObjectTrack(
                pose=np.asarray(o.pose)[sl].copy(), articulation=part(o.articulation), valid=part(o.valid)
            )
            for k, o in trajectory.objects.items()
        },
        notes=(
            *trajectory.notes,
            f"cut to phase {p.name!r}: frames [{p.start}, {p.stop}) of the original, whose time {t0:.5f} s "
            "is time 0 here",
        ),
    )


__all__ = [
    "SWITCH_OFF",
    "SWITCH_ON",
    "AnnotationMatch",
    "PhaseAnnotation",
    "cut",
    "split_by_switch",
    "switch_segments",
    "with_phases",
]
