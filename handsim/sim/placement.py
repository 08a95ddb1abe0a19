"""Where to put the object a glove recording grasped: where it fits in the closing hand and is gripped best.

GraspDB14 records the hand, not the object, and a CyberGlove's calibration usually over-reports flexion:
at the closed frame the recorded fingers lie *inside* the object they held (fingertips 22–26 mm from the
thumb tip around a 64 mm ball in the shared recordings). So the object is placed where it fits in the hand
*before* closure, and the recorded closing then grips it — the fingers the recording closes past the object
stop at its surface and press on it.

The search (:func:`place_object`):

1. **Candidates.** At the closing-ramp frames of :attr:`PlacementSpec.search_fractions`
   (:func:`handsim.sim.grasp_frame.closing_frames`), object poses on a grid over the hand's reach (24
   axis-aligned orientations unless the object is a sphere) are scored by MuJoCo's own collision detection
   (:class:`~handsim.sim.collide.HandObjectCollider`): poses with at most
   :attr:`PlacementSpec.penetration` of penetration that touch the most hand links, ties to the pose nearest
   the fingertips' centre at the closed frame. The best :attr:`PlacementSpec.seeds` of each level are
   refined on a finer grid.
2. **Fit frame.** Each candidate's fit frame is the latest frame of the closing ramp at which the hand at its
   targets penetrates it at most :attr:`PlacementSpec.penetration`: its flexion fraction says how far the
   recorded closing passes the object (1.0: it fits at full closure).
3. **Grip.** From its fit frame to the release, the recorded closing grips each candidate held in place, and
   the grasp stability test (gravity along ±x ±y ±z, after DexGraspNet; :mod:`handsim.sim.grip`) counts the
   directions the grip resists. The winner resists the most directions; ties go to the later fit (less
   over-closure assumed), then to the smaller mean displacement, then to more links and less penetration.

Every pose within the tolerance is a candidate: when none touches the hand, the feasible pose nearest the
fingertips' centre is kept (with a note); only when no pose of any level is within the tolerance is the
placement infeasible, and then it says so with the numbers (the replay's hold is then not judged).

Speed: the poses of one orientation are first screened together by cheap bounds
(:meth:`HandObjectCollider.screen`): a pose that touches nothing, or that is surely deeper than the
tolerance plus :data:`SCREEN_MARGIN`, is settled without a collision query; the result is the same as
querying every pose (an infeasible search is rerun without the bounds, so that its least penetration is
MuJoCo's). :func:`place_object` keeps each result in the placement cache (:mod:`handsim.sim.placement_cache`).
"""

from __future__ import annotations

import itertools
import math
import pickle
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import mujoco
import numpy as np
from scipy.spatial import cKDTree

from handsim.builders.decompose import default_cache_dir
from handsim.datatypes.fingers import finger_of
from handsim.datatypes.rotations import quat_multiply
from handsim.datatypes.trajectory import Trajectory
from handsim.sim.collide import CLEAR, DEEP, HandObjectCollider
from handsim.sim.compiled import SimScene
from handsim.sim.grasp_frame import GraspFrame, closing_frames, flexion_fraction
from handsim.sim.grip import GripBench, GripResult
from handsim.sim.hand_pose import targets_qpos
from handsim.sim.placement_cache import CorruptEntryError, entry_path, placement_key, read_entry, write_entry
from handsim.sim.self_contact import SelfCollider, SelfPenetration
from handsim.sim.stability import DIRECTIONS, DirectionResult, StabilityResult, StabilitySpec

PLACEMENT_SPEC_VERSION = "2"
SCREEN_MARGIN = 0.0005
"""A pose whose inscribed balls overlap the hand's by more than the penetration tolerance plus this is
settled as infeasible without a collision query, m: MuJoCo's convex penetration depths (GJK/EPA, tolerance
1e-6) came out at most 0.012 mm below the bound on the 140 000 queries of the shared recordings' searches,
so the margin is 40× that; the winner does not depend on it (docs/replay.md)."""
_FINGERS = frozenset({"index", "middle", "ring", "little"})


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
        if self.version != PLACEMENT_SPEC_VERSION:
            raise ValueError(
                f"unknown placement spec version {self.version!r}; "
                f"this handsim knows {PLACEMENT_SPEC_VERSION!r}"
            )
        for name in ("penetration", "touch", "coarse_step", "fine_step"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"placement {name} must be a positive finite number, got {value}")
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


def _axis_aligned() -> np.ndarray:
    """The 24 orientations that put one of the object's six face directions up, each at four spins."""
    h = np.sqrt(0.5)
    faces = [[1, 0, 0, 0], [h, h, 0, 0], [0, 1, 0, 0], [h, -h, 0, 0], [h, 0, h, 0], [h, 0, -h, 0]]
    spins = [[np.cos(a / 2), 0, 0, np.sin(a / 2)] for a in (0, np.pi / 2, np.pi, 3 * np.pi / 2)]
    return np.array([quat_multiply(s, f) for f, s in itertools.product(faces, spins)])


def _distinct(quats: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The orientations that give the object's collision points different shapes, the first of each kept.

    A box keeps one, a cylinder three (its axis along x, y or z), an asymmetric object all 24.
    """
    tolerance = 1e-6 + 1e-5 * float(np.abs(points).max())
    bound = np.nextafter(tolerance, np.inf)  # the tree finds every point within the tolerance
    kept: list[tuple[np.ndarray, cKDTree, np.ndarray, np.ndarray]] = []
    for quat in quats:
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, quat)
        turned = points @ rot.reshape(3, 3).T
        low, high = turned.min(axis=0), turned.max(axis=0)
        if any(
            # points all within the tolerance of the kept set lie within its box widened by the tolerance
            bool((low >= box_low - bound).all() and (high <= box_high + bound).all())
            and bool(tree.query(turned, distance_upper_bound=bound)[0].max() <= tolerance)
            for _, tree, box_low, box_high in kept
        ):
            continue
        kept.append((quat, cKDTree(turned), low, high))
    return np.array([q for q, *_ in kept])


_RING = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)


def _geom_points(model: mujoco.MjModel, geom: int) -> np.ndarray:
    """Points on a collision geom's surface in its own frame.

    A mesh's vertices; a primitive's extreme points, so that a symmetric primitive gives a symmetric set.
    """
    kind, size = mujoco.mjtGeom(int(model.geom_type[geom])), model.geom_size[geom]
    axes = np.vstack([np.eye(3), -np.eye(3)])
    if kind == mujoco.mjtGeom.mjGEOM_MESH and model.geom_dataid[geom] >= 0:
        mesh = int(model.geom_dataid[geom])
        return model.mesh_vert[model.mesh_vertadr[mesh] : model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return axes * size[0]
    if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        return axes * np.tile(size, 2)
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return np.array(list(itertools.product(*((-s, s) for s in size))))
    if kind in (mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_CAPSULE):
        rim = np.column_stack([np.cos(_RING), np.sin(_RING), np.zeros(_RING.size)]) * size[0]
        rims = [rim + np.array([0.0, 0.0, z]) for z in (-size[1], size[1])]
        if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
            rims.append(np.array([[0.0, 0.0, -size[1] - size[0]], [0.0, 0.0, size[1] + size[0]]]))
        return np.vstack(rims)
    r = model.geom_rbound[geom]
    return np.array(list(itertools.product((-r, r), repeat=3)))


def _object_points(collider: HandObjectCollider) -> np.ndarray:
    """The object's collision points in its root body's frame (:func:`_geom_points` of every geom)."""
    model, data = collider.model, collider.data
    a = collider.obj.free_qpos
    data.qpos[a : a + 7] = [0, 0, 0, 1, 0, 0, 0]
    mujoco.mj_kinematics(model, data)
    return np.vstack(
        [
            _geom_points(model, g) @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]
            for g in np.flatnonzero(collider.is_obj)
        ]
    )


def _grid(lo: np.ndarray, hi: np.ndarray, step: float) -> np.ndarray:
    axes = [
        np.arange(a, b + 1e-9, step) if b > a else np.array([(a + b) / 2])
        for a, b in zip(lo, hi, strict=True)
    ]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def _around(center: np.ndarray, half: float, step: float) -> np.ndarray:
    n = int(np.floor(half / step + 1e-9))
    offsets = np.arange(-n, n + 1) * step
    return center + np.stack(np.meshgrid(offsets, offsets, offsets, indexing="ij"), axis=-1).reshape(-1, 3)


class _Search:
    """The grid search at one hand posture (see the module docstring)."""

    def __init__(
        self, scene: SimScene, trajectory: Trajectory, grasp: GraspFrame, spec: PlacementSpec, screen: bool
    ) -> None:
        self.scene, self.trajectory, self.grasp, self.spec = scene, trajectory, grasp, spec
        self.screen = screen  # settle poses by bounds where they decide the query (CLEAR, DEEP)
        self.screened = 0  # poses settled without a collision query
        self.pruned_deep = False  # some pose was settled as infeasible: the least penetration is not known
        self.collider = HandObjectCollider(scene, spec.touch)
        self.points = _object_points(self.collider)
        self.quats = _distinct(_axis_aligned(), self.points)
        model, geoms = self.collider.model, np.flatnonzero(self.collider.is_obj)
        self.round = (  # one sphere about the object's origin: no turn changes it
            len(geoms) == 1
            and int(model.geom_type[geoms[0]]) == int(mujoco.mjtGeom.mjGEOM_SPHERE)
            and np.allclose(model.geom_pos[geoms[0]], 0.0)
        )
        self.radius = float(np.linalg.norm(self.points, axis=1).max())
        layout = scene.layout
        collider = self.collider
        collider.set_hand(targets_qpos(scene, trajectory, grasp.closed))
        mujoco.mj_kinematics(collider.model, collider.data)
        tips = collider.data.site_xpos[layout.tip_sites].copy()
        self.centre = tips.mean(axis=0)
        thumbs = [i for i, name in enumerate(layout.tip_names) if finger_of(name) == "thumb"]
        others = [i for i in range(len(tips)) if i not in thumbs]
        self.grasp_points = np.vstack(
            [self.centre, *((tips[t] + tips[o]) / 2 for t in thumbs for o in others)]
        )
        self.groups = [finger_of(name) for name in layout.link_names]
        self.feasible_poses = 0
        self.least: tuple[float, np.ndarray] | None = None  # least penetration seen, pose
        self.nearest: tuple[float, np.ndarray] | None = None  # feasible pose nearest the centre

    def _reach(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        collider, layout = self.collider, self.scene.layout
        mujoco.mj_kinematics(collider.model, collider.data)
        data = collider.data
        reach = np.vstack([data.xpos[layout.link_bodies], data.site_xpos[layout.tip_sites]])
        centres, radii = collider.hand_spheres()
        return reach.min(axis=0), reach.max(axis=0), centres, radii

    def _consider(self, pose: np.ndarray, depth: float) -> None:
        if self.least is None or depth < self.least[0]:
            self.least = (depth, pose)
        if depth <= self.spec.penetration:
            self.feasible_poses += 1
            distance = float(np.linalg.norm(pose[:3] - self.centre))
            if self.nearest is None or distance < self.nearest[0]:
                self.nearest = (distance, pose)

    def _verdicts(self, poses: list[np.ndarray]) -> np.ndarray:
        """:meth:`HandObjectCollider.screen` of each pose (runs of one orientation screened together)."""
        verdicts = np.zeros(len(poses), dtype=np.int8)
        if not self.screen or not poses:
            return verdicts
        array = np.asarray(poses)
        starts = [0, *(np.flatnonzero((array[1:, 3:] != array[:-1, 3:]).any(axis=1)) + 1), len(poses)]
        deep = self.spec.penetration + SCREEN_MARGIN
        for a, b in itertools.pairwise(starts):
            verdicts[a:b] = self.collider.screen(array[a:b, :3], array[a, 3:], deep)
        return verdicts

    def _fits(self, frame: int, poses: list[np.ndarray]) -> list[tuple[np.ndarray, int]]:
        """The poses that fit (within the tolerance) and touch the hand at ``frame``, with their links."""
        self.collider.set_hand(targets_qpos(self.scene, self.trajectory, frame))
        fitting = []
        for pose, verdict in zip(poses, self._verdicts(poses), strict=True):
            if verdict == CLEAR:  # no link within the touch distance: fits, touches nothing
                self.screened += 1
                self._consider(pose, 0.0)
                continue
            if verdict == DEEP:
                self.screened += 1
                self.pruned_deep = True
                continue
            depth, links = self.collider.depth_links(pose[:3], pose[3:])
            self._consider(pose, depth)
            if depth <= self.spec.penetration and links:
                fitting.append((pose, links))
        return fitting

    def _ranked(self, fitting: list[tuple[np.ndarray, int]]) -> list[tuple[tuple, np.ndarray]]:
        """Fitting poses ranked by what the recorded closing does to them (best first).

        At the closed frame a finger whose links lie deeper than the tolerance inside the object is one the
        recording closes past it: it will press on it. The key: the pressing fingers oppose each other (the
        thumb or the palm against a finger), how many finger groups press, how many links touch where it
        fits, and closeness to the fingertips' centre.
        """
        self.collider.set_hand(targets_qpos(self.scene, self.trajectory, self.grasp.closed))
        ranked = []
        for pose, links in fitting:
            touch = self.collider.touch_at(pose[:3], pose[3:])
            pressing = {self.groups[i] for i in np.flatnonzero(touch.distance < -self.spec.penetration)}
            pressing |= {"palm" for i in touch.links if self.groups[i] == "palm"}
            opposed = bool(pressing & {"thumb", "palm"}) and bool(pressing & _FINGERS)
            key = (opposed, len(pressing), links, -float(np.linalg.norm(pose[:3] - self.centre)))
            ranked.append((key, pose))
        ranked.sort(key=lambda item: item[0], reverse=True)
        return ranked

    def level(self, frame: int) -> list[tuple[tuple, np.ndarray]]:
        """The seeds of one closing frame, each refined on finer grids around it: (key, pose), best first."""
        spec, collider = self.spec, self.collider
        collider.set_hand(targets_qpos(self.scene, self.trajectory, frame))
        lo, hi, centres, radii = self._reach()
        coarse, steps = [], {}
        for quat in self.quats:
            rot = np.empty(9)
            mujoco.mju_quat2Mat(rot, quat)
            extent = self.points @ rot.reshape(3, 3).T
            # the object's box holds a point the closing converges on, and it lies within the hand's reach
            low = np.maximum(lo, self.grasp_points.min(axis=0) - spec.coarse_step) - extent.max(axis=0)
            high = np.minimum(hi, self.grasp_points.max(axis=0) + spec.coarse_step) - extent.min(axis=0)
            step = max(spec.coarse_step, float(np.prod(high - low) / spec.coarse_points) ** (1 / 3))
            grid = _grid(low, high, step)
            gap = np.linalg.norm(grid[:, None, :] - centres[None], axis=-1) - radii - self.radius
            grid = grid[(gap <= spec.touch).any(axis=1)]  # can touch some link at all
            steps[tuple(quat)] = step
            coarse.extend(np.concatenate([pos, quat]) for pos in grid)
        seeds = self._diverse(self._ranked(self._fits(frame, coarse)), steps)
        refined = []
        for key, pose in seeds:
            span = steps[tuple(pose[3:])]
            while span > spec.fine_step + 1e-12:  # halve the spacing around the best pose until fine
                span /= 2
                around = [np.concatenate([p, pose[3:]]) for p in _around(pose[:3], 2 * span, span)]
                best = self._ranked(self._fits(frame, around))
                if best and best[0][0] > key:
                    key, pose = best[0]
            refined.append((key, pose))
        return refined

    def _diverse(self, ranked: list, steps: dict) -> list:
        kept: list = []
        for key, pose in ranked:
            step = steps[tuple(pose[3:])]
            if all(
                not np.array_equal(pose[3:], other[3:]) or np.linalg.norm(pose[:3] - other[:3]) > 1.5 * step
                for _, other in kept
            ):
                kept.append((key, pose))
            if len(kept) == self.spec.seeds:
                break
        return kept

    def depth_at(self, frame: int, pose: np.ndarray) -> tuple[float, np.ndarray]:
        """Penetration and touching links of ``pose`` with the hand at the targets of ``frame``."""
        self.collider.set_hand(targets_qpos(self.scene, self.trajectory, frame))
        touch = self.collider.touch_at(pose[:3], pose[3:])
        return touch.depth, touch.links

    def candidate(self, pose: np.ndarray) -> Candidate:
        """The candidate at ``pose`` with its fit frame, searched down from the closed frame.

        Its contact frame is left at its fit frame until :meth:`with_contact`.
        """
        grasp, tolerance = self.grasp, self.spec.penetration
        frame, depth, links = grasp.open, *self.depth_at(grasp.open, pose)
        for f in range(grasp.closed, grasp.open - 1, -1):
            d, touching = self.depth_at(f, pose)
            if d <= tolerance:
                frame, depth, links = f, d, touching
                break
        return Candidate(
            pose=pose,
            links=tuple(self.scene.layout.link_names[i] for i in links),
            depth=depth,
            fit_frame=frame,
            fit_fraction=flexion_fraction(self.trajectory, grasp, frame),
            contact_frame=frame,
            depth_before_contact=0.0,
        )

    def with_contact(self, candidate: Candidate) -> Candidate:
        """The candidate with its contact frame (hand–object contacts act from there).

        It is the first frame of the run of frames up to its fit frame in which the hand at its targets is
        within the tolerance of it, searched back to the closing's open frame at most: the object is reached
        during the closing, and the hand moving before it (at rest, reaching) does not touch it.
        """
        opened = min(self.grasp.open, candidate.fit_frame)
        for f in range(candidate.fit_frame - 1, opened - 1, -1):
            depth, _ = self.depth_at(f, candidate.pose)
            if depth > self.spec.penetration:
                return replace(candidate, contact_frame=f + 1, depth_before_contact=depth)
        return replace(candidate, contact_frame=opened, depth_before_contact=0.0)


def _perturbed(
    pose: np.ndarray, shift: float, turn_deg: float, points: np.ndarray | None
) -> list[tuple[str, np.ndarray]]:
    """The pose moved by ±``shift`` along each world axis and turned by ±``turn_deg`` about each axis.

    Turns are about axes through the object's origin; a turn that leaves the object's collision points as
    they were is left out, and every turn when ``points`` is None (a sphere about its centre).
    """
    variants = []
    for axis, name in enumerate("xyz" if shift > 0 else ""):
        for sign, mark in ((1.0, "+"), (-1.0, "-")):
            moved = pose.copy()
            moved[axis] += sign * shift
            variants.append((f"{mark}{name} {shift * 1000:g} mm", moved))
    if turn_deg == 0 or points is None:
        return variants
    for axis, name in enumerate("xyz"):
        for sign, mark in ((1.0, "+"), (-1.0, "-")):
            half = math.radians(sign * turn_deg) / 2
            turn = np.zeros(4)
            turn[0], turn[1 + axis] = math.cos(half), math.sin(half)
            turned = pose.copy()
            turned[3:] = quat_multiply(turn, pose[3:])
            if len(_distinct(np.array([pose[3:], turned[3:]]), points)) == 2:
                variants.append((f"{mark}{name} {turn_deg:g}°", turned))
    return variants


_CACHED_CLASSES = {
    (cls.__module__, cls.__qualname__): cls
    for cls in (Placement, Candidate, GripResult, StabilityResult, DirectionResult, SelfPenetration)
}
"""What a placement cache entry may hold besides arrays and plain values."""


def _searched(
    scene: SimScene, trajectory: Trajectory, grasp: GraspFrame, spec: PlacementSpec, screen: bool
) -> tuple[_Search, list[tuple[tuple, int, np.ndarray]]]:
    """The search at every level and its seeds ranked by what the closing presses (ties: the later fit)."""
    search = _Search(scene, trajectory, grasp, spec, screen)
    ranked: list[tuple[tuple, int, np.ndarray]] = []
    for level, frame in enumerate(closing_frames(trajectory, grasp, spec.search_fractions)):
        for key, pose in search.level(frame):
            if all(not np.allclose(pose, other, atol=1e-9) for _, _, other in ranked):
                ranked.append((key, -level, pose))
    ranked.sort(key=lambda item: item[:2], reverse=True)
    return search, ranked


def place_object(
    scene: SimScene,
    trajectory: Trajectory,
    grasp: GraspFrame,
    spec: PlacementSpec,
    release_delay: float,
    control_rate: float,
    shift: float = 0.0,
    turn_deg: float = 0.0,
    *,
    use_cache: bool = True,
    cache_dir: str | Path | None = None,
) -> Placement:
    """Search the object pose that fits in the closing hand and that the recorded closing grips best.

    Args:
        scene: A scene with the hand (fixed root) and one free object on its support weld, no table.
        trajectory: The glove trajectory.
        grasp: Its grasp frames (:func:`handsim.sim.grasp_frame.grasp_frame`).
        spec: The search's parameters.
        release_delay: Seconds after the closed frame at which the support comes off: the grip is tested
            at that time.
        control_rate: Control frames per second of the replay the grip tests reproduce.
        shift: Distance the robustness ensemble moves the winner along each axis, m (0: no moves).
        turn_deg: Angle it turns the winner about each axis, degrees (0: no turns).
        use_cache: Read and write the placement cache (:mod:`handsim.sim.placement_cache`): a hit gives
            the stored placement bit for bit. When False, neither.
        cache_dir: Root of the cache; :func:`handsim.builders.decompose.default_cache_dir` when None.

    Returns:
        The placement (see the module docstring); never raises for want of a feasible pose: an infeasible
        placement says so (``feasible`` False, with the least penetration seen in the note).
    """
    arguments = {
        "spec": spec.to_dict(),
        "release_delay": release_delay,
        "control_rate": control_rate,
        "shift": shift,
        "turn_deg": turn_deg,
    }
    if not use_cache:
        return _place(scene, trajectory, grasp, spec, release_delay, control_rate, shift, turn_deg)
    key = placement_key(scene, trajectory, grasp, arguments)
    path = entry_path(cache_dir if cache_dir is not None else default_cache_dir(), key)
    notes = []
    if path.is_file():
        try:
            return read_entry(path, key, _CACHED_CLASSES)
        except CorruptEntryError as e:
            notes.append(f"placement cache entry {path} was corrupt ({e}) and was replaced")
    placement = _place(scene, trajectory, grasp, spec, release_delay, control_rate, shift, turn_deg)
    try:
        write_entry(path, key, placement)
    except (OSError, pickle.PicklingError, TypeError) as e:  # a full disk; a result that will not pickle
        notes.append(f"could not write placement cache entry {path}: {e}")
    return replace(placement, note="; ".join([placement.note, *notes])) if notes else placement


def _place(
    scene: SimScene,
    trajectory: Trajectory,
    grasp: GraspFrame,
    spec: PlacementSpec,
    release_delay: float,
    control_rate: float,
    shift: float,
    turn_deg: float,
) -> Placement:
    """The search of :func:`place_object`, without the cache."""
    search, ranked = _searched(scene, trajectory, grasp, spec, screen=True)
    if search.nearest is None and search.pruned_deep:  # infeasible: the least penetration needs every query
        search, ranked = _searched(scene, trajectory, grasp, spec, screen=False)
    times = np.asarray(trajectory.times, dtype=float)
    bench = GripBench(scene, trajectory, control_rate, float(times[grasp.closed]) + release_delay)

    def gripped(candidate: Candidate) -> Candidate:
        grip = bench.grip(candidate.pose, float(times[candidate.contact_frame]), spec.grip)
        return replace(candidate, grip=grip)

    tested = []
    for _, _, pose in ranked:  # in rank order, until enough grips resist every direction
        tested.append(gripped(search.with_contact(search.candidate(pose))))
        if sum(c.grip.directions_held == len(DIRECTIONS) for c in tested) > spec.alternatives:
            break
    tested.sort(key=Candidate.score, reverse=True)
    queries = search.collider.queries + search.screened
    if tested:
        best = tested[0]
        note = (
            f"object placed where it fits at frame {best.fit_frame} (flexion fraction "
            f"{best.fit_fraction:.2f} of the closing {grasp.open}–{grasp.closed}), touching "
            f"{len(best.links)} links ({', '.join(best.links)}), penetration {best.depth * 1000:.2f} mm; the "
            f"recorded closing grips it against {best.grip.directions_held} of 6 gravity directions; best of "
            f"{len(tested)} grip tests, {queries} poses tried, {search.feasible_poses} within "
            f"{spec.penetration * 1000:g} mm"
        )
        feasible = True
    elif search.nearest is not None:
        best = gripped(search.with_contact(search.candidate(search.nearest[1])))
        note = (
            f"no object pose within {spec.penetration * 1000:g} mm of penetration touches the hand on the "
            f"closing ramp: placed nearest the fingertips' centre without penetration ({queries} poses tried)"
        )
        feasible = True
    else:
        depth, pose = (
            search.least if search.least is not None else (np.inf, np.array([0, 0, 0, 1, 0, 0, 0.0]))
        )
        best = search.with_contact(search.candidate(pose))
        note = (
            f"no object pose on the closing ramp penetrates the hand less than "
            f"{spec.penetration * 1000:g} mm: the least penetrating of {queries} poses tried goes "
            f"{depth * 1000:.1f} mm deep; placement infeasible, the hold is not judged"
        )
        feasible = False
    perturbations = []
    if feasible and (shift > 0 or turn_deg > 0):
        points = None if search.round else search.points
        for label, pose in _perturbed(best.pose, shift, turn_deg, points):
            perturbations.append((label, search.with_contact(search.candidate(pose))))
    return Placement(
        best=best,
        alternatives=tuple(c for c in tested[1:] if c.grip.directions_held == best.grip.directions_held)[
            : spec.alternatives
        ]
        if tested
        else (),
        perturbations=tuple(perturbations),
        feasible=feasible,
        queries=queries,
        grip_tests=len(tested) + (1 if not tested and feasible else 0),
        feasible_poses=search.feasible_poses,
        object_points=search.points,
        self_penetration=SelfCollider(scene)(targets_qpos(scene, trajectory, grasp.closed)),
        spec=spec.to_dict(),
        note=note,
    )
