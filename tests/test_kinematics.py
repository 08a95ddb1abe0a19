"""Tests of the rotation-chain solver (handsim.datatypes.kinematics)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from handsim.datatypes.kinematics import fit_dof_angles
from handsim.datatypes.rotations import rotation_about_axis


def _axes(rotvec: list[float], n: int) -> np.ndarray:
    return Rotation.from_rotvec(rotvec).as_matrix().T[:n]  # rows: an orthonormal triad, randomly turned


def _chain(axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    out = np.eye(3)
    for a, q in zip(axes, angles, strict=True):
        out = out @ rotation_about_axis(a, q)
    return out


rotvecs = st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3)


@settings(max_examples=60, deadline=None)
@given(rotvecs, st.integers(1, 3), st.lists(st.floats(-1.4, 1.4), min_size=3, max_size=3), st.booleans())
def test_fit_dof_angles_recovers_the_angles_of_an_exact_chain(rotvec, n, angles, flip) -> None:
    axes = _axes(rotvec, n)
    if flip:
        axes = -axes  # left- and right-handed axis sets alike
    truth = np.array(angles[:n])
    found, residual = fit_dof_angles(_chain(axes, truth)[None], axes)
    np.testing.assert_allclose(found[0], truth, atol=1e-6)
    assert residual[0] < 1e-7


@settings(max_examples=40, deadline=None)
@given(rotvecs, rotvecs, st.integers(1, 2))
def test_fit_dof_angles_minimises_the_residual_angle(rotvec, target, n) -> None:
    axes = _axes(rotvec, n) if n == 1 else np.array([[0.0, 0.0, 1.0], _axes(rotvec, 1)[0]])
    axes[-1] /= np.linalg.norm(axes[-1])
    rotation = Rotation.from_rotvec(target).as_matrix()
    found, residual = fit_dof_angles(rotation[None], axes)
    for i in range(n):
        for step in (-1e-3, 1e-3):
            moved = found[0].copy()
            moved[i] += step
            angle = Rotation.from_matrix(_chain(axes, moved).T @ rotation).magnitude()
            assert angle >= residual[0] - 1e-9


def test_fit_dof_angles_without_axes_reports_the_whole_rotation() -> None:
    rotation = rotation_about_axis([0.0, 0.0, 1.0], 0.25)[None]
    angles, residual = fit_dof_angles(rotation, np.zeros((0, 3)))
    assert angles.shape == (1, 0)
    np.testing.assert_allclose(residual, [0.25])


def test_fit_dof_angles_refuses_four_axes() -> None:
    with pytest.raises(ValueError, match=re.escape("at most 3 axes can be fitted, got 4")):
        fit_dof_angles(np.eye(3)[None], np.eye(4, 3))
