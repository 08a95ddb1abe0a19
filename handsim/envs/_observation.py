"""Observation pieces shared by the environments: named slices, state gathers and the contact summary.

Everything is turned into index arrays once, so that an observation is a few ``numpy`` gathers into a
preallocated buffer: no Python loop over joints or contacts per step.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from handsim.sim.scene.compiled import SimScene
from handsim.sim.scene.layout import CONTACT_SLOT_SIZE, CONTACT_SLOTS

POSE_LABELS = ("x", "y", "z", "qw", "qx", "qy", "qz")
VELOCITY_LABELS = ("vx", "vy", "vz", "wx", "wy", "wz")


class ObservationLayout:
    """Names and slices of a flat observation vector, built group by group.

    Attributes:
        names: One name per element, ``<group>/<label>`` (e.g. ``hand_qpos/if_mcp_flex``).
        slices: The slice of each group.
    """

    def __init__(self) -> None:
        self.names: list[str] = []
        self.slices: dict[str, slice] = {}

    def add(self, group: str, labels: Sequence[str]) -> slice:
        """Append a group of elements; returns its slice."""
        if group in self.slices:
            raise ValueError(f"observation group {group!r} added twice")
        start = len(self.names)
        self.names.extend(f"{group}/{label}" for label in labels)
        self.slices[group] = slice(start, len(self.names))
        return self.slices[group]

    @property
    def size(self) -> int:
        """Number of elements."""
        return len(self.names)


def add_state(obs: ObservationLayout, scene: SimScene) -> tuple[slice, np.ndarray, slice, np.ndarray]:
    """Add the hand and object positions, then their velocities, as two contiguous runs.

    Positions: ``hand_qpos`` (DoFs in actuator order, rad), ``root_pose`` (a welded root: position m,
    quaternion w x y z), then per object ``<prefix>pose`` (7) and ``<prefix>hinge`` (rad, articulated
    objects). Velocities: ``hand_qvel`` (rad/s), ``root_velocity`` (linear m/s, angular rad/s, MuJoCo's
    free-joint convention: linear in the world frame, angular in the body frame), per object
    ``<prefix>velocity`` (6) and ``<prefix>hinge_velocity``.

    Returns:
        The slice of the positions and their qpos addresses, the slice of the velocities and their qvel
        addresses (``obs[positions] = qpos[qpos_adr]``, ``obs[velocities] = qvel[qvel_adr]``).
    """
    layout = scene.layout
    qpos = [layout.dof_qpos]
    qvel = [layout.dof_qvel]
    first = obs.add("hand_qpos", layout.dof_names)
    if layout.root_free_qpos >= 0:
        obs.add("root_pose", POSE_LABELS)
        qpos.append(layout.root_free_qpos + np.arange(7))
    for o in layout.objects:
        if o.free_qpos >= 0:
            obs.add(f"{o.prefix}pose", POSE_LABELS)
            qpos.append(o.free_qpos + np.arange(7))
        if o.hinge_qpos >= 0:
            obs.add(f"{o.prefix}hinge", ("angle",))
            qpos.append(np.array([o.hinge_qpos]))
    positions = slice(first.start, obs.size)
    first = obs.add("hand_qvel", layout.dof_names)
    if layout.root_free_qpos >= 0:
        obs.add("root_velocity", VELOCITY_LABELS)
        qvel.append(layout.root_free_dof + np.arange(6))
    for o in layout.objects:
        if o.free_dof >= 0:
            obs.add(f"{o.prefix}velocity", VELOCITY_LABELS)
            qvel.append(o.free_dof + np.arange(6))
        if o.hinge_qpos >= 0:
            obs.add(f"{o.prefix}hinge_velocity", ("angle",))
            qvel.append(np.array([o.hinge_dof]))
    velocities = slice(first.start, obs.size)
    return positions, np.concatenate(qpos).astype(np.int64), velocities, np.concatenate(qvel).astype(np.int64)


class ContactSummary:
    """Per hand link, the total normal force on every object part; the deepest hand–object penetration.

    Read from the metric sensors (:func:`handsim.sim.scene.layout.instrument`) that MuJoCo fills inside
    ``mj_step``: one gather and one small matrix product per step. As in
    :func:`handsim.sim.metrics.frame_metrics`, a link × part pair contributes its first
    :data:`~handsim.sim.scene.layout.CONTACT_SLOTS` contacts (MuJoCo zero-fills unused slots).
    """

    def __init__(self, scene: SimScene) -> None:
        layout = scene.layout
        adr = layout.contact_adr  # (links, parts)
        links = adr.shape[0]
        # normal force of every slot of every pair, link-major: (links, parts, slots)
        slots = adr[..., None] + CONTACT_SLOT_SIZE * np.arange(CONTACT_SLOTS) + 1
        self._force = slots.reshape(-1).astype(np.int64)
        per_link = self._force.size // links if links else 0
        self._sum = np.kron(np.eye(links), np.ones(per_link)) if links else np.zeros((0, 0))
        self._pen_found = np.asarray(layout.penetration_adr, dtype=np.int64)
        self._pen_dist = self._pen_found + 1
        self._single = int(self._pen_dist[0]) if self._pen_dist.size == 1 else None
        self.links = links
        self.link_names = layout.link_names

    def link_forces(self, sensordata: np.ndarray, out: np.ndarray) -> None:
        """Write the total normal force per link (N, ≥ 0) into ``out`` (links,)."""
        if not self.links:
            return
        np.dot(self._sum, sensordata[self._force], out=out)

    def penetration(self, sensordata: np.ndarray) -> float:
        """Deepest hand–object penetration, m (≥ 0; 0 without contact)."""
        # a part without contact reports distance 0
        if self._single is not None:
            return max(0.0, -float(sensordata[self._single]))
        if not self._pen_dist.size:
            return 0.0
        return max(0.0, -float(sensordata[self._pen_dist].min()))
