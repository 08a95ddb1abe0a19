"""A grasp episode of a glove recording: its frames, its phases and how it was found.

:mod:`handsim.glove.segmentation` finds the episodes of a recording, from its annotated phases or by the
hysteresis of :mod:`handsim.glove.grasp_hysteresis`.
"""

from __future__ import annotations

from dataclasses import dataclass

from handsim.datatypes.trajectory import Phase
from handsim.errors import TrajectoryError

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
