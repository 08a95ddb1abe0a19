"""Hand–object collision queries on a fixed hand posture, for many object poses: MuJoCo's own detection.

:class:`HandObjectCollider` keeps a private copy of a scene's model in which only hand–object geom pairs
collide (the hand's self-contacts are switched off: they do not change with the object's pose) and the
object's geoms carry a margin of the touch distance, so that MuJoCo reports the links within that distance
as contacts with a positive ``dist``. Moving the object is writing its free joint's ``qpos``; nothing is
recompiled.

:meth:`HandObjectCollider.screen` settles many poses at one posture without running collision detection,
where cheap bounds already decide a query's outcome: a pose whose geoms' bounding spheres all lie farther
than the touch distance from every hand geom's is clear (the query would find nothing, as MuJoCo's own
bounding-sphere test would), and a pose where a ball inscribed in one of the object's convex geoms overlaps
a ball or capsule core inscribed in a hand geom by more than a depth is at least that deep (separating two
convex shapes takes at least the overlap of balls they contain).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, QhullError

from handsim.datatypes.rotations import quat_to_matrix
from handsim.sim.compiled import SimScene
from handsim.sim.hand_samples import HandSamples, hand_samples
from handsim.sim.object_field import FIELD_REACH, ObjectField, object_field

_HAND_BIT, _OBJECT_BIT = 2, 2
_NO_LINKS, _NO_DISTANCES = np.zeros(0, dtype=np.int64), np.zeros(0)
_CHUNK = 4096  # poses per vectorised bound evaluation (memory: chunk × object balls × hand geoms × 3)
_CLEAR_SLACK = 1e-5  # m: a pose is clear only this much beyond the margin (GJK's distance tolerance)
UNDECIDED, CLEAR, DEEP = 0, 1, 2
"""What :meth:`HandObjectCollider.screen` says of a pose: run the query; no link within the touch distance;
deeper than the given depth."""


@dataclass(frozen=True)
class Touch:
    """What the hand does to the object at one pose.

    Attributes:
        links: Indices (into ``SceneLayout.link_names``) of the hand links within the touch distance.
        depth: Deepest penetration of a hand link into the object, m (0 when none).
        distance: Per hand link, its smallest signed distance to the object, m (negative: penetration;
            +inf beyond the touch distance).
    """

    links: np.ndarray
    depth: float
    distance: np.ndarray


class HandObjectCollider:
    """Collision queries between a scene's hand (at a posture) and its first object (at any pose).

    Args:
        scene: A scene with a hand and at least one free object.
        touch: A link within this distance of the object counts as touching, m.
        object_index: Which object (layout order).
    """

    def __init__(self, scene: SimScene, touch: float, object_index: int = 0) -> None:
        layout = scene.layout
        self.layout = layout
        self.model = copy.deepcopy(scene.model)
        self.obj = layout.objects[object_index]
        model = self.model
        body_of = model.geom_bodyid
        colliding = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
        self.is_obj = np.isin(body_of, self.obj.part_bodies) & colliding
        is_hand = np.isin(body_of, layout.link_bodies) & colliding
        model.geom_contype[:] = 0
        model.geom_conaffinity[:] = 0
        model.geom_contype[is_hand] = _HAND_BIT
        model.geom_conaffinity[self.is_obj] = _OBJECT_BIT
        model.geom_margin[self.is_obj] = touch
        self.touch = touch
        self.link_index = np.full(model.nbody, -1)
        self.link_index[layout.link_bodies] = np.arange(layout.link_bodies.size)
        self.data = mujoco.MjData(model)
        self.queries = 0
        self._hand_geoms = np.flatnonzero(is_hand)
        self._obj_geoms = np.flatnonzero(self.is_obj)
        self._cores = [_core(model, g) for g in self._hand_geoms]
        self._samples: HandSamples | None = None
        self._samples_step = 0.0
        self._balls = [_core(model, g) for g in self._obj_geoms]
        self._field: ObjectField | None = None
        self._field_made = False

    def fork(self) -> HandObjectCollider:
        """A collider on the same model with a data of its own, at this one's posture (for another thread)."""
        forked = copy.copy(self)
        forked.data = mujoco.MjData(self.model)
        forked.data.qpos[:] = self.data.qpos
        forked.queries = 0
        return forked

    def set_hand(self, qpos: np.ndarray) -> None:
        """Put the hand (and everything else but the object's pose) at ``qpos`` (nq,)."""
        a = self.obj.free_qpos
        pose = self.data.qpos[a : a + 7].copy()
        self.data.qpos[:] = qpos
        self.data.qpos[a : a + 7] = pose

    def _contacts(self, pos: np.ndarray, quat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Link index and distance of each hand–object contact within the touch distance at a pose."""
        d, a = self.data, self.obj.free_qpos
        d.qpos[a : a + 3] = pos
        d.qpos[a + 3 : a + 7] = quat
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_collision(self.model, d)
        self.queries += 1
        n = d.ncon
        if n == 0:
            return _NO_LINKS, _NO_DISTANCES
        geom = d.contact.geom[:n]
        dist = d.contact.dist[:n]
        other = np.where(self.is_obj[geom[:, 0]], geom[:, 1], geom[:, 0])
        link = self.link_index[self.model.geom_bodyid[other]]
        keep = (link >= 0) & (dist <= self.touch)
        return link[keep], dist[keep]

    def touch_at(self, pos: np.ndarray, quat: np.ndarray) -> Touch:
        """The links touching the object at pose (``pos``, ``quat``) and the deepest penetration."""
        link, dist = self._contacts(pos, quat)
        distance = np.full(self.layout.link_bodies.size, np.inf)
        if not link.size:
            return Touch(np.zeros(0, dtype=np.int64), 0.0, distance)
        np.minimum.at(distance, link, dist)
        return Touch(np.flatnonzero(np.isfinite(distance)), float(max(0.0, -dist.min())), distance)

    def depth_links(self, pos: np.ndarray, quat: np.ndarray) -> tuple[float, int]:
        """:meth:`touch_at`'s ``depth`` and number of ``links``, without the per-link distances."""
        link, dist = self._contacts(pos, quat)
        if not link.size:
            return 0.0, 0
        return float(max(0.0, -dist.min())), len(set(link.tolist()))

    def hand_spheres(self) -> tuple[np.ndarray, np.ndarray]:
        """Centres (G, 3) and bounding radii (G,) of the hand's colliding geoms at the current posture.

        Call after a query (or :func:`mujoco.mj_kinematics`) at that posture.
        """
        return self.data.geom_xpos[self._hand_geoms].copy(), self.model.geom_rbound[self._hand_geoms].copy()

    def screen(self, positions: np.ndarray, quat: np.ndarray, depth: float) -> np.ndarray:
        """What cheap bounds say of the object at each position with orientation ``quat``, hand as set.

        Args:
            positions: Object positions (N, 3), m.
            quat: The object's orientation (w, x, y, z) for all of them.
            depth: A pose whose inscribed balls overlap the hand's by more than this is :data:`DEEP`, m.

        Returns:
            Per position :data:`CLEAR` (the query would find no link within the touch distance),
            :data:`DEEP` (the query would find a penetration deeper than ``depth``) or :data:`UNDECIDED`.
        """
        clear, overlap = self.bounds(positions, quat, depth)
        result = np.full(len(positions), UNDECIDED, dtype=np.int8)
        result[clear] = CLEAR
        result[~clear & (overlap > depth)] = DEEP
        return result

    def bounds(
        self, positions: np.ndarray, quat: np.ndarray, floor: float = -np.inf
    ) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of the queries at each position with orientation ``quat``, hand as set.

        Args:
            positions: Object positions (N, 3), m.
            quat: The object's orientation (w, x, y, z) for all of them.
            floor: Overlaps not above this may be reported as −inf (pairs too far apart are not computed);
                one above it (a finite floor) may be reported as any value above it (the bounds stop looking).

        Returns:
            Per position: whether the query would find no link within the touch distance (clear: every
            object geom's bounding sphere lies farther than the touch distance from every hand geom's, or,
            with the object's field, every hand geom is shown apart from the object); and a lower bound of
            the penetration, m: the largest overlap of a ball inscribed in an object geom with a capsule
            core inscribed in a hand geom, or, with the field, of a ball inside a hand geom with the object
            (−inf without either).
        """
        mujoco.mj_kinematics(self.model, self.data)
        rot = quat_to_matrix(quat)
        frames = self._object_frames()
        positions = np.asarray(positions, dtype=float)
        field = self._field
        if field is None:
            clear = self._spheres_apart(positions, rot, frames)
        else:  # each hand geom's bounding sphere apart from the object itself
            near = self._near_geoms(positions, rot)
            clear = ~near.any(axis=1)
        overlap = np.full(len(positions), -np.inf)
        rows = np.flatnonzero(~clear)
        overlap[rows] = self._ball_overlaps(positions[rows], rot, frames, floor)
        if field is not None:  # the poses the balls left open: the points of the geoms that may touch
            settled = clear | (overlap > floor) if np.isfinite(floor) else clear
            rows = np.flatnonzero(~settled)
            if rows.size:
                touching, deepest = self._field_bounds(positions[rows], near[rows], rot, floor)
                clear[rows] = ~touching
                overlap[rows] = np.maximum(overlap[rows], deepest)
        return clear, overlap

    def _object_frames(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The object's colliding geoms' frames (position, rotation) in its own frame; the hand as set.

        The first call also makes the object's distance field (:func:`.object_field.object_field`).
        """
        model, data, a = self.model, self.data, self.obj.free_qpos
        pose = data.qpos[a : a + 7].copy()
        data.qpos[a : a + 7] = [0, 0, 0, 1, 0, 0, 0]
        mujoco.mj_kinematics(model, data)
        frames = [(data.geom_xpos[g].copy(), data.geom_xmat[g].reshape(3, 3).copy()) for g in self._obj_geoms]
        if not self._field_made:
            self._field, self._field_made = object_field(model, data, self._obj_geoms, FIELD_REACH), True
        data.qpos[a : a + 7] = pose
        mujoco.mj_kinematics(model, data)
        return frames

    def _spheres_apart(self, positions: np.ndarray, rot: np.ndarray, frames: list) -> np.ndarray:
        """Whether every object geom's bounding sphere lies beyond the margins from every hand geom's."""
        model, data, hand = self.model, self.data, self._hand_geoms
        h_pos, h_rb = data.geom_xpos[hand], model.geom_rbound[hand] + model.geom_margin[hand]
        o_pos = np.array([p for p, _ in frames]) @ rot.T
        o_rb = model.geom_rbound[self._obj_geoms] + model.geom_margin[self._obj_geoms]
        centres = (h_pos[None, :, :] - o_pos[:, None, :]).reshape(-1, 3)  # (O·G, 3) sphere pairs, shifted
        reach2 = ((o_rb[:, None] + h_rb[None, :]).reshape(-1) + 1e-6) ** 2
        clear = np.zeros(len(positions), dtype=bool)
        for first in range(0, len(positions), _CHUNK):  # squared distances: one matrix product per chunk
            x = positions[first : first + _CHUNK]
            d2 = (x * x).sum(axis=1)[:, None] - 2.0 * (x @ centres.T) + (centres * centres).sum(axis=1)[None]
            clear[first : first + _CHUNK] = (d2 > reach2[None]).all(axis=1)
        return clear

    def _ball_overlaps(
        self, positions: np.ndarray, rot: np.ndarray, frames: list, floor: float
    ) -> np.ndarray:
        """The largest overlap of a ball inscribed in an object geom with a hand geom's capsule core, m.

        −inf where no pair comes near enough to overlap by more than ``floor`` (or without balls or cores).
        """
        data = self.data
        balls = [(p + m @ c, r) for (p, m), (c, _, r) in zip(frames, self._balls, strict=True) if r > 0]
        cores = []
        for g, (c, axis, r) in zip(self._hand_geoms, self._cores, strict=True):
            if r > 0:
                m = data.geom_xmat[g].reshape(3, 3)
                cores.append((data.geom_xpos[g] + m @ c, m @ axis, r))
        overlap = np.full(len(positions), -np.inf)
        if not balls or not cores:
            return overlap
        # ball b (centre x + q_b) against core c (segment s_c + t·d_c): one segment per pair, shifted
        core_start = np.array([s - v for s, v, _ in cores])
        core_dir = np.array([2 * v for _, v, _ in cores])
        core_radius = np.array([r for _, _, r in cores])
        start_k = np.concatenate([core_start - rot @ q for q, _ in balls])  # pairs ball by ball
        dir_k = np.tile(core_dir, (len(balls), 1))
        rad_k = np.concatenate([rb + core_radius for _, rb in balls])
        len2_k = np.maximum((dir_k * dir_k).sum(axis=1), 1e-300)
        mid_k = start_k + dir_k / 2
        reach_k = rad_k - floor  # an overlap above the floor needs the segment nearer than this
        cull2 = np.where(reach_k > 0, (reach_k + np.sqrt(len2_k) / 2 + 1e-6) ** 2, -1.0)
        for first in range(0, len(positions), _CHUNK):
            x = positions[first : first + _CHUNK]
            near = (x * x).sum(axis=1)[:, None] - 2.0 * (x @ mid_k.T) + (mid_k * mid_k).sum(axis=1)[None]
            n, k = np.nonzero(near < cull2[None])
            rel = x[n] - start_k[k]
            t = np.clip((rel * dir_k[k]).sum(axis=1) / len2_k[k], 0.0, 1.0)
            depth = rad_k[k] - np.linalg.norm(rel - t[:, None] * dir_k[k], axis=1)
            np.maximum.at(overlap[first : first + _CHUNK], n, depth)
        return overlap

    def _field_inputs(self) -> tuple[ObjectField, HandSamples, float]:
        """The object's field, the hand's sample balls at its spacing, and the margins of a contact, m."""
        field, model = self._field, self.model
        assert field is not None
        if self._samples is None or self._samples_step != field.spacing:
            self._samples = hand_samples(model, self._hand_geoms, field.spacing)
            self._samples_step = field.spacing
        margin = float(model.geom_margin[self._obj_geoms].max() + model.geom_margin[self._hand_geoms].max())
        return field, self._samples, margin + _CLEAR_SLACK

    def _near_geoms(self, positions: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """(N, G): whether a hand geom's bounding sphere may come within the margins of the object."""
        field, _, margin = self._field_inputs()
        centres = self.data.geom_xpos[self._hand_geoms]
        reach = self.model.geom_rbound[self._hand_geoms] + margin
        near = np.empty((len(positions), len(centres)), dtype=bool)
        for first in range(0, len(positions), _CHUNK):
            x = positions[first : first + _CHUNK]
            _, lower = field.at((centres[None] - x[:, None]) @ rot)
            near[first : first + _CHUNK] = lower <= reach
        return near

    def _field_bounds(
        self, positions: np.ndarray, near: np.ndarray, rot: np.ndarray, floor: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Whether each pose may touch the hand, and a lower bound of its penetration, from the field.

        For each hand geom ``near`` the object (:meth:`_near_geoms`), the geoms with fewer points first: a
        ball inside the geom goes at least its radius minus the signed distance of its centre into the
        object, and the geom touches nothing when its covering balls all lie farther from the object than
        their radii plus the margins (:mod:`handsim.sim.hand_samples`, :mod:`handsim.sim.object_field`). A
        pose whose bound exceeds ``floor`` is settled (it touches) and its other geoms are not looked at.
        """
        field, samples, margin = self._field_inputs()
        points, inside, reach = samples.world(self.data), samples.inside, samples.cover + margin
        starts = np.searchsorted(samples.geom, self._hand_geoms, side="left")
        ends = np.searchsorted(samples.geom, self._hand_geoms, side="right")
        touching = np.zeros(len(positions), dtype=bool)
        deepest = np.full(len(positions), -np.inf)
        open_ = np.ones(len(positions), dtype=bool)
        for g in sorted(np.flatnonzero(near.any(axis=0)), key=lambda g: ends[g] - starts[g]):
            rows = np.flatnonzero(near[:, g] & open_)
            a, b = starts[g], ends[g]
            for first in range(0, len(rows), _CHUNK):
                part = rows[first : first + _CHUNK]
                upper, lower = field.at((points[a:b][None] - positions[part][:, None]) @ rot)
                deepest[part] = np.maximum(deepest[part], (inside[a:b] - upper).max(axis=1))
                touching[part[~(lower > reach[a:b]).all(axis=1)]] = True
            if np.isfinite(floor):
                open_[rows[deepest[rows] > floor]] = False
        return touching | ~open_, deepest


def _core(model: mujoco.MjModel, geom: int) -> tuple[np.ndarray, np.ndarray, float]:
    """A capsule core inside a colliding geom, in the geom's frame: centre, half axis and radius.

    The geom contains every ball of the radius centred on the segment centre ± half axis (a ball is a
    segment of length 0). Radius 0: no core (a geom type without one).
    """
    kind, size = int(model.geom_type[geom]), model.geom_size[geom]
    zero = np.zeros(3)
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return zero, zero, float(size[0])
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return zero, np.array([0.0, 0.0, size[1]]), float(size[0])
    if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return zero, zero, float(min(size[0], size[1]))
    if kind in (mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_ELLIPSOID):
        return zero, zero, float(size.min())
    if kind == mujoco.mjtGeom.mjGEOM_MESH and model.geom_dataid[geom] >= 0:
        mesh = int(model.geom_dataid[geom])
        points = model.mesh_vert[
            model.mesh_vertadr[mesh] : model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]
        ]
        centre, radius = _inscribed_ball(np.asarray(points, dtype=float))
        return centre, zero, radius
    return zero, zero, 0.0


def _inscribed_ball(points: np.ndarray) -> tuple[np.ndarray, float]:
    """The largest ball inside the convex hull of ``points`` (its Chebyshev centre), shrunk by 1 µm.

    MuJoCo collides a mesh geom as its vertices' convex hull. Radius 0 when the hull is flat or degenerate.
    """
    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError):
        return np.zeros(3), 0.0
    normals, offsets = hull.equations[:, :3], hull.equations[:, 3]
    scale = np.linalg.norm(normals, axis=1)
    # maximise r subject to n·c + |n| r ≤ −d for every face (variables c, r)
    result = linprog(
        np.array([0.0, 0.0, 0.0, -1.0]),
        A_ub=np.column_stack([normals, scale]),
        b_ub=-offsets,
        bounds=[(None, None)] * 3 + [(0.0, None)],
    )
    if result.status != 0 or result.x[3] <= 1e-6:
        return np.zeros(3), 0.0
    return result.x[:3], float(result.x[3]) - 1e-6
