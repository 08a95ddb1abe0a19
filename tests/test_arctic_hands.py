"""MANO hands for ARCTIC: built from the user's MANO files with a subject's betas, driven by their targets.

The acceptance test of issue 13 for the hands: each hand's joints, as simulated by the MuJoCo hand driven by
the converted targets and root pose, equal an independent numpy MANO forward kinematics of the same file
(betas, flat_hand_mean=False) to 1e-9 m, for both sides. Then the side check (left data under 'right').
"""

from __future__ import annotations

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from handsim.builders.mano_hand import HINGE_LIMITS, build_mano_hands
from handsim.datatypes.mesh import validate_mesh
from handsim.datatypes.object_model import Hinge, ObjectModel, ObjectPart
from handsim.datatypes.trajectory_ops import resample
from handsim.errors import InputFileError, ModelError, TrajectoryError
from handsim.io.arctic.mano import MANO_JOINT_NAMES, find_mano_files
from handsim.io.arctic.sequence import HANDS, read_arctic_sequence
from handsim.sim import compile_spec, warning_counts
from handsim.trials.arctic_hands import arctic_hand_trajectory, hand_side_check
from tests.mano_fixtures import (
    arctic_object_values,
    grasp_pose,
    mano_hand_params,
    mujoco_sites,
    numpy_mano_fk,
    write_arctic_mano_npy,
    write_arctic_object_npy,
    write_synthetic_mano_pkl,
)
from tests.test_zyx_continuity import TOLERANCE, angle_between, euler_matrices, hinge_steps, step_bound


@pytest.fixture(scope="module")
def mano_dir(tmp_path_factory):
    """A folder with synthetic MANO_RIGHT.pkl and MANO_LEFT.pkl (the left the right mirrored, as MANO's)."""
    folder = tmp_path_factory.mktemp("mano_models")
    arrays = {s: write_synthetic_mano_pkl(folder / f"MANO_{s.upper()}.pkl", side=s) for s in HANDS}
    return folder, arrays


def write_sequence(folder, n=6, name="box_grab_01"):
    raw = folder / "raw_seqs" / "s03"
    raw.mkdir(parents=True)
    params = {"right": mano_hand_params(n, seed=11), "left": mano_hand_params(n, seed=12, side="left")}
    path = raw / f"{name}.mano.npy"
    write_arctic_mano_npy(path, params["right"], params["left"])
    write_arctic_object_npy(raw / f"{name}.object.npy", arctic_object_values(n))
    return path, params


# --------------------------------------------------------------------------------------------------
# Acceptance: MuJoCo hand = numpy MANO of the file


@pytest.mark.parametrize("side", HANDS)
def test_each_arctic_hand_simulated_equals_numpy_mano_kinematics_of_the_file(mano_dir, tmp_path, side):
    folder, arrays = mano_dir
    path, params = write_sequence(tmp_path)
    sequence = read_arctic_sequence(path)
    hands = build_mano_hands(folder, {s: sequence.hand(s).shape for s in HANDS}, root="mocap")
    hand = hands[side]
    assert hand.spec.modelname == f"mano_{side}" and hand.model.side == side
    trajectory = arctic_hand_trajectory(sequence, side, hand.skeleton, hand.model)
    assert trajectory.objects["box"] is sequence.object
    p = {k: np.asarray(v, dtype=float) for k, v in params[side].items()}
    worst = 0.0
    for frame in range(sequence.nframes):  # frame 0 is the acceptance; every frame is checked
        full = p["pose"][frame] + arrays[side]["hands_mean"]  # ARCTIC: flat_hand_mean=False
        _, _, expected = numpy_mano_fk(arrays[side], p["shape"], p["rot"][frame], full, p["trans"][frame])
        sites = mujoco_sites(hand.spec, hand.skeleton, trajectory, frame)
        got = np.array([sites[name] for name in MANO_JOINT_NAMES])
        worst = max(worst, float(np.abs(got - expected).max()))
        if frame == 0:
            np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)
    assert worst < 1e-9


def test_both_arctic_hands_compile_and_hold_still_without_warnings(mano_dir, tmp_path):
    folder, _ = mano_dir
    sequence = read_arctic_sequence(write_sequence(tmp_path)[0])
    for hand in build_mano_hands(folder, {s: sequence.hand(s).shape for s in HANDS}).values():
        model = compile_spec(hand.spec)
        data = mujoco.MjData(model)
        mujoco.mj_step(model, data, 250)
        assert not any(warning_counts(data).values())


def test_left_hand_mirrors_the_right_one_in_x(mano_dir):
    folder, _ = mano_dir
    hands = build_mano_hands(folder, {"right": np.zeros(10), "left": np.zeros(10)})
    right = hands["right"].skeleton.rest_positions
    left = hands["left"].skeleton.rest_positions
    np.testing.assert_allclose(left, right * [-1.0, 1.0, 1.0], rtol=0, atol=1e-15)
    mean_r, mean_l = hands["right"].model.hands_mean, hands["left"].model.hands_mean
    np.testing.assert_allclose(mean_l.reshape(15, 3), mean_r.reshape(15, 3) * [1.0, -1.0, -1.0])


# --------------------------------------------------------------------------------------------------
# Continuous joint targets


def recorded_rotations(sequence, side, model):
    """Each MANO joint's recorded rotation, ``exp(pose + hands_mean)`` by scipy, shape (N, 15, 3, 3)."""
    full = np.asarray(sequence.hand(side).pose, dtype=float) + model.hands_mean
    return Rotation.from_rotvec(full.reshape(-1, 3)).as_matrix().reshape(sequence.nframes, 15, 3, 3)


def target_angles(trajectory):
    """The hinge targets as (z, y, x) per MANO joint, shape (N, 15, 3)."""
    column = {name: k for k, name in enumerate(trajectory.dof_names)}
    order = [[column[f"{j}_{ax}"] for ax in "zyx"] for j in MANO_JOINT_NAMES[1:]]
    return trajectory.targets[:, np.array(order)]


def thumb_through_180(folder, arrays, n=61):
    """A sequence whose right thumb2 turns from Z·Y·X (170°, 80°, −30°) to (190°, 100°, 10°): z crosses
    ±180° and y passes 90° (exactly at frame 30); every other joint and the left hand as in ARCTIC's files."""
    path, params = write_sequence(folder, n=n, name="ketchup_grab_01")
    full = np.radians(np.linspace([170.0, 80.0, -30.0], [190.0, 100.0, 10.0], n))
    thumb2 = MANO_JOINT_NAMES.index("thumb2") - 1
    pose = params["right"]["pose"].astype(float).reshape(n, 15, 3)
    mean = arrays["right"]["hands_mean"].reshape(15, 3)
    pose[:, thumb2] = Rotation.from_euler("ZYX", full).as_rotvec() - mean[thumb2]
    params["right"]["pose"] = pose.reshape(n, 45)  # float64: the rotations exactly as constructed
    write_arctic_mano_npy(path, params["right"], params["left"])
    return read_arctic_sequence(path), full


@pytest.mark.parametrize("side", HANDS)
@pytest.mark.parametrize("motion", ["random frames", "grasp", "thumb through 180°"])
def test_arctic_targets_are_the_recorded_rotations_and_never_step_beyond_the_bound(
    mano_dir, tmp_path, side, motion
):
    folder, arrays = mano_dir
    if motion == "random frames":  # ARCTIC's layout, each frame's pose drawn anew (large steps)
        sequence = read_arctic_sequence(write_sequence(tmp_path, n=40)[0])
    elif motion == "grasp":  # both hands close around balls and open again, smoothly
        sequence, _ = ball_grasp(tmp_path, arrays, 1)
    else:
        sequence, _ = thumb_through_180(tmp_path, arrays)
    hand = build_mano_hands(folder, {side: sequence.hand(side).shape})[side]
    trajectory = arctic_hand_trajectory(sequence, side, hand.skeleton, hand.model)
    recorded = recorded_rotations(sequence, side, hand.model)
    angles = target_angles(trajectory)
    assert angle_between(euler_matrices(angles), recorded).max() <= TOLERANCE
    assert np.all(hinge_steps(angles) <= step_bound(recorded) + TOLERANCE)
    for k, ax in enumerate("zyx"):
        low, high = HINGE_LIMITS[ax]
        assert low <= angles[..., k].min() and angles[..., k].max() <= high
    assert not any("moved by whole turns" in note for note in trajectory.notes)


def test_a_thumb_crossing_180_and_y_90_moves_at_its_own_pace_also_at_the_control_rate(mano_dir, tmp_path):
    folder, arrays = mano_dir
    sequence, full = thumb_through_180(tmp_path, arrays)
    hand = build_mano_hands(folder, {"right": sequence.right.shape})["right"]
    trajectory = arctic_hand_trajectory(sequence, "right", hand.skeleton, hand.model)
    thumb2 = target_angles(trajectory)[:, MANO_JOINT_NAMES.index("thumb2") - 1]
    assert hinge_steps(thumb2).max() <= hinge_steps(full).max() + TOLERANCE  # 0.67° per frame
    control = resample(trajectory, 100.0).trajectory  # what a replay drives, at 100 Hz
    column = [trajectory.dof_names.index(f"thumb2_{ax}") for ax in "zyx"]
    steps = np.abs(np.diff(control.targets[:, column], axis=0)).max()
    assert steps <= hinge_steps(full).max() * 30.0 / 100.0 + TOLERANCE  # no sweep round between frames
    z = control.targets[:, column[0]]
    assert np.ptp(z) <= math.radians(20.0) + TOLERANCE  # z passes ±180° without turning back round


def test_a_joint_turning_round_three_times_is_moved_into_its_range_with_a_note(mano_dir, tmp_path):
    folder, arrays = mano_dir
    n = 91
    path, params = write_sequence(tmp_path, n=n)
    pose = params["right"]["pose"].astype(float).reshape(n, 15, 3)
    pose[:, 0] = np.column_stack([np.zeros(n), np.zeros(n), np.linspace(0.0, 6 * np.pi, n)])
    pose[:, 0] -= arrays["right"]["hands_mean"][:3]  # index1: three whole turns about z
    params["right"]["pose"] = pose.reshape(n, 45)
    write_arctic_mano_npy(path, params["right"], params["left"])
    sequence = read_arctic_sequence(path)
    hand = build_mano_hands(folder, {"right": sequence.right.shape})["right"]
    trajectory = arctic_hand_trajectory(sequence, "right", hand.skeleton, hand.model)
    angles = target_angles(trajectory)
    assert angle_between(euler_matrices(angles), recorded_rotations(sequence, "right", hand.model)).max() <= (
        TOLERANCE
    )
    low, high = HINGE_LIMITS["z"]
    assert low <= angles[:, 0, 0].min() and angles[:, 0, 0].max() <= high
    (note,) = [n for n in trajectory.notes if "moved by whole turns" in n]
    assert note.startswith("61 hinge targets of 1 DoF (index1_z) moved by whole turns into the hinge ranges")
    assert note.endswith("the servo sweeps a turn at 1 frame (61)")  # 1080° in a 720° range: one at least
    assert np.flatnonzero(hinge_steps(angles[:, :1]) > math.pi).tolist() == [60]


# --------------------------------------------------------------------------------------------------
# Bad input


def test_missing_mano_folder_says_which_files_are_needed_and_where_to_put_them(tmp_path, monkeypatch):
    monkeypatch.delenv("HANDSIM_MANO_DIR", raising=False)
    advice = (
        "handsim needs the MANO hand models MANO_RIGHT.pkl and MANO_LEFT.pkl (MPI's MANO licence: register "
        "and download them from https://mano.is.tue.mpg.de/); put them in one folder and pass it with "
        "--mano-dir DIR (Python: mano_dir=DIR) or set HANDSIM_MANO_DIR=DIR"
    )
    with pytest.raises(InputFileError) as err:
        build_mano_hands(None, {"right": np.zeros(10), "left": np.zeros(10)})
    assert str(err.value) == f"no MANO folder given and HANDSIM_MANO_DIR is not set: {advice}"
    with pytest.raises(InputFileError) as err:
        find_mano_files(tmp_path / "nowhere")
    assert str(err.value) == f"{tmp_path / 'nowhere'}: MANO folder not found: {advice}"
    write_synthetic_mano_pkl(tmp_path / "MANO_RIGHT.pkl")
    with pytest.raises(InputFileError) as err:
        find_mano_files(tmp_path)
    assert str(err.value) == f"{tmp_path}: MANO_LEFT.pkl not found there: {advice}"
    monkeypatch.setenv("HANDSIM_MANO_DIR", str(tmp_path))
    assert find_mano_files(sides=("right",)) == {"right": tmp_path / "MANO_RIGHT.pkl"}


def test_a_left_model_saved_as_mano_right_raises_error(tmp_path):
    write_synthetic_mano_pkl(tmp_path / "MANO_RIGHT.pkl", side="left")
    with pytest.raises(ModelError) as err:
        build_mano_hands(tmp_path, {"right": np.zeros(10)})
    assert str(err.value) == (
        f"{tmp_path / 'MANO_RIGHT.pkl'}: the model is a left hand (fingers towards +x from the wrist), "
        "but the file is the right hand's MANO_RIGHT.pkl"
    )


def test_converting_with_a_hand_of_other_betas_raises_error(mano_dir, tmp_path):
    folder, _ = mano_dir
    sequence = read_arctic_sequence(write_sequence(tmp_path)[0])
    hand = build_mano_hands(folder, {"right": np.zeros(10)})["right"]
    j0 = hand.model.J_regressor[0] @ (hand.model.v_template + hand.model.shapedirs @ sequence.right.shape)
    off = np.linalg.norm(j0 - hand.skeleton.joints[0].position) * 1000
    with pytest.raises(TrajectoryError) as err:
        arctic_hand_trajectory(sequence, "right", hand.skeleton, hand.model)
    assert str(err.value) == (
        "the right hand was built with other betas than box_grab_01's right.shape: its wrist is "
        f"{off:.3g} mm from the sequence's J0; build it with betas=sequence.right.shape"
    )


def test_converting_a_hand_with_the_other_sides_model_raises_error(mano_dir, tmp_path):
    folder, _ = mano_dir
    sequence = read_arctic_sequence(write_sequence(tmp_path)[0])
    left = build_mano_hands(folder, {"left": sequence.left.shape})["left"]
    with pytest.raises(TrajectoryError) as err:
        arctic_hand_trajectory(sequence, "right", left.skeleton, left.model)
    assert str(err.value) == (
        f"{folder / 'MANO_LEFT.pkl'}: a left MANO model cannot convert the right hand of box_grab_01; "
        "use MANO_RIGHT.pkl"
    )


# --------------------------------------------------------------------------------------------------
# Side check: left-hand data stored under 'right'

N_GRASP = 60
BALLS = {"right": np.array([0.0, -0.12, 1.05]), "left": np.array([0.0, 0.12, 1.05])}
"""Each hand closes around a ball of its own (the object's two parts), 24 cm apart, about 1 m up."""


def ball_grasp(folder, arrays, seed, *, swap=False, offset=(0.0, 0.0, 0.0), name="balls_grab"):
    """A sequence in which each hand closes around a ball; ``swap`` stores each hand under the other's key.

    The files are ``folder/<name>_<seed>.mano.npy`` and ``.object.npy`` (the object's name is ``name``'s first
    word, as in ARCTIC's sequence names).

    Where the balls go comes from the independent numpy MANO kinematics of the fixture's arrays: the ball's
    centre is the centroid of the hand's 15 finger joints at full closure, its radius 3 mm less than the
    nearest joint's distance (the hand touches it while closed). ``offset`` moves the object away (metres).
    """
    params, parts = {}, []
    origin = np.array([0.0, 0.0, 1.0])
    for side, part in (("right", "bottom"), ("left", "top")):
        pose = grasp_pose(N_GRASP, arrays[side]["hands_mean"], side, seed=seed)
        rot = Rotation.random(random_state=2 * seed + (side == "left")).as_rotvec()
        full = pose[N_GRASP // 2].astype(float) + arrays[side]["hands_mean"]
        _, _, joints = numpy_mano_fk(arrays[side], np.zeros(10), rot, full, np.zeros(3))
        centre = joints[1:].mean(axis=0)
        radius = np.linalg.norm(joints[1:] - centre, axis=1).min() - 0.003
        params[side] = {
            "rot": np.tile(rot, (N_GRASP, 1)).astype(np.float32),
            "pose": pose,
            "trans": np.tile(BALLS[side] - centre, (N_GRASP, 1)).astype(np.float32),
            "shape": np.zeros(10, dtype=np.float32),
            "fitting_err": [0.004] * N_GRASP,
        }
        ball = trimesh.creation.icosphere(subdivisions=3, radius=radius)
        ball.apply_translation(BALLS[side] - origin)
        parts.append(ObjectPart(part, validate_mesh(ball.vertices, ball.faces, f"{part} ball")))
    obj = ObjectModel(name.split("_")[0], tuple(parts), density=300.0, hinge=Hinge(axis=(0.0, 0.0, -1.0)))
    path = folder / f"{name}_{seed:02d}.mano.npy"
    stored = (params["left"], params["right"]) if swap else (params["right"], params["left"])
    write_arctic_mano_npy(path, *stored)
    values = np.zeros((N_GRASP, 7), dtype=np.float32)
    values[:, 4:] = (origin + np.asarray(offset)) * 1000.0
    write_arctic_object_npy(path.with_name(f"{name}_{seed:02d}.object.npy"), values)
    return read_arctic_sequence(path), obj


@pytest.fixture(scope="module")
def both_hands(mano_dir):
    folder, _ = mano_dir
    hands = build_mano_hands(folder, {s: np.zeros(10) for s in HANDS})
    return {s: (h.skeleton, h.model) for s, h in hands.items()}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_side_check_finds_each_hand_under_its_own_key(mano_dir, both_hands, tmp_path, seed):
    sequence, obj = ball_grasp(tmp_path, mano_dir[1], seed)
    check = hand_side_check(sequence, both_hands, obj)
    assert check.verdict == "as stored"
    for contact in (check.right, check.left):
        assert contact.own_fraction >= 0.25 and contact.own_closest < 0.004 < contact.other_closest
        assert contact.own_inside == 0.0
    assert check.message == (
        f"{sequence.mano_path}: the hands are as stored (heuristic): {check.right.line()}; "
        f"{check.left.line()}"
    )


@pytest.mark.parametrize("seed", [0, 2, 3])
def test_side_check_flags_left_hand_data_stored_under_right_and_right_under_left(
    mano_dir, both_hands, tmp_path, seed
):
    sequence, obj = ball_grasp(tmp_path, mano_dir[1], seed, swap=True)
    check = hand_side_check(sequence, both_hands, obj)
    assert check.verdict == "swapped"
    assert (check.right.reading, check.left.reading) == ("other", "other")
    assert check.right.own_fraction == 0.0 and check.right.other_fraction >= 0.25
    assert check.message == (
        f"{sequence.mano_path}: 'right' and 'left' look swapped (heuristic): each hand touches the balls "
        f"only when driving the other hand's model: {check.right.line()}; {check.left.line()}; check the "
        "file's 'right'/'left' entries"
    )
    r = check.right
    assert r.line() == (
        f"'right' driving the right model touches the object in 0% of the frames (closest "
        f"{r.own_closest * 1000:.0f} mm, inside it in {r.own_inside:.0%}), driving the left model in "
        f"{r.other_fraction:.0%} (closest {r.other_closest * 1000:.0f} mm, inside it in {r.other_inside:.0%})"
    )


def test_side_check_never_flags_on_one_entry_alone(mano_dir, both_hands, tmp_path):
    """An idle hand whose mirror image lands on the object is not evidence enough."""
    sequence, obj = ball_grasp(tmp_path, mano_dir[1], 0, swap=True)
    idle = replace(sequence.left, trans=sequence.left.trans + np.array([0.0, 0.0, 0.5]))  # 50 cm up
    check = hand_side_check(replace(sequence, left=idle), both_hands, obj)
    assert (check.right.reading, check.left.reading) == ("other", None)
    assert check.verdict == "not judged"
    assert check.message.startswith(
        f"{sequence.mano_path}: sides not judged: one entry touches the balls only mirrored, the other does "
        "not agree (an idle hand's mirror image can land on the object): "
    )


def test_side_check_does_not_judge_hands_that_never_touch_the_object(mano_dir, both_hands, tmp_path):
    sequence, obj = ball_grasp(tmp_path, mano_dir[1], 0, offset=(0.0, 0.6, 0.0))
    check = hand_side_check(sequence, both_hands, obj)
    assert check.verdict == "not judged"
    assert check.right.own_fraction == check.right.other_fraction == 0.0
    assert check.message.startswith(
        f"{sequence.mano_path}: sides not judged: neither hand touches the balls in one reading only: "
    )


def test_side_check_counts_a_hand_inside_the_object_as_not_touching(mano_dir, both_hands, tmp_path):
    sequence, obj = ball_grasp(tmp_path, mano_dir[1], 0)
    touching = hand_side_check(sequence, both_hands, obj).right
    assert touching.own_inside == 0.0
    centre = BALLS["right"] - sequence.object.pose[0, :3]  # the right ball, in the object frame
    grown = replace(
        obj, parts=(replace(obj.parts[0], mesh=_grown(obj.parts[0].mesh, centre, 0.03)), obj.parts[1])
    )
    swallowed = hand_side_check(sequence, both_hands, grown).right
    assert swallowed.own_inside > 0.25 and swallowed.own_fraction < touching.own_fraction


def _grown(mesh, centre, by):
    """The mesh scaled about ``centre`` so that it grows by ``by`` metres in radius (swallowing fingers)."""
    radius = np.linalg.norm(mesh.vertices - centre, axis=1).mean()
    grown = centre + (mesh.vertices - centre) * (radius + by) / radius
    return validate_mesh(grown, mesh.faces, "grown ball")


def test_side_check_needs_both_hands(mano_dir, both_hands, tmp_path):
    sequence, obj = ball_grasp(tmp_path, mano_dir[1], 0)
    with pytest.raises(TrajectoryError, match=r"^the side check needs both hands; 'left' is missing$"):
        hand_side_check(sequence, {"right": both_hands["right"]}, obj)
