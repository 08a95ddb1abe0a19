"""Hand–object collision queries on a fixed hand posture, for many object poses: MuJoCo's own detection.

:class:`HandObjectCollider` keeps a private copy of a scene's model in which only hand–object geom pairs
collide (the hand's self-contacts are switched off: they do not change with the object's pose) and the
object's geoms carry a margin of the touch distance, so that MuJoCo reports the links within that distance
as contacts with a positive ``dist``. Moving the object is writing its free joint's ``qpos``; nothing is
recompiled.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.sim.compiled import SimScene

_HAND_BIT, _OBJECT_BIT = 2, 2


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

    def set_hand(self, qpos: np.ndarray) -> None:
        """Put the hand (and everything else but the object's pose) at ``qpos`` (nq,)."""
        a = self.obj.free_qpos
        pose = self.data.qpos[a : a + 7].copy()
        self.data.qpos[:] = qpos
        self.data.qpos[a : a + 7] = pose

    def touch_at(self, pos: np.ndarray, quat: np.ndarray) -> Touch:
        """The links touching the object at pose (``pos``, ``quat``) and the deepest penetration."""
        d, a = self.data, self.obj.free_qpos
        d.qpos[a : a + 3] = pos
        d.qpos[a + 3 : a + 7] = quat
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_collision(self.model, d)
        self.queries += 1
        distance = np.full(self.layout.link_bodies.size, np.inf)
        n = d.ncon
        if n == 0:
            return Touch(np.zeros(0, dtype=np.int64), 0.0, distance)
        geom = d.contact.geom[:n]
        dist = d.contact.dist[:n]
        other = np.where(self.is_obj[geom[:, 0]], geom[:, 1], geom[:, 0])
        link = self.link_index[self.model.geom_bodyid[other]]
        keep = (link >= 0) & (dist <= self.touch)
        if not keep.any():
            return Touch(np.zeros(0, dtype=np.int64), 0.0, distance)
        np.minimum.at(distance, link[keep], dist[keep])
        return Touch(np.flatnonzero(np.isfinite(distance)), float(max(0.0, -dist[keep].min())), distance)

    def hand_spheres(self) -> tuple[np.ndarray, np.ndarray]:
        """Centres (G, 3) and bounding radii (G,) of the hand's colliding geoms at the current posture.

        Call after a query (or :func:`mujoco.mj_kinematics`) at that posture.
        """
        return self.data.geom_xpos[self._hand_geoms].copy(), self.model.geom_rbound[self._hand_geoms].copy()
