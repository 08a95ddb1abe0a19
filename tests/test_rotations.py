"""The rotation module against independent computations: MuJoCo's mju_* functions and explicit matrices."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from handsim.datatypes.rotations import (
    axis_angle_to_matrix,
    axis_angle_to_quat,
    matrix_to_quat,
    matrix_to_zyx,
    quat_about,
    quat_angle,
    quat_conjugate,
    quat_multiply,
    quat_rotate,
    quat_to_axis_angle,
    quat_to_matrix,
    rotation_about_axis,
    rotation_error,
    rotation_onto,
    slerp,
    zyx_to_matrix,
)

_RNG = np.random.default_rng(16)
_QUATS = _RNG.normal(size=(200, 4))
_QUATS /= np.linalg.norm(_QUATS, axis=1, keepdims=True)
_QUARTER_Z = np.array([math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)])  # 90° about +z
_QUARTER_Z_MATRIX = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def _mj_mat(q: np.ndarray) -> np.ndarray:
    out = np.empty(9)
    mujoco.mju_quat2Mat(out, np.ascontiguousarray(q, dtype=float))
    return out.reshape(3, 3)


def _mj_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.empty(4)
    mujoco.mju_mulQuat(out, np.ascontiguousarray(a), np.ascontiguousarray(b))
    return out


def _same_rotation(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Quaternions compared up to sign (q and −q are one rotation)."""
    return np.minimum(np.abs(q1 - q2).max(axis=-1), np.abs(q1 + q2).max(axis=-1))


def test_quaternions_are_scalar_first_as_in_mujoco() -> None:
    np.testing.assert_allclose(quat_to_matrix(_QUARTER_Z), _QUARTER_Z_MATRIX, atol=1e-15)
    np.testing.assert_allclose(_mj_mat(_QUARTER_Z), _QUARTER_Z_MATRIX, atol=1e-15)
    np.testing.assert_allclose(quat_rotate(_QUARTER_Z, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(matrix_to_quat(_QUARTER_Z_MATRIX), _QUARTER_Z, atol=1e-15)


def test_quat_to_matrix_matches_mju_quat2mat_and_broadcasts() -> None:
    expected = np.array([_mj_mat(q) for q in _QUATS])
    np.testing.assert_allclose(quat_to_matrix(_QUATS), expected, atol=1e-15)
    stacked = quat_to_matrix(_QUATS.reshape(20, 10, 4))
    assert stacked.shape == (20, 10, 3, 3)
    np.testing.assert_array_equal(stacked.reshape(200, 3, 3), quat_to_matrix(_QUATS))


def test_matrix_to_quat_inverts_mju_quat2mat_up_to_sign() -> None:
    matrices = np.array([_mj_mat(q) for q in _QUATS])
    assert _same_rotation(matrix_to_quat(matrices), _QUATS).max() < 1e-15


def test_quat_multiply_is_mju_mulquat_and_composes_matrices_left_after_right() -> None:
    a, b = _QUATS[:100], _QUATS[100:]
    product = quat_multiply(a, b)
    np.testing.assert_allclose(product, [_mj_mul(x, y) for x, y in zip(a, b, strict=True)], atol=1e-15)
    np.testing.assert_allclose(quat_to_matrix(product), quat_to_matrix(a) @ quat_to_matrix(b), atol=1e-14)
    # Not renormalised: the product of non-unit quaternions keeps the product of the norms.
    np.testing.assert_allclose(np.linalg.norm(quat_multiply(2 * a, 3 * b), axis=1), 6.0, rtol=1e-14)


def test_quat_rotate_and_conjugate_match_mujoco() -> None:
    v = _RNG.normal(size=(200, 3))
    expected = np.empty((200, 3))
    for i, (q, x) in enumerate(zip(_QUATS, v, strict=True)):
        mujoco.mju_rotVecQuat(expected[i], x, q)
    np.testing.assert_allclose(quat_rotate(_QUATS, v), expected, atol=1e-14)
    np.testing.assert_allclose(quat_rotate(quat_conjugate(_QUATS), quat_rotate(_QUATS, v)), v, atol=1e-14)


def test_axis_angle_to_quat_matches_mju_axisangle2quat_and_keeps_the_sign_past_half_turn() -> None:
    axes = _RNG.normal(size=(50, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = _RNG.uniform(-2 * math.pi, 2 * math.pi, size=50)
    expected = np.empty((50, 4))
    for i, (a, t) in enumerate(zip(axes, angles, strict=True)):
        mujoco.mju_axisAngle2Quat(expected[i], a, t)
    np.testing.assert_allclose(axis_angle_to_quat(axes * angles[:, None]), expected, atol=1e-15)
    about_first = np.empty((50, 4))
    for i, t in enumerate(angles):
        mujoco.mju_axisAngle2Quat(about_first[i], axes[0], t)
    np.testing.assert_allclose(quat_about(axes[0], angles), about_first, atol=1e-15)
    np.testing.assert_allclose(quat_about([0.0, 0.0, 1.0], math.pi / 2), _QUARTER_Z, atol=1e-16)
    assert quat_about([1.0, 0.0, 0.0], 1.5 * math.pi)[0] < 0  # cos(3π/4): no flip to w ≥ 0
    np.testing.assert_array_equal(axis_angle_to_quat(np.zeros(3)), [1.0, 0.0, 0.0, 0.0])


def test_quat_to_axis_angle_is_mju_quat2vel_of_the_shorter_rotation() -> None:
    expected = np.empty((200, 3))
    for i, q in enumerate(_QUATS):
        mujoco.mju_quat2Vel(expected[i], q * (1.0 if q[0] >= 0 else -1.0), 1.0)
    np.testing.assert_allclose(quat_to_axis_angle(_QUATS), expected, atol=1e-14)
    np.testing.assert_allclose(quat_to_axis_angle(-_QUATS), expected, atol=1e-14)
    assert np.linalg.norm(expected, axis=1).max() <= math.pi
    rotvec = _RNG.normal(size=(100, 3))
    rotvec *= (np.linalg.norm(rotvec, axis=1, keepdims=True) < math.pi) * 1.0
    np.testing.assert_allclose(quat_to_axis_angle(axis_angle_to_quat(rotvec)), rotvec, atol=1e-14)


def test_axis_angle_to_matrix_is_rodrigues_formula() -> None:
    rotvec = _RNG.normal(scale=1.5, size=(100, 3))
    theta = np.linalg.norm(rotvec, axis=1)
    k = np.zeros((100, 3, 3))
    u = rotvec / theta[:, None]
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -u[:, 2], u[:, 1], -u[:, 0]
    k -= np.swapaxes(k, 1, 2)
    expected = np.eye(3) + np.sin(theta)[:, None, None] * k + (1 - np.cos(theta))[:, None, None] * (k @ k)
    np.testing.assert_allclose(axis_angle_to_matrix(rotvec), expected, atol=1e-14)
    quarter = rotation_about_axis([0.0, 0.0, 1.0], math.pi / 2)
    np.testing.assert_allclose(quarter, _QUARTER_Z_MATRIX, atol=1e-15)
    assert rotation_about_axis([1.0, 0.0, 0.0], np.zeros((4, 5))).shape == (4, 5, 3, 3)


def test_zyx_angles_are_intrinsic_z_then_y_then_x_as_mju_euler2quat() -> None:
    angles = _RNG.uniform(-3.0, 3.0, size=(100, 3))
    expected = np.empty((100, 4))
    for i, e in enumerate(angles):
        mujoco.mju_euler2Quat(expected[i], e, "zyx")  # lower case: intrinsic (axes turn with the frame)
    np.testing.assert_allclose(zyx_to_matrix(angles), quat_to_matrix(expected), atol=1e-14)
    a, b, c = 0.3, -0.4, 1.1
    rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rx = np.array([[1, 0, 0], [0, math.cos(c), -math.sin(c)], [0, math.sin(c), math.cos(c)]])
    np.testing.assert_allclose(zyx_to_matrix([a, b, c]), rz @ ry @ rx, atol=1e-15)
    np.testing.assert_allclose(matrix_to_zyx(rz @ ry @ rx), [a, b, c], atol=1e-14)


def test_quat_angle_and_rotation_error_measure_the_same_angle() -> None:
    a, b = _QUATS[:100], _QUATS[100:]
    expected = np.linalg.norm(quat_to_axis_angle(quat_multiply(quat_conjugate(a), b)), axis=1)
    np.testing.assert_allclose(quat_angle(a, b), expected, atol=1e-7)  # arccos near 0 and π: ~1e-8
    np.testing.assert_allclose(rotation_error(quat_to_matrix(a), quat_to_matrix(b)), expected, atol=1e-12)
    assert quat_angle(_QUARTER_Z, -_QUARTER_Z) == 0.0


@pytest.mark.parametrize(
    ("a", "b"),
    [
        ([0.0, 0.0, 1.0], [0.0, 0.0, -1.0]),  # opposite: a half turn
        ([0.0, 1.0, 0.0], [0.0, 0.0, -1.0]),
        ([0.6, 0.0, 0.8], [0.6, 0.0, 0.8]),  # equal: the identity
        ([0.48, 0.6, 0.64], [0.0, 0.0, -1.0]),
    ],
)
def test_rotation_onto_takes_a_onto_b_by_the_smallest_angle(a: list[float], b: list[float]) -> None:
    q = rotation_onto(a, b)
    np.testing.assert_allclose(quat_rotate(q, a), b, atol=1e-15)
    expected_angle = math.acos(float(np.clip(np.dot(a, b), -1.0, 1.0)))
    assert quat_angle([1.0, 0.0, 0.0, 0.0], q) == pytest.approx(expected_angle, abs=1e-7)
    assert q[0] >= 0.0


def test_slerp_follows_the_geodesic_of_mju_subquat_and_quatintegrate() -> None:
    a, b = _QUATS[:100], _QUATS[100:]
    w = _RNG.uniform(size=100)
    expected = np.empty((100, 4))
    for i in range(100):
        near = b[i] if a[i] @ b[i] >= 0 else -b[i]
        velocity = np.empty(3)
        mujoco.mju_subQuat(velocity, near, a[i])  # a ⊗ exp(velocity) = near
        expected[i] = a[i]
        mujoco.mju_quatIntegrate(expected[i], velocity, w[i])
    assert _same_rotation(slerp(a, b, w), expected).max() < 1e-14
