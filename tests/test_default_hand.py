"""The parametric default hand: proportions, sizes, GraspDB14 compatibility."""

from __future__ import annotations

import numpy as np
import pytest

from handsim.builders import default_hand, default_skeleton
from handsim.errors import SkeletonError
from handsim.io import read_skeleton, read_trajectory
from handsim.io.graspdb.default_skeleton import SEGMENT_RATIOS
from handsim.sim import compile_spec


@pytest.mark.parametrize("length", [0.16, 0.19, 0.22])
def test_default_hand_middle_finger_reaches_the_hand_length(length):
    skeleton = default_skeleton(length)
    tip = skeleton.joints[skeleton.joint_index("mf-tip")].position
    assert np.linalg.norm(tip) == pytest.approx(length, rel=1e-12)


def test_default_hand_segments_follow_buchholz_ratios():
    length = 0.2
    skeleton = default_skeleton(length)
    for finger, ratios in SEGMENT_RATIOS.items():
        names = ["tmc", "mcp", "ip", "tip"] if finger == "th" else ["cmc", "mcp", "pip", "dip", "tip"]
        for k, ratio in enumerate(ratios):
            child = skeleton.joint_index(f"{finger}-{names[k + 1]}")
            assert skeleton.bone_length(child) == pytest.approx(ratio * length, rel=1e-12)


def test_default_hand_has_graspdb_joint_names_and_dofs(graspdb_dir):
    graspdb = read_skeleton(graspdb_dir / "default.xmlskel")
    skeleton = default_skeleton()
    assert skeleton.joint_names == graspdb.joint_names
    assert skeleton.dof_names == graspdb.dof_names
    for ours, theirs in zip(skeleton.dofs, graspdb.dofs, strict=True):
        np.testing.assert_array_equal(ours.axis, theirs.axis)


def test_glove_recording_drives_the_default_hand_directly(graspdb_dir):
    skeleton = default_skeleton()
    traj = read_trajectory(graspdb_dir / "r_01_11_ex03-rad-004-grasp-su04.txt", skeleton=skeleton)
    assert traj.dof_names == skeleton.dof_names
    positions = skeleton.forward_kinematics(traj.targets).positions
    assert np.all(np.isfinite(positions))


def test_default_hand_mass_and_size_scale_with_length():
    small = compile_spec(default_hand(0.16))
    large = compile_spec(default_hand(0.22))
    ratio = float(large.body_subtreemass[0]) / float(small.body_subtreemass[0])
    assert ratio == pytest.approx((0.22 / 0.16) ** 3)


@pytest.mark.parametrize(
    ("length", "breadth", "message"),
    [
        (190.0, None, r"hand length 190.0 m is outside 0.08–0.30 m \(is it in mm\?\)"),
        (0.19, 0.01, r"hand breadth 0.01 m is implausible for a 0.19 m long hand"),
    ],
)
def test_default_skeleton_raises_error_if_size_is_implausible(length, breadth, message):
    with pytest.raises(SkeletonError, match=message):
        default_skeleton(length, breadth)
