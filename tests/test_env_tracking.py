"""What makes tracking learnable (issue 17): errors to the reference, a reference window, contact and held
state, object rotation and held reward terms, reset noise, the drift curriculum, Grasp-v0's open-hand zero
action and penetration penalty; the native vector env stays equal to N single envs with all of them."""

from __future__ import annotations

import re

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from scipy.spatial.transform import Rotation

import handsim  # noqa: F401  registers the environments
from handsim.datatypes.rotations import quat_error_rotvec as rotation_error
from handsim.envs.grasp_env import GraspEnv
from handsim.envs.replay_env import ReplayEnv
from handsim.envs.replay_reward import REWARD_TERMS, STEP_NUMBERS
from tests.helpers import glove_switch_inputs
from tests.test_vector_env import _pair, _run_both

REPLAY, GRASP = "handsim/Replay-v0", "handsim/Grasp-v0"
CONFIGURATIONS = [
    (REPLAY, {}),
    (REPLAY, {"reference_window": 3, "reset_noise_scale": 0.02, "random_start": True}),
    (REPLAY, {"max_object_drift": None}),
    (GRASP, {}),
    (GRASP, {"zero_action": "mid"}),
    (GRASP, {"root_control": "scripted"}),
    (GRASP, {"hand_action": "fingers"}),
    (GRASP, {"hand_action": "fingers", "root_control": "scripted", "zero_action": "mid"}),
    (GRASP, {"hand_action": "fingers", "hand_control": "rate"}),
    (GRASP, {"hand_control": "rate", "root_control": "scripted", "hand_rate": 1.0}),
    (GRASP, {"hand_action": "fingers", "hand_control": "rate", "max_penetration": 0.005}),
]


@pytest.mark.parametrize(("env_id", "kwargs"), CONFIGURATIONS)
def test_check_env_passes_for_every_documented_configuration(env_id, kwargs):
    check_env(gym.make(env_id, **kwargs).unwrapped, skip_render_check=True)


def test_rotation_error_is_the_rotation_vector_of_ref_times_q_inverse():
    rng = np.random.default_rng(0)
    out = np.zeros(3)
    for _ in range(50):
        ref, q = Rotation.random(2, random_state=rng)
        expected = (ref * q.inv()).as_rotvec()
        angle = rotation_error(ref.as_quat(scalar_first=True), -q.as_quat(scalar_first=True), out)
        np.testing.assert_allclose(out, expected, atol=1e-12)
        assert angle == pytest.approx(np.linalg.norm(expected), abs=1e-12)
    same = Rotation.random(random_state=rng).as_quat(scalar_first=True)
    assert rotation_error(same, same, out) == 0.0 and not out.any()


def test_error_features_are_the_reference_minus_the_state():
    env = ReplayEnv()
    s = env.observation_slices
    obs, _ = env.reset(seed=0)
    assert not obs[s["err_hand_qpos"]].any() and not obs[s["err_obj/position"]].any()
    rng = np.random.default_rng(1)
    for _ in range(40):
        obs, *_, info = env.step(rng.uniform(-1, 1, env.action_space.shape))
    k = info["frame"]
    ref_ctrl = env._ref_ctrl[k]
    np.testing.assert_array_equal(obs[s["err_hand_qpos"]], ref_ctrl - obs[s["hand_qpos"]])
    recorded = env.schedule.objects[0].pose[k]
    pose = obs[s["obj/pose"]]
    np.testing.assert_array_equal(obs[s["err_obj/position"]], recorded[:3] - pose[:3])
    expected = (
        Rotation.from_quat(recorded[3:], scalar_first=True)
        * Rotation.from_quat(pose[3:], scalar_first=True).inv()
    )
    np.testing.assert_allclose(obs[s["err_obj/rotation"]], expected.as_rotvec(), atol=1e-9)
    assert info["object_drift"] == pytest.approx(np.linalg.norm(recorded[:3] - pose[:3]), abs=1e-15)
    assert info["object_rotation_error"] == pytest.approx(expected.magnitude(), abs=1e-9)
    assert info["reward_rotation"] == pytest.approx(
        0.5 * np.exp(-(expected.magnitude() ** 2) / 0.2**2), abs=1e-9
    )


def test_the_reference_window_holds_the_next_k_frames_clamped_at_the_last():
    one, three = ReplayEnv(), ReplayEnv(reference_window=3)
    names = three.observation_names
    width = one.observation_slices["ref_obj/pose"].stop - one.observation_slices["ref_ctrl"].start
    assert three.observation_space.shape[0] == one.observation_space.shape[0] + 2 * width
    assert "ref2_ctrl/" + one.dof_names[0] in names and "ref3_obj/pose/qz" in names
    last = one.schedule.frames - 1
    for frame in (0, 100, last - 2, last - 1):
        obs, _ = three.reset(options={"frame": frame})
        s = three.observation_slices
        for j in (1, 2, 3):
            group = "ref_ctrl" if j == 1 else f"ref{j}_ctrl"
            np.testing.assert_array_equal(obs[s[group]], three._ref_ctrl[min(frame + j, last)])
        np.testing.assert_array_equal(
            obs[s["ref3_obj/pose"]], three.schedule.objects[0].pose[min(frame + 3, last)]
        )


def test_reset_info_has_every_step_number_and_the_terms_sum_to_the_reward():
    env = ReplayEnv()
    _, info = env.reset(seed=0)
    assert set(STEP_NUMBERS) <= set(info)
    assert (info["reward_tracking"], info["reward_object"], info["reward_rotation"]) == (1.0, 1.0, 0.5)
    _, reward, *_, info = env.step(np.full(env.action_space.shape, 0.5))
    assert reward == pytest.approx(sum(info[t] for t in REWARD_TERMS), abs=1e-12)


def test_reset_noise_is_seeded_bounded_and_within_the_joint_ranges():
    env = ReplayEnv(reset_noise_scale=0.05)
    plain = ReplayEnv()
    hand = env.observation_slices["hand_qpos"]
    a, _ = env.reset(seed=3)
    b, _ = env.reset(seed=3)
    c, _ = env.reset(seed=4)
    exact, _ = plain.reset(seed=3)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a[hand], c[hand])
    delta = a[hand] - exact[hand]
    assert np.abs(delta).max() <= 0.05 and np.abs(delta).max() > 0.02
    lo, hi = env.scene.layout.ctrl_range.T
    assert np.all(a[hand] >= lo) and np.all(a[hand] <= hi)


def test_the_drift_limit_can_be_changed_between_episodes():
    env = ReplayEnv(max_object_drift=1e-6)
    env.reset(seed=0)
    assert env.step(np.ones(env.action_space.shape))[2]
    env.set_max_object_drift(None)
    assert env.max_object_drift is None
    env.reset(seed=0)
    assert not env.step(np.ones(env.action_space.shape))[2]
    with pytest.raises(ValueError, match=re.escape("max_object_drift must be a finite number > 0, got -1.0")):
        env.max_object_drift = -1.0


def test_a_glove_scene_rewards_holding_the_object():
    scene, trajectory = glove_switch_inputs()
    env = ReplayEnv(scene, trajectory)
    s = env.observation_slices
    env.reset(seed=0)
    held = []
    for _ in range(env.schedule.frames - 1):
        obs, _, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
        assert info["reward_object"] == 0.0  # no recorded object
        assert info["reward_held"] == 0.5 * obs[s["contact_state"]][1]
        touching = np.count_nonzero(obs[s["contact_force"]] > 0)
        assert obs[s["contact_state"]][1] == (1.0 if touching >= 2 else 0.0)
        held.append(info["reward_held"])
        if terminated or truncated:
            break
    assert max(held) == 0.5 and held[0] == 0.0  # the closed hand grips the ball after contacts switch on


def test_native_vector_env_equals_single_envs_with_window_and_reset_noise():
    native, sync = _pair(3, random_start=True, reference_window=2, reset_noise_scale=0.03)
    try:
        assert _run_both(native, sync, steps=120, seed=5) >= 1
    finally:
        native.close()
        sync.close()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"reference_window": 0}, "reference_window must be a whole number ≥ 1, got 0"),
        ({"reference_window": 1.5}, "reference_window must be a whole number ≥ 1, got 1.5"),
        ({"reset_noise_scale": -0.1}, "reset_noise_scale must be a finite number ≥ 0, got -0.1"),
        ({"rotation_sigma": 0.0}, "rotation_sigma must be a finite number > 0, got 0.0"),
        ({"held_weight": float("nan")}, "held_weight must be a finite number ≥ 0, got nan"),
    ],
)
def test_replay_refuses_bad_new_keywords(kwargs, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        ReplayEnv(**kwargs)


def test_grasp_refuses_an_unknown_zero_action():
    with pytest.raises(
        ValueError, match=re.escape("unknown zero_action 'closed'; expected one of ['open', 'mid']")
    ):
        GraspEnv(zero_action="closed")


def test_grasp_refuses_an_unknown_hand_action():
    with pytest.raises(
        ValueError, match=re.escape("unknown hand_action 'tendons'; expected one of ['joints', 'fingers']")
    ):
        GraspEnv(hand_action="tendons")


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"hand_control": "torque"}, "unknown hand_control 'torque'; expected one of ['position', 'rate']"),
        ({"hand_control": "rate", "hand_rate": 0.0}, "hand_rate"),
        ({"hand_rate": -1.0}, "hand_rate"),
    ],
)
def test_grasp_refuses_a_bad_hand_control(kwargs, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        GraspEnv(**kwargs)


@pytest.mark.parametrize(("hand_action", "hand_rate"), [("fingers", 2.5), ("joints", 1.0)])
def test_a_rate_action_steps_as_the_position_action_it_integrates_to(hand_action, hand_rate):
    rate = GraspEnv(hand_action=hand_action, hand_control="rate", hand_rate=hand_rate)
    position = GraspEnv(hand_action=hand_action)
    n_hand = rate.action_space.shape[0] - 3
    command_slice = rate.observation_slices["hand_command"]
    assert rate.action_names == position.action_names
    assert rate.observation_names[command_slice][0] == f"hand_command/{rate.action_names[0]}"
    assert rate.observation_names[: command_slice.start] == position.observation_names
    rng = np.random.default_rng(5)
    for seed in (4, 5):  # the command starts again at the open hand after a reset
        rate.reset(seed=seed), position.reset(seed=seed)
        np.testing.assert_array_equal(rate.hand_command, np.zeros(n_hand))
        command = np.zeros(n_hand)
        for step in range(60):
            a = rng.uniform(-0.5, 1.3, n_hand + 3) if step < 40 else np.zeros(n_hand + 3)
            command = np.clip(command + np.clip(a[:n_hand], -1, 1) * (hand_rate * rate.dt), -1, 1)
            obs_r, reward_r, *_, info_r = rate.step(a)
            obs_p, reward_p, *_ = position.step(np.concatenate([command, a[n_hand:]]))
            np.testing.assert_array_equal(rate.data.ctrl, position.data.ctrl)
            np.testing.assert_array_equal(obs_r[: command_slice.start], obs_p)
            np.testing.assert_array_equal(obs_r[command_slice], command)
            np.testing.assert_array_equal(rate.hand_command, command)
            assert reward_r == reward_p and info_r["action_clipped"] == np.count_nonzero(np.abs(a) > 1)
        assert np.abs(command).max() > 0.1  # the rates moved the hand, and zero rates then held it


def test_a_zero_rate_action_holds_the_hand_open():
    env = GraspEnv(hand_action="fingers", hand_control="rate")
    env.reset(seed=0)
    lo, hi = env.scene.layout.ctrl_range.T
    for _ in range(50):
        env.step(np.zeros(env.action_space.shape))
    np.testing.assert_array_equal(env.data.ctrl, np.clip(0.0, lo, hi))


@pytest.mark.parametrize("zero_action", ["open", "mid"])
def test_a_finger_action_steps_as_the_joint_action_that_gives_each_dof_its_finger_value(zero_action):
    fingers, joints = (
        GraspEnv(hand_action="fingers", zero_action=zero_action),
        GraspEnv(zero_action=zero_action),
    )
    names = fingers.scene.layout.dof_names
    assert fingers.action_names[:6] == (
        "thumb_opposition",
        "thumb_flexion",
        "index",
        "middle",
        "ring",
        "little",
    )
    assert fingers.action_names[6:] == joints.action_names[-3:] == ("root_vx", "root_vy", "root_vz")
    group = {"th": 1, "if": 2, "mf": 3, "rf": 4, "lf": 5}  # written out here, not taken from the env
    rng = np.random.default_rng(3)
    fingers.reset(seed=4), joints.reset(seed=4)
    for _ in range(80):
        a = rng.uniform(-1.2, 1.2, 9)
        expanded = np.zeros(len(names) + 3)
        for i, name in enumerate(names):
            finger = name.split("_")[0]
            if "flex" in name:
                expanded[i] = a[group[finger]]
            elif finger == "th":
                expanded[i] = a[0]
        expanded[-3:] = a[6:]
        obs_f, reward_f, *_, info_f = fingers.step(a)
        obs_j, reward_j, *_ = joints.step(expanded)
        np.testing.assert_array_equal(fingers.data.ctrl, joints.data.ctrl)
        np.testing.assert_array_equal(obs_f, obs_j)
        assert reward_f == reward_j and info_f["action_clipped"] == np.count_nonzero(np.abs(a) > 1)
    ungrouped = [i for i, name in enumerate(names) if "flex" not in name and not name.startswith("th")]
    lo, hi = fingers.scene.layout.ctrl_range[ungrouped].T
    rest = np.clip(0.0, lo, hi) if zero_action == "open" else (lo + hi) / 2
    np.testing.assert_array_equal(fingers.data.ctrl[ungrouped], rest)  # a zero joint action


def test_grasp_zero_action_holds_the_hand_open_and_leaves_the_ball_on_the_table():
    for seed in (0, 1, 2):
        env = GraspEnv()
        env.reset(seed=seed)
        lo, hi = env.scene.layout.ctrl_range.T
        zero = np.zeros(env.action_space.shape)
        for _ in range(env.max_steps):
            _, reward, terminated, truncated, info = env.step(zero)
            assert not terminated
            assert reward == pytest.approx(sum(info[k] for k in info if k.startswith("reward_")), abs=1e-12)
        np.testing.assert_array_equal(env.data.ctrl, np.clip(0.0, lo, hi))
        assert truncated and not info["fell"] and abs(info["lift"]) < 1e-3


def test_grasp_penalises_penetration_per_millimetre():
    env = GraspEnv(penetration_weight=0.3)
    _, info = env.reset(seed=0)
    assert info["reward_penetration"] == -0.0 and info["reward_hold"] == 0.0
    for _ in range(60):
        _, _, _, _, info = env.step(np.concatenate([np.ones(len(env.dof_names)), [0.0, 0.0, -1.0]]))
        assert info["reward_penetration"] == pytest.approx(-300.0 * info["penetration"], abs=1e-15)


def test_grasp_max_penetration_ends_the_episode_at_the_first_deeper_step():
    """The same pressing actions, with and without the limit: identical until the first step deeper than
    it, which ends the limited episode (``penetrated``); the unlimited one goes on."""
    limit = 0.003
    free, limited = GraspEnv(), GraspEnv(max_penetration=limit)
    press = np.concatenate([np.ones(len(free.dof_names)), [0.0, 0.0, -1.0]])
    free.reset(seed=0), limited.reset(seed=0)
    for step in range(free.max_steps):
        obs_f, reward_f, terminated_f, _, info_f = free.step(press)
        obs_l, reward_l, terminated_l, _, info_l = limited.step(press)
        np.testing.assert_array_equal(obs_f, obs_l)
        assert reward_f == reward_l and not terminated_f and not info_f["penetrated"]
        assert terminated_l == info_l["penetrated"] == (info_l["penetration"] > limit)
        if terminated_l:
            ended_at = step
            break
    assert terminated_l and ended_at > 0  # pressing the closed hand onto the ball went deeper than 3 mm
    with pytest.raises(gym.error.ResetNeeded):
        limited.step(press)


@pytest.mark.parametrize("value", [0.0, -0.001, float("nan")])
def test_grasp_refuses_a_max_penetration_that_is_not_positive(value):
    with pytest.raises(ValueError, match="max_penetration must be a finite number > 0"):
        GraspEnv(max_penetration=value)


def test_fingertip_errors_are_zero_at_a_recorded_state_and_follow_the_sites():
    env = ReplayEnv()
    s = env.observation_slices
    assert env.observation_names[s["err_fingertips"]][:3] == tuple(
        f"err_fingertips/RFing_0_2_tip/{a}" for a in "xyz"
    )
    sites = env.scene.layout.tip_sites
    for frame in (0, 250):
        obs, _ = env.reset(options={"frame": frame})
        assert not obs[s["err_fingertips"]].any()
        recorded = env.data.site_xpos[sites].ravel().copy()
        for _ in range(20):
            obs, *_, info = env.step(np.full(env.action_space.shape, 0.7))
        # the sensors read the state one substep before the frame's: within 1 mm of the sites now
        now = env.data.site_xpos[sites].ravel()
        expected = env._ref_tips[info["frame"]] - now
        assert np.abs(obs[s["err_fingertips"]] - expected).max() < 1e-3
        assert np.abs(obs[s["err_fingertips"]]).max() > 1e-3  # the residual moved the fingers
        assert not np.array_equal(recorded, env._ref_tips[info["frame"]])
