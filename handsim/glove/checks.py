"""Checks of a glove recording before it is judged: which phase annotation is used, and its spikes.

:func:`check_recording` is what a GraspDB14 trial and ``handsim inspect`` do with a recording as read:
attach the phases of the annotation that belongs to it (as matched by
:func:`handsim.io.graspdb.annotations.match_annotation`) and remove single-sample spikes
(:func:`handsim.glove.spikes.remove_spikes`). :class:`RecordingChecks` says what was done, for notes,
records and the command line.
"""

from __future__ import annotations

from dataclasses import dataclass

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


def check_recording(
    trajectory: Trajectory, annotation: AnnotationMatch
) -> tuple[Trajectory, RecordingChecks]:
    """Attach the annotation's phases (when one is used) and remove single-sample spikes.

    Args:
        trajectory: A glove recording as read (every sample valid).
        annotation: The phase annotation it uses, with its intervals as read
            (:func:`handsim.io.graspdb.annotations.match_annotation`); the phases it attaches add their
            note to the trajectory's.

    Returns:
        The checked trajectory and what the checks did.

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
    return checked, RecordingChecks(annotation, spikes)


__all__ = ["CHECK_FIELDS", "RecordingChecks", "check_recording"]
