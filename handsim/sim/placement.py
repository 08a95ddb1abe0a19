"""Where to put the object a glove recording grasped.

The grasp frame, the hand's palm-down frame, and a search for the object pose with the most touching hand
links and little penetration.

GraspDB14 records the hand, not the object. The object is placed where the recorded grasp closes on it:
at the grasp frame the hand is put at its targets and candidate object poses (a grid over the hand's
reach, and 24 axis-aligned orientations unless the object is a sphere) are scored by MuJoCo's own
collision detection: the number of hand links within :attr:`MetricSpec.placement_touch` of the object,
among poses whose deepest penetration is at most :attr:`MetricSpec.placement_penetration`; ties go to the
shallower penetration, then to the pose nearest the fingertips' centre (the search is deterministic). The
best few are refined on finer grids (10 mm → 2.5 mm → 1 mm).
"""

from __future__ import annotations

import copy
import itertools
from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.errors import TrajectoryError
from handsim.poses import quat_multiply
from handsim.sim.compiled import SimScene
from handsim.sim.metrics import MetricSpec
from handsim.trajectory import Trajectory

GRASP_PHASE = "grasp"
PEAK_WINDOW = 0.8
"""Without a ``grasp`` phase, the hold window is the frames around peak flexion above this fraction of
the flexion range."""
CLOSED_FRACTION = 0.98
"""The grasp has closed at the first frame of the window whose flexion has risen this fraction of the way
from the window's first frame to its peak."""
GRID_STEPS = (0.01, 0.0025, 0.001)
"""Search grid spacings, m; each refinement spans ±2 steps of the previous grid around each seed."""
SEEDS = 6
"""Best candidates of a grid level that seed the next, finer level."""


@dataclass(frozen=True)
class GraspFrame:
    """The frame a glove trial's grasp closes at, and the frames holding is judged over.

    Attributes:
        frame: Trajectory frame index of first contact, where the object is placed.
        closed: Frame at which the grasp has closed (flexion reaches its peak within the window): the
            object's support is released from there.
        window: First and last frame of the hold window (inclusive).
        source: ``"phase"`` (the annotated ``grasp`` phase) or ``"peak flexion"``.
        note: For people.
    """

    frame: int
    closed: int
    window: tuple[int, int]
    source: str
    note: str

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {
            "frame": self.frame,
            "closed": self.closed,
            "window": list(self.window),
            "source": self.source,
        }


def _flexion(trajectory: Trajectory) -> np.ndarray:
    cols = [i for i, n in enumerate(trajectory.dof_names) if "flex" in n and not n.startswith("root")]
    if not cols:
        raise TrajectoryError(
            f"{trajectory.source or 'trajectory'}: no finger flexion DoFs (names containing 'flex') "
            "to find the grasp frame from; annotate a 'grasp' phase"
        )
    return np.asarray(trajectory.targets, dtype=float)[:, cols].sum(axis=1)


def grasp_frame(trajectory: Trajectory) -> GraspFrame:
    """The grasp frame and the frame the grasp has closed at.

    With an annotated ``grasp`` phase: its first frame (the hand reaches the object), closed at
    :data:`CLOSED_FRACTION` of the flexion rise within the phase; the window is the phase. Without one:
    the frames above :data:`PEAK_WINDOW` of the flexion range around the peak; the grasp frame is their
    first, closed at the same fraction of the rise to the peak.

    Raises:
        TrajectoryError: No flexion DoFs (names containing ``flex``).
    """
    flex = _flexion(trajectory)
    for phase in trajectory.phases:
        if phase.name.strip(".") == GRASP_PHASE and phase.stop > phase.start:
            lo, hi = phase.start, phase.stop - 1
            closed = _closed(flex, lo, hi)
            return GraspFrame(
                frame=lo,
                closed=closed,
                window=(lo, hi),
                source="phase",
                note=f"grasp frame {lo} = start of the annotated 'grasp' phase (frames {lo}–{hi}, 0-based); "
                f"closed at frame {closed}",
            )
    peak = int(np.argmax(flex))
    level = flex.min() + PEAK_WINDOW * (flex[peak] - flex.min())
    lo = peak
    while lo > 0 and flex[lo - 1] >= level:
        lo -= 1
    hi = peak
    while hi + 1 < flex.shape[0] and flex[hi + 1] >= level:
        hi += 1
    closed = _closed(flex, lo, hi)
    return GraspFrame(
        frame=lo,
        closed=closed,
        window=(lo, hi),
        source="peak flexion",
        note=f"no 'grasp' phase: grasp frame {lo} = first of frames {lo}–{hi} above {PEAK_WINDOW:.0%} of the "
        f"flexion range (peak at {peak}); closed at frame {closed}",
    )


def _closed(flex: np.ndarray, lo: int, hi: int) -> int:
    window = flex[lo : hi + 1]
    level = window[0] + CLOSED_FRACTION * (window.max() - window[0])
    return lo + int(np.argmax(window >= level))


def _targets_qpos(scene: SimScene, trajectory: Trajectory, frame: int) -> np.ndarray:
    layout = scene.layout
    qpos = scene.model.qpos0.copy()
    column = {n: i for i, n in enumerate(trajectory.dof_names)}
    values = np.array(
        [trajectory.targets[frame, column[n]] if n in column else 0.0 for n in layout.dof_names]
    )
    qpos[layout.dof_qpos] = np.clip(values, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
    return qpos


def hand_frame(scene: SimScene) -> np.ndarray:
    """Orientation (w, x, y, z) to attach the hand with: fingers along +x, palm facing −z (palm down).

    The palm normal is where the fingertips move when every finger flexion DoF goes to half its upper
    limit, so it does not depend on the hand being left or right.

    Args:
        scene: A scene with the hand attached with the identity orientation.
    """
    model, layout = scene.model, scene.layout
    data = mujoco.MjData(model)
    flex = np.array(["flex" in n and not n.startswith("root") for n in layout.dof_names])
    rest = np.clip(0.0, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
    data.qpos[layout.dof_qpos] = rest
    mujoco.mj_kinematics(model, data)
    tips0 = data.site_xpos[layout.tip_sites].copy()
    root = data.xpos[layout.root_body].copy()
    data.qpos[layout.dof_qpos] = np.where(flex, 0.5 * layout.ctrl_range[:, 1], rest)
    mujoco.mj_kinematics(model, data)
    tips1 = data.site_xpos[layout.tip_sites]
    fingers = tips0.mean(axis=0) - root
    fingers /= np.linalg.norm(fingers)
    palm = (tips1 - tips0).mean(axis=0)
    palm -= fingers * (palm @ fingers)
    palm /= np.linalg.norm(palm)
    hand = np.column_stack([fingers, palm, np.cross(fingers, palm)])
    world = np.column_stack([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, (world @ hand.T).ravel())
    return quat


def _orientations(model: mujoco.MjModel, bodies: tuple[int, ...]) -> np.ndarray:
    geoms = [
        g
        for g in range(model.ngeom)
        if model.geom_bodyid[g] in bodies and (model.geom_contype[g] or model.geom_conaffinity[g])
    ]
    if all(int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_SPHERE) for g in geoms) and len(bodies) == 1:
        return np.array([[1.0, 0.0, 0.0, 0.0]])
    h = np.sqrt(0.5)
    faces = [
        [1, 0, 0, 0],
        [h, h, 0, 0],
        [0, 1, 0, 0],
        [h, -h, 0, 0],
        [h, 0, h, 0],
        [h, 0, -h, 0],
    ]  # which axis is up
    spins = [[np.cos(a / 2), 0, 0, np.sin(a / 2)] for a in (0, np.pi / 2, np.pi, 3 * np.pi / 2)]
    return np.array([quat_multiply(s, f) for f, s in itertools.product(faces, spins)])


@dataclass(frozen=True)
class Placement:
    """The object pose a search found.

    Attributes:
        pose: Object pose (x, y, z, qw, qx, qy, qz) in the search scene's world.
        links: Hand links touching it.
        penetration: Deepest penetration, m.
        candidates: Poses evaluated.
        lowest_z: World height of the object's lowest collision point at ``pose``, m.
        note: For people.
    """

    pose: np.ndarray
    links: tuple[str, ...]
    penetration: float
    candidates: int
    lowest_z: float
    note: str

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {
            "pose": self.pose.tolist(),
            "links": list(self.links),
            "penetration_m": self.penetration,
            "candidates": self.candidates,
        }


class _Scorer:
    def __init__(self, scene: SimScene, qpos: np.ndarray, spec: MetricSpec) -> None:
        self.model = copy.deepcopy(scene.model)
        layout = scene.layout
        self.obj = layout.objects[0]
        body_of = self.model.geom_bodyid
        self.is_obj = np.isin(body_of, self.obj.part_bodies)
        self.model.geom_margin[self.is_obj] = spec.placement_touch
        self.link_index = np.full(self.model.nbody, -1)
        self.link_index[layout.link_bodies] = np.arange(layout.link_bodies.size)
        self.data = mujoco.MjData(self.model)
        self.data.qpos[:] = qpos
        self.tolerance = spec.placement_penetration
        self.touch = spec.placement_touch
        self.count = 0

    def __call__(self, pos: np.ndarray, quat: np.ndarray) -> tuple[int, float, np.ndarray]:
        d, a = self.data, self.obj.free_qpos
        d.qpos[a : a + 3] = pos
        d.qpos[a + 3 : a + 7] = quat
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_collision(self.model, d)
        self.count += 1
        n = d.ncon
        if n == 0:
            return 0, 0.0, np.zeros(0, dtype=np.int64)
        geom = d.contact.geom[:n]
        dist = d.contact.dist[:n]
        obj1, obj2 = self.is_obj[geom[:, 0]], self.is_obj[geom[:, 1]]
        other = np.where(obj1, geom[:, 1], geom[:, 0])
        link = self.link_index[self.model.geom_bodyid[other]]
        mask = (obj1 ^ obj2) & (link >= 0)
        if not mask.any():
            return 0, 0.0, np.zeros(0, dtype=np.int64)
        depth = float(max(0.0, -dist[mask].min()))
        links = np.unique(link[mask & (dist <= self.touch)])
        return int(links.size), depth, links


def _grid(center: np.ndarray, half: np.ndarray, step: float) -> np.ndarray:
    axes = [
        np.arange(-np.floor(h / step), np.floor(h / step) + 1) * step + c
        for c, h in zip(center, half, strict=True)
    ]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def place_object(scene: SimScene, trajectory: Trajectory, frame: int, spec: MetricSpec) -> Placement:
    """Search the object pose that the hand, at its targets of ``frame``, touches with the most links.

    Args:
        scene: A scene with the hand (fixed root) and one free object, no table.
        trajectory: The glove trajectory.
        frame: The grasp frame.
        spec: Touch distance and penetration tolerance.

    Returns:
        The best pose found (with the touching links); when no pose touches the hand without too much
        penetration, the pose nearest the fingertips' centre without penetration, and a note saying so.
    """
    layout = scene.layout
    qpos = _targets_qpos(scene, trajectory, frame)
    score = _Scorer(scene, qpos, spec)
    data = score.data
    mujoco.mj_kinematics(score.model, data)
    reach = np.vstack([data.xpos[layout.link_bodies], data.site_xpos[layout.tip_sites]])
    lo, hi = reach.min(axis=0), reach.max(axis=0)
    center, half = (lo + hi) / 2, (hi - lo) / 2 + 0.01
    tips = data.site_xpos[layout.tip_sites].mean(axis=0)
    quats = _orientations(score.model, score.obj.part_bodies)

    survivors = [(center, half, quat) for quat in quats]
    best: list[tuple] = []
    for level, step in enumerate(GRID_STEPS):
        # a coarse grid cannot hit the thin shell where many links touch without penetrating: coarse levels
        # accept half a step more penetration, and the best few seed the next, finer level
        tolerance = spec.placement_penetration + (step / 2 if level < len(GRID_STEPS) - 1 else 0.0)
        scored = []
        for c, h, quat in survivors:
            for pos in _grid(c, h, step):
                links, depth, touched = score(pos, quat)
                if depth <= tolerance:
                    scored.append(((links, -depth, -float(np.linalg.norm(pos - tips))), touched, pos, quat))
        scored.sort(key=lambda item: item[0], reverse=True)
        best = scored
        survivors = [(item[2], np.full(3, 2 * step), item[3]) for item in scored[:SEEDS]]
        if not survivors:
            break
    if not best:
        raise TrajectoryError(
            f"{trajectory.source or 'trajectory'}: no object pose within the hand's reach at frame {frame} "
            f"penetrates less than {spec.placement_penetration * 1000:g} mm"
        )
    best = best[0]
    names = tuple(layout.link_names[i] for i in best[1])
    pose = np.concatenate([best[2], best[3]])
    _, depth, _ = score(best[2], best[3])
    data.qpos[score.obj.free_qpos : score.obj.free_qpos + 7] = pose
    mujoco.mj_kinematics(score.model, data)
    lowest = _lowest_point(score.model, data, score.is_obj)
    if names:
        note = (
            f"object placed touching {len(names)} links ({', '.join(names)}), "
            f"penetration {depth * 1000:.2f} mm, {score.count} poses tried"
        )
    else:
        note = (
            f"no object pose touches the hand at frame {frame}: placed nearest the fingertips "
            f"without penetration ({score.count} poses tried)"
        )
    return Placement(
        pose=pose, links=names, penetration=depth, candidates=score.count, lowest_z=lowest, note=note
    )


@dataclass(frozen=True)
class ContactStart:
    """From which frame on the hand may touch the placed object.

    Attributes:
        frame: Trajectory frame.
        depth_before: Deepest penetration of the hand at its targets in the frame before, m (0 when the
            hand is clear of the object from the first frame on).
        note: For people.
    """

    frame: int
    depth_before: float
    note: str


def contact_start(
    scene: SimScene, trajectory: Trajectory, frame: int, pose: np.ndarray, spec: MetricSpec
) -> ContactStart:
    """The first frame of the run of frames up to ``frame`` in which the hand stays out of the object.

    The glove records the hand alone: where the object was while the hand reached is unknown, and the
    placed object (where the grasp closes) often lies where the fingers were earlier (a relaxed ring finger
    at the start of a recording, say). Walking back from the grasp frame with the hand at its targets, the
    frames whose deepest penetration of the object at ``pose`` is at most
    :attr:`MetricSpec.placement_penetration` are the approach; contacts act from its first frame.

    Args:
        scene: The placement search's scene (:func:`place_object`'s).
        trajectory: The glove trajectory.
        frame: The grasp frame.
        pose: The placed object's pose in that scene.
        spec: The penetration tolerance.

    Returns:
        The frame, the penetration just before it, and a note.
    """
    score = _Scorer(scene, _targets_qpos(scene, trajectory, frame), spec)
    pos, quat = pose[:3], pose[3:]
    for f in range(frame, -1, -1):
        score.data.qpos[:] = _targets_qpos(scene, trajectory, f)
        _, depth, _ = score(pos, quat)
        if depth > spec.placement_penetration:
            times = trajectory.times
            return ContactStart(
                frame=f + 1,
                depth_before=depth,
                note=f"hand–object contacts act from frame {f + 1} ({times[f + 1]:.3f} s); at frame {f} the "
                f"hand at its targets is {depth * 1000:.1f} mm inside the placed object",
            )
    return ContactStart(frame=0, depth_before=0.0, note="the hand is clear of the placed object from frame 0")


def _lowest_point(model: mujoco.MjModel, data: mujoco.MjData, mask: np.ndarray) -> float:
    """World z of the lowest point of the geoms in ``mask`` (mesh vertices; primitive bounding radius)."""
    lowest = np.inf
    for g in np.flatnonzero(mask):
        if not (model.geom_contype[g] or model.geom_conaffinity[g]):
            continue
        mesh = int(model.geom_dataid[g])
        if int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_MESH) and mesh >= 0:
            start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
            verts = model.mesh_vert[start : start + count]
            world = verts @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]
            lowest = min(lowest, float(world[:, 2].min()))
        else:
            lowest = min(lowest, float(data.geom_xpos[g, 2] - model.geom_rbound[g]))
    return lowest
