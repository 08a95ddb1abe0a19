"""Tests of the Tzionas/Ballan motion reader (handsim.io.tzionas.motion)."""

from __future__ import annotations

import functools
import hashlib
import math
import re
import shutil
from pathlib import Path

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handsim.builders import build_hand
from handsim.datatypes.rotations import rotation_about_axis
from handsim.datatypes.skeleton import mj_name
from handsim.errors import FormatError, InputFileError, TrajectoryError
from handsim.io import read_trajectory
from handsim.io.tzionas.configs import read_index_bounds, read_models_info
from handsim.io.tzionas.motion import (
    DEFAULT_FPS,
    fit_tzionas_motion,
    fit_tzionas_object_motion,
    read_tzionas_motion,
    read_tzionas_object_motion,
)
from handsim.io.tzionas.sequence import read_tzionas_sequence
from handsim.io.tzionas.skeleton import read_tzionas_skeleton

MM = 1e-3
HAND_FRAMES = 186  # Configs/20/INDEX_BOUNDS.txt: TotalAlligned
PIPE_FRAMES = 400  # Configs/17/INDEX_BOUNDS.txt


def where(path: Path, line: int | None, field: str) -> str:
    """The ``file:line [field]`` prefix of a FormatError message."""
    return f"{path}:{line} [{field}]" if line is not None else f"{path} [{field}]"


def parse_motion(path: Path, nframes: int) -> dict[str, np.ndarray]:
    """Every row of every bone of a MOTION file, parsed independently of the reader: (z, 12), mm."""
    lines = [s.strip() for s in path.read_text().splitlines() if s.strip()]
    return {
        lines[k]: np.array([r.split() for r in lines[k + 1 : k + 1 + nframes]], dtype=float)
        for k in range(0, len(lines), nframes + 1)
    }


def quat_to_matrix(quats: np.ndarray) -> np.ndarray:
    """Rotation matrices of (w, x, y, z) quaternions, through MuJoCo."""
    out = np.empty((len(quats), 9))
    for q, m in zip(quats, out, strict=True):
        mujoco.mju_quat2Mat(m, q)
    return out.reshape(-1, 3, 3)


# --------------------------------------------------------------------------------------------------
# Real data: sequence 20 (hand + cube) and 17 (pipe)


@functools.cache
def _hand_fit(skel: Path):
    return fit_tzionas_motion(skel)


@pytest.fixture
def hand_skel(tzionas_dir: Path) -> Path:
    return tzionas_dir / "Models" / "20" / "Model_Hand_R.SKEL"


@pytest.fixture
def hand_fit(hand_skel: Path):
    return _hand_fit(hand_skel)


@pytest.fixture
def recorded(hand_skel: Path) -> dict[str, np.ndarray]:
    """Rows 1..186 (aligned frames) of the hand MOTION, independently parsed, (186, 12) per bone, mm."""
    return {k: v[1 : 1 + HAND_FRAMES] for k, v in parse_motion(hand_skel.with_suffix(".MOTION"), 187).items()}


def test_hand_trajectory_has_186_frames_of_31_dofs_at_30_hz(hand_fit, hand_skel: Path) -> None:
    trajectory, fit = hand_fit
    skeleton = read_tzionas_skeleton(hand_skel)
    assert trajectory.dof_names == skeleton.dof_names
    assert trajectory.targets.shape == (HAND_FRAMES, 31)
    assert trajectory.valid.all()
    assert trajectory.root_pose.shape == (HAND_FRAMES, 7)
    np.testing.assert_allclose(np.linalg.norm(trajectory.root_pose[:, 3:], axis=1), 1.0, atol=1e-12)
    assert DEFAULT_FPS == 30.0
    np.testing.assert_allclose(trajectory.times, np.arange(HAND_FRAMES) / 30.0)
    assert trajectory.source == str(hand_skel.with_suffix(".MOTION"))
    assert trajectory.sha256 == hashlib.sha256(hand_skel.with_suffix(".MOTION").read_bytes()).hexdigest()
    assert fit.bones == tuple(j.name for j in skeleton.joints[1:20])
    assert fit.joints == skeleton.joint_names
    assert fit.rotation_residual.shape == (HAND_FRAMES, 19)
    assert fit.position_error.shape == (HAND_FRAMES, 25)


def test_read_tzionas_motion_returns_the_fitted_trajectory(hand_fit, hand_skel: Path) -> None:
    trajectory = read_tzionas_motion(hand_skel)
    np.testing.assert_array_equal(trajectory.targets, hand_fit[0].targets)
    np.testing.assert_array_equal(trajectory.root_pose, hand_fit[0].root_pose)
    assert trajectory.notes == hand_fit[0].notes


def test_root_pose_is_the_root_bone_row_of_each_aligned_frame(hand_fit, recorded) -> None:
    root = recorded["Lower Arm R"]
    pose = hand_fit[0].root_pose
    np.testing.assert_allclose(pose[:, :3], root[:, 9:] * MM, atol=1e-15)
    np.testing.assert_allclose(quat_to_matrix(pose[:, 3:]), root[:, :9].reshape(-1, 3, 3), atol=1e-5)
    assert pose[0, 3] >= 0
    assert np.all(np.sum(pose[1:, 3:] * pose[:-1, 3:], axis=1) > 0)  # no sign flips


def test_rebuilding_every_frame_puts_every_bone_origin_within_1_mm(
    hand_fit, hand_skel: Path, recorded
) -> None:
    trajectory, fit = hand_fit
    skeleton = read_tzionas_skeleton(hand_skel)
    fk = skeleton.forward_kinematics(trajectory.targets)
    root = skeleton.joints[0]
    turn = quat_to_matrix(trajectory.root_pose[:, 3:]) @ root.frame.T
    placed = trajectory.root_pose[:, None, :3] + np.einsum("kij,knj->kni", turn, fk.positions - root.position)
    errors = {
        name: np.linalg.norm(placed[:, skeleton.joint_index(name)] - rows[:, 9:] * MM, axis=1)
        for name, rows in recorded.items()
    }
    worst = max(e.max() for e in errors.values())
    assert worst < 1 * MM
    assert (
        worst < 0.2 * MM
    )  # measured 0.161 mm (RFing.4_1, thumb tip bone), from the thumb metacarpal's twist
    for name, e in errors.items():
        np.testing.assert_allclose(fit.position_error[:, fit.joints.index(name)], e, atol=1e-9)
    assert fit.position_error.max() < 0.25 * MM  # fingertip joints included: 0.232 mm (RFing.4_1_tip)


def test_mujoco_hand_with_a_mocap_root_reproduces_the_recorded_bone_origins(
    hand_fit, hand_skel: Path, recorded
) -> None:
    trajectory, _ = hand_fit
    skeleton = read_tzionas_skeleton(hand_skel)
    spec = build_hand(skeleton)
    spec.body(mj_name(skeleton.joints[0].name)).mocap = True
    model = spec.compile()
    data = mujoco.MjData(model)
    adr = [model.joint(name).qposadr[0] for name in trajectory.dof_names]
    sites = {name: model.site(mj_name(name)).id for name in recorded}
    worst = 0.0
    for k in range(trajectory.nframes):
        data.mocap_pos[0] = trajectory.root_pose[k, :3]
        data.mocap_quat[0] = trajectory.root_pose[k, 3:]
        data.qpos[adr] = trajectory.targets[k]
        mujoco.mj_kinematics(model, data)
        for name, rows in recorded.items():
            worst = max(worst, float(np.linalg.norm(data.site_xpos[sites[name]] - rows[k, 9:] * MM)))
    assert worst < 0.2 * MM


def test_the_root_pose_at_the_rigging_pose_is_the_built_hands_root_body_pose(hand_skel: Path) -> None:
    skeleton = read_tzionas_skeleton(hand_skel)
    rig = hand_skel.parent.parent.parent / "Configs" / "20" / "INDEX_BOUNDS.txt"
    assert read_index_bounds(rig).motion_offset == 1
    rows = parse_motion(hand_skel.with_suffix(".MOTION"), 187)["Lower Arm R"]
    body = build_hand(skeleton).body(mj_name("Lower Arm R"))
    np.testing.assert_allclose(body.pos, rows[0, 9:] * MM, atol=1e-15)
    rest = quat_to_matrix(np.asarray(body.quat)[None])[0]
    np.testing.assert_allclose(rest, rows[0, :9].reshape(3, 3), atol=1e-5)


def test_rotation_residuals_are_file_precision_except_the_2_dof_metacarpals(
    hand_fit, hand_skel: Path
) -> None:
    _, fit = hand_fit
    skeleton = read_tzionas_skeleton(hand_skel)
    worst = fit.max_rotation_residual
    for bone, residual in worst.items():
        ndof = len(skeleton.dofs_of(bone))
        if bone in ("RFing.1_Hand", "RFing.4_Hand"):  # 2 DoFs, but the recording twists them a little
            assert ndof == 2
            continue
        assert residual < (1e-7 if ndof == 3 else 2e-6), bone  # 6-digit file: ~1e-6 rad
    assert math.radians(0.05) < worst["RFing.1_Hand"] < math.radians(0.1)  # measured 0.091°
    assert math.radians(1.7) < worst["RFing.4_Hand"] < math.radians(1.9)  # measured 1.78°


def test_trajectory_notes_give_every_bones_residual_and_the_frame_rate_assumption(hand_fit) -> None:
    trajectory, fit = hand_fit
    note = next(n for n in trajectory.notes if n.startswith("max rotation residual per bone"))
    for bone in fit.bones:
        assert f"{bone} " in note
    assert any("30 Hz" in n and "assumed" in n for n in trajectory.notes)
    assert any("row k + 1" in n for n in trajectory.notes)
    assert any(n.startswith("fit over 186 frames") for n in trajectory.notes)
    assert trajectory.notes == fit.notes


def test_fps_sets_the_times_and_a_bad_fps_is_refused(hand_skel: Path) -> None:
    trajectory = read_tzionas_motion(hand_skel, fps=15)
    np.testing.assert_allclose(trajectory.times, np.arange(HAND_FRAMES) / 15.0)
    with pytest.raises(ValueError, match=re.escape("fps must be a finite number > 0 (Hz), got 0")):
        read_tzionas_motion(hand_skel, fps=0)


def test_cube_track_moves_mesh_vertices_like_the_recorded_transform(tzionas_dir: Path) -> None:
    skel = tzionas_dir / "Models" / "20" / "Model_Object_Cube.SKEL"
    track, fit = fit_tzionas_object_motion(skel)
    assert track.articulation is None
    assert track.valid.all()
    assert fit.bones == ()
    rows = parse_motion(skel.with_suffix(".MOTION"), 187)["Bone001"]
    vertices = read_tzionas_skeleton(skel).mesh.vertices
    r0, t0 = rows[0, :9].reshape(3, 3), rows[0, 9:] * MM
    rotation = quat_to_matrix(track.pose[:, 3:])
    worst_raw = worst_svd = 0.0
    for k in range(HAND_FRAMES):
        rk, tk = rows[k + 1, :9].reshape(3, 3), rows[k + 1, 9:] * MM
        moved = vertices @ rotation[k].T + track.pose[k, :3]
        raw = (vertices - t0) @ (rk @ np.linalg.inv(r0)).T + tk  # M_k · M_0⁻¹ as written in the file
        u, _, vt = np.linalg.svd(rk)
        svd = (vertices - t0) @ (u @ vt @ r0.T).T + tk  # r0 is exactly the identity
        worst_raw = max(worst_raw, float(np.abs(moved - raw).max()))
        worst_svd = max(worst_svd, float(np.abs(moved - svd).max()))
    assert worst_raw < 1e-6  # the file's 6 digits: R orthonormal to ~4e-6, cube vertices 0.3 m from T_0
    assert worst_svd < 1e-14


def test_sequence_20_is_the_hand_trajectory_with_the_cube_track(tzionas_dir: Path, hand_fit) -> None:
    models = tzionas_dir / "Models" / "20"
    sequence = read_tzionas_sequence(models)
    assert list(sequence.objects) == ["cube"]
    cube = read_tzionas_object_motion(models / "Model_Object_Cube.SKEL")
    np.testing.assert_array_equal(sequence.objects["cube"].pose, cube.pose)
    np.testing.assert_array_equal(sequence.targets, hand_fit[0].targets)
    np.testing.assert_array_equal(sequence.root_pose, hand_fit[0].root_pose)
    assert any(n.startswith("object 'cube': pose = M_root,k") for n in sequence.notes)
    assert read_models_info(tzionas_dir / "Configs" / "20" / "MODELS_INFO.txt") == (
        ("Model_Hand_R", 2),
        ("Model_Object_Cube", 3),
    )


def test_pipe_articulation_is_the_hinge_angle_of_its_second_bone(tzionas_dir: Path) -> None:
    from handsim.io.tzionas.objects import read_tzionas_object

    skel = tzionas_dir / "Models" / "17" / "Model_Object_Pipe_Gray.SKEL"
    track, fit = fit_tzionas_object_motion(skel)
    assert track.pose.shape == (PIPE_FRAMES, 7)
    angle = track.articulation
    assert math.radians(-122) < angle.min() < math.radians(-121)  # measured -121.3°
    assert math.radians(-5) < angle.max() < math.radians(-4)  # measured -4.3°
    assert fit.bones == ("Bone002",)
    assert fit.rotation_residual.max() < 1e-6  # measured 6e-7 rad
    hinge = read_tzionas_object(skel).hinge
    rows = parse_motion(skel.with_suffix(".MOTION"), 401)
    r0, t0 = rows["Bone002"][0, :9].reshape(3, 3), rows["Bone002"][0, 9:] * MM
    tip = t0 + 0.17465 * r0[:, 0]  # end of the second bone, rest pose (mesh frame)
    root = quat_to_matrix(track.pose[:, 3:])
    worst = 0.0
    for k in range(PIPE_FRAMES):
        bend = rotation_about_axis(hinge.axis, angle[k])
        predicted = root[k] @ (bend @ (tip - hinge.pos) + hinge.pos) + track.pose[k, :3]
        rk, tk = rows["Bone002"][k + 1, :9].reshape(3, 3), rows["Bone002"][k + 1, 9:] * MM
        recorded_tip = rk @ np.linalg.solve(r0, tip - t0) + tk
        worst = max(worst, float(np.linalg.norm(predicted - recorded_tip)))
    assert worst < 0.01 * MM


def test_sequence_20_notes_its_fitted_angles_beyond_the_limits_per_dof(hand_fit) -> None:
    trajectory, fit = hand_fit
    note = next(n for n in trajectory.notes if "DoF limits" in n)
    assert note == (
        "fitted angles outside the DoF limits of 'Model_Hand_R' in 95 samples (position actuators clamp them "
        "to the joint range): RFing_0_Hand_abd 49/186 (up to 0.7° beyond), RFing_0_Hand_flex 6/186 (up to "
        "0.3° beyond), RFing_2_0_pron 4/186 (up to 1.1° beyond), RFing_3_0_pron 28/186 (up to 1.4° beyond), "
        "RFing_4_0_abd 8/186 (up to 0.2° beyond)"
    )
    assert fit.notes == trajectory.notes


def test_sequence_17_without_its_hand_files_names_the_missing_file(tzionas_dir: Path) -> None:
    models = tzionas_dir / "Models" / "17"
    info = tzionas_dir / "Configs" / "17" / "MODELS_INFO.txt"
    msg = f"{models / 'Model_Hand_R.SKEL'}: file not found; {info}:2 lists model 'Model_Hand_R'"
    with pytest.raises(InputFileError, match=re.escape(msg)):
        read_tzionas_sequence(models)
    with pytest.raises(
        TrajectoryError, match=re.escape(f"{info}: no hand 'Model_Hand_X' (Model_Hand_*) listed")
    ):
        read_tzionas_sequence(models, hand="Model_Hand_X")


def test_a_folder_named_like_a_motion_is_called_a_folder_not_a_missing_file(
    tzionas_dir: Path, tmp_path
) -> None:
    models = tmp_path / "Models" / "20"
    models.mkdir(parents=True)
    for ext in ("SKEL", "LIMITS"):
        shutil.copy(tzionas_dir / "Models" / "20" / f"Model_Hand_R.{ext}", models)
    folder = models / "Model_Hand_R.MOTION"
    folder.mkdir()
    for read in (read_trajectory, lambda p: read_tzionas_motion(p.with_suffix(".SKEL"))):
        with pytest.raises(InputFileError) as err:
            read(folder)
        assert str(err.value) == f"{folder}: is a directory, expected a file"


def test_without_index_bounds_every_row_after_the_rigging_pose_is_a_frame(
    tzionas_dir: Path, tmp_path
) -> None:
    models = tmp_path / "Models" / "20"
    models.mkdir(parents=True)
    for f in (tzionas_dir / "Models" / "20").glob("Model_Object_Cube.*"):
        shutil.copy(f, models / f.name)
    track, fit = fit_tzionas_object_motion(models / "Model_Object_Cube.SKEL")
    assert track.pose.shape == (186, 7)
    missing = tmp_path / "Configs" / "20" / "INDEX_BOUNDS.txt"
    assert (
        f"no {missing}: aligned frame k = MOTION row k + 1 for every row after the rigging pose" in fit.notes
    )


# --------------------------------------------------------------------------------------------------
# Synthetic model: known angles, and bad input

SYN_FRAMES = 6


def _synthetic_rest() -> dict[str, tuple[str, float, np.ndarray, np.ndarray]]:
    """Bone → (parent, length mm, rest frame, rest origin mm): a root, a 3-DoF bone and a 1-DoF bone."""
    f_root = Rotation.from_euler("xyz", [0.3, -0.2, 0.5]).as_matrix()
    f_a = Rotation.from_euler("xyz", [0.1, 0.4, -0.3]).as_matrix()
    f_b = Rotation.from_euler("xyz", [-0.2, 0.1, 0.2]).as_matrix()
    x_root = np.array([10.0, -20.0, 300.0])
    x_a = x_root + 40.0 * f_root[:, 0]
    x_b = x_a + 30.0 * f_a[:, 0]
    return {
        "Root": ("Root_NULL_Bone_0", 40.0, f_root, x_root),
        "A": ("Root", 30.0, f_a, x_a),
        "B": ("A", 20.0, f_b, x_b),
    }


LIMITS = """Root
1 1 1 1
0 0 0
0 0 0
0 0 0
-3.40282e+38 3.40282e+38
-3.40282e+38 3.40282e+38
-3.40282e+38 3.40282e+38

A
0 1 1 1
1 0 0
0 1 0
0 0 1
-30 30
-90 20
-20 20

B
0 0 1 0
1 0 0
0 1 0
0 0 1
-0 0
-95 10
-0 0
"""


def synthetic_angles() -> np.ndarray:
    """(SYN_FRAMES, 4): A abd (z), A flex (y), A pron (x), B flex (y), radians."""
    k = np.arange(SYN_FRAMES)[:, None]
    return np.array([0.3, -0.9, 0.2, -1.2]) * np.sin(0.5 * (k + 1)) + np.array([0.05, 0.1, -0.05, 0.0])


def write_synthetic(folder: Path, frames: int = SYN_FRAMES + 1) -> Path:
    """Write Models/01/Syn.{SKEL,LIMITS,MOTION} + Configs/01/INDEX_BOUNDS.txt; rows 1.. follow the angles."""
    models = folder / "Models" / "01"
    config = folder / "Configs" / "01"
    models.mkdir(parents=True)
    config.mkdir(parents=True)
    rest = _synthetic_rest()
    skel = models / "Syn.SKEL"
    skel.write_text(f"{frames}\n" + "".join(f"{p}\n{b}\n{length}\n" for b, (p, length, _, _) in rest.items()))
    (models / "Syn.LIMITS").write_text(LIMITS)
    angles = np.vstack([np.zeros(4), synthetic_angles()])[:frames]
    root_turn = Rotation.from_rotvec(np.outer(np.arange(frames), [0.05, -0.1, 0.02])).as_matrix()
    rows: dict[str, list[str]] = {b: [] for b in rest}
    for k in range(frames):
        (_, _, f_r, x_r), (_, _, f_a, x_a), (_, _, f_b, x_b) = rest.values()
        r_root = root_turn[k] @ f_r
        t_root = x_r + np.array([1.0, 2.0, -3.0]) * k
        local_a = (
            rotation_about_axis([0, 0, 1], angles[k, 0])
            @ rotation_about_axis([0, 1, 0], angles[k, 1])
            @ rotation_about_axis([1, 0, 0], angles[k, 2])
        )
        r_a = r_root @ f_r.T @ f_a @ local_a
        t_a = t_root + r_root @ f_r.T @ (x_a - x_r)
        r_b = r_a @ f_a.T @ f_b @ rotation_about_axis([0, 1, 0], angles[k, 3])
        t_b = t_a + r_a @ f_a.T @ (x_b - x_a)
        for bone, (r, t) in zip(rest, ((r_root, t_root), (r_a, t_a), (r_b, t_b)), strict=True):
            rows[bone].append(" ".join(f"{v:.12f}" for v in [*r.ravel(), *t]))
    skel.with_suffix(".MOTION").write_text("".join(f"{b}\n" + "\n".join(r) + "\n" for b, r in rows.items()))
    (config / "INDEX_BOUNDS.txt").write_text(
        f"TotalAlligned\t{frames - 1}\nMotionnOffset\t1\nVideoooOffset\t0\n"
    )
    return skel


def test_synthetic_angles_and_root_pose_are_recovered(tmp_path: Path) -> None:
    skel = write_synthetic(tmp_path)
    trajectory, fit = fit_tzionas_motion(skel)
    assert trajectory.dof_names == ("A_abd", "A_flex", "A_pron", "B_flex")
    np.testing.assert_allclose(trajectory.targets, synthetic_angles(), atol=1e-7)
    assert fit.rotation_residual.max() < 1e-7
    assert fit.position_error.max() < 1e-12
    rest = _synthetic_rest()["Root"]
    k = np.arange(1, SYN_FRAMES + 1)
    np.testing.assert_allclose(trajectory.root_pose[:, :3], (rest[3] + np.outer(k, [1.0, 2.0, -3.0])) * MM)
    turn = Rotation.from_rotvec(np.outer(k, [0.05, -0.1, 0.02])).as_matrix()
    np.testing.assert_allclose(quat_to_matrix(trajectory.root_pose[:, 3:]), turn @ rest[2], atol=1e-12)


def motion_lines(skel: Path) -> list[str]:
    return skel.with_suffix(".MOTION").read_text().splitlines()


def test_motion_with_fewer_rows_than_the_skel_frame_count_raises_error(tmp_path: Path) -> None:
    skel = write_synthetic(tmp_path)
    lines = motion_lines(skel)
    del lines[1 + SYN_FRAMES + 1 + 3]  # a row of bone A (line 9 holds A's name)
    motion = skel.with_suffix(".MOTION")
    motion.write_text("\n".join(lines) + "\n")
    msg = f"{where(motion, 9, 'rows')}: bone 'A' has 6 rows, expected 7 (the .SKEL frame count)"
    with pytest.raises(FormatError, match=re.escape(msg)):
        fit_tzionas_motion(skel)


def test_a_bone_missing_from_the_motion_raises_error(tmp_path: Path) -> None:
    skel = write_synthetic(tmp_path)
    motion = skel.with_suffix(".MOTION")
    motion.write_text("\n".join(motion_lines(skel)[: 2 * (SYN_FRAMES + 2)]) + "\n")
    msg = (
        f"{where(motion, None, 'bone name')}: no block for bone 'B' ({skel}:9); expected one block per .SKEL"
    )
    with pytest.raises(FormatError, match=re.escape(msg)):
        fit_tzionas_motion(skel)


@pytest.mark.parametrize(
    ("text", "line", "field", "reason"),
    [
        (
            "TotalAlligned\tx\nMotionnOffset\t1\nVideoooOffset\t0\n",
            1,
            "TotalAlligned",
            "expected an integer ≥ 1, got 'x'",
        ),
        (
            "TotalAlligned\t0\nMotionnOffset\t1\nVideoooOffset\t0\n",
            1,
            "TotalAlligned",
            "expected an integer ≥ 1, got '0'",
        ),
        (
            "TotalAlligned\t6\nMotionnOffset\t-1\nVideoooOffset\t0\n",
            2,
            "MotionnOffset",
            "expected an integer ≥ 0, got '-1'",
        ),
        (
            "TotalAlligned\t6\nMotionOffset\t1\nVideoooOffset\t0\n",
            2,
            "key",
            "expected '<key> <integer>' with key one of ['TotalAlligned', 'MotionnOffset', 'VideoooOffset'], "
            "got 'MotionOffset\\t1'",
        ),
        (
            "TotalAlligned\t6\nVideoooOffset\t0\n",
            2,
            "MotionnOffset",
            "no 'MotionnOffset' line; expected the keys",
        ),
        (
            "TotalAlligned\t6\nTotalAlligned\t5\n",
            2,
            "TotalAlligned",
            "second 'TotalAlligned' (first at line 1)",
        ),
    ],
)
def test_malformed_index_bounds_raise_error(
    tmp_path: Path, text: str, line: int, field: str, reason: str
) -> None:
    skel = write_synthetic(tmp_path)
    bounds = tmp_path / "Configs" / "01" / "INDEX_BOUNDS.txt"
    bounds.write_text(text)
    with pytest.raises(FormatError, match=re.escape(f"{where(bounds, line, field)}: {reason}")):
        fit_tzionas_motion(skel)


def test_index_bounds_beyond_the_rows_raise_error(tmp_path: Path) -> None:
    skel = write_synthetic(tmp_path)
    bounds = tmp_path / "Configs" / "01" / "INDEX_BOUNDS.txt"
    bounds.write_text("TotalAlligned\t7\nMotionnOffset\t1\nVideoooOffset\t0\n")
    msg = (
        f"{where(bounds, 1, 'TotalAlligned')}: TotalAlligned 7 + MotionnOffset 1 = 8 rows needed, but "
        "Syn.MOTION has 7 rows per bone (the .SKEL frame count); expected TotalAlligned + MotionnOffset ≤ 7"
    )
    with pytest.raises(FormatError, match=re.escape(msg)):
        fit_tzionas_motion(skel)
    other = tmp_path / "elsewhere.txt"
    other.write_text("TotalAlligned\t3\nMotionnOffset\t4\nVideoooOffset\t0\n")
    trajectory = read_tzionas_motion(skel, index_bounds=other)
    assert trajectory.nframes == 3
    np.testing.assert_allclose(trajectory.targets, synthetic_angles()[3:6], atol=1e-7)


def _set_rotation(skel: Path, line: int, rotation: np.ndarray) -> Path:
    motion = skel.with_suffix(".MOTION")
    lines = motion_lines(skel)
    translation = lines[line - 1].split()[9:]
    lines[line - 1] = " ".join([*(f"{v:.12f}" for v in rotation.ravel()), *translation])
    motion.write_text("\n".join(lines) + "\n")
    return motion


def test_a_rotation_that_is_not_orthonormal_raises_error_naming_bone_and_row(tmp_path: Path) -> None:
    skel = write_synthetic(tmp_path)
    motion = _set_rotation(skel, 9 + 1 + 3, np.diag([1.001, 1.0, 1.0]))  # bone A, row 3
    msg = (
        f"{where(motion, 13, 'R')}: bone 'A' row 3: max |RᵀR − I| = 0.002 > 0.001; expected a rotation "
        "matrix (R row-major, then T)"
    )
    with pytest.raises(FormatError, match=re.escape(msg)):
        fit_tzionas_motion(skel)


def test_a_reflection_raises_error(tmp_path: Path) -> None:
    skel = write_synthetic(tmp_path)
    motion = _set_rotation(skel, 17 + 1 + 5, np.diag([1.0, 1.0, -1.0]))  # bone B, row 5
    msg = f"{where(motion, 23, 'R')}: bone 'B' row 5: det R = -1, a reflection; expected a rotation matrix"
    with pytest.raises(FormatError, match=re.escape(msg)):
        fit_tzionas_motion(skel)


def test_a_slightly_non_orthonormal_rotation_is_repaired_and_noted(tmp_path: Path) -> None:
    skel = write_synthetic(tmp_path)
    _set_rotation(skel, 1 + 1 + 6, np.diag([1.0004, 1.0, 1.0]))  # root, row 6 (last aligned frame)
    trajectory = read_tzionas_motion(skel)
    assert "Syn.MOTION: every R re-orthonormalised by SVD (max |RᵀR − I| 0.0008 ≤ 0.001" in "\n".join(
        trajectory.notes
    )
    np.testing.assert_allclose(trajectory.root_pose[-1, 3:], [1.0, 0.0, 0.0, 0.0], atol=1e-12)


def test_a_skeleton_that_does_not_match_the_skel_raises_error(tmp_path: Path, hand_skel: Path) -> None:
    skel = write_synthetic(tmp_path)
    with pytest.raises(TrajectoryError, match=re.escape(f"does not match {skel}: root 'Lower Arm R'")):
        fit_tzionas_motion(skel, skeleton=read_tzionas_skeleton(hand_skel))


def test_an_object_with_a_3_dof_bone_is_not_an_object_track(tmp_path: Path) -> None:
    skel = write_synthetic(tmp_path)
    msg = f"{skel}: 3 bones with 4 DoFs; an object track holds a rigid pose and at most one hinge angle"
    with pytest.raises(TrajectoryError, match=re.escape(msg)):
        read_tzionas_object_motion(skel)


def test_models_info_count_must_match_the_names(tmp_path: Path) -> None:
    info = tmp_path / "MODELS_INFO.txt"
    info.write_text("3\nModel_Hand_R\nModel_Object_Cube\n")
    msg = f"{where(info, 3, 'model names')}: 2 model names follow, expected 3 (the count on line 1)"
    with pytest.raises(FormatError, match=re.escape(msg)):
        read_models_info(info)
