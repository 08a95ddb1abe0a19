"""Rotations: quaternions (w, x, y, z, as in MuJoCo), axis-angle vectors, matrices and Z·Y·X angles.

The one place in handsim where rotation math lives. Conventions (pinned by ``tests/test_rotations.py``
against MuJoCo's ``mju_*`` functions and explicit matrices):

* **Quaternions** are ``(w, x, y, z)`` (scalar first, MuJoCo's order; scipy's default is scalar last and
  is only ever used with ``scalar_first=True`` here). ``q`` and ``−q`` are the same rotation; functions
  that return a quaternion say which sign they give.
* **Active rotations** of column vectors: ``quat_rotate(q, v) = R(q) v``; matrices' columns are the
  rotated frame's axes.
* **Composition** ``quat_multiply(a, b)`` is the Hamilton product ``a ⊗ b``: rotate by ``b``, then by
  ``a`` (``R(a ⊗ b) = R(a) R(b)``), as ``mju_mulQuat``.
* **Axis-angle** vectors are unit axis × angle in radians (scipy's rotation vectors).
* **Z·Y·X angles** ``(a, b, c)`` mean ``Rz(a) · Ry(b) · Rx(c)``: intrinsic z, then y, then x (scipy's
  ``"ZYX"``, upper case).
* Every function broadcasts over leading axes: shape (..., 4) quaternions, (..., 3) vectors, (..., 3, 3)
  matrices.

The conversions go through :class:`scipy.spatial.transform.Rotation` (``scalar_first`` needs scipy ≥ 1.14).
Four things do not, each for a measured reason:

* The Hamilton product, conjugate, vector rotation and angle between quaternions are numpy closed forms:
  they run per frame in the metrics and per candidate in the placement search, where a scipy ``Rotation``
  costs about 40 µs per call, and they must not renormalise their input (scipy's ``from_quat`` does).
* :func:`matrix_to_zyx` keeps its own extraction: scipy's ``as_euler("ZYX")`` warns and sets the third
  angle to zero at gimbal lock and reconstructs rotations 1e-4 rad from the lock only to 3.5e-8 rad,
  where this one is exact to rounding (< 1e-14 rad) everywhere.
* :func:`slerp` is element-wise between pairs with exact endpoints and NaN for a zero quaternion;
  scipy's ``Slerp`` interpolates along one keyframe sequence and rejects zero quaternions.
* :func:`rotation_error` measures the angle between matrices from their Frobenius distance, accurate
  near zero without a conversion.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

_GIMBAL_COS = 1e-12
_SLERP_LINEAR_DOT = 0.9995
"""Above this |q0·q1| (angle below about 3.6°) slerp falls back to normalised linear interpolation."""
_PARALLEL_SIN = 1e-12


def _scipy_rotation() -> type:
    """The ``scipy.spatial.transform.Rotation`` class."""
    # lazy: scipy costs ~0.5 s at start-up, and light commands (``handsim catalog``) need only the numpy parts
    from scipy.spatial.transform import Rotation

    return Rotation


def _scipy(stack: np.ndarray, width: int) -> tuple[np.ndarray, tuple[int, ...]]:
    """``stack`` (..., *width) as a 2-D batch for scipy (which wants (N, ...) before 1.17), and its shape."""
    lead = stack.shape[: stack.ndim - width]
    return stack.reshape((-1, *stack.shape[stack.ndim - width :])), lead


# --------------------------------------------------------------------------------------------------
# Quaternion algebra (numpy closed forms; see the module notes)


def quat_multiply(a: npt.ArrayLike, b: npt.ArrayLike) -> np.ndarray:
    """Hamilton product ``a ⊗ b`` (rotate by ``b``, then by ``a``), as ``mju_mulQuat``.

    Args:
        a: Quaternions (w, x, y, z), shape (..., 4).
        b: Quaternions (w, x, y, z), shape (..., 4), broadcast against ``a``.

    Returns:
        The products, shape (..., 4); not renormalised.
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    wa, va, wb, vb = a[..., :1], a[..., 1:], b[..., :1], b[..., 1:]
    w = wa * wb - np.sum(va * vb, axis=-1, keepdims=True)
    return np.concatenate([w, wa * vb + wb * va + np.cross(va, vb)], axis=-1)


def quat_conjugate(q: npt.ArrayLike) -> np.ndarray:
    """The conjugate ``(w, −x, −y, −z)``: the inverse rotation of a unit quaternion, shape (..., 4)."""
    return np.asarray(q, dtype=float) * np.array([1.0, -1.0, -1.0, -1.0])


def quat_rotate(q: npt.ArrayLike, v: npt.ArrayLike) -> np.ndarray:
    """Rotate vectors ``v`` (..., 3) by unit quaternions ``q`` (..., 4): ``R(q) v``, as ``mju_rotVecQuat``."""
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    w, u = q[..., :1], q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def quat_angle(a: npt.ArrayLike, b: npt.ArrayLike) -> np.ndarray:
    """Angle of the rotation between unit quaternions ``a`` and ``b``, radians in [0, π], shape (...)."""
    dot = np.abs(np.sum(np.asarray(a, dtype=float) * np.asarray(b, dtype=float), axis=-1))
    return 2.0 * np.arccos(np.clip(dot, 0.0, 1.0))


# --------------------------------------------------------------------------------------------------
# Conversions (scipy)


def quat_to_matrix(q: npt.ArrayLike) -> np.ndarray:
    """Rotation matrices of quaternions (w, x, y, z), shape (..., 4) → (..., 3, 3); ``q`` is normalised."""
    flat, lead = _scipy(np.asarray(q, dtype=float), 1)
    return _scipy_rotation().from_quat(flat, scalar_first=True).as_matrix().reshape((*lead, 3, 3))


def matrix_to_quat(matrix: npt.ArrayLike) -> np.ndarray:
    """Unit quaternions (w, x, y, z) of rotation matrices, shape (..., 3, 3) → (..., 4).

    The sign is scipy's (not canonicalised): callers that need continuity or ``w ≥ 0`` choose it.
    """
    flat, lead = _scipy(np.asarray(matrix, dtype=float), 2)
    return _scipy_rotation().from_matrix(flat).as_quat(scalar_first=True).reshape((*lead, 4))


def axis_angle_to_quat(aa: npt.ArrayLike) -> np.ndarray:
    """Unit quaternions (w, x, y, z) of axis-angle vectors.

    Args:
        aa: Axis-angle vectors (unit axis × angle in radians), shape (..., 3).

    Returns:
        ``(cos θ/2, sin(θ/2) · axis)``, shape (..., 4): w ≥ 0 for angles ≤ π, w < 0 beyond (no sign flip).
    """
    flat, lead = _scipy(np.asarray(aa, dtype=float), 1)
    return _scipy_rotation().from_rotvec(flat).as_quat(scalar_first=True).reshape((*lead, 4))


def quat_about(axis: npt.ArrayLike, angles: npt.ArrayLike) -> np.ndarray:
    """Quaternions (w, x, y, z) of rotations by ``angles`` (radians, shape S) about one unit ``axis`` (3,).

    Returns ``(cos q/2, sin(q/2) · axis)``, shape ``S + (4,)`` (w < 0 for |q| > π).
    """
    a = np.asarray(axis, dtype=float)
    return axis_angle_to_quat(np.asarray(angles, dtype=float)[..., None] * a)


def quat_to_axis_angle(q: npt.ArrayLike) -> np.ndarray:
    """Axis-angle vectors of quaternions (w, x, y, z), shape (..., 4) → (..., 3), angles in [0, π].

    ``q`` is normalised, and ``q`` and ``−q`` give the same vector (the shorter rotation).
    """
    flat, lead = _scipy(np.asarray(q, dtype=float), 1)
    return _scipy_rotation().from_quat(flat, scalar_first=True).as_rotvec().reshape((*lead, 3))


def axis_angle_to_matrix(aa: npt.ArrayLike) -> np.ndarray:
    """Rotation matrices of axis-angle vectors (unit axis × angle, radians), shape (..., 3) → (..., 3, 3)."""
    flat, lead = _scipy(np.asarray(aa, dtype=float), 1)
    return _scipy_rotation().from_rotvec(flat).as_matrix().reshape((*lead, 3, 3))


def quat_error_rotvec(ref: np.ndarray, q: np.ndarray, out: np.ndarray) -> float:
    """The rotation taking ``q`` to ``ref`` (``ref ⊗ q⁻¹``, world frame) as a rotation vector, in place.

    The per-step path of the environments: one pair of quaternions in Python floats, no SciPy call and no
    array allocated (:func:`quat_angle` and :func:`quat_to_axis_angle` are the vectorised forms).

    Args:
        ref: Recorded orientation, unit quaternion w x y z.
        q: Simulated orientation, unit quaternion w x y z.
        out: Where the rotation vector goes (3,), rad; its norm is the angle in [0, π].

    Returns:
        The angle, rad.
    """
    w1, x1, y1, z1 = ref.tolist()
    w2, x2, y2, z2 = q.tolist()
    w = w1 * w2 + x1 * x2 + y1 * y2 + z1 * z2
    x = -w1 * x2 + x1 * w2 - y1 * z2 + z1 * y2
    y = -w1 * y2 + x1 * z2 + y1 * w2 - z1 * x2
    z = -w1 * z2 - x1 * y2 + y1 * x2 + z1 * w2
    if w < 0.0:  # the shorter way round
        w, x, y, z = -w, -x, -y, -z
    sine = math.sqrt(x * x + y * y + z * z)
    if sine < 1e-12:
        out[0], out[1], out[2] = 2.0 * x, 2.0 * y, 2.0 * z
        return 2.0 * sine
    angle = 2.0 * math.atan2(sine, w)
    f = angle / sine
    out[0], out[1], out[2] = f * x, f * y, f * z
    return angle


def rotation_about_axis(axis: npt.ArrayLike, angles: npt.ArrayLike) -> np.ndarray:
    """Rotation matrices about one fixed unit axis.

    Args:
        axis: Unit rotation axis, shape (3,).
        angles: Angles in radians, any shape ``S``.

    Returns:
        Rotation matrices of shape ``S + (3, 3)``.
    """
    a = np.asarray(axis, dtype=float)
    return axis_angle_to_matrix(np.asarray(angles, dtype=float)[..., None] * a)


def zyx_to_matrix(angles: npt.ArrayLike) -> np.ndarray:
    """``Rz(a) · Ry(b) · Rx(c)`` for angles ``(a, b, c)`` in radians, shape (..., 3) → (..., 3, 3).

    The product of the three axis quaternions in closed form, then scipy's quaternion → matrix: within
    9e-16 of scipy's ``from_euler("ZYX")`` and about 6× faster (150,000 angle triples: 58 ms, 343 ms).
    """
    half = 0.5 * np.asarray(angles, dtype=float)
    (cz, cy, cx), (sz, sy, sx) = np.moveaxis(np.cos(half), -1, 0), np.moveaxis(np.sin(half), -1, 0)
    quat = np.stack(  # q_z(a) ⊗ q_y(b) ⊗ q_x(c), expanded
        [
            cz * cy * cx + sz * sy * sx,
            cz * cy * sx - sz * sy * cx,
            cz * sy * cx + sz * cy * sx,
            sz * cy * cx - cz * sy * sx,
        ],
        axis=-1,
    )
    return quat_to_matrix(quat)


def matrix_to_zyx(rotation: npt.ArrayLike) -> np.ndarray:
    """Angles ``(a, b, c)`` with ``Rz(a) · Ry(b) · Rx(c) = R`` (exact up to rounding, also at gimbal lock).

    ``a`` and ``b`` come from the first column; ``c`` from the remainder ``Ry(b)ᵀ Rz(a)ᵀ R``, so errors in
    ``a`` near the singularity (|b| → π/2, where only a ± c is defined) are absorbed by ``c`` and the
    product still equals ``R`` to rounding. (scipy's ``as_euler`` does not: see the module notes.)

    Args:
        rotation: Rotation matrices, shape (..., 3, 3).

    Returns:
        Angles in radians, shape (..., 3): a, c in [−π, π], b in [−π/2, π/2].
    """
    r = np.asarray(rotation, dtype=float)
    cos_b = np.hypot(r[..., 0, 0], r[..., 1, 0])
    b = np.arctan2(-r[..., 2, 0], cos_b)
    a = np.where(cos_b > _GIMBAL_COS, np.arctan2(r[..., 1, 0], r[..., 0, 0]), 0.0)
    turned = zyx_to_matrix(np.stack([a, b, np.zeros_like(a)], axis=-1))  # Rz(a) · Ry(b)
    rest = np.swapaxes(turned, -1, -2) @ r
    c = np.arctan2(rest[..., 2, 1] - rest[..., 1, 2], rest[..., 1, 1] + rest[..., 2, 2])
    return np.stack([a, b, c], axis=-1)


def rotation_error(r1: npt.ArrayLike, r2: npt.ArrayLike) -> np.ndarray:
    """Angle in radians of ``r1ᵀ r2``, accurate near zero (from ``‖r1 − r2‖_F = 2√2 sin(θ/2)``)."""
    diff = np.linalg.norm(np.asarray(r1) - np.asarray(r2), axis=(-2, -1))
    return 2.0 * np.arcsin(np.minimum(1.0, diff / (2.0 * math.sqrt(2.0))))


def rotation_onto(a: npt.ArrayLike, b: npt.ArrayLike) -> np.ndarray:
    """Smallest rotation taking unit vector ``a`` onto unit vector ``b``, quaternion (w, x, y, z), w ≥ 0.

    For opposite vectors (no unique smallest rotation) it is the half turn about ``a × e``, ``e`` the
    coordinate axis least aligned with ``a``.

    Args:
        a: Unit vector, shape (3,).
        b: Unit vector, shape (3,).

    Returns:
        Unit quaternion, shape (4,).
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    axis = np.cross(a, b)
    s, c = float(np.linalg.norm(axis)), float(np.dot(a, b))
    if s < _PARALLEL_SIN:
        if c > 0:
            return np.array([1.0, 0.0, 0.0, 0.0])
        axis = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
        return np.concatenate([[0.0], axis / np.linalg.norm(axis)])
    return axis_angle_to_quat(axis * (math.atan2(s, c) / s))


# --------------------------------------------------------------------------------------------------
# Interpolation


def slerp(q0: npt.ArrayLike, q1: npt.ArrayLike, w: npt.ArrayLike) -> np.ndarray:
    """Spherical linear interpolation of unit quaternions (w, x, y, z) along the shorter arc.

    Args:
        q0: Start quaternions, shape (..., 4); normalised first.
        q1: End quaternions, shape (..., 4); normalised first, and negated where ``q0 · q1 < 0`` (the
            same rotation in the hemisphere of ``q0``).
        w: Interpolation weights in [0, 1], shape (...): 0 gives ``q0``, 1 gives ``q1`` (as given,
            normalised, without the sign flip).

    Returns:
        Unit quaternions, shape (..., 4). Pairs closer than about 3.6° are interpolated linearly and
        normalised (slerp's formula loses precision there). A zero quaternion gives NaN.
    """
    with np.errstate(divide="ignore", invalid="ignore"):  # a zero quaternion gives NaN, not a warning
        a = np.asarray(q0, dtype=float)
        b = np.asarray(q1, dtype=float)
        a = a / np.linalg.norm(a, axis=-1, keepdims=True)
        b = b / np.linalg.norm(b, axis=-1, keepdims=True)
        return _slerp_unit(a, b, np.asarray(w, dtype=float))


def _slerp_unit(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """:func:`slerp` of normalised quaternions."""
    weights = np.broadcast_to(w, a.shape[:-1])[..., None]
    dot = np.sum(a * b, axis=-1, keepdims=True)
    b_near = np.where(dot < 0, -b, b)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin_theta = np.sin(theta)
    close = dot > _SLERP_LINEAR_DOT
    safe = np.where(close, 1.0, sin_theta)
    s0 = np.where(close, 1.0 - weights, np.sin((1.0 - weights) * theta) / safe)
    s1 = np.where(close, weights, np.sin(weights * theta) / safe)
    q = s0 * a + s1 * b_near
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(weights == 0, a, np.where(weights == 1, b, q))
