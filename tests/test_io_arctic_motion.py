"""ARCTIC motion files (``*.mano.npy``, ``*.object.npy``) in exactly ARCTIC's layout, read in SI units."""

from __future__ import annotations

import hashlib
import pickle
import re
from pathlib import Path

import mujoco
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from handsim.builders.mano_hand import build_mano_hand, mano_hand_skeleton
from handsim.errors import FormatError, InputFileError
from handsim.io.arctic.mano import read_mano_model
from handsim.io.arctic.mano_pose import mano_pose_to_trajectory
from handsim.io.arctic.sequence import read_arctic_mano, read_arctic_object, read_arctic_sequence
from handsim.io.arctic.templates import ARCTIC_HINGE_AXIS
from handsim.io.safe_pickle import load_npy
from handsim.sim import compile_spec
from tests.mano_fixtures import (
    arctic_object_values,
    mano_hand_params,
    write_arctic_mano_npy,
    write_arctic_object_npy,
    write_malicious_npy,
    write_synthetic_mano_pkl,
)


def object_values(n: int, seed: int = 0) -> np.ndarray:
    """ARCTIC object rows: articulation rad, axis-angle, translation mm (float32), z-up world."""
    return arctic_object_values(n, seed)


@pytest.fixture
def mano_file(tmp_path):
    path = tmp_path / "box_grab_01.mano.npy"
    right, left = mano_hand_params(8, seed=1), mano_hand_params(8, seed=2, side="left")
    write_arctic_mano_npy(path, right, left)
    return path, right, left


# --------------------------------------------------------------------------------------------------
# MANO parameters


def test_arctic_mano_file_reads_both_hands_as_stored(mano_file):
    path, right, left = mano_file
    assert isinstance(right["fitting_err"], list) and isinstance(right["fitting_err"][0], float)
    for hand, params in (("right", right), ("left", left)):
        seq = read_arctic_mano(path, hand)
        assert seq.side == hand
        for key in ("rot", "pose", "trans", "shape", "fitting_err"):
            np.testing.assert_array_equal(getattr(seq, key), np.asarray(params[key], dtype=float))
            assert getattr(seq, key).dtype == np.float64
        assert seq.nframes == 8
        assert seq.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
        assert seq.source == str(path)
        assert seq.notes == ()


def test_arctic_mano_fitting_err_given_as_an_array_is_accepted(tmp_path):
    path = tmp_path / "a.mano.npy"
    right = mano_hand_params(5)
    right["fitting_err"] = np.asarray(right["fitting_err"], dtype=np.float32)
    write_arctic_mano_npy(path, right, mano_hand_params(5, 2, side="left"))
    np.testing.assert_array_equal(read_arctic_mano(path).fitting_err, right["fitting_err"].astype(float))


def test_arctic_mano_per_frame_shape_is_averaged_with_a_note(tmp_path):
    path = tmp_path / "s01.mano.npy"
    right = mano_hand_params(3)
    right["shape"] = np.tile(right["shape"], (3, 1))
    write_arctic_mano_npy(path, right, mano_hand_params(3, 2, side="left"))
    seq = read_arctic_mano(path)
    np.testing.assert_allclose(seq.shape, right["shape"][0], rtol=1e-7)
    assert seq.notes == ("right.shape given per frame; their mean used (largest spread 0.0e+00)",)


def test_arctic_mano_pose_of_wrong_length_raises_error_naming_file_and_field(tmp_path):
    path = tmp_path / "bad.mano.npy"
    right = mano_hand_params(4)
    right["pose"] = right["pose"][:, :12]
    write_arctic_mano_npy(path, right, mano_hand_params(4, 2, side="left"))
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path)
    assert (
        str(err.value)
        == f"{path} [right.pose]: expected 45 values per frame (15 joints × 3 axis-angle), got 12"
    )
    assert err.value.field == "right.pose"


def test_arctic_mano_translation_in_millimetres_raises_error(tmp_path):
    path = tmp_path / "mm.mano.npy"
    right = mano_hand_params(4)
    right["trans"] = right["trans"] * 1000.0
    write_arctic_mano_npy(path, right, mano_hand_params(4, 2, side="left"))
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path)
    largest = float(np.abs(right["trans"].astype(float)).max())
    assert str(err.value) == (
        f"{path} [right.trans]: translation component reaches {largest:.4g}; MANO translations are metres "
        "and a hand more than 5 m from the origin means the file holds millimetres"
    )


def test_arctic_mano_translation_spike_of_x1000_names_the_frame(tmp_path):
    path = tmp_path / "spike.mano.npy"
    left = mano_hand_params(10, 2, side="left")
    left["trans"][6] *= 1000.0
    write_arctic_mano_npy(path, mano_hand_params(10), left)
    distance = float(np.linalg.norm(left["trans"][6].astype(float)))
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path, "right")  # both hands are validated whichever is asked for
    assert str(err.value) == (
        f"{path} [left.trans]: frame 6: the hand is {distance:.4g} m from the origin, beyond the 5 m of a "
        "capture volume (1 such frame); a corrupted or mis-scaled frame"
    )


def test_arctic_mano_hand_jumping_faster_than_a_human_hand_raises_error(tmp_path):
    path = tmp_path / "jump.mano.npy"
    right = mano_hand_params(10)
    right["trans"][4:] += np.float32(0.5)  # 0.87 m in one frame: 26 m/s at 30 fps
    write_arctic_mano_npy(path, right, mano_hand_params(10, 2, side="left"))
    trans = right["trans"].astype(float)
    jump = float(np.linalg.norm(trans[4] - trans[3]))
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path)
    assert str(err.value) == (
        f"{path} [right.trans]: frame 4: the hand jumps {jump:.4g} m from frame 3 ({jump * 30:.4g} m/s at 30 "
        "fps); expected at most 0.3333 m per frame (10 m/s)"
    )
    assert read_arctic_mano(path, fps=10.0).nframes == 10  # at 10 fps the same jump is 8.7 m/s: allowed


@pytest.mark.parametrize(
    ("field", "value", "reason"),
    [
        ("rot", np.zeros((4, 3), dtype=np.int64), "expected floating-point values, got dtype int64"),
        ("trans", np.zeros((4, 2)), "expected shape (4, 3), got (4, 2)"),
        ("shape", np.zeros(8), "expected shape (10,), got (8,)"),
        ("fitting_err", [0.01, 0.02, 0.03, 0.04, 0.05], "expected 4 values (one per frame), got 5"),
        ("fitting_err", [0.01, "x", 0.03, 0.04], "entry 1 is str 'x'; expected a number"),
        ("fitting_err", [0.01, 0.02, float("nan"), 0.04], "non-finite value at frame 2"),
        ("fitting_err", 0.01, "expected a list of 4 floats (one per frame), got float"),
        ("fitting_err", np.zeros(5), "expected shape (4,), got (5,)"),
        ("rot", np.full((4, 3), np.nan), "non-finite value at frame 0"),
    ],
)
def test_arctic_mano_bad_field_raises_error_naming_file_and_field(tmp_path, field, value, reason):
    path = tmp_path / "bad.mano.npy"
    write_arctic_mano_npy(path, {**mano_hand_params(4), field: value}, mano_hand_params(4, 2, side="left"))
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path)
    assert str(err.value) == f"{path} [right.{field}]: {reason}"


@pytest.mark.parametrize("present", ["left", "right"])
def test_arctic_mano_file_without_both_hands_raises_error_whichever_hand_is_read(tmp_path, present):
    path = tmp_path / "one.mano.npy"
    np.save(path, {present: mano_hand_params(2)}, allow_pickle=True)
    missing = "right" if present == "left" else "left"
    for hand in ("right", "left"):
        with pytest.raises(FormatError) as err:
            read_arctic_mano(path, hand)
        assert str(err.value) == (
            f"{path} [{missing}]: no '{missing}' entry; entries are ['{present}']. ARCTIC sequences are "
            "bimanual: a .mano.npy holds both 'right' and 'left'"
        )


def test_arctic_mano_file_with_one_hand_copied_into_the_other_raises_error(tmp_path):
    path = tmp_path / "copied.mano.npy"
    left = mano_hand_params(6, 2, side="left")
    write_arctic_mano_npy(path, dict(left), left)
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path, "left")
    assert str(err.value) == (
        f"{path} [right]: 'right' and 'left' hold identical trans and pose in every frame: one hand's data "
        "was copied into the other's entry (two hands cannot share a place); expected each hand's own fit"
    )


def test_arctic_mano_hands_of_different_lengths_raise_error(tmp_path):
    path = tmp_path / "uneven.mano.npy"
    write_arctic_mano_npy(path, mano_hand_params(6), mano_hand_params(5, 2, side="left"))
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path)
    assert str(err.value) == (
        f"{path} [left.rot]: the right hand has 6 frames and the left 5; expected the same"
    )


def test_npy_with_a_non_allowed_global_is_refused_and_not_executed(tmp_path):
    marker = tmp_path / "executed"
    path = tmp_path / "evil.mano.npy"
    write_malicious_npy(path, marker)
    expected = f"{path}: the pickle refers to the global 'os.system', which handsim refuses to load"
    with pytest.raises(FormatError, match="^" + re.escape(expected)):
        read_arctic_mano(path)
    with pytest.raises(FormatError, match="^" + re.escape(expected)):
        load_npy(path)
    assert not marker.exists()


def test_npy_with_a_pickled_class_instance_is_refused(tmp_path):
    path = tmp_path / "cls.mano.npy"
    np.save(path, {"right": {"rot": HandsomeObject()}}, allow_pickle=True)
    name = f"{HandsomeObject.__module__}.HandsomeObject"
    with pytest.raises(FormatError, match=re.escape(f"refers to the global '{name}', which handsim refuses")):
        read_arctic_mano(path)


class HandsomeObject:
    """A harmless class: even so, the restricted loader must not import it."""


def test_plain_npy_arrays_load_like_numpy(tmp_path):
    path = tmp_path / "a.npy"
    values = np.arange(12, dtype=np.float32).reshape(3, 4)
    np.save(path, np.asfortranarray(values))
    loaded = load_npy(path)
    np.testing.assert_array_equal(loaded, values)
    assert loaded.dtype == np.float32


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(n=st.integers(1, 20), seed=st.integers(0, 2**16), protocol=st.sampled_from([2, 3, 4, 5]))
def test_arctic_mano_round_trips_any_valid_sequence(tmp_path, n, seed, protocol):
    right, left = mano_hand_params(n, seed), mano_hand_params(n, seed + 1)
    path = tmp_path / f"p{protocol}.mano.npy"
    with path.open("wb") as f:  # np.save's layout, with the pickle protocol varied
        np.lib.format.write_array_header_1_0(f, {"descr": "|O", "fortran_order": False, "shape": ()})
        pickle.dump(np.array({"right": right, "left": left}, dtype=object), f, protocol=protocol)
    seq = read_arctic_mano(path, "left")
    np.testing.assert_array_equal(seq.pose, left["pose"])
    np.testing.assert_array_equal(seq.trans, left["trans"])


# --------------------------------------------------------------------------------------------------
# Object poses


def test_arctic_object_track_is_in_metres_with_wxyz_quaternions(tmp_path):
    path = tmp_path / "box_grab_01.object.npy"
    values = object_values(10)
    write_arctic_object_npy(path, values)
    assert np.load(path).dtype == np.float32 and np.load(path).shape == (10, 7)
    track = read_arctic_object(path)
    v = values.astype(float)
    np.testing.assert_allclose(track.pose[:, :3], v[:, 4:] / 1000.0, rtol=1e-15)
    np.testing.assert_allclose(
        track.pose[:, 3:], Rotation.from_rotvec(v[:, 1:4]).as_quat(scalar_first=True), atol=1e-15
    )
    np.testing.assert_array_equal(track.articulation, v[:, 0])
    assert track.valid.all() and track.valid.shape == (10,)


def test_arctic_top_part_vertex_follows_r_global_rz_minus_theta_plus_t(tmp_path):
    """ARCTIC: top vertex (mm) → R(ω) · R_z(−θ) · v + t; the track drives a hinge about (0, 0, −1)."""
    path = tmp_path / "laptop_use_01.object.npy"
    values = object_values(6, seed=4)
    write_arctic_object_npy(path, values)
    track = read_arctic_object(path)
    top_vertex_mm = np.array([120.0, -35.0, 48.0])
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    bottom = spec.worldbody.add_body(name="bottom")
    bottom.add_freejoint(name="free")
    bottom.add_geom(size=[0.01, 0, 0])
    top = bottom.add_body(name="top")
    top.add_joint(name="hinge", type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(ARCTIC_HINGE_AXIS))
    top.add_geom(size=[0.01, 0, 0])
    top.add_site(name="vertex", pos=(top_vertex_mm / 1000.0).tolist())
    model = compile_spec(spec)
    data = mujoco.MjData(model)
    for frame, row in enumerate(values.astype(float)):
        theta, omega, t_mm = row[0], row[1:4], row[4:]
        rz = Rotation.from_rotvec([0.0, 0.0, -theta]).as_matrix()
        expected = (Rotation.from_rotvec(omega).as_matrix() @ rz @ top_vertex_mm + t_mm) / 1000.0
        data.qpos[:7] = track.pose[frame]
        data.qpos[7] = track.articulation[frame]
        mujoco.mj_kinematics(model, data)
        np.testing.assert_allclose(data.site("vertex").xpos, expected, rtol=0, atol=1e-12)


def test_arctic_object_translation_in_metres_raises_error(tmp_path):
    path = tmp_path / "m.object.npy"
    values = object_values(5)
    values[:, 4:] /= 1000.0
    write_arctic_object_npy(path, values)
    largest = float(np.linalg.norm(values[:, 4:].astype(float), axis=1).max())
    with pytest.raises(FormatError) as err:
        read_arctic_object(path)
    assert str(err.value) == (
        f"{path} [translation]: every translation is shorter than 5 (largest {largest:.4g}); ARCTIC object "
        "translations are millimetres, so these look like metres"
    )


@pytest.mark.parametrize(
    ("values", "reason"),
    [
        (np.zeros((4, 7), dtype=np.int32), "expected floating-point values, got dtype int32"),
        (np.zeros((4, 6), dtype=np.float32), "expected shape (N, 7), got (4, 6)"),
        (np.zeros(7, dtype=np.float32), "expected shape (N, 7), got (7,)"),
    ],
)
def test_arctic_object_of_wrong_dtype_or_shape_raises_error_naming_the_file(tmp_path, values, reason):
    path = tmp_path / "bad.object.npy"
    np.save(path, values)
    with pytest.raises(FormatError) as err:
        read_arctic_object(path)
    assert str(err.value) == f"{path} [object]: {reason}"


def test_arctic_object_translation_spike_of_x1000_names_the_frame(tmp_path):
    path = tmp_path / "spike.object.npy"
    values = object_values(12)
    values[7, 4:] *= 1000.0
    write_arctic_object_npy(path, values)
    distance = float(np.linalg.norm(values[7, 4:].astype(float)))
    with pytest.raises(FormatError) as err:
        read_arctic_object(path)
    assert str(err.value) == (
        f"{path} [translation]: frame 7: the object is {distance:.4g} mm from the origin, beyond the 5000 mm "
        "of a capture volume (1 such frame); a corrupted or mis-scaled frame"
    )


def test_arctic_object_jumping_faster_than_it_can_be_carried_raises_error(tmp_path):
    path = tmp_path / "jump.object.npy"
    values = object_values(12)
    values[5:, 6] += np.float32(600.0)  # 0.6 m up in one frame: 18 m/s at 30 fps
    write_arctic_object_npy(path, values)
    t = values[:, 4:].astype(float)
    jump = float(np.linalg.norm(t[5] - t[4]))
    with pytest.raises(FormatError) as err:
        read_arctic_object(path)
    assert str(err.value) == (
        f"{path} [translation]: frame 5: the object jumps {jump:.4g} mm from frame 4 "
        f"({jump / 1000 * 30:.4g} m/s at 30 fps); expected at most 333.3 mm per frame (10 m/s)"
    )


def test_arctic_object_articulation_in_degrees_raises_error(tmp_path):
    path = tmp_path / "deg.object.npy"
    values = object_values(4)
    values[:, 0] = np.float32(75.0)
    write_arctic_object_npy(path, values)
    with pytest.raises(FormatError) as err:
        read_arctic_object(path)
    assert (
        str(err.value)
        == f"{path} [articulation]: articulation reaches 75; ARCTIC articulations are radians (≤ 2π)"
    )


# --------------------------------------------------------------------------------------------------
# End to end


def write_sequence(folder, n=6, name="box_grab_01"):
    raw = folder / "raw_seqs" / "s01"
    raw.mkdir(parents=True)
    mano_path = raw / f"{name}.mano.npy"
    write_arctic_mano_npy(mano_path, mano_hand_params(n, seed=7), mano_hand_params(n, seed=8, side="left"))
    write_arctic_object_npy(raw / f"{name}.object.npy", object_values(n))
    return mano_path


def test_arctic_sequence_reads_both_hands_and_the_object_beside_them(tmp_path):
    mano_path = write_sequence(tmp_path)
    seq = read_arctic_sequence(mano_path)
    assert (seq.nframes, seq.object_name, seq.subject, seq.name, seq.fps) == (
        6,
        "box",
        "s01",
        "box_grab_01",
        30.0,
    )
    assert (seq.right.side, seq.left.side) == ("right", "left")
    assert seq.hand("left") is seq.left
    assert seq.object_path == str(mano_path.with_name("box_grab_01.object.npy"))
    values = object_values(6).astype(float)
    assert seq.articulation_range == (values[:, 0].min(), values[:, 0].max())
    assert seq.object_sha256 == hashlib.sha256(Path(seq.object_path).read_bytes()).hexdigest()
    assert seq.notes == ()


def test_arctic_sequence_without_its_object_motion_raises_error(tmp_path):
    mano_path = write_sequence(tmp_path)
    obj = mano_path.with_name("box_grab_01.object.npy")
    obj.unlink()
    with pytest.raises(InputFileError) as err:
        read_arctic_sequence(mano_path)
    assert str(err.value) == (
        f"{obj}: file not found; the ARCTIC sequence box_grab_01.mano.npy needs its object motion "
        "box_grab_01.object.npy (from the same raw_seqs folder)"
    )


def test_arctic_sequence_with_an_object_track_of_another_length_raises_error(tmp_path):
    mano_path = write_sequence(tmp_path)
    obj = mano_path.with_name("box_grab_01.object.npy")
    write_arctic_object_npy(obj, object_values(9))
    with pytest.raises(FormatError) as err:
        read_arctic_sequence(mano_path)
    assert str(err.value) == (
        f"{obj} [object]: 9 frames, but box_grab_01.mano.npy has 6; expected one object pose per hand frame"
    )


def test_arctic_sequence_of_an_unknown_object_is_read_with_a_note(tmp_path):
    seq = read_arctic_sequence(write_sequence(tmp_path, name="teapot_use_01"))
    assert seq.object_name == "teapot"
    assert seq.notes == ("object 'teapot' (from the file name) is not one of ARCTIC's 11",)


def test_arctic_sequence_becomes_a_trajectory_with_its_object_track(tmp_path):
    pkl = tmp_path / "MANO_RIGHT.pkl"
    write_synthetic_mano_pkl(pkl)
    seq = read_arctic_sequence(write_sequence(tmp_path, n=5))
    model = read_mano_model(pkl)
    skeleton = mano_hand_skeleton(pkl, seq.right.shape)
    trajectory = mano_pose_to_trajectory(
        seq.right, skeleton, hands_mean=model.hands_mean, objects={"box": seq.object}
    )
    assert trajectory.nframes == 5
    np.testing.assert_allclose(trajectory.times, np.arange(5) / 30.0)
    assert trajectory.sha256 == seq.right.sha256
    assert trajectory.objects["box"].pose.shape == (5, 7)
    compile_spec(build_mano_hand(pkl, seq.right.shape, root="mocap"))
