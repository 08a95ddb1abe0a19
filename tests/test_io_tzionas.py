"""Tests of the Tzionas/Ballan reader (handsim.io.tzionas.skeleton)."""

from __future__ import annotations

import math
import re
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from handsim.errors import FormatError, InputFileError
from handsim.io.off import read_off
from handsim.io.tzionas.motion_file import read_motion
from handsim.io.tzionas.skel import read_limits, read_skel
from handsim.io.tzionas.skeleton import read_tzionas_skeleton
from handsim.io.tzionas.surface import read_skin, read_voi

HAND_BONES = 20
HAND_DOFS = 31  # rx + ry + rz flags of the 19 non-root bones of Model_Hand_R.LIMITS, counted by hand


def where(path: Path, line: int, field: str) -> str:
    """The ``file:line [field]`` prefix of a FormatError message, as a regex."""
    return re.escape(f"{path}:{line} [{field}]")


# --------------------------------------------------------------------------------------------------
# Real data


@pytest.fixture
def hand_skel(tzionas_dir: Path) -> Path:
    return tzionas_dir / "Models" / "20" / "Model_Hand_R.SKEL"


@pytest.fixture
def hand(hand_skel: Path):
    return read_tzionas_skeleton(hand_skel)


def parse_motion_row0(path: Path, nframes: int) -> dict[str, np.ndarray]:
    """Row 0 of every bone of a MOTION file, parsed independently of the reader (mm)."""
    lines = [s.strip() for s in path.read_text().splitlines() if s.strip()]
    out = {}
    for k in range(0, len(lines), nframes + 1):
        out[lines[k]] = np.array(lines[k + 1].split(), dtype=float)
    return out


def test_hand_has_20_bones_plus_5_tip_joints(hand) -> None:
    assert hand.njoints == HAND_BONES + 5
    assert hand.joints[0].name == "Lower Arm R"
    assert hand.joints[0].parent == -1
    assert sum(j.name.endswith("_tip") for j in hand.joints) == 5


def test_hand_dof_count_equals_rotation_flags_of_non_root_bones(hand, hand_skel: Path) -> None:
    blocks = hand_skel.with_suffix(".LIMITS").read_text().strip().split("\n\n")
    counted = 0
    for block in blocks:
        name, flags = block.splitlines()[:2]
        if name.strip() != "Lower Arm R":
            counted += sum(int(f) for f in flags.split()[1:])
    assert counted == HAND_DOFS
    assert hand.ndof == HAND_DOFS
    assert hand.dofs_of("Lower Arm R") == []
    assert [d.kind for d in hand.dofs_of("RFing.0_0")] == ["abd", "flex", "pron"]


def test_hand_dof_axes_and_limits_follow_limits_file(hand) -> None:
    dof = hand.dofs[hand.dof_index("RFing_0_1_flex")]
    axis = np.array([6.18992e-08, -0.0899474, 0.995948])
    np.testing.assert_allclose(dof.axis, axis / np.linalg.norm(axis), atol=1e-12)
    assert dof.lower == pytest.approx(math.radians(-95))
    assert dof.upper == pytest.approx(math.radians(10))
    assert dof.joint == "RFing.0_1"


def test_hand_rest_pose_equals_motion_row_0(hand, hand_skel: Path) -> None:
    row0 = parse_motion_row0(hand_skel.with_suffix(".MOTION"), 187)
    assert len(row0) == HAND_BONES
    worst_pos, worst_frame = 0.0, 0.0
    for name, row in row0.items():
        joint = hand.joints[hand.joint_index(name)]
        worst_pos = max(worst_pos, float(np.abs(joint.position * 1e3 - row[9:]).max()))
        worst_frame = max(worst_frame, float(np.abs(joint.frame - row[:9].reshape(3, 3)).max()))
    assert worst_pos <= 0.01  # mm
    assert worst_frame <= 1e-5


def test_hand_tip_joints_sit_at_bone_length_along_local_x(hand) -> None:
    tip = hand.joints[hand.joint_index("RFing.2_2_tip")]
    bone = hand.joints[tip.parent]
    assert bone.name == "RFing.2_2"
    np.testing.assert_allclose(tip.position, bone.position + 22.2019e-3 * bone.frame[:, 0], atol=1e-12)


def test_hand_fingertips_are_ordered_thumb_index_middle_ring_little(hand) -> None:
    assert hand.fingertips == (
        "RFing.4_1_tip",
        "RFing.3_2_tip",
        "RFing.2_2_tip",
        "RFing.1_2_tip",
        "RFing.0_2_tip",
    )


def test_hand_skin_has_one_row_per_vertex(hand) -> None:
    assert hand.mesh is not None
    assert hand.mesh.vertices.shape == (10002, 3)
    assert hand.mesh.weights.shape == (10002, HAND_BONES)
    assert hand.mesh.faces.shape == (20000, 3)
    assert hand.mesh.bones[0] == "Lower Arm R"
    np.testing.assert_allclose(hand.mesh.weights.sum(axis=1), 1.0, atol=1e-3)


def test_hand_mesh_bounds_are_plausible_in_metres(hand) -> None:
    extent = hand.mesh.vertices.max(axis=0) - hand.mesh.vertices.min(axis=0)
    assert 0.1 < extent.max() < 0.3
    assert 0.05 < extent.min()


def test_hand_fingertip_vertices_are_near_their_fingertips(hand) -> None:
    assert hand.fingertip_vertices[0] == (7065, 8067, 8719)  # thumb: 5th id of each VOI group
    assert hand.fingertip_vertices[4] == (7769, 5764, 5585)  # little: 1st id of each VOI group
    for tip, ids in zip(hand.fingertips, hand.fingertip_vertices, strict=True):
        tip_pos = hand.rest_positions[hand.joint_index(tip)]
        assert np.linalg.norm(hand.mesh.vertices[list(ids)] - tip_pos, axis=1).max() < 0.015
    assert any("confirmed by SKIN weights" in n for n in hand.notes)


def test_hand_forward_kinematics_at_zero_pose_returns_rest_positions(hand) -> None:
    fk = hand.forward_kinematics(hand.zero_pose())
    np.testing.assert_allclose(fk.positions, hand.rest_positions, atol=1e-12)


def test_hand_notes_record_root_pose_and_reorthonormalisation(hand) -> None:
    assert any("root bone 'Lower Arm R'" in n for n in hand.notes)
    assert any("re-orthonormalised" in n for n in hand.notes)


def test_read_motion_returns_metres_and_all_frames(hand_skel: Path) -> None:
    motion = read_motion(hand_skel.with_suffix(".MOTION"), expected_frames=187)
    rot, trans = motion["RFing.0_1"]
    assert rot.shape == (187, 3, 3)
    assert trans.shape == (187, 3)
    assert np.abs(trans).max() < 1.0


def test_cube_reads_as_one_bone_without_dofs(tzionas_dir: Path) -> None:
    cube = read_tzionas_skeleton(tzionas_dir / "Models" / "20" / "Model_Object_Cube.SKEL")
    assert cube.joint_names == ("Bone001", "Bone001_tip")
    assert cube.ndof == 0
    extent = cube.mesh.vertices.max(axis=0) - cube.mesh.vertices.min(axis=0)
    np.testing.assert_allclose(extent, 0.053, atol=1e-3)


def test_pipe_has_two_bones_and_one_dof_of_170_degrees(tzionas_dir: Path) -> None:
    pipe = read_tzionas_skeleton(tzionas_dir / "Models" / "17" / "Model_Object_Pipe_Gray.SKEL")
    assert pipe.joint_names == ("Bone001", "Bone002", "Bone002_tip")
    assert pipe.dof_names == ("Bone002_flex",)
    assert pipe.limits[0] == pytest.approx([-math.radians(170), math.radians(170)])
    np.testing.assert_allclose(pipe.dofs[0].axis, [0, 1, 0])
    assert pipe.mesh.vertices.shape == (6359, 3)


# --------------------------------------------------------------------------------------------------
# Synthetic models

SKEL = """2
Root_NULL_Bone_0
Lower Arm
10
Lower Arm
Fing.0
20
Fing.0
Fing.1
15
"""

LIMITS = """Lower Arm
1 1 1 1
5 6 7
5 6 7
5 6 7
-3.40282e+38 3.40282e+38
-3.40282e+38 3.40282e+38
-3.40282e+38 3.40282e+38

Fing.0
0 1 1 1
1 0 0
0 1 0
0 0 1
-5 5
-90 10
-20 30

Fing.1
0 0 1 0
1 0 0
0 0.6 0.8
0 0.8 -0.6
-0 0
-100 5
0 0
"""

_I = "1 0 0 0 1 0 0 0 1"
MOTION = f"""Lower Arm
{_I} 0 0 0
{_I} 1 0 0
Fing.0
{_I} 10 0 0
{_I} 11 0 0
Fing.1
{_I} 30 0 0
{_I} 31 0 0
"""

OFF = """OFF
5 2 0
0 0 0
10 0 0
10 10 0
0 10 0
30 0 0
4 0 1 2 3
3 1 4 2
"""

SKIN = """3
Lower Arm Fing.0 Fing.1
1 0 0
0 1 0
0 1 0
0 0.5 0.5
0 0 1
"""


def write_model(tmp_path: Path, **texts: str) -> Path:
    """Write the synthetic model (override a file with e.g. ``LIMITS=...``; ``None`` omits it)."""
    files = {"SKEL": SKEL, "LIMITS": LIMITS, "MOTION": MOTION} | texts
    for ext, text in files.items():
        if text is not None:
            (tmp_path / f"m.{ext}").write_text(text)
    return tmp_path / "m.SKEL"


def test_synthetic_model_reads_with_names_containing_spaces(tmp_path: Path) -> None:
    skel = read_tzionas_skeleton(write_model(tmp_path))
    assert skel.joint_names == ("Lower Arm", "Fing.0", "Fing.1", "Fing.1_tip")
    assert skel.dof_names == ("Fing_0_abd", "Fing_0_flex", "Fing_0_pron", "Fing_1_flex")
    np.testing.assert_allclose(skel.rest_positions[-1], [0.045, 0, 0])
    np.testing.assert_allclose(skel.dofs[3].axis, [0, 0.6, 0.8])
    assert skel.fingertips == ("Fing.1_tip",)
    assert skel.mesh is None


def test_limits_unlimited_range_becomes_pi_with_a_note(tmp_path: Path) -> None:
    text = LIMITS.replace("-100 5", "-3.40282e+38 3.40282e+38")
    skel = read_tzionas_skeleton(write_model(tmp_path, LIMITS=text))
    assert skel.limits[-1] == pytest.approx([-math.pi, math.pi])
    assert any("'Fing_1_flex': unlimited" in n for n in skel.notes)


def test_limits_tolerate_extra_blank_lines_and_trailing_spaces(tmp_path: Path) -> None:
    text = "\n\n" + LIMITS.replace("Fing.0\n", "Fing.0   \n").replace("\n\n", "\n\n\n  \n") + "\n\n"
    skel = read_tzionas_skeleton(write_model(tmp_path, LIMITS=text))
    assert skel.ndof == 4


def test_missing_motion_lays_chain_along_x_with_a_note(tmp_path: Path) -> None:
    skel = read_tzionas_skeleton(write_model(tmp_path, MOTION=None))
    np.testing.assert_allclose(skel.rest_positions, [[0, 0, 0], [0.01, 0, 0], [0.03, 0, 0], [0.045, 0, 0]])
    assert any("rest pose unknown" in n for n in skel.notes)


def test_mesh_and_skin_are_attached_in_metres(tmp_path: Path) -> None:
    skel = read_tzionas_skeleton(write_model(tmp_path, OFF=OFF, SKIN=SKIN))
    assert skel.mesh.bones == ("Lower Arm", "Fing.0", "Fing.1")
    np.testing.assert_allclose(skel.mesh.vertices[4], [0.03, 0, 0])
    np.testing.assert_array_equal(skel.mesh.faces, [[0, 1, 2], [0, 2, 3], [1, 4, 2]])


def test_read_voi_returns_the_raw_groups(tmp_path: Path) -> None:
    (tmp_path / "a.VOI").write_text("1\n2\n3\n4\n5\n\n\n6\n7\n8\n9\n10\n")
    assert read_voi(tmp_path / "a.VOI") == ((1, 2, 3, 4, 5), (6, 7, 8, 9, 10))


# --------------------------------------------------------------------------------------------------
# Bad inputs


def test_read_skel_raises_error_if_triples_are_incomplete(tmp_path: Path) -> None:
    path = write_model(tmp_path, SKEL=SKEL + "Fing.1\nFing.2\n")
    with pytest.raises(FormatError, match=where(path, 11, "triple") + r".*1 \+ 3k .*got 12"):
        read_skel(path)


def test_read_skel_raises_error_if_parent_is_undefined(tmp_path: Path) -> None:
    path = write_model(tmp_path, SKEL=SKEL.replace("Fing.0\nFing.1", "Fing.9\nFing.1"))
    with pytest.raises(FormatError, match=where(path, 8, "parent") + ".*'Fing.9' of bone 'Fing.1'"):
        read_skel(path)


def test_read_skel_raises_error_if_length_is_not_a_number(tmp_path: Path) -> None:
    path = write_model(tmp_path, SKEL=SKEL.replace("\n20\n", "\n2O\n"))
    with pytest.raises(FormatError, match=where(path, 7, "length") + ".*expected a number, got '2O'"):
        read_skel(path)


def test_read_skel_raises_error_if_bone_names_repeat(tmp_path: Path) -> None:
    path = write_model(tmp_path, SKEL=SKEL + "Fing.1\nFing.0\n3\n")
    with pytest.raises(
        FormatError, match=where(path, 12, "bone name") + ".*'Fing.0' is already defined at line 6"
    ):
        read_skel(path)


def test_read_skel_raises_error_if_frame_count_is_not_an_integer(tmp_path: Path) -> None:
    path = write_model(tmp_path, SKEL="2.5" + SKEL[1:])
    with pytest.raises(FormatError, match=where(path, 1, "frame count") + ".*integer ≥ 1, got '2.5'"):
        read_skel(path)


def test_read_skel_raises_error_if_there_are_two_roots(tmp_path: Path) -> None:
    path = write_model(tmp_path, SKEL=SKEL + "Root_NULL_Bone_0\nOther\n1\n")
    with pytest.raises(FormatError, match=where(path, 11, "parent") + ".*exactly one bone"):
        read_skel(path)


def test_read_skel_raises_error_if_parents_form_a_cycle(tmp_path: Path) -> None:
    path = write_model(tmp_path, SKEL=SKEL + "B\nA\n1\nA\nB\n1\n")
    with pytest.raises(FormatError, match=where(path, 11, "parent") + ".*'A' is not connected to the root"):
        read_skel(path)


def test_read_skeleton_raises_error_if_limits_file_is_missing(tmp_path: Path) -> None:
    path = write_model(tmp_path, LIMITS=None)
    with pytest.raises(InputFileError, match=re.escape(str(tmp_path / "m.LIMITS")) + ": file not found"):
        read_tzionas_skeleton(path)


def test_read_limits_raises_error_if_entry_names_an_unknown_bone(tmp_path: Path) -> None:
    path = write_model(tmp_path, LIMITS=LIMITS.replace("Fing.1\n", "Fing.7\n"))
    with pytest.raises(FormatError, match=where(path.with_suffix(".LIMITS"), 19, "bone name") + ".*'Fing.7'"):
        read_tzionas_skeleton(path)


def test_read_limits_raises_error_if_min_exceeds_max(tmp_path: Path) -> None:
    path = write_model(tmp_path, LIMITS=LIMITS.replace("-90 10", "10 -90"))
    limits = path.with_suffix(".LIMITS")
    with pytest.raises(FormatError, match=where(limits, 16, "ry limits") + ".*min 10 > max -90"):
        read_limits(limits, ["Lower Arm", "Fing.0", "Fing.1"], root="Lower Arm")


def test_read_limits_raises_error_if_limit_is_not_a_number(tmp_path: Path) -> None:
    path = write_model(tmp_path, LIMITS=LIMITS.replace("-90 10", "-90 ten"))
    limits = path.with_suffix(".LIMITS")
    with pytest.raises(FormatError, match=where(limits, 16, "ry max") + ".*expected a number, got 'ten'"):
        read_limits(limits, ["Lower Arm", "Fing.0", "Fing.1"], root="Lower Arm")


def test_read_limits_raises_error_if_axis_is_not_unit(tmp_path: Path) -> None:
    path = write_model(tmp_path, LIMITS=LIMITS.replace("0 0.8 -0.6", "0 0.8 -0.7"))
    limits = path.with_suffix(".LIMITS")
    with pytest.raises(FormatError, match=where(limits, 23, "rz axis") + ".*expected a unit vector"):
        read_limits(limits, ["Lower Arm", "Fing.0", "Fing.1"], root="Lower Arm")


def test_read_limits_raises_error_if_flags_are_not_0_or_1(tmp_path: Path) -> None:
    path = write_model(tmp_path, LIMITS=LIMITS.replace("0 1 1 1", "0 1 2 1"))
    limits = path.with_suffix(".LIMITS")
    with pytest.raises(FormatError, match=where(limits, 11, "flags") + ".*'t rx ry rz' of 0 or 1"):
        read_limits(limits, ["Lower Arm", "Fing.0", "Fing.1"], root="Lower Arm")


def test_read_limits_raises_error_if_entry_has_a_missing_line(tmp_path: Path) -> None:
    path = write_model(tmp_path, LIMITS=LIMITS.replace("-5 5\n", ""))
    limits = path.with_suffix(".LIMITS")
    with pytest.raises(FormatError, match=where(limits, 10, "entry") + ".*7 non-blank lines; expected 8"):
        read_limits(limits, ["Lower Arm", "Fing.0", "Fing.1"], root="Lower Arm")


def test_read_limits_raises_error_if_bone_has_two_entries(tmp_path: Path) -> None:
    path = write_model(tmp_path, LIMITS=LIMITS + "\n" + LIMITS.split("\n\n")[2])
    limits = path.with_suffix(".LIMITS")
    with pytest.raises(FormatError, match=where(limits, 28, "bone name") + ".*first at line 19"):
        read_limits(limits, ["Lower Arm", "Fing.0", "Fing.1"], root="Lower Arm")


def test_read_motion_raises_error_if_bone_has_fewer_rows_than_skel_frames(tmp_path: Path) -> None:
    path = write_model(tmp_path, SKEL="3" + SKEL[1:])
    motion = path.with_suffix(".MOTION")
    with pytest.raises(FormatError, match=where(motion, 1, "rows") + ".*'Lower Arm' has 2 rows, expected 3"):
        read_tzionas_skeleton(path)


def test_read_motion_raises_error_if_bone_is_unknown(tmp_path: Path) -> None:
    path = write_model(tmp_path, MOTION=MOTION.replace("Fing.1", "Fing.5"))
    motion = path.with_suffix(".MOTION")
    with pytest.raises(FormatError, match=where(motion, 7, "bone name") + ".*unknown bone 'Fing.5'"):
        read_motion(motion, ["Lower Arm", "Fing.0", "Fing.1"])


@pytest.mark.parametrize("bones", [["Lower Arm", "Fing.0", "Fing.1"], None])
def test_read_motion_row_whose_first_entry_is_not_a_number_names_that_entry(tmp_path: Path, bones) -> None:
    path = write_model(tmp_path, MOTION=MOTION.replace(f"{_I} 11 0 0", f"l{_I[1:]} 11 0 0"))
    motion = path.with_suffix(".MOTION")
    with pytest.raises(FormatError) as err:
        read_motion(motion, bones)
    assert str(err.value) == f"{motion}:6 [R[0][0]]: expected a number, got 'l'"


def test_read_motion_raises_error_if_row_has_wrong_token_count(tmp_path: Path) -> None:
    path = write_model(tmp_path, MOTION=MOTION.replace(f"{_I} 11 0 0", f"{_I} 11 0"))
    motion = path.with_suffix(".MOTION")
    with pytest.raises(FormatError, match=where(motion, 6, "row") + ".*expected 12 numbers.*got 11"):
        read_motion(motion)


def test_read_skeleton_raises_error_if_rest_rotation_is_not_a_rotation(tmp_path: Path) -> None:
    path = write_model(tmp_path, MOTION=MOTION.replace(f"{_I} 10 0 0", "1 0 0 0 1 0 0 0 -1 10 0 0"))
    motion = path.with_suffix(".MOTION")
    with pytest.raises(FormatError, match=where(motion, 5, "R") + ".*expected a rotation matrix"):
        read_tzionas_skeleton(path)


def test_read_skin_raises_error_if_row_count_differs_from_off_vertex_count(tmp_path: Path) -> None:
    path = write_model(tmp_path, OFF=OFF, SKIN=SKIN + "0 0 1\n")
    pattern = (
        where(path.with_suffix(".SKIN"), 8, "rows")
        + ".*6 weight rows, but "
        + re.escape(str(tmp_path / "m.OFF"))
    )
    with pytest.raises(FormatError, match=pattern + " has 5 vertices"):
        read_tzionas_skeleton(path)


def test_read_skin_raises_error_if_bone_name_is_unknown(tmp_path: Path) -> None:
    (tmp_path / "a.SKIN").write_text(SKIN.replace("Fing.0", "Thumb"))
    with pytest.raises(FormatError, match=where(tmp_path / "a.SKIN", 2, "bone names") + ".*at 'Thumb'"):
        read_skin(tmp_path / "a.SKIN", ["Lower Arm", "Fing.0", "Fing.1"], 5)


def test_read_skin_splits_names_by_longest_known_bone(tmp_path: Path) -> None:
    (tmp_path / "a.SKIN").write_text("2\nLower Arm Lower\n0.5 0.5\n")
    weights, bones = read_skin(tmp_path / "a.SKIN", ["Lower", "Lower Arm"], 1)
    assert bones == ("Lower Arm", "Lower")
    assert weights.shape == (1, 2)


def test_read_off_raises_error_if_face_index_is_out_of_range(tmp_path: Path) -> None:
    (tmp_path / "a.OFF").write_text(OFF.replace("3 1 4 2", "3 1 5 2"))
    with pytest.raises(FormatError, match=where(tmp_path / "a.OFF", 9, "face index") + ".*5 out of range"):
        read_off(tmp_path / "a.OFF")


def test_read_off_raises_error_if_face_has_wrong_token_count(tmp_path: Path) -> None:
    (tmp_path / "a.OFF").write_text(OFF.replace("4 0 1 2 3", "4 0 1 2"))
    with pytest.raises(FormatError, match=where(tmp_path / "a.OFF", 8, "face") + ".*needs 5 tokens, got 4"):
        read_off(tmp_path / "a.OFF")


def test_read_off_raises_error_if_vertex_has_wrong_token_count(tmp_path: Path) -> None:
    (tmp_path / "a.OFF").write_text(OFF.replace("10 10 0", "10 10"))
    with pytest.raises(FormatError, match=where(tmp_path / "a.OFF", 5, "vertex") + ".*3 coordinates, got 2"):
        read_off(tmp_path / "a.OFF")


def test_read_voi_raises_error_if_id_is_not_an_integer(tmp_path: Path) -> None:
    (tmp_path / "a.VOI").write_text("1\nx\n")
    with pytest.raises(FormatError, match=where(tmp_path / "a.VOI", 2, "vertex id") + ".*got 'x'"):
        read_voi(tmp_path / "a.VOI")


def hand_like_model(tmp_path: Path) -> Path:
    """A five-finger model named like the IJCV16 hand (one bone per finger), for VOI tests."""
    skel, limits, motion = ["2", "Root_NULL_Bone_0", "Arm", "10"], [], ["Arm", f"{_I} 0 0 0", f"{_I} 0 0 0"]
    for k in range(5):
        skel += ["Arm", f"RFing.{k}_0", "10"]
        motion += [f"RFing.{k}_0", f"{_I} 10 {k} 0", f"{_I} 10 {k} 0"]
    for name in ["Arm"] + [f"RFing.{k}_0" for k in range(5)]:
        limits += [name, "0 0 1 0", "1 0 0", "0 1 0", "0 0 1", "0 0", "-90 10", "0 0", ""]
    return write_model(tmp_path, SKEL="\n".join(skel), LIMITS="\n".join(limits), MOTION="\n".join(motion))


def test_voi_groups_are_regrouped_per_finger_thumb_first(tmp_path: Path) -> None:
    path = hand_like_model(tmp_path)
    path.with_suffix(".VOI").write_text("0\n1\n2\n3\n4\n\n10\n11\n12\n13\n14\n")
    skel = read_tzionas_skeleton(path)
    assert skel.fingertips[0] == "RFing.4_0_tip"
    assert skel.fingertip_vertices == ((4, 14), (3, 13), (2, 12), (1, 11), (0, 10))


def test_voi_raises_error_if_group_does_not_have_five_ids(tmp_path: Path) -> None:
    path = hand_like_model(tmp_path)
    path.with_suffix(".VOI").write_text("0\n1\n2\n3\n4\n\n10\n11\n12\n13\n")
    with pytest.raises(FormatError, match=where(path.with_suffix(".VOI"), 7, "group") + ".*has 4 vertex ids"):
        read_tzionas_skeleton(path)


# --------------------------------------------------------------------------------------------------
# Round trip


@st.composite
def chains(draw: st.DrawFn) -> dict:
    n = draw(st.integers(1, 5))
    seed = draw(st.integers(0, 2**32 - 1))
    lengths = draw(st.lists(st.floats(0.5, 100.0), min_size=n, max_size=n))
    flags = draw(st.lists(st.tuples(*[st.booleans()] * 3), min_size=n, max_size=n))
    bounds = draw(
        st.lists(st.tuples(st.integers(-180, 180), st.integers(0, 180)), min_size=3 * n, max_size=3 * n)
    )
    return {"n": n, "seed": seed, "lengths": lengths, "flags": flags, "bounds": bounds}


@settings(max_examples=40, deadline=None)
@given(chains())
def test_random_chain_round_trips_joints_limits_and_rest_pose(chain: dict) -> None:
    n, rng = chain["n"], np.random.default_rng(chain["seed"])
    names = [f"Bone {i} x" for i in range(n)]
    rots = Rotation.random(n, random_state=chain["seed"]).as_matrix().reshape(n, 3, 3)
    origins = [rng.uniform(-500, 500, 3)]
    for i in range(1, n):
        origins.append(origins[-1] + rots[i - 1] @ [chain["lengths"][i - 1], 0, 0])
    axes = rng.normal(size=(n, 3, 3))
    axes /= np.linalg.norm(axes, axis=2, keepdims=True)
    skel = ["2"]
    limits, motion = [], []
    for i, name in enumerate(names):
        skel += ["Root_NULL_Bone_0" if i == 0 else names[i - 1], name, repr(chain["lengths"][i])]
        limits += [name, "0 " + " ".join(str(int(f)) for f in chain["flags"][i])]
        limits += [" ".join(repr(float(v)) for v in a) for a in axes[i]]
        limits += [f"{lo} {lo + w}" for lo, w in chain["bounds"][3 * i : 3 * i + 3]] + [""]
        row = " ".join(repr(float(v)) for v in [*rots[i].ravel(), *origins[i]])
        motion += [name, row, row]
    with tempfile.TemporaryDirectory() as tmp:
        path = write_model(
            Path(tmp), SKEL="\n".join(skel), LIMITS="\n".join(limits), MOTION="\n".join(motion)
        )
        result = read_tzionas_skeleton(path)
        shutil.rmtree(tmp, ignore_errors=True)
    assert result.njoints == n + 1
    expected = []
    for i in range(1, n):
        for axis in (2, 1, 0):
            if chain["flags"][i][axis]:
                lo, w = chain["bounds"][3 * i + axis]
                expected.append([math.radians(lo), math.radians(lo + w)])
                dof = result.dofs[len(expected) - 1]
                np.testing.assert_allclose(dof.axis, axes[i, axis], atol=1e-12)
    np.testing.assert_allclose(result.limits, np.array(expected).reshape(-1, 2), atol=1e-12)
    np.testing.assert_allclose(result.rest_positions[:n], np.array(origins) * 1e-3, atol=1e-12)
    tip = origins[-1] + rots[-1] @ [chain["lengths"][-1], 0, 0]
    np.testing.assert_allclose(result.rest_positions[n], tip * 1e-3, atol=1e-9)
    for i in range(n):
        np.testing.assert_allclose(result.joints[i].frame, rots[i], atol=1e-9)
