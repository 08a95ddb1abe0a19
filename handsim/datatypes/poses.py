"""Rigid poses as numpy arrays: position (m) + unit quaternion (w, x, y, z), as in MuJoCo.

The quaternion algebra is in :mod:`handsim.datatypes.rotations`.

Every function broadcasts over leading axes: a pose array has shape (..., 7), a quaternion (..., 4).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from handsim.datatypes.rotations import quat_conjugate, quat_multiply, quat_rotate


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
