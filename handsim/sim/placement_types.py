"""The glove placement search's parameters and results: the spec, each candidate, the placement.

The search itself is :func:`handsim.sim.placement.place_object` (its module docstring says how it works).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from handsim.sim.grip import GripResult
from handsim.sim.self_contact import SelfPenetration
from handsim.sim.spec_checks import check_positive, check_version
from handsim.sim.stability import StabilitySpec

PLACEMENT_SPEC_VERSION = "2"


@dataclass(frozen=True)
class PlacementSpec:
    """Every parameter of the glove placement search (written into each result).

    Attributes:
        version: Changes whenever a definition or default below changes.
        penetration: Largest penetration of the hand at its targets into the placed object at its fit
            frame, m (about a finger pad's compression under 1 N; see docs/physics.md).
        touch: A link within this distance of the object counts as touching, m.
        search_fractions: Flexion fractions of the closing ramp at which the pose grid is searched.
        coarse_step: Smallest spacing of the coarse grid, m.
        coarse_points: Most grid positions per orientation on the coarse grid (its spacing grows for big
            objects to stay under it).
        fine_step: Finest spacing of the refinement around each seed, m: the spacing is halved from the
            coarse step down to it, each time on the 5 × 5 × 5 grid around the best pose so far.
        seeds: Best coarse poses per search level that are refined and grip-tested.
        grip: The stability test that scores each candidate's grip (the documented test: 1 s per direction;
            a direction's run stops once the object has moved its limit).
        alternatives: Next-best placements kept for the hold-robustness ensemble.
    """

    version: str = PLACEMENT_SPEC_VERSION
    penetration: float = 0.002
    touch: float = 0.002
    search_fractions: tuple[float, ...] = (0.8, 0.7, 0.6, 0.5)
    coarse_step: float = 0.01
    coarse_points: int = 700
    fine_step: float = 0.0025
    seeds: int = 4
    grip: StabilitySpec = field(default_factory=StabilitySpec)
    alternatives: int = 2

    def __post_init__(self) -> None:
        check_version(self.version, PLACEMENT_SPEC_VERSION, "placement")
        check_positive(self, ("penetration", "touch", "coarse_step", "fine_step"), label="placement ")
        if not self.search_fractions or not all(0.0 <= s <= 1.0 for s in self.search_fractions):
            raise ValueError(f"search_fractions must be fractions in [0, 1], got {self.search_fractions}")
        for name in ("coarse_points", "seeds"):
            if getattr(self, name) < 1:
                raise ValueError(f"placement {name} must be ≥ 1, got {getattr(self, name)}")
        if self.alternatives < 0:
            raise ValueError(f"placement alternatives must be ≥ 0, got {self.alternatives}")
        object.__setattr__(self, "search_fractions", tuple(float(s) for s in self.search_fractions))

    def to_dict(self) -> dict:
        """JSON-ready parameters."""
        result = asdict(self)
        result["search_fractions"] = list(self.search_fractions)
        result["grip"] = self.grip.to_dict()
        return result

    @classmethod
    def from_dict(cls, fields: dict) -> PlacementSpec:
        """The spec whose :meth:`to_dict` gave ``fields``."""
        values = dict(fields)
        values["search_fractions"] = tuple(values["search_fractions"])
        grip = dict(values["grip"])
        grip["obman_direction"] = tuple(grip["obman_direction"])
        values["grip"] = StabilitySpec(**grip)
        return cls(**values)


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
