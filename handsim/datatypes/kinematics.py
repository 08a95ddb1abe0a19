"""Rotation chains: a rotation split into rotations about fixed axes, ``R ≈ Rot(a_1, q_1) ⋯ Rot(a_n, q_n)``.

The one job here is :func:`fit_dof_angles`: the angles of a joint's degrees of freedom (up to three hinge
axes, outermost first, as :meth:`~handsim.datatypes.skeleton.Skeleton.forward_kinematics` composes them)
that reproduce a recorded rotation, with the residual angle where the chain cannot reproduce it exactly
(fewer than three axes). It serves every reader that turns recorded bone rotations into hinge angles
(:mod:`handsim.io.tzionas.motion`); rotations of a fixed axis order with a closed form, such as MANO's
Z·Y·X, use :func:`handsim.datatypes.rotations.matrix_to_zyx` instead.

Quaternions are ``(w, x, y, z)`` and every rotation operation comes from :mod:`handsim.datatypes.rotations`.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from handsim.datatypes.rotations import (
    matrix_to_quat,
    quat_about,
    quat_conjugate,
    quat_multiply,
    quat_to_axis_angle,
    rotation_about_axis,
)

_GRID = 180  # samples of the outermost angle of a 3-DoF bone (2° apart)
_GOLDEN_STEPS = 24  # brackets the outermost angle to ~1e-6 rad
_NEWTON_STEPS = 3  # Gauss-Newton polish: exact chains are then recovered to ~1e-15 rad
_TIE = 1e-9  # two 3-DoF solutions whose fit (cos of half the residual) differs less than this are equal


def _wrap(angles: np.ndarray) -> np.ndarray:
    return np.pi - np.mod(np.pi - angles, 2.0 * np.pi)  # (-π, π]


def _pair_matrix(q: np.ndarray, a1: np.ndarray, a2: np.ndarray) -> np.ndarray:
    """M with ⟨q, r(a1, x) r(a2, y)⟩ = [cos x/2, sin x/2] M [cos y/2, sin y/2]ᵀ, shape (…, 2, 2)."""
    w, v = q[..., 0], q[..., 1:]
    m11 = -w * float(a1 @ a2) + v @ np.cross(a1, a2)
    return np.stack([np.stack([w, v @ a2], -1), np.stack([v @ a1, m11], -1)], -2)


def _largest_singular(m: np.ndarray) -> np.ndarray:
    """Largest singular value of 2 × 2 matrices (closed form)."""
    s = np.sum(m * m, axis=(-2, -1))
    det = m[..., 0, 0] * m[..., 1, 1] - m[..., 0, 1] * m[..., 1, 0]
    return np.sqrt(0.5 * (s + np.sqrt(np.maximum(s * s - 4.0 * det * det, 0.0))))


def _fit_one(q: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The angle about ``a`` closest to ``q``: its twist about ``a``."""
    return _wrap(2.0 * np.arctan2(q[..., 1:] @ a, q[..., 0]))


def _fit_two(q: np.ndarray, a1: np.ndarray, a2: np.ndarray) -> np.ndarray:
    """Angles (…, 2) maximising |⟨q, r(a1, x) r(a2, y)⟩|: the largest singular pair of the pair matrix."""
    u, _, vt = np.linalg.svd(_pair_matrix(q, a1, a2))
    x = 2.0 * np.arctan2(u[..., 1, 0], u[..., 0, 0])
    y = 2.0 * np.arctan2(vt[..., 0, 1], vt[..., 0, 0])
    return _wrap(np.stack([x, y], axis=-1))


def _profile(q: np.ndarray, axes: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Best fit (|⟨q, fit⟩|) of a 3-DoF chain with its outermost angle fixed at ``x``."""
    rest = quat_multiply(quat_conjugate(quat_about(axes[0], x)), q)
    return _largest_singular(_pair_matrix(rest, axes[1], axes[2]))


def _golden_max(q: np.ndarray, axes: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Golden-section search for the maximum of :func:`_profile` in [lo, hi], all frames at once."""
    ratio = 0.5 * (math.sqrt(5.0) - 1.0)
    x1, x2 = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
    f1, f2 = _profile(q, axes, x1), _profile(q, axes, x2)
    for _ in range(_GOLDEN_STEPS):
        left = f1 >= f2  # the maximum lies in [lo, x2]
        lo, hi = np.where(left, lo, x1), np.where(left, x2, hi)
        new = np.where(left, hi - ratio * (hi - lo), lo + ratio * (hi - lo))
        f_new = _profile(q, axes, new)
        x1, x2 = np.where(left, new, x2), np.where(left, x1, new)
        f1, f2 = np.where(left, f_new, f2), np.where(left, f1, f_new)
    return 0.5 * (lo + hi)


def _fit_three(q: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Angles (T, 3): search the outermost angle, the other two in closed form; smallest exact solution."""
    step = 2.0 * np.pi / _GRID
    grid = -np.pi + step * np.arange(_GRID)
    values = _profile(q[:, None, :], axes, grid[None, :])  # (T, G)
    peaks = (values >= np.roll(values, 1, axis=1)) & (values >= np.roll(values, -1, axis=1))
    ranked = np.argsort(np.where(peaks, -values, np.inf), axis=1)[:, :2]
    candidates, fits = [], []
    for c in range(2):  # the two best peaks: a 3-DoF chain generally has two exact solutions
        x = _golden_max(q, axes, grid[ranked[:, c]] - step, grid[ranked[:, c]] + step)
        inner = _fit_two(quat_multiply(quat_conjugate(quat_about(axes[0], x)), q), axes[1], axes[2])
        candidates.append(np.concatenate([_wrap(x)[:, None], inner], axis=1))
        fits.append(_profile(q, axes, x))
    smaller = np.sum(candidates[1] ** 2, axis=1) < np.sum(candidates[0] ** 2, axis=1)
    second = (fits[1] >= np.maximum(fits[0], fits[1]) - _TIE) & (smaller | (fits[1] > fits[0] + _TIE))
    angles = np.where(second[:, None], candidates[1], candidates[0])
    for _ in range(_NEWTON_STEPS):
        angles = _newton_step(q, axes, angles)
    return angles


def _chain_quats(axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    out = np.tile([1.0, 0.0, 0.0, 0.0], (len(angles), 1))
    for i, axis in enumerate(axes):
        out = quat_multiply(out, quat_about(axis, angles[:, i]))
    return out


def _residual(q: np.ndarray, axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Rotation vector (T, 3) taking the chain to ``q``, in the chain's end frame."""
    return quat_to_axis_angle(quat_multiply(quat_conjugate(_chain_quats(axes, angles)), q))


def _newton_step(q: np.ndarray, axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """One Gauss-Newton step on the residual rotation, kept only where it lowers the residual."""
    error = _residual(q, axes, angles)
    jacobian = np.empty((len(angles), 3, len(axes)))
    for i, axis in enumerate(axes):  # d(chain)/d(q_i) in the end frame: a_i turned back by the inner DoFs
        inner = np.tile(np.eye(3), (len(angles), 1, 1))
        for j in range(i + 1, len(axes)):
            inner = inner @ rotation_about_axis(axes[j], angles[:, j])
        jacobian[:, :, i] = np.einsum("kji,j->ki", inner, axis)
    step = np.einsum("kij,kj->ki", np.linalg.pinv(jacobian), error)
    moved = _wrap(angles + step)
    better = np.linalg.norm(_residual(q, axes, moved), axis=1) < np.linalg.norm(error, axis=1)
    return np.where(better[:, None], moved, angles)


def fit_dof_angles(rotations: npt.ArrayLike, axes: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Split rotations into a chain of rotations about fixed axes, ``R ≈ Rot(a_1, q_1) ⋯ Rot(a_n, q_n)``.

    The angles minimise the angle between ``R`` and the chain. One axis: the twist of ``R`` about it
    (closed form). Two axes: the largest singular pair of a 2 × 2 matrix (closed form). Three axes: a
    search over ``q_1`` (2° grid, then golden section) with the other two in closed form, polished by
    Gauss-Newton steps; where two exact solutions exist, the one with the smaller ``Σ q²`` is returned.

    Args:
        rotations: Rotation matrices, shape (T, 3, 3).
        axes: Unit axes, outermost first, shape (n, 3) with n ≤ 3.

    Returns:
        Angles in radians in (−π, π], shape (T, n), and the residual angle between each rotation and its
        reconstruction, radians, shape (T,).

    Raises:
        ValueError: More than 3 axes, an axis that is not a unit vector, or wrongly shaped input.
    """
    r = np.asarray(rotations, dtype=float)
    a = np.asarray(axes, dtype=float).reshape(-1, 3)
    if r.ndim != 3 or r.shape[1:] != (3, 3):
        raise ValueError(f"rotations must have shape (T, 3, 3), got {r.shape}")
    if len(a) > 3:
        raise ValueError(f"at most 3 axes can be fitted, got {len(a)}")
    if len(a) and np.abs(np.linalg.norm(a, axis=1) - 1.0).max() > 1e-6:
        raise ValueError(f"axes must be unit vectors, got norms {np.linalg.norm(a, axis=1)}")
    q = matrix_to_quat(r)
    if len(a) == 0:
        angles = np.zeros((len(r), 0))
    elif len(a) == 1:
        angles = _fit_one(q, a[0])[:, None]
    elif len(a) == 2:
        angles = _fit_two(q, a[0], a[1])
    else:
        angles = _fit_three(q, a)
    return angles, np.linalg.norm(_residual(q, a, angles), axis=1)
