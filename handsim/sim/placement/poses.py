"""The object poses the glove placement search tries, and the object's collision points that judge them.

The 24 axis-aligned orientations, reduced to those that give the object's collision points different
shapes (:func:`distinct_orientations`); position grids (:func:`box_grid`, :func:`grid_around`); and the moves
and turns of the hold-robustness ensemble (:func:`perturbed_poses`). The search that uses them is
:mod:`handsim.sim.placement.search`.
"""

from __future__ import annotations

import itertools
import math

import mujoco
import numpy as np
from scipy.spatial import cKDTree

from handsim.datatypes.rotations import quat_about, quat_multiply, quat_to_matrix
from handsim.sim.placement.collide import HandObjectCollider


def axis_aligned_orientations() -> np.ndarray:
    """The 24 orientations that put one of the object's six face directions up, each at four spins."""
    h = np.sqrt(0.5)
    faces = [[1, 0, 0, 0], [h, h, 0, 0], [0, 1, 0, 0], [h, -h, 0, 0], [h, 0, h, 0], [h, 0, -h, 0]]
    spins = quat_about([0.0, 0.0, 1.0], np.array([0, np.pi / 2, np.pi, 3 * np.pi / 2]))
    return np.array([quat_multiply(s, f) for f, s in itertools.product(faces, spins)])


def distinct_orientations(quats: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The orientations that give the object's collision points different shapes, the first of each kept.

    A box keeps one, a cylinder three (its axis along x, y or z), an asymmetric object all 24.
    """
    tolerance = 1e-6 + 1e-5 * float(np.abs(points).max())
    bound = np.nextafter(tolerance, np.inf)  # the tree finds every point within the tolerance
    kept: list[tuple[np.ndarray, cKDTree, np.ndarray, np.ndarray]] = []
    for quat in quats:
        turned = points @ quat_to_matrix(quat).T
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


def object_points(collider: HandObjectCollider) -> np.ndarray:
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


def box_grid(lo: np.ndarray, hi: np.ndarray, step: float) -> np.ndarray:
    """Points (N, 3) spaced ``step`` apart from ``lo`` up to ``hi`` per axis (the middle where hi ≤ lo), m."""
    axes = [
        np.arange(a, b + 1e-9, step) if b > a else np.array([(a + b) / 2])
        for a, b in zip(lo, hi, strict=True)
    ]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def grid_around(center: np.ndarray, half: float, step: float) -> np.ndarray:
    """The cube of points (N, 3) spaced ``step`` apart within ``half`` of ``center`` along each axis, m."""
    n = int(np.floor(half / step + 1e-9))
    offsets = np.arange(-n, n + 1) * step
    return center + np.stack(np.meshgrid(offsets, offsets, offsets, indexing="ij"), axis=-1).reshape(-1, 3)


def perturbed_poses(
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
            turned = pose.copy()
            turned[3:] = quat_multiply(quat_about(np.eye(3)[axis], math.radians(sign * turn_deg)), pose[3:])
            if len(distinct_orientations(np.array([pose[3:], turned[3:]]), points)) == 2:
                variants.append((f"{mark}{name} {turn_deg:g}°", turned))
    return variants
