"""ARCTIC motion files (``*.mano.npy``, ``*.object.npy``) in exactly ARCTIC's layout, read in SI units."""

from __future__ import annotations

import hashlib
import pickle
import re

import mujoco
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from handsim.builders.mano_hand import build_mano_hand, mano_hand_skeleton
from handsim.errors import FormatError
from handsim.io.arctic import ARCTIC_HINGE_AXIS
from handsim.io.arctic_motion import read_arctic_mano, read_arctic_object
from handsim.io.mano import mano_pose_to_trajectory, read_mano_model
from handsim.io.safe_pickle import load_npy
from handsim.sim import compile_spec
from tests.mano_fixtures import (
    mano_hand_params,
    write_arctic_mano_npy,
    write_arctic_object_npy,
    write_malicious_npy,
    write_synthetic_mano_pkl,
)


def object_values(n: int, seed: int = 0) -> np.ndarray:
    """ARCTIC object rows: articulation rad, axis-angle, translation mm (float32)."""
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [
            rng.uniform(0.0, 1.5, n),
            rng.normal(scale=1.0, size=(n, 3)),
            rng.uniform(-600.0, 600.0, size=(n, 3)),
        ]
    ).astype(np.float32)


@pytest.fixture
def mano_file(tmp_path):
    path = tmp_path / "box_grab_01.mano.npy"
    right, left = mano_hand_params(8, seed=1), mano_hand_params(8, seed=2)
    write_arctic_mano_npy(path, right, left)
    return path, right, left


# --------------------------------------------------------------------------------------------------
# MANO parameters


def test_arctic_mano_file_reads_both_hands_as_stored(mano_file):
    path, right, left = mano_file
    for hand, params in (("right", right), ("left", left)):
        seq = read_arctic_mano(path, hand)
        assert seq.side == hand
        for key in ("rot", "pose", "trans", "shape", "fitting_err"):
            np.testing.assert_array_equal(getattr(seq, key), params[key].astype(float))
            assert getattr(seq, key).dtype == np.float64
        assert seq.nframes == 8
        assert seq.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
        assert seq.source == str(path)


def test_arctic_mano_per_frame_shape_is_averaged_with_a_note(tmp_path):
    path = tmp_path / "s01.mano.npy"
    right = mano_hand_params(3)
    right["shape"] = np.tile(right["shape"], (3, 1))
    write_arctic_mano_npy(path, right, mano_hand_params(3))
    seq = read_arctic_mano(path)
    np.testing.assert_allclose(seq.shape, right["shape"][0], rtol=1e-7)
    assert seq.notes == ("right.shape given per frame; their mean used (largest spread 0.0e+00)",)


def test_arctic_mano_pose_of_wrong_length_raises_error_naming_file_and_field(tmp_path):
    path = tmp_path / "bad.mano.npy"
    right = mano_hand_params(4)
    right["pose"] = right["pose"][:, :12]
    write_arctic_mano_npy(path, right, mano_hand_params(4))
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
    right["trans"] = right["trans"] * 1000.0 + 400.0
    write_arctic_mano_npy(path, right, mano_hand_params(4))
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path)
    largest = float(np.abs(right["trans"].astype(float)).max())
    assert str(err.value) == (
        f"{path} [right.trans]: translation component reaches {largest:.4g}; MANO translations are metres "
        "and a hand more than 5 m from the origin means the file holds millimetres"
    )


@pytest.mark.parametrize(
    ("field", "value", "reason"),
    [
        ("rot", np.zeros((4, 3), dtype=np.int64), "expected floating-point values, got dtype int64"),
        ("trans", np.zeros((4, 2)), "expected shape (4, 3), got (4, 2)"),
        ("shape", np.zeros(8), "expected shape (10,), got (8,)"),
        ("fitting_err", np.zeros(5), "expected shape (4,), got (5,)"),
        ("rot", np.full((4, 3), np.nan), "non-finite value at frame 0"),
    ],
)
def test_arctic_mano_bad_field_raises_error_naming_file_and_field(tmp_path, field, value, reason):
    path = tmp_path / "bad.mano.npy"
    write_arctic_mano_npy(path, {**mano_hand_params(4), field: value}, mano_hand_params(4))
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path)
    assert str(err.value) == f"{path} [right.{field}]: {reason}"


def test_arctic_mano_file_without_the_hand_raises_error(tmp_path):
    path = tmp_path / "one.mano.npy"
    np.save(path, {"left": mano_hand_params(2)}, allow_pickle=True)
    with pytest.raises(FormatError) as err:
        read_arctic_mano(path, "right")
    assert str(err.value) == f"{path} [right]: no 'right' entry; entries are ['left']"


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


def test_arctic_sequence_becomes_a_trajectory_with_its_object_track(tmp_path):
    pkl = tmp_path / "MANO_RIGHT.pkl"
    write_synthetic_mano_pkl(pkl)
    mano_path, object_path = tmp_path / "s01.mano.npy", tmp_path / "s01.object.npy"
    write_arctic_mano_npy(mano_path, mano_hand_params(5, seed=7), mano_hand_params(5, seed=8))
    write_arctic_object_npy(object_path, object_values(5))
    seq = read_arctic_mano(mano_path, "right")
    model = read_mano_model(pkl)
    skeleton = mano_hand_skeleton(pkl, seq.shape)
    trajectory = mano_pose_to_trajectory(
        seq, skeleton, hands_mean=model.hands_mean, objects={"box": read_arctic_object(object_path)}
    )
    assert trajectory.nframes == 5
    np.testing.assert_allclose(trajectory.times, np.arange(5) / 30.0)
    assert trajectory.sha256 == seq.sha256
    assert trajectory.objects["box"].pose.shape == (5, 7)
    compile_spec(build_mano_hand(pkl, seq.shape, root="mocap"))
