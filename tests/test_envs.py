"""Gymnasium environments: registration, API conformance, determinism, pickling, vectorisation, rendering,
bad inputs, and that Replay-v0 with zero residuals is the replay core bitwise."""

from __future__ import annotations

import functools
import os
import pickle
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import handsim  # noqa: F401  registers the environments
from handsim.builders.graspdb_objects import UnknownObjectError
from handsim.datatypes.fingers import finger_of
from handsim.envs import ENVS, register_envs
from handsim.envs.grasp_env import GraspEnv
from handsim.envs.recordings import default_replay_inputs
from handsim.envs.replay_env import ReplayEnv
from handsim.envs.replay_reward import REWARD_TERMS
from handsim.sim.drive import scenario_switches
from handsim.sim.replay import ReplayConfig, replay
from tests.helpers import glove_switch_inputs

ROOT = Path(__file__).resolve().parents[1]
REPLAY, GRASP = "handsim/Replay-v0", "handsim/Grasp-v0"
IDS = (REPLAY, GRASP)
REPLAY_REWARDS = REWARD_TERMS  # tracking, object, rotation, articulation, held, penetration, action
GRASP_REWARDS = (
    "reward_reach",
    "reward_contact",
    "reward_lift",
    "reward_hold",
    "reward_penetration",
    "reward_success",
)


@functools.lru_cache(maxsize=1)
def _in_process_gl() -> str:
    """'' when this process can render offscreen, else why not.

    A process that imported ``mujoco`` before ``handsim`` (e.g. the whole test suite) keeps MuJoCo's
    default GLFW backend, which cannot render without a display.
    """
    from handsim.envs import RenderError

    env = GraspEnv(render_mode="rgb_array", width=32, height=24)
    try:
        env.reset(seed=0)
        env.render()
    except RenderError as err:
        return str(err)
    finally:
        env.close()
    return ""


def _actions(env: gym.Env, n: int, seed: int = 0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    shape = env.action_space.shape
    return [rng.uniform(-1, 1, shape).astype(np.float32) for _ in range(n)]


def _rollout(env: gym.Env, seed: int, actions: list[np.ndarray]) -> list[tuple]:
    obs, _ = env.reset(seed=seed)
    out = [(obs,)]
    for a in actions:
        obs, reward, terminated, truncated, info = env.step(a)
        out.append((obs, reward, terminated, truncated, info))
        if terminated or truncated:
            break
    return out


def _same(a: list[tuple], b: list[tuple]) -> bool:
    if len(a) != len(b):
        return False
    for x, y in zip(a, b, strict=True):
        if not np.array_equal(x[0], y[0]) or x[1:] != y[1:]:
            return False
    return True


# ---- registration ----------------------------------------------------------------------------------------
def test_import_handsim_registers_both_envs():
    for env_id in IDS:
        assert env_id in gym.registry
        assert gym.registry[env_id].entry_point == ENVS[env_id]


def test_registering_again_neither_warns_nor_duplicates():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        register_envs()
    assert sum(1 for k in gym.registry if k.startswith("handsim/")) == len(ENVS)


def test_importing_handsim_does_not_import_mujoco():
    code = (
        "import sys, handsim, gymnasium; assert 'handsim/Replay-v0' in gymnasium.registry; "
        "print('mujoco' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("env_id", IDS)
def test_make_after_import_handsim_gives_the_env(env_id):
    env = gym.make(env_id)
    assert isinstance(env.unwrapped, ReplayEnv if env_id == REPLAY else GraspEnv)
    assert env.unwrapped.frame_skip == 5
    assert env.unwrapped.dt == pytest.approx(0.01)
    env.close()


# ---- gymnasium's checker ---------------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", IDS)
def test_check_env_passes(env_id):
    env = gym.make(env_id)
    # the render modes are checked through env.spec.make(render_mode=...) when this process can render;
    # test_render_rgb_array_headless checks rendering in a fresh process either way
    check_env(env.unwrapped, skip_render_check=bool(_in_process_gl()))
    env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_observation_names_and_slices_cover_the_observation(env_id):
    env = gym.make(env_id).unwrapped
    names, slices = env.observation_names, env.observation_slices
    assert len(names) == env.observation_space.shape[0]
    assert len(set(names)) == len(names)
    covered = sorted(i for s in slices.values() for i in range(s.start, s.stop))
    assert covered == list(range(len(names)))
    assert names[slices["hand_qpos"]] == tuple(f"hand_qpos/{n}" for n in env.dof_names)


# ---- determinism, pickling, vectorisation -----------------------------------------------------------------
@pytest.mark.parametrize("env_id", IDS)
def test_same_seed_gives_bitwise_identical_observation_sequences(env_id):
    env_a, env_b = gym.make(env_id), gym.make(env_id)
    actions = _actions(env_a, 20)
    first = _rollout(env_a, 7, actions)
    assert len(first) == 21
    assert _same(first, _rollout(env_b, 7, actions))
    assert _same(first, _rollout(env_a, 7, actions))  # and again after a reset of the same env


def test_grasp_seed_moves_the_object():
    env = gym.make(GRASP)
    obj = env.unwrapped.observation_slices["obj/pose"]
    a, _ = env.reset(seed=1)
    b, _ = env.reset(seed=2)
    assert not np.array_equal(a[obj][:2], b[obj][:2])
    assert np.all(np.abs(a[obj][:2] - b[obj][:2]) <= 2 * 0.01)


def test_replay_random_start_is_seeded():
    env = gym.make(REPLAY, random_start=True)
    starts = [env.reset(seed=s)[1]["frame"] for s in (3, 3, 4)]
    assert starts[0] == starts[1]
    assert starts[0] != starts[2]


def test_replay_with_zero_residuals_is_the_replay_core_bitwise():
    scene, trajectory = default_replay_inputs()
    result = replay(scene, trajectory, ReplayConfig(keep_states=True))
    env = ReplayEnv(scene, trajectory)
    env.reset(seed=0)
    zero = np.zeros(env.action_space.shape)
    assert np.array_equal(env.data.qpos, result.states[0])
    steps = 0
    truncated = False
    while not truncated:
        _, _, terminated, truncated, info = env.step(zero)
        steps += 1
        assert not terminated
        assert np.array_equal(env.data.qpos, result.states[steps]), f"frame {steps}"
    assert steps == env.schedule.frames - 1 == result.states.shape[0] - 1
    assert info["frame"] == steps


def test_replay_env_switches_contacts_and_releases_a_glove_scenes_support_like_the_replay_core():
    scene, trajectory = glove_switch_inputs()
    result = replay(scene, trajectory, ReplayConfig(keep_states=True))
    env = ReplayEnv(scene, trajectory)
    env.reset(seed=0)
    assert "ref_root_pose" not in env.observation_slices
    support = scene.layout.objects[0].support_eq
    switches = scenario_switches(scene, env.schedule, 0.1)
    assert 0 < switches.contact_frame < switches.release_frame
    zero = np.zeros(env.action_space.shape)
    for frame in range(1, result.states.shape[0]):
        env.step(zero)
        assert np.array_equal(env.data.qpos, result.states[frame]), f"frame {frame}"
        assert env.data.eq_active[support] == (frame <= switches.release_frame)
        contacts_on = env.model.geom_contype[scene.layout.objects[0].collision_geoms[0]] != 0
        assert contacts_on == (frame > switches.contact_frame)  # switched at the start of that frame


@pytest.mark.parametrize("env_id", IDS)
def test_pickle_round_trip_continues_exactly_like_the_original(env_id):
    env = gym.make(env_id)
    actions = _actions(env, 16, seed=3)
    env.reset(seed=5)
    for a in actions[:8]:
        env.step(a)
    copy = pickle.loads(pickle.dumps(env))
    for a in actions[8:]:
        original, clone = env.step(a), copy.step(a)
        assert np.array_equal(original[0], clone[0])
        assert original[1:] == clone[1:]
    assert copy.unwrapped.data is not env.unwrapped.data


def test_each_env_has_its_own_model():
    env_a, env_b = ReplayEnv(), ReplayEnv()
    env_a.model.opt.timestep = 0.001
    assert env_b.model.opt.timestep == 0.002
    assert default_replay_inputs()[0].model.opt.timestep == 0.002


@pytest.mark.parametrize("mode", ["sync", "async"])
@pytest.mark.parametrize("env_id", IDS)
def test_make_vec_steps(env_id, mode):
    envs = gym.make_vec(env_id, num_envs=2, vectorization_mode=mode)
    try:
        obs, _ = envs.reset(seed=11)
        assert obs.shape == (2, *envs.single_observation_space.shape)
        envs.action_space.seed(0)
        for _ in range(3):
            obs, reward, _, _, info = envs.step(envs.action_space.sample())
        assert obs.shape[0] == reward.shape[0] == 2
        assert np.all(np.isfinite(obs))
        assert "diverged" in info
    finally:
        envs.close()


# ---- rewards and episodes ---------------------------------------------------------------------------------
@pytest.mark.parametrize(("env_id", "terms"), [(REPLAY, REPLAY_REWARDS), (GRASP, GRASP_REWARDS)])
def test_reward_components_in_info_sum_to_the_reward(env_id, terms):
    env = gym.make(env_id)
    env.reset(seed=0)
    for a in _actions(env, 10):
        _, reward, _, _, info = env.step(a)
        assert reward == pytest.approx(sum(info[t] for t in terms), abs=1e-12)
    assert info["reward_tracking" if env_id == REPLAY else "reward_reach"] > 0


def test_replay_truncates_at_the_last_frame_and_then_needs_a_reset():
    env = ReplayEnv()
    last = env.schedule.frames - 1
    env.reset(seed=0, options={"frame": last - 2})
    zero = np.zeros(env.action_space.shape)
    assert env.step(zero)[3] is False
    _, _, terminated, truncated, info = env.step(zero)
    assert (terminated, truncated, info["frame"]) == (False, True, last)
    with pytest.raises(gym.error.ResetNeeded, match="call reset"):
        env.step(zero)


def test_replay_terminates_when_the_object_drifts_too_far():
    env = ReplayEnv(max_object_drift=1e-6)
    env.reset(seed=0)
    _, _, terminated, truncated, info = env.step(np.ones(env.action_space.shape))
    assert terminated and not truncated
    assert info["object_drift"] > 1e-6


def test_replay_reset_rejects_a_frame_outside_the_schedule():
    env = ReplayEnv()
    with pytest.raises(ValueError, match=r"options\['frame'\] must be a frame in \[0, 615\], got 616"):
        env.reset(options={"frame": 616})


def test_grasp_closing_and_lifting_succeeds():
    env = GraspEnv(zero_action="mid")  # the actions below map −1 … 1 onto each joint's range
    env.reset(seed=0)
    layout = env.scene.layout
    lo, hi = layout.ctrl_range.T
    flex = np.array(["flex" in n for n in layout.dof_names])
    thumb = np.array([n.startswith("th") for n in layout.dof_names]) & ~flex
    grip = np.where(flex, 0.7 * hi, np.where(thumb, np.clip(0.5 * hi, lo, hi), np.clip(0.0, lo, hi)))
    opened = np.clip(0.0, lo, hi)
    success = []
    for k in range(env.max_steps):
        t = k * env.dt
        closing = np.clip((t - 0.1) / 0.4, 0.0, 1.0)
        target = (1 - closing) * opened + closing * grip
        down_up = -1.0 if t < 0.1 else (0.5 if t > 0.8 else 0.0)
        action = np.concatenate([(target - (lo + hi) / 2) / ((hi - lo) / 2), [0.0, 0.0, down_up]])
        _, _, terminated, truncated, info = env.step(action)
        success.append(info["success"])
        assert not terminated
    assert truncated
    assert info["lift"] > 0.05
    assert success[-1] and info["is_success"]
    assert not any(success[: int(0.5 / env.dt)])  # needs hold_time (0.5 s) of holding first
    assert info["reward_lift"] == pytest.approx(1.0)  # the held lift is paid in full


def _sides_touching(env: GraspEnv, obs: np.ndarray) -> set[str]:
    """The sides (thumb, fingers, palm) whose links push on the object, read from the observation."""
    forces = obs[env.observation_slices["contact_force"]]
    sides = {"thumb": "thumb", "palm": "palm"}
    links = env.scene.layout.link_names
    return {sides.get(finger_of(n), "fingers") for n, f in zip(links, forces, strict=True) if f > 0}


def test_grasp_lift_reward_is_zero_unless_the_hand_holds_the_object():
    """Random actions knock the ball about (and up) without holding it: no lift is paid for that."""
    env = GraspEnv()
    env.action_space.seed(0)
    knocked_up = 0
    for seed in range(3):
        env.reset(seed=seed)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(env.action_space.sample())
            done = terminated or truncated
            knocked_up += info["lift"] > 0
            if len(_sides_touching(env, obs)) < 2:
                assert info["reward_lift"] == 0.0
    assert knocked_up  # the rollout does lift the ball at times: the gate is what keeps the term at 0


def test_grasp_scripted_root_has_joint_targets_only():
    env = GraspEnv(root_control="scripted")
    assert env.action_space.shape == (len(env.dof_names),)


# ---- rendering ---------------------------------------------------------------------------------------------
def test_render_rgb_array_headless():
    """In a fresh process that imports handsim first (as users do), render both environments."""
    code = textwrap.dedent(
        """
        import handsim, gymnasium as gym, numpy as np
        from handsim.envs import RenderError
        for env_id in ("handsim/Grasp-v0", "handsim/Replay-v0"):
            env = gym.make(env_id, render_mode="rgb_array", width=64, height=48)
            env.reset(seed=0)
            env.step(np.zeros(env.action_space.shape))
            try:
                img = env.render()
            except RenderError as err:
                print("NO-GL", err)
                raise SystemExit(0)
            colours = len(np.unique(img.reshape(-1, 3), axis=0))
            print(env_id, img.shape, img.dtype, colours)
            env.close()
            env.close()
        """
    )
    environ = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL")}
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=environ, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    if out.stdout.startswith("NO-GL"):
        pytest.skip(f"no offscreen OpenGL backend works here: {out.stdout.strip()}")
    lines = out.stdout.strip().splitlines()
    assert len(lines) == 2, out.stdout
    for line in lines:
        _, shape, dtype, colours = line.split(" ", 1)[0], *line.split(" ", 1)[1].rsplit(" ", 2)
        assert shape == "(48, 64, 3)"
        assert dtype == "uint8"
        assert int(colours) > 10


def test_render_in_process_gives_rgb_frames_and_close_is_idempotent():
    if _in_process_gl():
        pytest.skip(f"this process cannot render (mujoco imported before handsim): {_in_process_gl()[:200]}")
    env = gym.make(GRASP, render_mode="rgb_array", width=80, height=60, camera="overview")
    env.reset(seed=0)
    img = env.render()
    assert img.shape == (60, 80, 3) and img.dtype == np.uint8
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 10
    copy = pickle.loads(pickle.dumps(env))  # a pickled env renders with its own context
    assert np.array_equal(copy.render(), img)
    env.close()
    env.close()
    copy.close()


def test_render_without_render_mode_warns_and_returns_none():
    env = GraspEnv()
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="without a render_mode"):
        assert env.render() is None


# ---- bad inputs -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", IDS)
def test_step_raises_value_error_if_action_shape_is_wrong(env_id):
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    n = env.action_space.shape[0]
    with pytest.raises(ValueError, match=rf"action must have shape \({n},\) \(.*\), got shape \({n - 1},\)"):
        env.step(np.zeros(n - 1))
    with pytest.raises(ValueError, match=r"got shape \(2, " + str(n) + r"\)"):
        env.step(np.zeros((2, n)))


@pytest.mark.parametrize("env_id", IDS)
def test_step_raises_value_error_if_action_is_not_finite(env_id):
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape)
    action[2] = np.nan
    with pytest.raises(ValueError, match="action has NaN or infinite values"):
        env.step(action)


def test_step_before_reset_raises_reset_needed():
    with pytest.raises(gym.error.ResetNeeded, match="call reset"):
        GraspEnv().step(np.zeros(GraspEnv().action_space.shape))


def test_replay_raises_value_error_if_only_the_scene_is_given():
    scene, _ = default_replay_inputs()
    with pytest.raises(ValueError, match="pass both scene and trajectory, or neither"):
        ReplayEnv(scene)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"residual_scale": -0.1}, "residual_scale must be a number ≥ 0 or 31 of them"),
        ({"residual_scale": [0.1, 0.2]}, "residual_scale must be a number ≥ 0 or 31 of them"),
        ({"tracking_sigma": 0.0}, "tracking_sigma must be a finite number > 0, got 0.0"),
        ({"max_object_drift": -1.0}, "max_object_drift must be a finite number > 0"),
        ({"render_mode": "human"}, r"unknown render_mode 'human'; expected one of \[None, 'rgb_array'\]"),
        ({"camera": "nope"}, r"unknown camera 'nope'; the scene's cameras are \['hand_cam', 'overview'\]"),
        ({"width": 4000}, "larger than the scene's offscreen buffer 1280 × 960"),
    ],
)
def test_replay_raises_value_error_for_bad_parameters(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ReplayEnv(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"root_control": "teleport"},
            r"unknown root_control 'teleport'; expected one of \['velocity', 'scripted'\]",
        ),
        ({"root_range": (0.1, 0.1)}, r"root_range must be 3 finite numbers ≥ 0 \(x, y, z\)"),
        ({"lift_height": 0.0}, "lift_height must be a finite number > 0, got 0.0"),
        ({"duration": -1.0}, "duration must be a finite number > 0"),
    ],
)
def test_grasp_raises_value_error_for_bad_parameters(kwargs, message):
    with pytest.raises(ValueError, match=message):
        GraspEnv(**kwargs)


def test_grasp_raises_if_object_is_not_in_the_catalogue():
    with pytest.raises(
        UnknownObjectError, match=r"unknown object 'football'; catalogue objects are: .*tennis_ball"
    ):
        GraspEnv(object_name="football")
