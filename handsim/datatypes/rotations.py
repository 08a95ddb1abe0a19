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
  where this one is exact to rounding (< 1e-14 rad) everywhere. :func:`continuous_zyx` chooses, frame by
  frame, among the exact solutions the one nearest the previous frame's (scipy has no such choice).
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
        Angles in radians, shape (..., 3): a, c in [−π, π], b in [−π/2, π/2]; a = 0 at gimbal lock.
    """
    r = np.asarray(rotation, dtype=float)
    cos_b = np.hypot(r[..., 0, 0], r[..., 1, 0])
    b = np.arctan2(-r[..., 2, 0], cos_b)
    a = np.where(cos_b > _GIMBAL_COS, np.arctan2(r[..., 1, 0], r[..., 0, 0]), 0.0)
    return np.stack([a, b, _zyx_third(r, a, b)], axis=-1)


def _zyx_third(r: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The x angle ``c`` of ``R`` given ``a`` and ``b``: the angle of the remainder ``Ry(b)ᵀ Rz(a)ᵀ R``."""
    turned = zyx_to_matrix(np.stack([a, b, np.zeros_like(a)], axis=-1))  # Rz(a) · Ry(b)
    rest = np.swapaxes(turned, -1, -2) @ r
    return np.arctan2(rest[..., 2, 1] - rest[..., 1, 2], rest[..., 1, 1] + rest[..., 2, 2])


def zyx_alternative(angles: npt.ArrayLike) -> np.ndarray:
    """The other Z·Y·X solution of the same rotation: ``(a + π, π − b, c + π)``, shape (..., 3).

    ``Rz(a + π) Ry(π − b) Rx(c + π) = Rz(a) Ry(b) Rx(c)`` exactly. Away from gimbal lock every solution is
    one of these two plus whole turns of each angle; at lock (cos b = 0) they coincide and only
    ``a − c`` (b = π/2) or ``a + c`` (b = −π/2) is defined.
    """
    x = np.asarray(angles, dtype=float)
    return np.stack([x[..., 0] + math.pi, math.pi - x[..., 1], x[..., 2] + math.pi], axis=-1)


def wrap_angle(x: npt.ArrayLike) -> np.ndarray:
    """Angles in radians moved by whole turns into [−π, π)."""
    return (np.asarray(x, dtype=float) + math.pi) % (2.0 * math.pi) - math.pi


def continuous_zyx(rotation: npt.ArrayLike) -> np.ndarray:
    """Z·Y·X angles of rotations over time, continuous in time: each frame's solution nearest the last.

    :func:`matrix_to_zyx` returns each rotation's principal angles, which jump by a turn where an angle
    crosses ±π and flip to the other solution (:func:`zyx_alternative`) where the path passes near
    b = ±π/2. Here every frame after the first takes, among all exact solutions (both families, any whole
    turns of each angle), the one whose largest angle change from the previous frame's is smallest. At
    gimbal lock only ``a ∓ c`` is defined: ``a`` and ``c`` then share the change evenly, towards the middle
    of the neighbouring frames' solutions (a path through the lock keeps its own pace). Each column is
    finally moved as a whole by the solutions' symmetries (whole turns; the other family where the
    middle of the y angle's range lies beyond ±π/2) so that the middle of its range lies nearest zero: y
    in [−π/2, π/2], z and x in [−π, π].

    The change this gives between frames is bounded by the recorded rotation's (proof and measurements in
    ``docs/mano.md``): with φ the angle of the rotation from one frame to the next and
    ``β = (|b₀| + |b₁| + φ) / 2`` (principal y angles of both frames), every angle changes by at most
    ``φ / cos β`` when β < π/2, and by at most π always.

    Args:
        rotation: Rotation matrices, shape (T, ..., 3, 3); axis 0 is time.

    Returns:
        Angles (a, b, c) in radians, shape (T, ..., 3), with ``Rz(a) Ry(b) Rx(c)`` equal to each rotation to
        rounding.

    Raises:
        ValueError: ``rotation`` is not of shape (T, ..., 3, 3).
    """
    r = np.asarray(rotation, dtype=float)
    if r.ndim < 3 or r.shape[-2:] != (3, 3):
        raise ValueError(f"expected rotation matrices of shape (T, ..., 3, 3), got {r.shape}")
    n = r.shape[0]
    if n == 0:
        return np.zeros((*r.shape[:-2], 3))
    flat_r = r.reshape(n, -1, 3, 3)
    angles = matrix_to_zyx(flat_r)
    locked = np.hypot(flat_r[..., 0, 0], flat_r[..., 1, 0]) <= _GIMBAL_COS
    for k in np.flatnonzero(locked[0] & ~locked[min(1, n - 1)]):  # a first frame at lock: towards the next
        angles[0, k] = _locked_nearest(flat_r[0, k], angles[0, k], angles[1, k])
    for t, k in zip(*np.nonzero(locked[1:]), strict=True):  # frame order: each after the one it follows
        before = angles[t, k]
        if t + 2 < n and not locked[t + 2, k]:  # aim between the frames either side (the path's own way)
            after = _nearest_solution(angles[t + 2, k], before)
            before = before + wrap_angle(after - before) / 2.0
        angles[t + 1, k] = _locked_nearest(flat_r[t + 1, k], angles[t + 1, k], before)
    same_step, cross_step = _steps(angles[1:], angles[:-1])
    # the steps between two frames are the same whichever family the previous frame took (the map is an
    # isometry of the wrapped angles), so each frame switches family where the other one is nearer
    flip = np.concatenate([np.zeros((1, angles.shape[1]), dtype=bool), cross_step < same_step])
    family = np.cumsum(flip, axis=0) % 2 == 1
    lifted = np.unwrap(np.where(family[..., None], zyx_alternative(angles), angles), axis=0)
    return _centred(lifted).reshape((*r.shape[:-2], 3))


def _steps(angles: np.ndarray, previous: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Largest wrapped change over the three angles from ``previous``: of ``angles``, of the other family."""
    same = np.abs(wrap_angle(angles - previous)).max(axis=-1)
    return same, np.abs(wrap_angle(zyx_alternative(angles) - previous)).max(axis=-1)


def _nearest_solution(angles: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """``angles`` (3,) or their other family, whichever changes least from ``previous`` (:func:`_steps`)."""
    same, cross = _steps(angles, previous)
    return zyx_alternative(angles) if cross < same else angles


def _locked_nearest(r: np.ndarray, angles: np.ndarray, near: np.ndarray) -> np.ndarray:
    """A rotation at gimbal lock as the angles nearest ``near``: ``a`` and ``c`` share the change."""
    a, b, c = angles
    a0, _, c0 = near
    sign = 1.0 if b > 0 else -1.0  # b = π/2: R depends on a − c; b = −π/2: on a + c
    delta = float(wrap_angle(a0 - sign * c0 - (a - sign * c)))
    a_near = a0 - delta / 2.0
    return np.array([a_near, b, float(_zyx_third(r, np.array(a_near), np.array(b)))])


def _centred(angles: np.ndarray) -> np.ndarray:
    """Each column (T, K, 3) moved by Z·Y·X symmetries so that the middle of its range is nearest zero."""
    out = angles.copy()
    turn = 2.0 * math.pi
    middle = (out.min(axis=0) + out.max(axis=0)) / 2.0
    out[..., 1] -= turn * np.round(middle[:, 1] / turn)
    middle_b = middle[:, 1] - turn * np.round(middle[:, 1] / turn)
    other = np.abs(middle_b) > math.pi / 2.0  # reflect about ±π/2: the other family
    out[..., 1] = np.where(other, np.sign(middle_b) * math.pi - out[..., 1], out[..., 1])
    out[..., 0] += np.where(other, math.pi, 0.0)
    out[..., 2] += np.where(other, math.pi, 0.0)
    middle_ac = (out[..., ::2].min(axis=0) + out[..., ::2].max(axis=0)) / 2.0
    out[..., ::2] -= turn * np.round(middle_ac / turn)
    return out


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
