"""Z·Y·X angles continuous in time (``continuous_zyx``), against independent rotations from scipy.

The bound pinned here (proof in docs/mano.md): between two frames whose rotations differ by the angle φ, every
angle changes by at most ``φ / cos β`` with ``β = (|b₀| + |b₁| + φ) / 2`` (b the principal y angles) when
β < π/2, and by at most π always. "At most φ" is not achievable away from y = 0 (pinned too).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handsim.datatypes.rotations import continuous_zyx, matrix_to_zyx, zyx_alternative

TOLERANCE = 1e-9
"""Rotation error of a target, and slack of a step bound, radians."""


def euler_matrices(angles: np.ndarray) -> np.ndarray:
    """``Rz(a) Ry(b) Rx(c)`` by scipy (intrinsic ``"ZYX"``), shape (..., 3, 3)."""
    flat = np.asarray(angles, dtype=float).reshape(-1, 3)
    return Rotation.from_euler("ZYX", flat).as_matrix().reshape((*np.shape(angles)[:-1], 3, 3))


def angle_between(r0: np.ndarray, r1: np.ndarray) -> np.ndarray:
    """Angle of ``r0ᵀ r1`` by scipy, radians, shape (...)."""
    a = Rotation.from_matrix(np.reshape(r0, (-1, 3, 3)))
    b = Rotation.from_matrix(np.reshape(r1, (-1, 3, 3)))
    return (a.inv() * b).magnitude().reshape(np.shape(r0)[:-2])


def step_bound(rotations: np.ndarray) -> np.ndarray:
    """The largest hinge change the bound allows between consecutive frames (T − 1, ...), radians.

    φ: the recorded rotation between the frames; b: each frame's principal y angle, −asin(R[2, 0]).
    """
    r = np.asarray(rotations, dtype=float)
    phi = angle_between(r[:-1], r[1:])
    b = np.abs(np.arcsin(np.clip(-r[..., 2, 0], -1.0, 1.0)))
    beta = (b[:-1] + b[1:] + phi) / 2.0
    with np.errstate(divide="ignore"):
        bound = np.where(beta < math.pi / 2, phi / np.cos(np.minimum(beta, math.pi / 2)), math.pi)
    return np.minimum(bound, math.pi)


def hinge_steps(angles: np.ndarray) -> np.ndarray:
    """The largest change over the three angles between consecutive frames (T − 1, ...), radians."""
    return np.abs(np.diff(np.asarray(angles, dtype=float), axis=0)).max(axis=-1)


def smooth_rotations(n: int, seed: int, speed: float = 0.05) -> np.ndarray:
    """A rotation path (n, 3, 3): a random start turned by a smoothly varying angular velocity per frame."""
    rng = np.random.default_rng(seed)
    velocity = np.cumsum(rng.normal(scale=speed / 3, size=(n, 3)), axis=0)
    velocity *= speed / max(1e-12, float(np.linalg.norm(velocity, axis=1).max()))
    frames = [Rotation.from_rotvec(rng.normal(size=3) * 1.5)]
    for k in range(1, n):
        frames.append(Rotation.from_rotvec(velocity[k]) * frames[-1])
    return np.array([f.as_matrix() for f in frames])


@pytest.mark.parametrize(
    ("start", "stop"),
    [
        ((170.0, 80.0, -30.0), (190.0, 100.0, 10.0)),  # z crosses 180°, y passes +90°
        ((-150.0, -70.0, 160.0), (-210.0, -110.0, 200.0)),  # z crosses −180°, y −90°, x 180°
    ],
)
def test_angles_crossing_180_and_passing_y_90_follow_the_path_without_a_turn_or_flip(start, stop):
    path = np.radians(np.linspace(start, stop, 61))  # frame 30 is exactly at y = ±90°
    rotations = euler_matrices(path)
    angles = continuous_zyx(rotations)
    assert angle_between(euler_matrices(angles), rotations).max() <= TOLERANCE
    steps = hinge_steps(angles)
    assert steps.max() <= hinge_steps(path).max() + TOLERANCE  # the path's own pace, 0.67° per frame
    assert np.all(steps <= step_bound(rotations) + TOLERANCE)
    principal = matrix_to_zyx(rotations)
    assert hinge_steps(principal).max() > math.radians(170.0)  # what continuity removes: a turn or a flip


@pytest.mark.parametrize("seed", range(12))
def test_steps_stay_within_the_bound_of_the_recorded_rotation_on_smooth_paths(seed):
    rotations = smooth_rotations(400, seed, speed=0.05 + 0.02 * seed)
    angles = continuous_zyx(rotations)
    assert angle_between(euler_matrices(angles), rotations).max() <= TOLERANCE
    assert np.all(hinge_steps(angles) <= step_bound(rotations) + TOLERANCE)


def test_no_solution_keeps_every_hinge_step_within_the_recorded_rotation_away_from_y_zero():
    # at y = 45°, turning by φ about (1, 0, 1)/√2 in the frame after Rz(a) moves z by √2·φ in every solution
    phi = 1e-3
    a, b, c = 0.3, math.pi / 4, -0.2
    r0 = euler_matrices(np.array([a, b, c]))
    turn = Rotation.from_rotvec(phi * np.array([1.0, 0.0, 1.0]) / math.sqrt(2.0)).as_matrix()
    rz = euler_matrices(np.array([a, 0.0, 0.0]))
    r1 = rz @ turn @ rz.T @ r0
    assert angle_between(r0, r1) == pytest.approx(phi, rel=1e-9)
    angles = continuous_zyx(np.stack([r0, r1]))
    wrapped = [np.angle(np.exp(1j * (s - angles[0]))) for s in (angles[1], zyx_alternative(angles[1]))]
    least = min(float(np.abs(w).max()) for w in wrapped)  # over both families and any whole turns
    assert least > 1.4 * phi  # every exact solution moves a hinge by more than the rotation turned
    assert hinge_steps(angles)[0] == pytest.approx(least, rel=1e-9)  # continuous_zyx takes the least
    assert hinge_steps(angles)[0] <= step_bound(np.stack([r0, r1]))[0] + TOLERANCE


def test_a_first_frame_at_gimbal_lock_is_solved_towards_the_next_frame():
    path = np.array([[0.3, math.pi / 2, 1.0], [0.32, math.pi / 2 - 0.01, 1.01]])
    rotations = euler_matrices(path)
    angles = continuous_zyx(rotations)
    assert angle_between(euler_matrices(angles), rotations).max() <= TOLERANCE
    np.testing.assert_allclose(angles[1], path[1], atol=1e-9)
    assert hinge_steps(angles)[0] <= hinge_steps(path)[0] + TOLERANCE


def test_each_column_is_centred_by_whole_turns_and_the_other_family():
    # z runs 170° → 250° and y 70° → 130°: y's middle (100°) is beyond 90°, so the other family
    # (z + 180°, 180° − y, x + 180°), then whole turns bring z's middle (390°) and x's (210°) nearest zero
    path = np.radians(np.linspace([170.0, 70.0, 20.0], [250.0, 130.0, 40.0], 41))
    rotations = euler_matrices(path)
    angles = continuous_zyx(rotations)
    assert angle_between(euler_matrices(angles), rotations).max() <= TOLERANCE
    middle = (angles.min(axis=0) + angles.max(axis=0)) / 2
    assert -math.pi <= middle[0] <= math.pi and -math.pi <= middle[2] <= math.pi
    assert -math.pi / 2 <= middle[1] <= math.pi / 2
    np.testing.assert_allclose(np.degrees(middle), [30.0, 80.0, -150.0], atol=1e-9)


def test_continuous_zyx_keeps_leading_axes_and_refuses_other_shapes():
    rotations = np.stack([smooth_rotations(5, seed) for seed in range(4)], axis=1)  # (5, 4, 3, 3)
    assert continuous_zyx(rotations).shape == (5, 4, 3)
    assert continuous_zyx(np.zeros((0, 2, 3, 3))).shape == (0, 2, 3)
    with pytest.raises(ValueError) as err:
        continuous_zyx(np.eye(3))
    assert str(err.value) == "expected rotation matrices of shape (T, ..., 3, 3), got (3, 3)"
