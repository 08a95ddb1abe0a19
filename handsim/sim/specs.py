"""The simulation layer's parameter specs, together, and the checks each makes on construction.

:class:`MetricSpec` holds every parameter of the metrics and the glove scenario; it carries the placement
search's :class:`PlacementSpec` and the stability tests' :class:`StabilitySpec`. Each spec is versioned and
written into each result; one made from a file of another handsim version, or with a threshold that is
not a finite positive number, is refused with the field's name and value. The specs sit below every module
that reads them, so no import runs back up the simulation layer.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field

import numpy as np


def check_version(version: str, known: str, what: str) -> None:
    """Refuse a spec of another version.

    Args:
        version: The spec's ``version`` field.
        known: The version this handsim writes.
        what: The spec's name in the message, e.g. ``"metric"``.

    Raises:
        ValueError: ``version`` is not ``known``.
    """
    if version != known:
        raise ValueError(f"unknown {what} spec version {version!r}; this handsim knows {known!r}")


def check_positive(spec: object, names: Iterable[str], label: str = "") -> None:
    """Refuse a field that is not a positive finite number.

    Args:
        spec: The spec.
        names: The fields that must be positive and finite.
        label: Put before the field's name in the message (``"placement "``).

    Raises:
        ValueError: The first such field that is not, with its value.
    """
    for name in names:
        value = getattr(spec, name)
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{label}{name} must be a positive finite number, got {value}")


def check_nonnegative(spec: object, names: Iterable[str], label: str = "") -> None:
    """Refuse a field that is not a finite number ≥ 0 (arguments as :func:`check_positive`).

    Raises:
        ValueError: The first such field that is not, with its value.
    """
    for name in names:
        value = getattr(spec, name)
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"{label}{name} must be a finite number ≥ 0, got {value}")


STABILITY_SPEC_VERSION = "1"
"""Version of :class:`StabilitySpec`: bumped whenever a parameter's meaning or a default changes."""


@dataclass(frozen=True)
class StabilitySpec:
    """Every parameter of a stability test; written into each stability result.

    The test is :func:`~handsim.sim.stability.gravity.stability_test`; its result is a
    :class:`~handsim.sim.stability.gravity.StabilityResult`.

    Attributes:
        version: :data:`STABILITY_SPEC_VERSION`; a result is comparable with another only at the same
            version.
        duration: Simulated time per gravity direction, s (rounded to whole simulation steps).
        gravity: Magnitude of the gravity applied to the objects, m/s².
        max_displacement: Success threshold on the object's centre-of-mass displacement between the start
            and the end of a direction's run, m (strict: displacement < threshold).
        max_rotation_deg: Success threshold on the object's rotation over a run, degrees; None: not judged.
        require_contact: A direction succeeds only if the object still touches the hand at its end.
        obman_duration: Simulated time of the ObMan simulation displacement, s (ObMan: 35 steps of
            1/240 s).
        obman_direction: Direction of gravity for the ObMan displacement, world frame (normalised).
        environment_contacts: Keep the contacts of the world body's geoms (table, floor). False: only the
            hand can hold the object.
    """

    version: str = STABILITY_SPEC_VERSION
    duration: float = 1.0
    gravity: float = 9.81
    max_displacement: float = 0.02
    max_rotation_deg: float | None = None
    require_contact: bool = True
    obman_duration: float = 35.0 / 240.0
    obman_direction: tuple[float, float, float] = (0.0, 0.0, -1.0)
    environment_contacts: bool = False

    def __post_init__(self) -> None:
        check_version(self.version, STABILITY_SPEC_VERSION, "stability")
        check_positive(self, ("duration", "gravity", "max_displacement", "obman_duration"))
        if self.max_rotation_deg is not None and not (
            math.isfinite(self.max_rotation_deg) and self.max_rotation_deg > 0
        ):
            raise ValueError(f"max_rotation_deg must be positive or None, got {self.max_rotation_deg}")
        direction = np.asarray(self.obman_direction, dtype=float)
        if direction.shape != (3,) or not np.all(np.isfinite(direction)) or not np.linalg.norm(direction) > 0:
            raise ValueError(
                f"obman_direction must be 3 finite numbers, not all zero, got {self.obman_direction}"
            )
        object.__setattr__(self, "obman_direction", tuple(float(x) for x in direction))

    def to_dict(self) -> dict:
        """The parameters, JSON-ready."""
        result = asdict(self)
        result["obman_direction"] = list(self.obman_direction)
        return result


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


GRIP_SPEC_VERSION = "1"


@dataclass(frozen=True)
class GripSpec:
    """What a glove hold needs to count as a grip (:func:`handsim.sim.grip_check.check_grip`).

    Attributes:
        version: Changes whenever a definition or default below changes.
        max_depth: Deepest a hand link may be inside the object over the hold window, m: the pad's modelled
            compliance (its impedance reaches full stiffness over the 3 mm width of
            :data:`~handsim.builders.surfaces.PAD_SOLIMP`) plus the placement's 2 mm penetration tolerance
            (:attr:`PlacementSpec.penetration`). Deeper, the outcome is not judged.
        min_opposition: Share of the examined window frames in which the thumb and a finger, or fingers and
            the palm, must press on the object from opposing sides (two contacts in force closure) for a
            hold to count.
        frames: Frames of the window examined for opposition and force (evenly spaced; every frame when the
            window has fewer): one every 50 ms or less over a 1 s hold, each costing a collision query and the
            closure test (about 0.5 ms).
    """

    version: str = GRIP_SPEC_VERSION
    max_depth: float = 0.005
    min_opposition: float = 0.5
    frames: int = 20

    def __post_init__(self) -> None:
        check_version(self.version, GRIP_SPEC_VERSION, "grip")
        check_positive(self, ("max_depth",), label="grip ")
        if not 0.0 <= self.min_opposition <= 1.0:
            raise ValueError(f"grip min_opposition must be a fraction in [0, 1], got {self.min_opposition}")
        if self.frames < 1:
            raise ValueError(f"grip frames must be ≥ 1, got {self.frames}")

    def to_dict(self) -> dict:
        """JSON-ready parameters."""
        return asdict(self)


METRIC_SPEC_VERSION = "3"
HOLD_ORIENTATIONS = ("grip", "palm down")
"""How the glove scenario orients the hand for the hold (:attr:`MetricSpec.hold_orientation`)."""


@dataclass(frozen=True)
class MetricSpec:
    """Every parameter the metrics and scenarios use; written into each result (sources: docs/physics.md).

    Attributes:
        version: Changes whenever a definition or default below changes.
        drift_tolerance: Recorded objects: a frame is "on track" when the object's position is within this
            distance of the recording, m.
        release_delay: Glove scenario: the support is switched off this long after the grasp has closed, s
            (lets the fingers reach the grasp the recording reached; ~3 servo time constants).
        slip_limit: Glove scenario: the object is lost once it moved this far relative to the hand root
            since release, m.
        contact_gap: Glove scenario: the object is lost once no hand link touched it for this long, s.
        min_hold_window: Glove scenario: holding is judged only over at least this long after release, s;
            a shorter window is "not judged". An object in free fall crosses the 2 cm slip limit in 64 ms
            (√(2 · 0.02 / 9.81)); over 0.3 s any slip accelerating at 0.45 m/s² (5 % of g) or more does.
        robustness_shift: Glove scenario: the hold-robustness ensemble moves the placed object by this much
            along each axis of the scene, m.
        robustness_turn_deg: … and turns it by this much about each axis, degrees.
        robustness_undriven_deg: Glove scenario: the ensemble turns each undriven thumb DoF, and the other
            DoFs no glove sensor drives together, by ± this much, degrees (0: no such members).
        robustness_sensor_deg: … and offsets every sensor-driven DoF together by ± this much, degrees: the
            CyberGlove's repeatability between wearings (0: no such members).
        hold_orientation: Glove scenario: ``"grip"`` — the hand is palm down (GraspDB14's objects are picked
            up from a table) when its grip resists gravity that way, else turned so that gravity pulls along
            the axis direction its grip resists best (a hand on its side, fingers down), never into the palm
            (an object lying on an open hand is no grasp); ``"palm down"`` — always palm down.
        placement: The glove placement search's parameters (:class:`PlacementSpec`).
        stability: The grasp stability tests' parameters (:class:`StabilitySpec`).
        grip: What a glove hold needs to count as a grip (:class:`GripSpec`).
    """

    version: str = METRIC_SPEC_VERSION
    drift_tolerance: float = 0.01
    release_delay: float = 0.1
    slip_limit: float = 0.02
    contact_gap: float = 0.1
    min_hold_window: float = 0.3
    robustness_shift: float = 0.002
    robustness_turn_deg: float = 5.0
    robustness_undriven_deg: float = 5.0
    robustness_sensor_deg: float = 3.0
    hold_orientation: str = "grip"
    placement: PlacementSpec = field(default_factory=PlacementSpec)
    stability: StabilitySpec = field(default_factory=StabilitySpec)
    grip: GripSpec = field(default_factory=GripSpec)

    def __post_init__(self) -> None:
        check_version(self.version, METRIC_SPEC_VERSION, "metric")
        check_positive(self, ("drift_tolerance", "slip_limit", "contact_gap", "min_hold_window"))
        if self.hold_orientation not in HOLD_ORIENTATIONS:
            raise ValueError(
                f"unknown hold_orientation {self.hold_orientation!r}; "
                f"expected one of {list(HOLD_ORIENTATIONS)}"
            )
        check_nonnegative(
            self,
            (
                "release_delay",
                "robustness_shift",
                "robustness_turn_deg",
                "robustness_undriven_deg",
                "robustness_sensor_deg",
            ),
        )

    def to_dict(self) -> dict:
        """JSON-ready parameters."""
        result = asdict(self)
        result["placement"] = self.placement.to_dict()
        result["stability"] = self.stability.to_dict()
        result["grip"] = self.grip.to_dict()
        return result

    @classmethod
    def from_dict(cls, fields: dict) -> MetricSpec:
        """The spec whose :meth:`to_dict` gave ``fields`` (as read back from JSON).

        Raises:
            ValueError: ``fields`` are of another version, or a value is out of its range.
        """
        values = dict(fields)
        if values.get("version") != METRIC_SPEC_VERSION:
            raise ValueError(
                f"metric spec version {values.get('version')!r}; this handsim reads {METRIC_SPEC_VERSION!r}"
            )
        stability = dict(values["stability"])
        stability["obman_direction"] = tuple(stability["obman_direction"])
        values["stability"] = StabilitySpec(**stability)
        values["placement"] = PlacementSpec.from_dict(values["placement"])
        values["grip"] = GripSpec(**values["grip"])
        return cls(**values)


TRACK_SPEC_VERSION = "1"
"""Version of :class:`TrackSpec`: bumped whenever a tolerance's meaning or a default changes."""


@dataclass(frozen=True)
class TrackSpec:
    """The tolerances of the verdict on a recorded object's track and of its flags (sources: docs/physics.md).

    The verdict is :func:`handsim.sim.track.track_verdict`: a recorded object is *followed* while its
    simulated pose stays within these tolerances of its recording; the frames judged are those in which the
    recording has moved it beyond them from where it started (an object left where it was would not follow).

    Attributes:
        version: :data:`TRACK_SPEC_VERSION`.
        position: Largest distance of the object's origin from its recording, m. ManipTrans's (Li et al.,
            CVPR 2025) object-tracking failure threshold at the end of its curriculum: 2 cm.
        rotation_deg: Largest rotation from the recorded orientation, degrees (ManipTrans: 30°).
        articulation_deg: Largest hinge angle from the recorded articulation, degrees: a lid is a rigid part,
            so ManipTrans's rotation threshold applies to its angle too.
        floor_clearance: An object whose lowest point ends within this of the floor lies on the floor, m.
        max_penetration: A hand deeper than this inside an object at any frame passes through it, m: more
            than a finger's half thickness (MANO's joints lie 6–10 mm under the skin), two and a half times
            the 4 mm at which a finger pad carries 15–26 N (docs/physics.md, "Finger pad calibration").
    """

    version: str = TRACK_SPEC_VERSION
    position: float = 0.02
    rotation_deg: float = 30.0
    articulation_deg: float = 30.0
    floor_clearance: float = 0.01
    max_penetration: float = 0.01

    def __post_init__(self) -> None:
        check_version(self.version, TRACK_SPEC_VERSION, "track")
        check_positive(
            self, ("position", "rotation_deg", "articulation_deg", "floor_clearance", "max_penetration")
        )

    def to_dict(self) -> dict:
        """The tolerances, JSON-ready."""
        return asdict(self)
