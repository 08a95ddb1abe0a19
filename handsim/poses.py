"""Rigid poses as numpy arrays: position (m) + unit quaternion (w, x, y, z), as in MuJoCo.

Every function broadcasts over leading axes: a pose array has shape (..., 7), a quaternion (..., 4).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


def quat_multiply(a: npt.ArrayLike, b: npt.ArrayLike) -> np.ndarray:
    """Hamilton product ``a ⊗ b`` (rotate by ``b``, then by ``a``)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    wa, va, wb, vb = a[..., :1], a[..., 1:], b[..., :1], b[..., 1:]
    w = wa * wb - np.sum(va * vb, axis=-1, keepdims=True)
    return np.concatenate([w, wa * vb + wb * va + np.cross(va, vb)], axis=-1)


def quat_conjugate(q: npt.ArrayLike) -> np.ndarray:
    """The inverse rotation of a unit quaternion."""
    return np.asarray(q, dtype=float) * np.array([1.0, -1.0, -1.0, -1.0])


def quat_rotate(q: npt.ArrayLike, v: npt.ArrayLike) -> np.ndarray:
    """Rotate vectors ``v`` (..., 3) by unit quaternions ``q`` (..., 4)."""
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    w, u = q[..., :1], q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def quat_angle(a: npt.ArrayLike, b: npt.ArrayLike) -> np.ndarray:
    """Angle of the rotation between unit quaternions ``a`` and ``b``, radians in [0, π]."""
    dot = np.abs(np.sum(np.asarray(a, dtype=float) * np.asarray(b, dtype=float), axis=-1))
    return 2.0 * np.arccos(np.clip(dot, 0.0, 1.0))


def compose(a: npt.ArrayLike, b: npt.ArrayLike) -> np.ndarray:
    """Pose ``a ∘ b``: the frame ``b`` given in ``a``'s frame, expressed where ``a`` is expressed."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    position = a[..., :3] + quat_rotate(a[..., 3:], b[..., :3])
    return np.concatenate([position, quat_multiply(a[..., 3:], b[..., 3:])], axis=-1)


def inverse(a: npt.ArrayLike) -> np.ndarray:
    """The inverse pose: ``compose(inverse(a), a)`` is the identity."""
    a = np.asarray(a, dtype=float)
    q = quat_conjugate(a[..., 3:])
    return np.concatenate([-quat_rotate(q, a[..., :3]), q], axis=-1)


def transform_points(pose: npt.ArrayLike, points: npt.ArrayLike) -> np.ndarray:
    """Points (..., 3) given in the frame ``pose``, expressed where ``pose`` is expressed."""
    pose = np.asarray(pose, dtype=float)
    return pose[..., :3] + quat_rotate(pose[..., 3:], points)
