"""The glove placement search's parameters and results: the spec, each candidate, the placement.

The search itself is :func:`handsim.sim.placement.place.place_object` (its module docstring says how it
works).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handsim.sim.placement.grip import GripResult
from handsim.sim.self_contact import SelfPenetration


@dataclass(frozen=True)
class Candidate:
    """An object pose the search keeps, with what it found out about it.

    Attributes:
        pose: (x, y, z, qw, qx, qy, qz) in the search scene's world.
        links: Hand links touching it at its fit frame.
        depth: Deepest penetration at its fit frame, m.
        fit_frame: Latest closing-ramp frame at which it fits (penetration within the tolerance).
        fit_fraction: The fit frame's flexion fraction (1.0: it fits at full closure).
        contact_frame: First frame of the run of frames up to the fit frame in which it fits: hand–object
            contacts act from there.
        depth_before_contact: Deepest penetration in the frame before ``contact_frame``, m (0 when the run
            starts at frame 0).
        grip: Its grip test, or None before it is run.
    """

    pose: np.ndarray
    links: tuple[str, ...]
    depth: float
    fit_frame: int
    fit_fraction: float
    contact_frame: int
    depth_before_contact: float
    grip: GripResult | None = None

    def score(self) -> tuple:
        """Larger is better: directions held, later fit, smaller mean displacement, more links, less depth."""
        held = -1 if self.grip is None else self.grip.directions_held
        moved = np.inf if self.grip is None else self.grip.mean_displacement
        return (held, round(self.fit_fraction, 6), -moved, len(self.links), -self.depth)

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {
            "pose": self.pose.tolist(),
            "links": list(self.links),
            "penetration_m": self.depth,
            "fit_frame": self.fit_frame,
            "fit_fraction": self.fit_fraction,
            "contact_frame": self.contact_frame,
            "depth_before_contact_m": self.depth_before_contact,
            "grip": None if self.grip is None else self.grip.to_dict(),
        }


@dataclass(frozen=True)
class Placement:
    """The object pose a search found, and how it found it.

    Attributes:
        best: The winning candidate (its pose in the search scene's world).
        alternatives: The next-best grip-tested candidates whose grip resists as many directions as the
            winner's, best first (for the robustness ensemble: placements the search could as well have
            chosen).
        perturbations: The winner moved and turned by fixed amounts (for the robustness ensemble), each with
            its label (``"+x 2 mm"``, ``"-z 5°"`` …) and its own fit and contact frames.
        feasible: Some pose was within the penetration tolerance; False: ``best`` is the least penetrating
            pose seen and the hold cannot be judged.
        queries: Poses and frames tried (by a collision query, or settled by the bounds).
        grip_tests: Candidates whose grip was tested.
        feasible_poses: Poses within the tolerance seen on the grids.
        object_points: The object's collision points in its own frame (mesh vertices; primitives' extreme
            points), m: where its lowest point is in any pose.
        self_penetration: The hand through itself at the closed frame (at its targets): a recording-quality
            number (a thumb through the index: glove calibration, or a thumb the skeleton cannot place).
        spec: The :class:`PlacementSpec` used (JSON-ready).
        note: For people.
    """

    best: Candidate
    alternatives: tuple[Candidate, ...]
    perturbations: tuple[tuple[str, Candidate], ...]
    feasible: bool
    queries: int
    grip_tests: int
    feasible_poses: int
    object_points: np.ndarray
    self_penetration: SelfPenetration
    spec: dict
    note: str

    @property
    def pose(self) -> np.ndarray:
        """The winning pose."""
        return self.best.pose

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {
            **self.best.to_dict(),
            "feasible": self.feasible,
            "candidates": self.queries,
            "grip_tests": self.grip_tests,
            "feasible_poses": self.feasible_poses,
            "alternatives": [c.to_dict() for c in self.alternatives],
            "perturbations": [{"label": label, **c.to_dict()} for label, c in self.perturbations],
            "self_penetration_at_closure": self.self_penetration.to_dict(),
            "spec": self.spec,
        }
