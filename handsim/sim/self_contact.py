"""The hand through itself: how deep one link of a recorded posture lies inside another.

A recording whose fingers pass through each other (a thumb through the index, say) is a recording-quality
problem: glove calibration, a skeleton whose thumb cannot reach where the real one was. :class:`SelfCollider`
measures it kinematically, on a private copy of a scene's model in which only the hand's own geom pairs
collide (those the hand model does not exclude: links of different fingers, and the palm against distal
links), MuJoCo's collision detection giving the depth.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.sim.scene.compiled import SimScene


@dataclass(frozen=True)
class SelfPenetration:
    """The deepest hand self-penetration of a posture.

    Attributes:
        depth: How deep, m (0 when no two links overlap).
        links: The two links (names without ``hand/``), or None when none overlap.
    """

    depth: float
    links: tuple[str, str] | None

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {"depth_m": self.depth, "links": None if self.links is None else list(self.links)}


class SelfCollider:
    """Hand self-penetration of any posture of a scene's hand.

    Args:
        scene: A scene with a hand.
    """

    def __init__(self, scene: SimScene) -> None:
        layout = scene.layout
        self.model = copy.deepcopy(scene.model)
        model = self.model
        hand = np.isin(model.geom_bodyid, layout.link_bodies) & (
            (model.geom_contype != 0) | (model.geom_conaffinity != 0)
        )
        contype, conaffinity = model.geom_contype.copy(), model.geom_conaffinity.copy()
        model.geom_contype[:] = 0
        model.geom_conaffinity[:] = 0
        model.geom_contype[hand] = contype[hand]
        model.geom_conaffinity[hand] = conaffinity[hand]
        model.geom_margin[:] = 0.0
        self.data = mujoco.MjData(model)
        self._names = {int(b): name for b, name in zip(layout.link_bodies, layout.link_names, strict=True)}

    def __call__(self, qpos: np.ndarray) -> SelfPenetration:
        """The deepest self-penetration with the scene's state at ``qpos`` (nq,)."""
        model, data = self.model, self.data
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        mujoco.mj_collision(model, data)
        n = data.ncon
        if n == 0:
            return SelfPenetration(0.0, None)
        dist = data.contact.dist[:n]
        worst = int(np.argmin(dist))
        if dist[worst] >= 0:
            return SelfPenetration(0.0, None)
        geom = data.contact.geom[worst]
        a, b = (self._names.get(int(model.geom_bodyid[g]), "?") for g in geom)
        return SelfPenetration(float(-dist[worst]), (a, b))


def self_penetration_track(scene: SimScene, qpos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The hand's self-penetration at every posture of a replay.

    Args:
        scene: The replayed scene.
        qpos: States (N, nq): the simulated state at each frame, or the hand put at its targets.

    Returns:
        The deepest self-penetration per posture, m (N,), 0 where no two links overlap; and its two links
        as indices into the layout's ``link_names`` (N, 2), -1 where none overlap.
    """
    collider = SelfCollider(scene)
    index = {name: i for i, name in enumerate(scene.layout.link_names)}
    depth = np.zeros(qpos.shape[0])
    pair = np.full((qpos.shape[0], 2), -1, dtype=np.int64)
    for k in range(qpos.shape[0]):
        found = collider(qpos[k])
        depth[k] = found.depth
        if found.links is not None:
            pair[k] = [index[found.links[0]], index[found.links[1]]]
    return depth, pair
