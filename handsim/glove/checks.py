"""Checks of a glove recording before it is judged: which phase annotation is used, its spikes, its motion.

:func:`check_recording` is what a GraspDB14 trial and ``handsim inspect`` do with a recording as read:
attach the phases of the annotation that belongs to it (as matched by
:func:`handsim.io.graspdb.annotations.match_annotation`), remove single-sample spikes
(:func:`handsim.glove.spikes.remove_spikes`) and flag a recording that cannot hold a task
(:func:`recording_flags`: a hand that never moves, a switch off in every row). :class:`RecordingChecks`
says what was done, for notes, records and the command line; the flags travel with the trajectory
(:attr:`~handsim.datatypes.trajectory.Trajectory.flags`) into every replay's flags.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from handsim.datatypes.flags import Flag
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import TrajectoryError
from handsim.glove.phases import AnnotationMatch, with_phases
from handsim.glove.spikes import MAX_JOINT_SPEED, Spike, remove_spikes

CHECK_FIELDS = ("annotation", "annotation_note", "spikes", "spike_frames", "spike_max_speed_rad_s")
"""The keys of :meth:`RecordingChecks.to_dict`."""


@dataclass(frozen=True)
class RecordingChecks:
    """What the checks of a glove recording found and did.

    Attributes:
        annotation: The phase annotation used (or None) and why.
        spikes: The single-sample spikes marked invalid and filled.
        max_speed: The speed bound the spikes exceed, rad/s.
    """

    annotation: AnnotationMatch
    spikes: tuple[Spike, ...] = ()
    max_speed: float = MAX_JOINT_SPEED

    def to_dict(self) -> dict:
        """JSON-ready, keys :data:`CHECK_FIELDS`.

        ``annotation`` (path or None), ``annotation_note``, ``spikes`` (count), ``spike_frames``,
        ``spike_max_speed_rad_s``.
        """
        path = self.annotation.path
        return {
            "annotation": None if path is None else str(path),
            "annotation_note": self.annotation.note,
            "spikes": len(self.spikes),
            "spike_frames": [s.frame for s in self.spikes],
            "spike_max_speed_rad_s": self.max_speed,
        }

    def spike_text(self) -> str:
        """The spikes for people, one line."""
        if not self.spikes:
            return f"none (no sample jumps faster than {self.max_speed:.1f} rad/s and back)"
        frames = ", ".join(str(s.frame) for s in self.spikes)
        return (
            f"{len(self.spikes)} single-sample spike{'s' if len(self.spikes) != 1 else ''} at frame"
            f"{'s' if len(self.spikes) != 1 else ''} {frames}, marked invalid and filled (linear)"
        )


def recording_flags(trajectory: Trajectory) -> tuple[Flag, ...]:
    """Notes on a glove recording that cannot hold a task: a hand that never moves, a switch never on.

    * ``no_motion``: every row holds the same joint angles (a glove lying still, a frozen stream): there is
      no grasp to judge, which the hold's "not judged: no grasp" says too.
    * ``switch_off``: the glove's switch is off in every row. GraspDB14's actors toggled it to mark the
      start and end of each task (spec §3.5–3.7), and its trials keep it on while the task runs.

    Both are notes (``invalid`` False): the replay's numbers are still the physics of what was recorded.

    Args:
        trajectory: The recording as read.

    Returns:
        The flags, ``no_motion`` before ``switch_off``; none for a recording that moves with its switch on.
    """
    flags = []
    rows = trajectory.nframes
    targets = np.asarray(trajectory.targets, dtype=float)
    if rows > 1 and targets.size and np.array_equal(targets, np.broadcast_to(targets[:1], targets.shape)):
        flags.append(
            Flag(
                "no_motion",
                False,
                f"the hand does not move: all {rows} rows hold the same joint angles, so the recording holds "
                "no grasp (a glove lying still, or a frozen data stream?)",
                {"rows": rows},
            )
        )
    switch = trajectory.switch
    if switch is not None and len(switch) and not np.any(switch):
        flags.append(
            Flag(
                "switch_off",
                False,
                f"the glove's switch is off in all {len(switch)} rows; GraspDB14 actors switch it on for the "
                "task (spec §3.5–3.7): is this the recording of a task?",
                {"rows": len(switch)},
            )
        )
    return tuple(flags)


def check_recording(
    trajectory: Trajectory, annotation: AnnotationMatch
) -> tuple[Trajectory, RecordingChecks]:
    """Attach the annotation's phases (when one is used), remove single-sample spikes, add the flags.

    Args:
        trajectory: A glove recording as read (every sample valid).
        annotation: The phase annotation it uses, with its intervals as read
            (:func:`handsim.io.graspdb.annotations.match_annotation`); the phases it attaches add their
            note to the trajectory's.

    Returns:
        The checked trajectory (its :attr:`~handsim.datatypes.trajectory.Trajectory.flags` extended by
        :func:`recording_flags`) and what the checks did.

    Raises:
        TrajectoryError: An annotated interval ends after the recording's last frame, or the annotation names
            a file but carries none of its intervals (it was not made by ``match_annotation`` or
            ``check_annotation``).
    """
    checked = trajectory
    if annotation.path is not None and not annotation.intervals:
        raise TrajectoryError(
            f"phase annotation {annotation.path}: the match carries none of its intervals; match it with "
            "handsim.io.graspdb.annotations.match_annotation or check_annotation, which read them"
        )
    if annotation.path is not None and not checked.phases:
        checked = with_phases(checked, annotation.intervals, source=str(annotation.path))
    checked, spikes = remove_spikes(checked)
    flags = recording_flags(trajectory)
    if flags:
        checked = dataclasses.replace(checked, flags=(*checked.flags, *flags))
    return checked, RecordingChecks(annotation, spikes)


__all__ = ["CHECK_FIELDS", "RecordingChecks", "check_recording", "recording_flags"]
