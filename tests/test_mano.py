"""MANO: restricted pkl loading, shaped joints, the hinge skeleton, pose conversion, and the MuJoCo hand."""

from __future__ import annotations

import re
import sys

import mujoco
import numpy as np
import pytest
import scipy.sparse
from scipy.spatial.transform import Rotation

from handsim.builders.mano_hand import build_mano_hand, mano_hand_skeleton, mano_model_skeleton, mano_skeleton
from handsim.datatypes.rotations import axis_angle_to_matrix, matrix_to_zyx, rotation_error, zyx_to_matrix
from handsim.errors import FormatError, ModelError, SkeletonError, TrajectoryError
from handsim.io.arctic.mano import FINGERS, MANO_JOINT_NAMES, mano_joints, mano_mean_joints, read_mano_model
from handsim.io.arctic.mano_pickle import CscStub, CsrStub
from handsim.io.arctic.mano_pose import MANOSequence, full_mano_pose, mano_pose_to_trajectory
from handsim.io.safe_pickle import load_restricted_pickle
from handsim.sim import compile_spec, warning_counts
from tests.mano_fixtures import (
    PARENTS,
    TIP_IDS,
    malicious_pickle,
    mujoco_sites,
    numpy_mano_fk,
    write_synthetic_mano_pkl,
)

INDEX = {n: i for i, n in enumerate(MANO_JOINT_NAMES)}


@pytest.fixture(scope="module")
def mano_pkl(tmp_path_factory):
    path = tmp_path_factory.mktemp("mano") / "MANO_RIGHT.pkl"
    return path, write_synthetic_mano_pkl(path)


@pytest.fixture(scope="module")
def mano_left_pkl(tmp_path_factory):
    path = tmp_path_factory.mktemp("mano_left") / "MANO_LEFT.pkl"
    return path, write_synthetic_mano_pkl(path, side="left", seed=3)


# --------------------------------------------------------------------------------------------------
# Restricted loading


@pytest.mark.parametrize("protocol", [0, 1, 2, 4, 5])
def test_mano_pkl_is_read_without_chumpy_importable(tmp_path, monkeypatch, protocol):
    path = tmp_path / "MANO_RIGHT.pkl"
    arrays = write_synthetic_mano_pkl(path, protocol=protocol)
    raw = path.read_bytes()
    assert b"chumpy.ch" in raw and b"scipy.sparse.csc" in raw  # references them like a real MANO file
    monkeypatch.setitem(sys.modules, "chumpy", None)  # any import of chumpy now fails
    model = read_mano_model(path)
    for key in (
        "v_template",
        "shapedirs",
        "J_regressor",
        "weights",
        "posedirs",
        "hands_components",
        "hands_mean",
    ):
        np.testing.assert_array_equal(
            getattr(model, key if key != "J_regressor" else "J_regressor"), arrays[key]
        )
    np.testing.assert_array_equal(model.faces, arrays["f"])
    assert model.parents.tolist() == list(PARENTS)
    assert model.side == "right"
    assert "chumpy.ch" not in sys.modules


def test_pickle_that_calls_os_system_is_refused_and_not_run(tmp_path):
    marker = tmp_path / "executed"
    path = tmp_path / "evil.pkl"
    path.write_bytes(malicious_pickle(marker))
    expected = (
        f"{path}: the pickle refers to the global 'os.system', which handsim refuses to load (it was neither "
        "imported nor called); allowed globals: "
    )
    with pytest.raises(FormatError, match="^" + re.escape(expected)):
        load_restricted_pickle(path)
    with pytest.raises(FormatError, match="^" + re.escape(expected)):
        read_mano_model(path)
    assert not marker.exists()


def test_mano_pkl_missing_an_entry_raises_error_naming_it(tmp_path):
    import pickle

    arrays = write_synthetic_mano_pkl(tmp_path / "ok.pkl")
    path = tmp_path / "MANO_RIGHT.pkl"
    path.write_bytes(pickle.dumps({k: v for k, v in arrays.items() if k != "weights"}, protocol=2))
    with pytest.raises(FormatError) as err:
        read_mano_model(path)
    assert str(err.value) == (
        f"{path} [weights]: missing entry; a MANO model needs "
        "['v_template', 'shapedirs', 'J_regressor', 'kintree_table', 'weights', 'f']"
    )


def test_mano_pkl_with_a_wrong_regressor_shape_raises_error_naming_it(tmp_path):
    import pickle

    arrays = write_synthetic_mano_pkl(tmp_path / "ok.pkl")
    path = tmp_path / "MANO_RIGHT.pkl"
    path.write_bytes(pickle.dumps({**arrays, "J_regressor": arrays["J_regressor"][:15]}, protocol=2))
    with pytest.raises(FormatError) as err:
        read_mano_model(path)
    assert str(err.value) == f"{path} [J_regressor]: expected shape (16, 778), got (15, 778)"


# --------------------------------------------------------------------------------------------------
# Joints, skeleton, fingertips


@pytest.mark.parametrize("layout", ["csc", "csr"])
def test_sparse_regressor_is_rebuilt_exactly_as_scipy_sparse_densifies_it(layout):
    rng = np.random.default_rng(3)
    dense = np.where(rng.uniform(size=(16, 50)) < 0.2, rng.normal(size=(16, 50)), 0.0)
    matrix = scipy.sparse.csc_array(dense) if layout == "csc" else scipy.sparse.csr_array(dense)
    stub = CscStub() if layout == "csc" else CsrStub()
    stub.__setstate__(
        {"data": matrix.data, "indices": matrix.indices, "indptr": matrix.indptr, "_shape": (16, 50)}
    )
    np.testing.assert_array_equal(stub.to_dense(), dense)


_INCONSISTENT = "inconsistent csc arrays for shape (16, 2): "  # then scipy.sparse's own reason


@pytest.mark.parametrize(
    ("indices", "indptr", "message"),
    [
        ([0, 16], [0, 1, 2], _INCONSISTENT),  # a row index past the last row
        ([0, 1], [1, 1, 2], _INCONSISTENT),  # index pointers not starting at 0 (was read shifted before)
        ([0, 1], [0, 2, 1], _INCONSISTENT),  # decreasing index pointers
        ([0.5, 1], [0, 1, 2], "sparse indices and indptr must be integers, got float64 and int64"),
    ],
)
def test_inconsistent_sparse_regressor_arrays_raise_before_densifying(indices, indptr, message):
    stub = CscStub()
    stub.__setstate__(
        {"data": np.ones(2), "indices": np.array(indices), "indptr": np.array(indptr), "_shape": (16, 2)}
    )
    with pytest.raises(ValueError, match="^" + re.escape(message)):
        stub.to_dense()


def test_mano_joints_are_regressed_from_shaped_vertices(mano_pkl):
    path, arrays = mano_pkl
    model = read_mano_model(path)
    betas = np.linspace(-1.0, 1.0, 10)
    expected = arrays["J_regressor"] @ (
        arrays["v_template"] + np.einsum("vcs,s->vc", arrays["shapedirs"], betas)
    )
    np.testing.assert_allclose(mano_joints(model, betas), expected, rtol=0, atol=1e-15)
    np.testing.assert_allclose(mano_joints(model, betas[:4]), mano_joints(model, [*betas[:4], *[0.0] * 6]))
    with pytest.raises(ModelError, match=r"^betas must be at most 10 finite values"):
        mano_joints(model, np.zeros(11))


def test_mano_skeleton_has_45_hinges_in_mano_order_with_ranges_for_continuous_angles():
    skeleton = mano_skeleton(mano_mean_joints())
    assert skeleton.name == "mano_right"
    assert skeleton.ndof == 45
    assert skeleton.dof_names[:6] == ("index1_z", "index1_y", "index1_x", "index2_z", "index2_y", "index2_x")
    assert skeleton.dof_names[-3:] == ("thumb3_z", "thumb3_y", "thumb3_x")
    assert skeleton.fingertips == ("thumb_tip", "index_tip", "middle_tip", "ring_tip", "pinky_tip")
    assert all(np.array_equal(j.frame, np.eye(3)) for j in skeleton.joints)
    limits = skeleton.limits.reshape(15, 3, 2)
    np.testing.assert_allclose(limits[:, 0], [[-2 * np.pi, 2 * np.pi]] * 15)
    np.testing.assert_allclose(limits[:, 1], [[-2 * np.pi, 2 * np.pi]] * 15)
    np.testing.assert_allclose(limits[:, 2], [[-2 * np.pi, 2 * np.pi]] * 15)


def test_fingertips_are_the_mano_tip_vertices_when_a_model_is_given(mano_pkl):
    path, arrays = mano_pkl
    skeleton = mano_model_skeleton(read_mano_model(path))
    for finger in FINGERS:
        tip = skeleton.joints[skeleton.joint_index(f"{finger}_tip")]
        np.testing.assert_array_equal(tip.position, arrays["v_template"][TIP_IDS[finger]])
        assert skeleton.joints[tip.parent].name == f"{finger}3"
    assert "fingertips at MANO vertices 744/320/443/554/671" in skeleton.notes[0]


def test_fingertips_are_extrapolated_when_the_model_has_too_few_vertices(tmp_path):
    write_synthetic_mano_pkl(tmp_path / "small.pkl", nverts=200)
    skeleton = mano_model_skeleton(read_mano_model(tmp_path / "small.pkl"))
    assert skeleton.notes == ("model has 200 vertices, fewer than MANO's 778: fingertips extrapolated",)
    j = {n: skeleton.joints[skeleton.joint_index(n)].position for n in skeleton.joint_names}
    direction = j["index3"] - j["index2"]
    np.testing.assert_allclose(np.cross(j["index_tip"] - j["index3"], direction), 0.0, atol=1e-15)


def test_mano_skeleton_raises_error_if_side_contradicts_the_joints():
    with pytest.raises(SkeletonError) as err:
        mano_skeleton(mano_mean_joints("right"), side="left")
    assert (
        str(err.value)
        == "the joints are a right MANO hand (fingers towards −x from the wrist), but side='left'"
    )


def test_left_model_file_for_a_right_hand_raises_error(mano_left_pkl):
    path, _ = mano_left_pkl
    with pytest.raises(ModelError) as err:
        build_mano_hand(path, side="right")
    assert str(err.value) == f"{path}: the model is a left hand, but side='right'"


# --------------------------------------------------------------------------------------------------
# Pose conversion


def test_zyx_decomposition_is_exact_including_gimbal_lock():
    rng = np.random.default_rng(0)
    rotations = Rotation.random(2000, random_state=1).as_matrix()
    assert rotation_error(zyx_to_matrix(matrix_to_zyx(rotations)), rotations).max() < 1e-14
    locked = zyx_to_matrix(
        np.column_stack([rng.uniform(-3, 3, 50), np.full(50, np.pi / 2), rng.uniform(-3, 3, 50)])
    )
    assert rotation_error(zyx_to_matrix(matrix_to_zyx(locked)), locked).max() < 1e-14
    near = zyx_to_matrix(
        np.column_stack([np.full(50, 0.4), -np.pi / 2 + np.logspace(-12, -4, 50), np.full(50, 1.0)])
    )
    assert rotation_error(zyx_to_matrix(matrix_to_zyx(near)), near).max() < 1e-14
    aa = rng.normal(scale=1.5, size=(500, 3))
    np.testing.assert_allclose(axis_angle_to_matrix(aa), Rotation.from_rotvec(aa).as_matrix(), atol=1e-15)


def _sequence(n, seed, side="right", flat=False, hands_mean=None):
    rng = np.random.default_rng(seed)
    return MANOSequence(
        rot=rng.normal(scale=1.2, size=(n, 3)),
        pose=rng.normal(scale=0.6, size=(n, 45)),
        trans=rng.uniform(-0.5, 0.5, size=(n, 3)),
        shape=rng.normal(scale=0.8, size=10),
        side=side,
    )


def test_zero_pose_gives_the_rest_joints_exactly(mano_pkl):
    path, _ = mano_pkl
    skeleton = mano_hand_skeleton(path)
    seq = MANOSequence(
        rot=np.zeros((1, 3)), pose=np.zeros((1, 45)), trans=np.zeros((1, 3)), shape=np.zeros(10)
    )
    trajectory = mano_pose_to_trajectory(seq, skeleton, flat_hand_mean=True)
    assert np.all(trajectory.targets == 0.0)
    np.testing.assert_array_equal(trajectory.root_pose[0], [*skeleton.joints[0].position, 1, 0, 0, 0])
    sites = mujoco_sites(build_mano_hand(path, root="mocap"), skeleton, trajectory, 0)
    for joint in skeleton.joints:
        np.testing.assert_allclose(sites[joint.name], joint.position, rtol=0, atol=1e-15)


@pytest.mark.parametrize("side", ["right", "left"])
def test_mujoco_joint_positions_equal_numpy_mano_kinematics_on_random_poses(mano_pkl, mano_left_pkl, side):
    path, arrays = mano_pkl if side == "right" else mano_left_pkl
    model = read_mano_model(path)
    seq = _sequence(6, seed=5, side=side)
    skeleton = mano_hand_skeleton(path, seq.shape, side=side)
    trajectory = mano_pose_to_trajectory(seq, skeleton, hands_mean=model.hands_mean)
    spec = build_mano_hand(path, seq.shape, side=side, root="mocap")
    worst = 0.0
    for frame in range(seq.nframes):
        full = seq.pose[frame] + arrays["hands_mean"]  # ARCTIC/smplx: flat_hand_mean=False
        joints, frames, expected = numpy_mano_fk(arrays, seq.shape, seq.rot[frame], full, seq.trans[frame])
        sites = mujoco_sites(spec, skeleton, trajectory, frame)
        got = np.array([sites[name] for name in MANO_JOINT_NAMES])
        worst = max(worst, float(np.abs(got - expected).max()))
        for finger in FINGERS:  # tips ride rigidly on the last joint
            j3 = INDEX[f"{finger}3"]
            tip_rest = skeleton.joints[skeleton.joint_index(f"{finger}_tip")].position
            tip = expected[j3] + frames[j3] @ (tip_rest - joints[j3])
            np.testing.assert_allclose(sites[f"{finger}_tip"], tip, rtol=0, atol=1e-9)
    assert worst < 1e-9
    residual = next(n for n in trajectory.notes if "residual" in n)
    assert float(re.search(r"residual (\S+) rad", residual).group(1)) < 1e-12


def test_root_pose_rotates_about_the_wrist_then_translates(mano_pkl):
    path, _ = mano_pkl
    skeleton = mano_hand_skeleton(path)
    rot = np.array([[0.0, 0.0, np.pi / 2]])
    seq = MANOSequence(rot=rot, pose=np.zeros((1, 45)), trans=np.array([[0.1, 0.2, 0.3]]), shape=np.zeros(10))
    trajectory = mano_pose_to_trajectory(seq, skeleton, flat_hand_mean=True)
    wrist = skeleton.joints[0].position
    np.testing.assert_allclose(trajectory.root_pose[0, :3], wrist + np.array([0.1, 0.2, 0.3]))
    np.testing.assert_allclose(trajectory.root_pose[0, 3:], [np.sqrt(0.5), 0, 0, np.sqrt(0.5)], atol=1e-15)


def test_pca_coefficients_are_expanded_with_the_components(mano_pkl):
    path, _ = mano_pkl
    model = read_mano_model(path)
    coeffs = np.random.default_rng(2).normal(size=(4, 12))
    seq = MANOSequence(rot=np.zeros((4, 3)), pose=coeffs, trans=np.zeros((4, 3)), shape=np.zeros(10))
    full = full_mano_pose(seq, hands_mean=model.hands_mean, hands_components=model.hands_components)
    np.testing.assert_allclose(full, coeffs @ model.hands_components[:12] + model.hands_mean)


def test_pca_coefficients_without_components_raise_error():
    seq = MANOSequence(
        rot=np.zeros((2, 3)), pose=np.zeros((2, 12)), trans=np.zeros((2, 3)), shape=np.zeros(10)
    )
    with pytest.raises(TrajectoryError) as err:
        mano_pose_to_trajectory(seq, mano_hand_skeleton(), flat_hand_mean=True)
    assert str(err.value) == (
        "pose has 12 values per frame: PCA coefficients need hands_components (MANO's PCA basis, "
        "read_mano_model(pkl).hands_components); axis-angle poses have 45"
    )


def test_left_hand_sequence_for_a_right_hand_raises_error():
    seq = _sequence(2, seed=0, side="left")
    with pytest.raises(TrajectoryError) as err:
        mano_pose_to_trajectory(seq, mano_hand_skeleton(side="right"), flat_hand_mean=True)
    assert str(err.value) == (
        "a left-hand MANO sequence cannot drive a right MANO hand: MANO's left model is the mirror image of "
        "the right one; build the hand with side='left' (and MANO_LEFT.pkl)"
    )


def test_relative_pose_without_hands_mean_raises_error():
    with pytest.raises(TrajectoryError, match=r"^flat_hand_mean=False: the pose is relative to MANO's mean"):
        mano_pose_to_trajectory(_sequence(2, seed=0), mano_hand_skeleton())


# --------------------------------------------------------------------------------------------------
# The MuJoCo hand


def test_build_mano_hand_without_a_model_uses_the_bundled_mean_joints():
    spec = build_mano_hand()
    model = compile_spec(spec)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    joints = mano_mean_joints()
    for name, position in zip(MANO_JOINT_NAMES, joints, strict=True):
        np.testing.assert_allclose(data.site(name).xpos, position, rtol=0, atol=1e-15)
    assert (model.njnt, model.nu, model.nmocap) == (45, 45, 0)
    assert [model.actuator(i).name for i in range(3)] == ["index1_z_act", "index1_y_act", "index1_x_act"]


@pytest.mark.parametrize("collision", ["capsules", "mesh"])
def test_mano_hand_has_no_rest_contacts_and_runs_one_second_of_random_control(mano_pkl, collision):
    path, _ = mano_pkl
    model = compile_spec(build_mano_hand(path, collision=collision))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert data.ncon == 0
    if collision == "mesh":
        hulls = [model.geom(i).name for i in range(model.ngeom) if model.geom(i).name.endswith("_hull")]
        assert "wrist_hull" in hulls and "index3_hull" in hulls and "thumb1_hull" in hulls
    rng = np.random.default_rng(0)
    low, high = model.actuator_ctrlrange.T
    for step in range(round(1.0 / model.opt.timestep)):
        if step % 50 == 0:
            data.ctrl[:] = rng.uniform(0.5 * low, 0.5 * high)
        mujoco.mj_step(model, data)
    assert warning_counts(data) == {}


def test_build_mano_hand_raises_error_for_mesh_collision_without_a_model():
    with pytest.raises(ModelError) as err:
        build_mano_hand(collision="mesh")
    assert (
        str(err.value)
        == "collision='mesh' needs the MANO mesh: pass pkl_path (MANO_RIGHT.pkl / MANO_LEFT.pkl)"
    )


def test_build_mano_hand_raises_error_for_betas_without_a_model():
    with pytest.raises(ModelError, match=r"^betas need the MANO model file \(pkl_path\)"):
        build_mano_hand(betas=np.ones(10))
