"""The hand builder: compile, naming contract, dynamics options, masses, round trip, zero warnings."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from handsim.builders import build_hand, default_skeleton
from handsim.datatypes.skeleton import mj_name
from handsim.errors import ModelError, SkeletonError
from handsim.io import read_skeleton
from handsim.sim import compile_spec, warning_counts
from tests.conftest import GRASPDB, TZIONAS
from tests.helpers import random_in_limits, set_pose, site_positions

HAND_CASES = [
    ("default-0.16", lambda: default_skeleton(0.16), "capsules"),
    ("default-0.19", lambda: default_skeleton(0.19), "capsules"),
    ("default-0.22", lambda: default_skeleton(0.22), "capsules"),
    ("graspdb", lambda: read_skeleton(GRASPDB / "default.xmlskel"), "capsules"),
    ("tzionas", lambda: read_skeleton(TZIONAS / "Models/20/Model_Hand_R.SKEL"), "capsules"),
    ("tzionas-mesh", lambda: read_skeleton(TZIONAS / "Models/20/Model_Hand_R.SKEL"), "mesh"),
]
IDS = [c[0] for c in HAND_CASES]


@pytest.fixture(params=HAND_CASES, ids=IDS)
def hand(request):
    label, make, collision = request.param
    if label.startswith("graspdb") and not GRASPDB.exists():
        pytest.skip("needs ../shared/data/graspdb14 (present in CI, not in a user's clone)")
    skeleton = make()
    spec = build_hand(skeleton, collision=collision)
    return skeleton, spec, compile_spec(spec)


def test_hand_runs_one_second_of_random_in_range_control_with_zero_warnings(hand):
    _, _, model = hand
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    low, high = model.actuator_ctrlrange.T
    for step in range(round(1.0 / model.opt.timestep)):
        if step % 20 == 0:
            data.ctrl[:] = rng.uniform(low, high)
        mujoco.mj_step(model, data)
        assert warning_counts(data) == {}, f"step {step}"
    assert np.all(np.isfinite(data.qpos))


def test_hand_joint_names_equal_dof_names_and_every_joint_has_a_site(hand):
    skeleton, _, model = hand
    names = [model.joint(i).name for i in range(model.njnt)]
    assert names == list(skeleton.dof_names)
    assert [model.actuator(i).name for i in range(model.nu)] == [f"{d}_act" for d in skeleton.dof_names]
    for joint in skeleton.joints:
        model.site(mj_name(joint.name))  # raises KeyError if missing
    for tip in skeleton.fingertips:
        model.site(mj_name(tip))
    assert model.nsite == skeleton.njoints


def test_hand_joint_ranges_and_ctrlranges_equal_dof_limits(hand):
    skeleton, _, model = hand
    np.testing.assert_allclose(model.jnt_range, skeleton.limits)
    np.testing.assert_allclose(model.actuator_ctrlrange, skeleton.limits)
    assert np.all(model.jnt_limited == 1)
    assert all(int(t) == int(mujoco.mjtJoint.mjJNT_HINGE) for t in model.jnt_type)


def test_hand_uses_implicitfast_elliptic_cones_and_impratio_above_one(hand):
    _, _, model = hand
    assert int(model.opt.integrator) == int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST)
    assert int(model.opt.cone) == int(mujoco.mjtCone.mjCONE_ELLIPTIC)
    assert model.opt.impratio > 1
    assert np.all(model.dof_armature > 0)
    assert np.all(model.dof_damping > 0)


def test_hand_mass_is_anthropometric(hand):
    skeleton, _, model = hand
    mass = float(model.body_subtreemass[0])
    expected = 0.45 * (skeleton.hand_length / 0.19) ** 3
    assert mass == pytest.approx(expected, rel=1e-9)
    if 0.185 <= skeleton.hand_length <= 0.205:  # a typical adult hand
        assert 0.4 <= mass <= 0.6


def test_hand_has_no_contacts_in_the_rest_pose(hand):
    _, _, model = hand
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert data.ncon == 0


def test_hand_mjcf_round_trip_keeps_counts_and_kinematics(hand):
    _, spec, model = hand
    again = mujoco.MjSpec.from_string(spec.to_xml()).compile()
    for attr in ("nbody", "njnt", "nq", "nv", "nu", "ngeom", "nsite", "nmesh", "nexclude"):
        assert getattr(again, attr) == getattr(model, attr), attr
    np.testing.assert_allclose(again.body_mass, model.body_mass, rtol=1e-5)  # MJCF keeps 6 digits
    np.testing.assert_allclose(again.jnt_range, model.jnt_range, rtol=1e-5)


def test_numpy_and_mujoco_fk_agree_on_random_in_limit_poses(hand):
    skeleton, _, model = hand
    data = mujoco.MjData(model)
    poses = random_in_limits(skeleton, 25, seed=1)
    numpy_fk = skeleton.forward_kinematics(poses).positions
    for q, expected in zip(poses, numpy_fk, strict=True):
        set_pose(model, data, skeleton, q)
        np.testing.assert_allclose(site_positions(model, data, skeleton), expected, atol=1e-9, rtol=0)


def test_adjacent_links_do_not_collide():
    skeleton = default_skeleton()
    model = compile_spec(build_hand(skeleton))
    excluded = {
        frozenset((model.body(int(b1)).name, model.body(int(b2)).name))
        for b1, b2 in zip(model.exclude_signature >> 16, model.exclude_signature & 0xFFFF, strict=True)
    }
    for child, parent in (("if_mcp", "root"), ("if_pip", "if_mcp"), ("th_mcp", "th_tmc"), ("th_tmc", "root")):
        assert frozenset((child, parent)) in excluded


def test_build_hand_raises_error_if_collision_option_is_unknown():
    with pytest.raises(ModelError, match="unknown collision option 'spheres'; expected 'capsules' or 'mesh'"):
        build_hand(default_skeleton(), collision="spheres")


def test_build_hand_raises_error_if_mesh_collision_has_no_skinned_mesh():
    with pytest.raises(ModelError, match=r"has no skinned mesh .*use collision='capsules'"):
        build_hand(default_skeleton(), collision="mesh")


def test_build_hand_honours_an_explicit_mass():
    model = compile_spec(build_hand(default_skeleton(), mass=0.5))
    assert float(model.body_subtreemass[0]) == pytest.approx(0.5)


def test_skeleton_lookup_raises_error_listing_valid_names():
    skeleton = default_skeleton()
    with pytest.raises(SkeletonError, match=r"has no joint 'if-mc'; joints are \['root', 'th-tmc'"):
        skeleton.joint_index("if-mc")
    with pytest.raises(SkeletonError, match=r"has no DoF 'if_mcp'; DoFs are \['root_abd'"):
        skeleton.dof_index("if_mcp")
