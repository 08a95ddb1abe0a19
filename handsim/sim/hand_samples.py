"""Balls inside the hand's colliding geoms and balls covering them, for bounds of hand–object queries.

:meth:`handsim.sim.collide.HandObjectCollider.bounds` bounds a query from the object's distance field
(:mod:`handsim.sim.object_field`) at a few points of each hand geom:

* a ball of radius ``inside`` centred at a point lies inside its geom, so the geom goes into the object at
  least as deep as that ball does;
* the balls of radius ``cover`` centred at a geom's cover points together hold the whole geom, so the geom
  touches nothing when each of them is farther than its radius (plus the margins) from the object.

A capsule's points run along its axis (both roles, the cover radius grown by half their spacing); a sphere is
one point; a mesh or box is cut into cells of at most :data:`CELL` (a cell's centre covers the geom's part in
it with the cell's half diagonal, and is a ball inside the geom as deep as it lies); another geom is its
inscribed ball and its bounding sphere.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.spatial import ConvexHull, QhullError

CELL = 0.016
"""Largest cell edge of a mesh or box geom's cover, m (a palm: about 60 cells of ~12 mm half diagonal)."""
MIN_INSIDE = 0.0005
"""Cell centres less deep than this inside a mesh are no inside ball, m."""


@dataclass(frozen=True)
class HandSamples:
    """Sample points of hand geoms in their geoms' frames.

    Attributes:
        geom: (K,) the geom of each point.
        local: (K, 3) the points in their geom's frame, m.
        inside: (K,) radius of a ball centred there inside the geom, m (−inf: none).
        cover: (K,) radius of the point's covering ball, m (−inf: the point covers nothing).
    """

    geom: np.ndarray
    local: np.ndarray
    inside: np.ndarray
    cover: np.ndarray

    def world(self, data: mujoco.MjData) -> np.ndarray:
        """The points in the world frame at ``data``'s geom poses (after kinematics), (K, 3)."""
        mats = data.geom_xmat[self.geom].reshape(-1, 3, 3)
        return data.geom_xpos[self.geom] + np.einsum("kij,kj->ki", mats, self.local)


def hand_samples(model: mujoco.MjModel, geoms: np.ndarray, step: float) -> HandSamples:
    """The sample points of ``geoms`` (see the module docstring).

    Args:
        model: The model.
        geoms: The hand's colliding geom ids.
        step: Largest spacing of the points along a capsule's axis, m.

    Returns:
        The points of all geoms, geom by geom.
    """
    parts = [(int(g), *_samples(model, int(g), step)) for g in geoms]
    return HandSamples(
        geom=np.concatenate([np.full(len(p[1]), p[0], dtype=np.intp) for p in parts]),
        local=np.concatenate([p[1] for p in parts]),
        inside=np.concatenate([p[2] for p in parts]),
        cover=np.concatenate([p[3] for p in parts]),
    )


def _samples(model: mujoco.MjModel, geom: int, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    kind, size = int(model.geom_type[geom]), model.geom_size[geom]
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        count = int(np.ceil(2.0 * size[1] / step)) + 1
        along = np.linspace(-size[1], size[1], count)
        half_gap = size[1] / (count - 1)
        points = np.column_stack([np.zeros(count), np.zeros(count), along])
        return points, np.full(count, size[0]), np.full(count, size[0] + half_gap)
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return np.zeros((1, 3)), np.array([size[0]]), np.array([size[0]])
    vertices = None
    if kind == mujoco.mjtGeom.mjGEOM_MESH and model.geom_dataid[geom] >= 0:
        mesh = int(model.geom_dataid[geom])
        start = model.mesh_vertadr[mesh]
        vertices = np.asarray(model.mesh_vert[start : start + model.mesh_vertnum[mesh]], dtype=float)
    elif kind == mujoco.mjtGeom.mjGEOM_BOX:
        vertices = np.array(np.meshgrid(*([-1.0, 1.0],) * 3, indexing="ij")).reshape(3, -1).T * size[:3]
    cells = _cells(vertices) if vertices is not None else None
    if cells is not None:
        return cells
    core_centre, core_radius = _inscribed(model, geom)
    points = np.vstack([core_centre, np.zeros(3)])
    return (
        points,
        np.array([core_radius if core_radius > 0 else -np.inf, -np.inf]),
        np.array([-np.inf, float(model.geom_rbound[geom])]),
    )


def _cells(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Cell centres of a convex polytope's box: their depths (inside balls), half diagonals (covers)."""
    try:
        planes = ConvexHull(vertices).equations  # n·x + d ≤ 0 inside, |n| = 1
    except (QhullError, ValueError):
        return None
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    counts = np.maximum(1, np.ceil((high - low) / CELL)).astype(int)
    edge = (high - low) / counts
    axes = [low[a] + edge[a] * (np.arange(counts[a]) + 0.5) for a in range(3)]
    centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    signed = (centres @ planes[:, :3].T + planes[:, 3]).max(axis=1)  # exact inside; at most the distance
    half_diagonal = 0.5 * float(np.linalg.norm(edge))
    covering = signed <= half_diagonal  # every cell holding a point of the geom (and maybe a few more)
    inside = np.where(-signed >= MIN_INSIDE, -signed, -np.inf)
    keep = covering | np.isfinite(inside)
    return centres[keep], inside[keep], np.where(covering, half_diagonal, -np.inf)[keep]


def _inscribed(model: mujoco.MjModel, geom: int) -> tuple[np.ndarray, float]:
    """The largest simple ball inside a cylinder or an ellipsoid (0: none for another type)."""
    kind, size = int(model.geom_type[geom]), model.geom_size[geom]
    if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return np.zeros(3), float(min(size[0], size[1]))
    if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        return np.zeros(3), float(size.min())
    return np.zeros(3), 0.0
