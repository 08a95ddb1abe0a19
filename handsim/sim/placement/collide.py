"""Hand–object collision queries on a fixed hand posture, for many object poses: MuJoCo's own detection.

:class:`HandObjectCollider` keeps a private copy of a scene's model in which only hand–object geom pairs
collide (the hand's self-contacts are switched off: they do not change with the object's pose) and the
object's geoms carry a margin of the touch distance, so that MuJoCo reports the links within that distance
as contacts with a positive ``dist``. Moving the object is writing its free joint's ``qpos``; nothing is
recompiled.

:meth:`HandObjectCollider.screen` settles many poses at one posture without running collision detection,
where cheap bounds already decide a query's outcome: a pose whose geoms' bounding spheres all lie farther
than the touch distance from every hand geom's is clear (the query would find nothing, as MuJoCo's own
bounding-sphere test would), and a pose where a ball inscribed in one of the object's sphere or convex-mesh
geoms overlaps a ball or capsule core inscribed in a hand geom by more than a depth is at least that deep
(separating two convex shapes takes at least the overlap of balls they contain; boxes and cylinders bound no
depth, :meth:`HandObjectCollider.bounds` says why).

:meth:`HandObjectCollider.depth_links` can also settle a pose as too deep with a probe, MuJoCo's own
detection on one hand–object geom pair (the deepest of the last query that found one too deep): a pair's
contacts are the same whichever other pairs collide, so a probe contact deeper than the tolerance is one
the full query would report. (Two MuJoCo cases where that reasoning would not hold are excluded or
checked: a contact filter callback, ``mjcb_contactfilter``, would let every pair collide in the probe too,
making it a full query, still exact; a full query that ran out of contact memory would have dropped pairs,
and raises instead, :meth:`HandObjectCollider.distances`.) It pays where the object has mesh geoms, and an
infeasible search is then more often run twice (:mod:`handsim.sim.placement.place`), as it always was when the
bounds settled a pose as deep.
"""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.spatial import ConvexHull, QhullError

from handsim.datatypes.rotations import quat_to_matrix
from handsim.errors import SimulationError
from handsim.sim.scene.compiled import SimScene

_HAND_BIT, _OBJECT_BIT = 2, 2
_NO_CORE = (np.zeros(3), np.zeros(3), 0.0)
_BALL_TYPES = frozenset({int(mujoco.mjtGeom.mjGEOM_SPHERE), int(mujoco.mjtGeom.mjGEOM_MESH)})
"""Object geom types whose inscribed ball bounds a query's depth (:meth:`HandObjectCollider.bounds`)."""
_CHUNK = 4096  # poses per vectorised bound evaluation (memory: chunk × object balls × hand geoms × 3)
_CONTACTFULL = int(mujoco.mjtWarning.mjWARN_CONTACTFULL)
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
        # the link of each colliding hand geom, -1 for every other geom: contype and conaffinity above let
        # only hand–object pairs collide, so a contact's link is the larger of its two geoms' (-1 for the
        # contacts of an articulated object's explicit part–part pairs, which no filter stops: dropped)
        self._geom_link = np.where(is_hand, self.link_index[body_of], -1)
        self._bind(mujoco.MjData(model))
        self.queries = 0
        self._probe: _Probe | None = None  # made at the first query that probes
        self._hand_geoms = np.flatnonzero(is_hand)
        self._obj_geoms = np.flatnonzero(self.is_obj)
        # the probe pays where the object has a mesh geom: the mug's full query (16 convex pieces) takes
        # ~30 µs, a probe ~4 µs (MuJoCo's broadphase); a ball's full query, ~7.5 µs, is not worth probing.
        # Explicit geom pairs would collide in the probe too.
        self._probes = model.npair == 0 and bool(
            (model.geom_type[self._obj_geoms] == mujoco.mjtGeom.mjGEOM_MESH).any()
        )
        self._cores = [_core(model, g) for g in self._hand_geoms]
        # MuJoCo's capsule–box routine can miss a capsule crossing a thin plate: boxes (and cylinders, not
        # checked) bound no depth; spheres and convex meshes do (bounds())
        self._balls = [
            _core(model, g) if int(model.geom_type[g]) in _BALL_TYPES else _NO_CORE for g in self._obj_geoms
        ]

    def _bind(self, data: mujoco.MjData) -> None:
        """Query with ``data``: views of the object's pose in its ``qpos``, written by every query."""
        a = self.obj.free_qpos
        self.data = data
        self._object_pos, self._object_quat = data.qpos[a : a + 3], data.qpos[a + 3 : a + 7]

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        del state["_object_pos"], state["_object_quat"]  # views into data: recreated from the copy's data
        state["_probe"] = None  # made again when needed
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._bind(self.data)

    def fork(self) -> HandObjectCollider:
        """A collider on the same model with a data (and probe) of its own, at this one's posture.

        For another thread: keep it and :meth:`follow` this one again for later queries.
        """
        forked = copy.copy(self)
        forked._bind(mujoco.MjData(self.model))
        forked._probe = None  # its own: the probe switches pairs on its model
        forked.queries = 0
        forked.follow(self)
        return forked

    def follow(self, other: HandObjectCollider) -> None:
        """Take the posture (and object orientation) of ``other``, a collider on the same model."""
        self.data.qpos[:] = other.data.qpos

    def set_hand(self, qpos: np.ndarray) -> None:
        """Put the hand (and everything else but the object's pose) at ``qpos`` (nq,)."""
        a = self.obj.free_qpos
        pose = self.data.qpos[a : a + 7].copy()
        self.data.qpos[:] = qpos
        self.data.qpos[a : a + 7] = pose

    def touch_at(self, pos: np.ndarray, quat: np.ndarray) -> Touch:
        """The links touching the object at pose (``pos``, ``quat``) and the deepest penetration."""
        distance = self.distances(np.asarray(pos, dtype=float)[None], quat)[0]
        links = np.flatnonzero(np.isfinite(distance))
        return Touch(links, float(max(0.0, -distance.min())) if links.size else 0.0, distance)

    def depth_links(
        self, positions: np.ndarray, quat: np.ndarray, settle: float | None = None
    ) -> tuple[list[float], list[int]]:
        """:meth:`touch_at`'s ``depth`` and number of ``links`` at each of ``positions`` (N, 3), one ``quat``.

        Args:
            positions: Object positions (N, 3), m.
            quat: The object's orientation (w, x, y, z) for all of them.
            settle: When given, and the object has a mesh geom and no explicit contact pair (elsewhere it
                is ignored), each pose is first probed once a full query has found a pose deeper than this
                (see the module docstring): a pose the probe finds deeper than this is settled without the
                full query (not counted in :attr:`queries`).

        Returns:
            Per position, the depth (m; ``inf`` for a pose the probe settled: deeper than ``settle``, how
            deep not known) and the number of links within the touch distance (0 for a settled pose).
        """
        distance, settled = self._distances(positions, quat, settle)
        least = distance.min(axis=1, initial=np.inf)
        depth = np.where(-least > 0.0, -least, 0.0)  # max(0, −least) as Python's max gives it (never −0.0)
        depth[settled] = np.inf
        return depth.tolist(), np.isfinite(distance).sum(axis=1).tolist()

    def distances(self, positions: np.ndarray, quat: np.ndarray) -> np.ndarray:
        """Each hand link's least signed distance to the object at each of ``positions`` (N, 3), one ``quat``.

        One MuJoCo collision query per position; the loop only runs MuJoCo and keeps each query's raw
        contacts, which are filtered and reduced for all the queries at once afterwards (the placement
        search's hot loop: little Python per query).

        Returns:
            (N, links) distances, m: negative for a penetration, +inf beyond the touch distance.

        Raises:
            SimulationError: A query ran out of MuJoCo's contact memory (``mjWARN_CONTACTFULL``): it dropped
                contacts, so its distances would be wrong.
        """
        return self._distances(positions, quat, None)[0]

    def _distances(
        self, positions: np.ndarray, quat: np.ndarray, settle: float | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`distances`, and which poses the probe settled (their rows +inf) when ``settle`` is given."""
        model, data = self.model, self.data
        self._object_quat[:] = quat
        place, kinematics, collision = self._object_pos, mujoco.mj_kinematics, mujoco.mj_collision
        probing = settle is not None and self._probes
        if probing and self._probe is None:
            self._probe = _Probe(model)
        probe = self._probe if probing else None
        limit = -settle if probing else 0.0
        warnings = data.warning.number  # a view: MuJoCo counts in place
        dropped = int(warnings[_CONTACTFULL])
        owners, found, geoms, dists, settled = [], [], [], [], []
        for i, pos in enumerate(np.asarray(positions, dtype=float)):
            place[:] = pos
            kinematics(model, data)
            if probe is not None and probe.pair is not None:
                collision(probe.model, data)
                if data.ncon and min(data.contact.dist.tolist()) < limit:  # Python min: cheaper here
                    settled.append(i)
                    continue
            collision(model, data)
            if data.ncon:
                contact = data.contact
                owners.append(i)
                found.append(data.ncon)
                geoms.append(contact.geom.copy())
                dists.append(contact.dist.copy())
                if probe is not None:
                    deepest = int(dists[-1].argmin())
                    if dists[-1][deepest] < limit:
                        probe.aim(int(geoms[-1][deepest, 0]), int(geoms[-1][deepest, 1]))
        if warnings[_CONTACTFULL] != dropped:
            raise SimulationError(
                f"the placement's collision queries ran out of MuJoCo's contact memory (mjWARN_CONTACTFULL "
                f"{int(warnings[_CONTACTFULL]) - dropped} times in {len(positions)} queries): contacts were "
                f"dropped, so the depths would be wrong; give the scene more memory than its {model.narena} "
                "bytes (MjSpec.memory, <size memory=.../>)"
            )
        self.queries += len(positions) - len(settled)
        distance = np.full((len(positions), self.layout.link_bodies.size), np.inf)
        if owners:
            owner, dist = np.repeat(owners, found), np.concatenate(dists)
            link = self._geom_link[np.concatenate(geoms)].max(axis=1)
            keep = (link >= 0) & (dist <= self.touch)
            np.minimum.at(distance, (owner[keep], link[keep]), dist[keep])
        mask = np.zeros(len(positions), dtype=bool)
        mask[settled] = True
        return distance, mask

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
            floor: Overlaps not above this may be reported as −inf (pairs too far apart are not computed).

        Returns:
            Per position: whether every object geom's bounding sphere lies farther than the touch distance
            from every hand geom's (clear); and the largest overlap of a ball inscribed in one of the
            object's sphere or convex-mesh geoms with a capsule core inscribed in a hand geom, m (a lower
            bound of MuJoCo's penetration depth; −inf without either). The search judges MuJoCo's depths,
            and those are not always the true penetration: a box gives no bound (MuJoCo's capsule–box
            routine can miss a capsule crossing a thin plate), nor does a cylinder (not checked); a convex
            mesh's inscribed ball lies deep in it, where MuJoCo's capsule–mesh depths stay close to the
            bound (``search.SCREEN_MARGIN`` gives the measured shortfall and the margin).
        """
        model, data = self.model, self.data
        mujoco.mj_kinematics(model, data)
        rot = quat_to_matrix(quat)
        hand = self._hand_geoms
        h_pos, h_rb = data.geom_xpos[hand].copy(), model.geom_rbound[hand] + model.geom_margin[hand]
        # bounding spheres of the object's geoms (relative to its free joint's frame)
        a = self.obj.free_qpos
        pose = data.qpos[a : a + 7].copy()
        data.qpos[a : a + 7] = [0, 0, 0, 1, 0, 0, 0]
        mujoco.mj_kinematics(model, data)
        objs = self._obj_geoms
        o_pos = data.geom_xpos[objs] @ rot.T
        o_rb = model.geom_rbound[objs] + model.geom_margin[objs]
        o_frames = [(data.geom_xpos[g].copy(), data.geom_xmat[g].reshape(3, 3).copy()) for g in objs]
        data.qpos[a : a + 7] = pose
        mujoco.mj_kinematics(model, data)
        # clear: every pair of bounding spheres apart (squared distances as one matrix product per chunk)
        centres = (h_pos[None, :, :] - o_pos[:, None, :]).reshape(-1, 3)  # (O·G, 3)
        reach2 = ((o_rb[:, None] + h_rb[None, :]).reshape(-1) + 1e-6) ** 2
        balls = [(p + m @ c, r) for (p, m), (c, _, r) in zip(o_frames, self._balls, strict=True) if r > 0]
        cores = []
        for g, (c, axis, r) in zip(hand, self._cores, strict=True):
            if r > 0:
                m = data.geom_xmat[g].reshape(3, 3)
                cores.append((data.geom_xpos[g] + m @ c, m @ axis, r))
        # deep: ball b (centre x + q_b) against core c (segment s_c + t·d_c): one segment per pair, shifted
        if balls and cores:  # the pairs ball by ball, each over all cores
            core_start = np.array([s - v for s, v, _ in cores])
            core_radius = np.array([r for _, _, r in cores])
            start_k = np.concatenate([core_start - rot @ q for q, _ in balls])
            dir_k = np.tile(np.array([2 * v for _, v, _ in cores]), (len(balls), 1))
            rad_k = np.concatenate([rb + core_radius for _, rb in balls])
        else:
            start_k, dir_k, rad_k = np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
        len2_k = np.maximum((dir_k * dir_k).sum(axis=1), 1e-300)
        mid_k = start_k + dir_k / 2
        reach_k = rad_k - floor  # an overlap above the floor needs the segment nearer than this
        cull2 = np.where(reach_k > 0, (reach_k + np.sqrt(len2_k) / 2 + 1e-6) ** 2, -1.0)
        clear = np.zeros(len(positions), dtype=bool)
        overlap = np.full(len(positions), -np.inf)
        centres2, mid2 = (centres * centres).sum(axis=1), (mid_k * mid_k).sum(axis=1)
        for first in range(0, len(positions), _CHUNK):
            x = np.asarray(positions[first : first + _CHUNK], dtype=float)
            x2 = (x * x).sum(axis=1)[:, None]
            apart = _squared_distances(x, x2, centres, centres2) > reach2
            clear[first : first + _CHUNK] = apart.all(axis=1)
            if rad_k.size:
                near = _squared_distances(x, x2, mid_k, mid2) < cull2
                n, k = np.nonzero(near)
                rel = x[n] - start_k[k]
                t = np.clip((rel * dir_k[k]).sum(axis=1) / len2_k[k], 0.0, 1.0)
                depth = rad_k[k] - np.linalg.norm(rel - t[:, None] * dir_k[k], axis=1)
                chunk = overlap[first : first + _CHUNK]
                np.maximum.at(chunk, n, depth)
        return clear, overlap


class _Probe:
    """A copy of a collider's model in which one hand–object geom pair collides (none until aimed).

    Its contacts at a pose are the full query's contacts of that pair, bit for bit: MuJoCo's narrowphase of a
    pair does not depend on the other pairs.
    """

    def __init__(self, model: mujoco.MjModel) -> None:
        self.model = copy.deepcopy(model)
        self._contype, self._conaffinity = self.model.geom_contype, self.model.geom_conaffinity  # views
        self._contype[:] = 0
        self._conaffinity[:] = 0
        self._colliding = (model.geom_contype.tolist(), model.geom_conaffinity.tolist())
        self.pair: tuple[int, int] | None = None

    def aim(self, g1: int, g2: int) -> None:
        """Make geoms ``g1`` and ``g2`` (a contact's pair) the only pair that collides."""
        if self.pair == (g1, g2):
            return
        contype, conaffinity = self._contype, self._conaffinity
        if self.pair is not None:
            for g in self.pair:
                contype[g] = conaffinity[g] = 0
        for g in (g1, g2):
            contype[g], conaffinity[g] = self._colliding[0][g], self._colliding[1][g]
        self.pair = (g1, g2)


def _squared_distances(x: np.ndarray, x2: np.ndarray, y: np.ndarray, y2: np.ndarray) -> np.ndarray:
    """``x2 − 2 x·yᵀ + y2`` (N, M) for points ``x`` (N, 3), ``y`` (M, 3) and their squared norms (N, 1), (M,).

    In place on the one (N, M) product (no temporaries of that size), bit for bit the expression.
    """
    d2 = x @ y.T
    d2 *= -2.0
    d2 += x2
    d2 += y2
    return d2


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
        vertices = np.ascontiguousarray(points, dtype=float)
        centre, radius = _inscribed_ball(vertices.tobytes(), vertices.shape)
        return centre.copy(), zero, radius
    return zero, zero, 0.0


@functools.lru_cache(maxsize=1024)
def _inscribed_ball(vertices: bytes, shape: tuple[int, ...]) -> tuple[np.ndarray, float]:
    """The largest ball inside the convex hull of the points (its Chebyshev centre), shrunk by 1 µm.

    MuJoCo collides a mesh geom as its vertices' convex hull. Radius 0 when the hull is flat or degenerate.
    The points come as the bytes of a float64 array of ``shape``, so that a process building many
    colliders of the same hand and object (a dataset run's worker: one per trial) solves each mesh's
    linear programme once (~2 ms each; the mug's 16 pieces and the palm). The centre is shared: copy it.
    """
    from scipy.optimize import linprog  # lazy: SciPy's optimisers (60 ms), only where a hull needs one

    points = np.frombuffer(vertices, dtype=float).reshape(shape)
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
