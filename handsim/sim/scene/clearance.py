"""Where a recording puts the hands, and how deep they would pass into the scene's static bodies.

A recorded hand follows its recording whatever the scene holds; a table, stand or floor in its path pushes
it off its targets (its wrist is welded to the recorded pose, so it is shoved, not stopped). Before a run,
:func:`recorded_qpos` puts the scene's hands where the recording puts them (each DoF at its target, each
welded root at its recorded pose in the scene's world) and the objects at their recorded poses, frame by
frame; :func:`hand_paths` reads every hand site there (each MANO joint and fingertip of an ARCTIC hand:
the sites the hand builders put on each joint and tip); :func:`passages` finds, for every static body
(a geom welded to the world that collides), how deep the deepest of those points goes into it.

Depths are exact for the geoms handsim's scenes put in the world: planes, boxes, spheres, capsules,
cylinders and convex meshes (a mesh collides as its convex hull, so its hull is what a point is inside of).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.datatypes.poses import compose
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import ModelError, TrajectoryError
from handsim.sim.scene.compiled import SimScene

_GEOM = mujoco.mjtGeom


@dataclass(frozen=True)
class HandPaths:
    """The recorded hands' sites (joints and fingertips) at every frame of a recording, in the scene's world.

    Attributes:
        times: Recording time of each frame, s (N,).
        points: Site positions, m (N, P, 3).
        labels: Each site's name without the scene's ``hand/`` prefix (``right/index3``), (P,).
        hand: The hand of each site: index into the scene layout's hands (P,).
    """

    times: np.ndarray
    points: np.ndarray
    labels: tuple[str, ...]
    hand: np.ndarray


@dataclass(frozen=True)
class Passage:
    """How deep the recorded hands go into one static body.

    Attributes:
        body: The static geom's name (``stand``, ``floor``).
        depth: The deepest point's depth inside it, m (0: none inside).
        label: That point's site (``right/index3``).
        time: Its recording time, s.
        frames: Frames in which some point lies deeper than the limit :func:`passages` was given.
    """

    body: str
    depth: float
    label: str
    time: float
    frames: int

    def describe(self) -> str:
        """One line: the body, how deep, which point and when."""
        return (
            f"the recorded {self.label} goes {self.depth * 1000:.0f} mm into the {self.body} at "
            f"{self.time:.2f} s ({self.frames} frames deeper than the limit)"
        )


def recorded_qpos(
    scene: SimScene, trajectory: Trajectory, frames: npt.ArrayLike | None = None, *, clip: bool = False
) -> np.ndarray:
    """The scene's state at recording frames, as the recording puts it: qpos per frame (n, nq).

    Each hand DoF the trajectory drives is at its target (invalid or non-finite samples at the model's
    rest value), each welded hand root at its recorded pose in the scene's world
    (``setup.world_from_recording``), each object with a track at its recorded pose and articulation; the
    rest at the model's ``qpos0``.

    Args:
        scene: The compiled scene.
        trajectory: The recording (its frames, not the control schedule's).
        frames: The recording frames (default: all).
        clip: Clip the targets to the joints' ranges (the actuators' control ranges), as a replay's start
            does; False: the recorded angles as they are (where the recording puts the hand).

    Returns:
        qpos per frame.

    Raises:
        TrajectoryError: A welded hand without a root pose in the trajectory, or an object's track missing.
    """
    model, layout, setup = scene.model, scene.layout, scene.setup
    index = np.arange(trajectory.nframes) if frames is None else np.asarray(frames, dtype=np.int64)
    qpos = np.tile(model.qpos0, (index.size, 1))
    column = {name: c for c, name in enumerate(trajectory.dof_names)}
    driven = [k for k, name in enumerate(layout.dof_names) if name in column]
    if driven:
        columns = [column[layout.dof_names[k]] for k in driven]
        adr = layout.dof_qpos[driven]
        target = np.asarray(trajectory.targets, dtype=float)[np.ix_(index, columns)]
        usable = np.asarray(trajectory.valid, dtype=bool)[np.ix_(index, columns)] & np.isfinite(target)
        if clip:
            target = np.clip(target, layout.ctrl_range[driven, 0], layout.ctrl_range[driven, 1])
        qpos[:, adr] = np.where(usable, target, model.qpos0[adr])
    world = np.asarray(setup.world_from_recording, dtype=float)
    for hand in layout.hands:
        if hand.root_free_qpos < 0:
            continue
        root = trajectory.hand_roots.get(hand.name) if hand.name else trajectory.root_pose
        if root is None:
            raise TrajectoryError(
                f"{trajectory.source or 'trajectory'}: no recorded root pose for the welded hand "
                f"{hand.name or 'of the scene'!r}"
            )
        qpos[:, hand.root_free_qpos : hand.root_free_qpos + 7] = compose(world, np.asarray(root)[index])
    for obj, key in zip(layout.objects, setup.object_tracks, strict=False):
        if not key:
            continue
        if key not in trajectory.objects:
            raise TrajectoryError(
                f"{trajectory.source or 'trajectory'}: no object track {key!r}; it has "
                f"{list(trajectory.objects)}"
            )
        track = trajectory.objects[key]
        qpos[:, obj.free_qpos : obj.free_qpos + 7] = compose(world, np.asarray(track.pose)[index])
        if track.articulation is not None and obj.hinge_qpos >= 0:
            joint = int(np.flatnonzero(model.jnt_qposadr == obj.hinge_qpos)[0])
            angle = np.asarray(track.articulation, dtype=float)[index]
            if model.jnt_limited[joint]:
                angle = np.clip(angle, *model.jnt_range[joint])
            qpos[:, obj.hinge_qpos] = angle
    return qpos


def hand_sites(scene: SimScene) -> tuple[np.ndarray, np.ndarray]:
    """Every site on the scene's hands (joints and fingertips): their ids and hands (layout indices)."""
    model = scene.model
    sites, owners = [], []
    for h, hand in enumerate(scene.layout.hands):
        bodies = np.flatnonzero(model.body_rootid == model.body_rootid[hand.root_body])
        own = np.flatnonzero(np.isin(model.site_bodyid, bodies))
        sites.append(own)
        owners.append(np.full(own.size, h))
    return np.concatenate(sites), np.concatenate(owners)


def hand_paths(scene: SimScene, trajectory: Trajectory, data: mujoco.MjData | None = None) -> HandPaths:
    """Where the recording puts every hand site, frame by frame (kinematics only, one pass per frame).

    Args:
        scene: The compiled scene (its hands' roots welded to recorded poses, or fixed).
        trajectory: The recording.
        data: An ``MjData`` of the scene's model whose contents may be overwritten (None: a new one).

    Returns:
        The sites' world positions at every recording frame.

    Raises:
        TrajectoryError: See :func:`recorded_qpos`.
    """
    model = scene.model
    sites, owner = hand_sites(scene)
    points = site_positions(model, recorded_qpos(scene, trajectory), data)[:, sites]
    labels = tuple(model.site(int(s)).name.split("/", 1)[1] for s in sites)
    return HandPaths(np.asarray(trajectory.times, dtype=float), points, labels, owner)


def site_positions(model: mujoco.MjModel, qpos: np.ndarray, data: mujoco.MjData | None = None) -> np.ndarray:
    """Every site's world position for each qpos row, m (N, nsite, 3): kinematics only.

    One ``mj_kinematics`` per row, in ``data`` when given (else a new ``MjData``: 0.5 ms with a scene's
    15 MB arena); the loop body is the least Python around it (every site copied, the caller picks).
    """
    data = mujoco.MjData(model) if data is None else data
    sites = np.empty((qpos.shape[0], model.nsite, 3))
    state, site_xpos, kinematics = data.qpos, data.site_xpos, mujoco.mj_kinematics
    for k, row in enumerate(qpos):
        state[:] = row
        kinematics(model, data)
        sites[k] = site_xpos
    return sites


def static_geoms(model: mujoco.MjModel) -> list[int]:
    """The colliding geoms welded to the world (tables, stands, floors), in geom order."""
    return [
        g
        for g in range(model.ngeom)
        if model.body_weldid[model.geom_bodyid[g]] == 0
        and (model.geom_contype[g] or model.geom_conaffinity[g])
    ]


def inside_depth(model: mujoco.MjModel, data: mujoco.MjData, geom: int, points: npt.ArrayLike) -> np.ndarray:
    """How deep each point lies inside a geom, m (0 outside): its distance to the geom's surface.

    Args:
        model: The model.
        data: Its data, with the geom's pose computed (``mj_kinematics``).
        geom: The geom id.
        points: World points, shape (..., 3).

    Returns:
        Depth per point, shape (...).

    Raises:
        ModelError: A geom type whose inside is not defined here (ellipsoid, height field, SDF).
    """
    p = np.asarray(points, dtype=float)
    local = (p - data.geom_xpos[geom]) @ data.geom_xmat[geom].reshape(3, 3)
    size = model.geom_size[geom]
    kind = int(model.geom_type[geom])
    if kind == _GEOM.mjGEOM_PLANE:
        depth = -local[..., 2]
    elif kind == _GEOM.mjGEOM_BOX:
        depth = np.min(size - np.abs(local), axis=-1)
    elif kind == _GEOM.mjGEOM_SPHERE:
        depth = size[0] - np.linalg.norm(local, axis=-1)
    elif kind == _GEOM.mjGEOM_CAPSULE:
        along = np.clip(local[..., 2], -size[1], size[1])
        depth = size[0] - np.linalg.norm(local - np.stack([0 * along, 0 * along, along], -1), axis=-1)
    elif kind == _GEOM.mjGEOM_CYLINDER:
        depth = np.minimum(size[0] - np.linalg.norm(local[..., :2], axis=-1), size[1] - np.abs(local[..., 2]))
    elif kind == _GEOM.mjGEOM_MESH:
        normals, offsets = _hull_planes(model, int(model.geom_dataid[geom]))
        depth = -np.max(local @ normals.T + offsets, axis=-1)
    else:
        raise ModelError(
            f"geom {model.geom(geom).name!r}: the inside of a {_GEOM(kind).name} is not computed; static "
            "bodies must be planes, boxes, spheres, capsules, cylinders or meshes"
        )
    return np.maximum(depth, 0.0)


def _hull_planes(model: mujoco.MjModel, mesh: int) -> tuple[np.ndarray, np.ndarray]:
    """The outward face planes (unit normals, offsets) of a mesh's convex hull, in the geom's frame."""
    from scipy.spatial import ConvexHull  # lazy: SciPy's Qhull, only where a static mesh is checked

    start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    hull = ConvexHull(np.asarray(model.mesh_vert[start : start + count], dtype=float))
    return hull.equations[:, :3], hull.equations[:, 3]


def passages(
    scene: SimScene, paths: HandPaths, limit: float, data: mujoco.MjData | None = None
) -> list[Passage]:
    """For each static body, the deepest recorded hand point inside it.

    Args:
        scene: The compiled scene (static bodies do not move: their pose is the model's).
        paths: The recorded hands' sites (:func:`hand_paths`).
        limit: Depth that counts a frame as passing through, m.
        data: An ``MjData`` of the scene's model whose contents may be overwritten (None: a new one).

    Returns:
        One :class:`Passage` per static geom, in geom order.
    """
    model = scene.model
    data = mujoco.MjData(model) if data is None else data
    mujoco.mj_kinematics(model, data)
    found = []
    for geom in static_geoms(model):
        depth = inside_depth(model, data, geom, paths.points)  # (N, P)
        k, p = np.unravel_index(int(np.argmax(depth)), depth.shape) if depth.size else (0, 0)
        found.append(
            Passage(
                body=model.geom(geom).name,
                depth=float(depth[k, p]) if depth.size else 0.0,
                label=paths.labels[p] if paths.labels else "",
                time=float(paths.times[k]) if paths.times.size else 0.0,
                frames=int((depth > limit).any(axis=1).sum()),
            )
        )
    return found
