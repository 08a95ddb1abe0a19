"""Forward kinematics pinned to the GraspDB14 MATLAB tools' output (the FK oracle in ../shared)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
import scipy.io

from handsim.builders import build_hand
from handsim.io import read_skeleton, read_trajectory
from handsim.sim import compile_spec
from tests.helpers import set_pose, site_positions

ORACLES = ["01_11_ex03-rad-004-grasp-su04.txt", "16_14_ex01-rad-004-grasp-su06"]
TOLERANCE_MM = 0.1


def _oracle(graspdb_dir, name):
    mot = scipy.io.loadmat(
        graspdb_dir / "fk_oracle" / f"{name}_w_traj.mat", squeeze_me=True, struct_as_record=False
    )["motion"]
    truth_mm = np.stack([np.asarray(t, dtype=float).T for t in mot.jointtrajectories], axis=1)
    return mot, truth_mm  # truth: (T, 25 joints, 3) in mm, joint ids 1..25 = skeleton order


@pytest.fixture(scope="module")
def skeleton():
    from tests.conftest import GRASPDB

    if not GRASPDB.exists():
        pytest.skip("needs ../shared/data/graspdb14 (present in CI, not in a user's clone)")
    return read_skeleton(GRASPDB / "default.xmlskel")


@pytest.mark.parametrize("name", ORACLES)
def test_glove_file_equals_oracle_angledata(graspdb_dir, skeleton, name):
    mot, _ = _oracle(graspdb_dir, name)
    traj = read_trajectory(graspdb_dir / "fk_oracle" / name)
    assert traj.nframes == mot.angledata.shape[0]
    sensor_names = [str(s) for s in mot.sensornames]
    np.testing.assert_array_equal(traj.column("if_pip_flex"), -mot.angledata[:, sensor_names.index("I-PIPJ")])


@pytest.mark.parametrize("name", ORACLES)
def test_numpy_fk_reproduces_oracle_joint_trajectories(graspdb_dir, skeleton, name):
    _, truth_mm = _oracle(graspdb_dir, name)
    traj = read_trajectory(graspdb_dir / "fk_oracle" / name, skeleton=skeleton)
    assert traj.dof_names == skeleton.dof_names
    positions_mm = skeleton.forward_kinematics(traj.targets).positions * 1000.0
    error = np.abs(positions_mm - truth_mm).max()
    assert error <= TOLERANCE_MM
    assert error < 1e-9  # the conventions are exact, not merely close


@pytest.mark.parametrize("name", ORACLES)
def test_mujoco_fk_reproduces_oracle_joint_trajectories(graspdb_dir, skeleton, name):
    _, truth_mm = _oracle(graspdb_dir, name)
    traj = read_trajectory(graspdb_dir / "fk_oracle" / name, skeleton=skeleton)
    model = compile_spec(build_hand(skeleton))
    data = mujoco.MjData(model)
    worst = 0.0
    for q, truth in zip(traj.targets, truth_mm, strict=True):
        set_pose(model, data, skeleton, q)
        worst = max(worst, float(np.abs(site_positions(model, data, skeleton) * 1000.0 - truth).max()))
    assert worst <= TOLERANCE_MM
    assert worst < 1e-9


def test_oracle_frames_are_joint_frames_before_their_own_dofs_rotate(graspdb_dir, skeleton):
    # The MATLAB tools rotate a joint's subtree about the joint's axes but leave the joint's own frame
    # alone, so its stored frame is the parent's frame times the rest offset: R_p · F_pᵀ F_j. This is
    # why, with two DoFs in one joint, abduction (applied second, about the unrotated z) is outermost.
    mot, _ = _oracle(graspdb_dir, ORACLES[0])
    traj = read_trajectory(graspdb_dir / "fk_oracle" / ORACLES[0], skeleton=skeleton)
    frames = skeleton.forward_kinematics(traj.targets[:50]).frames
    cs = mot.localcoordinatesystems  # (25, T) cells of 3x3, columns = local axes
    for j, joint in enumerate(skeleton.joints):
        for t in range(50):
            if joint.parent < 0:
                expected = joint.frame
            else:
                parent = skeleton.joints[joint.parent]
                expected = frames[t, joint.parent] @ parent.frame.T @ joint.frame
            np.testing.assert_allclose(expected, np.asarray(cs[j, t], dtype=float), atol=1e-12)
