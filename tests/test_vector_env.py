"""The native vector environment of Replay-v0: registration, gymnasium's vector conventions (next-step
autoreset, seeds, info masks), and exactly the results of N single environments with the same seeds."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import handsim  # noqa: F401  registers the environments
from handsim.envs import VECTOR_ENVS
from handsim.envs.replay_vector_env import ReplayVectorEnv
from tests.helpers import glove_switch_inputs

REPLAY = "handsim/Replay-v0"


def _pair(num_envs: int, **kwargs):
    native = gym.make_vec(REPLAY, num_envs=num_envs, vectorization_mode="vector_entry_point", **kwargs)
    sync = gym.make_vec(REPLAY, num_envs=num_envs, vectorization_mode="sync", **kwargs)
    return native, sync


def _assert_same_step(native_out: tuple, sync_out: tuple, step: int) -> None:
    names = ("obs", "reward", "terminated", "truncated")
    for name, a, b in zip(names, native_out[:4], sync_out[:4], strict=True):
        assert np.array_equal(a, b), f"step {step}: {name} differs"
    native_info, sync_info = native_out[4], sync_out[4]
    assert set(native_info) == set(sync_info), f"step {step}"
    for key, value in sync_info.items():
        assert np.array_equal(native_info[key], value), f"step {step}: info[{key!r}] differs"


def _run_both(native, sync, steps: int, seed: int, *, scale: float = 1.2) -> int:
    """Step both with the same actions; returns how many worlds were autoreset."""
    obs_a, info_a = native.reset(seed=seed)
    obs_b, info_b = sync.reset(seed=seed)
    assert np.array_equal(obs_a, obs_b)
    assert np.array_equal(info_a["frame"], info_b["frame"])
    rng = np.random.default_rng(seed)
    resets = 0
    for step in range(steps):
        actions = rng.uniform(-scale, scale, native.action_space.shape).astype(np.float32)
        out_a, out_b = native.step(actions), sync.step(actions)
        _assert_same_step(out_a, out_b, step)
        resets += int(np.count_nonzero(out_a[2] | out_a[3]))
    return resets


def test_make_vec_with_the_vector_entry_point_gives_the_native_vector_env():
    assert gym.registry[REPLAY].vector_entry_point == VECTOR_ENVS[REPLAY]
    envs = gym.make_vec(REPLAY, num_envs=3, vectorization_mode="vector_entry_point")
    try:
        assert isinstance(envs, ReplayVectorEnv)
        assert envs.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
        assert envs.num_envs == 3
        assert envs.observation_space.shape == (3, *envs.single_observation_space.shape)
        assert envs.action_space.shape == (3, *envs.single_action_space.shape)
        obs, info = envs.reset(seed=0)
        assert obs in envs.observation_space
        assert info["frame"].tolist() == [0, 0, 0]
        assert info["_frame"].all()
    finally:
        envs.close()


def test_native_vector_env_equals_single_envs_with_the_same_seeds_through_autoresets():
    native, sync = _pair(3, random_start=True)
    try:
        resets = _run_both(native, sync, steps=120, seed=7)
        assert resets >= 1  # a world started near the end was truncated and reset on the next step
    finally:
        native.close()
        sync.close()


def test_native_vector_env_resets_terminated_worlds_on_the_next_step_like_gymnasium():
    native, sync = _pair(2, max_object_drift=1e-6)
    try:
        native.reset(seed=1)
        zero = np.zeros(native.action_space.shape, np.float32)
        _, reward, terminated, truncated, info = native.step(zero)
        assert terminated.all() and not truncated.any()
        _, reward, terminated, truncated, info = native.step(zero)  # the autoreset step: actions ignored
        assert reward.tolist() == [0.0, 0.0]
        assert not terminated.any() and not truncated.any()
        assert info["frame"].tolist() == [0, 0]
        # the reset's info: frame, time, recording and the numbers of the reset state (issue 17), no step's
        assert info["reward_tracking"].tolist() == [1.0, 1.0]  # at the recorded state: no joint error
        assert info["_reward_tracking"].tolist() == [True, True]
        assert "diverged" not in info and "action_clipped" not in info
        assert _run_both(native, sync, steps=6, seed=2) == 6  # terminated every other step, in both worlds
    finally:
        native.close()
        sync.close()


def test_native_vector_env_switches_contacts_and_releases_supports_like_single_envs():
    scene, trajectory = glove_switch_inputs()
    native, sync = _pair(2, scene=scene, trajectory=trajectory)
    try:
        _run_both(native, sync, steps=110, seed=3, scale=0.5)  # through the switches and a truncation
    finally:
        native.close()
        sync.close()
    # random starts: worlds pass the switches at different steps and restart before or after them
    native, sync = _pair(3, scene=scene, trajectory=trajectory, random_start=True)
    try:
        assert _run_both(native, sync, steps=200, seed=11, scale=1.1) >= 3
    finally:
        native.close()
        sync.close()


def test_native_vector_env_reports_a_divergence_in_one_world_like_a_single_env():
    native, sync = _pair(2)
    try:
        native.reset(seed=0)
        sync.reset(seed=0)
        native.unwrapped._qvel[1, 0] = 1e30  # world 1 only: MuJoCo resets it (mjWARN_BADQVEL)
        sync.envs[1].unwrapped.data.qvel[0] = 1e30
        zero = np.zeros(native.action_space.shape, np.float32)
        out_a, out_b = native.step(zero), sync.step(zero)
        _assert_same_step(out_a, out_b, 0)
        assert out_a[2].tolist() == [False, True]
        assert out_a[4]["diverged"].tolist() == [False, True]
        assert out_a[4]["_warnings"].tolist() == [False, True]
        assert "diverged: mjWARN_BADQVEL" in out_a[4]["warnings"][1][0]
    finally:
        native.close()
        sync.close()


def test_native_vector_env_seeds_worlds_like_sync_vector_env():
    native, sync = _pair(4, random_start=True)
    try:
        for seed in (5, [1, 2, 3, 4]):
            frames = native.reset(seed=seed)[1]["frame"]
            assert frames.tolist() == sync.reset(seed=seed)[1]["frame"].tolist()
        assert len(set(frames.tolist())) > 1
    finally:
        native.close()
        sync.close()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"num_envs": 0}, "num_envs must be ≥ 1, got 0"),
        ({"num_envs": 2, "nthread": 0}, "nthread must be ≥ 1"),
        ({"num_envs": 2, "render_mode": "rgb_array"}, "does not render"),
        ({"num_envs": 2, "max_episode_steps": 10}, "max_episode_steps must be None, got 10"),
    ],
)
def test_native_vector_env_raises_value_error_for_bad_parameters(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ReplayVectorEnv(**kwargs)


def test_native_vector_env_step_raises_for_bad_actions_and_before_reset():
    envs = ReplayVectorEnv(num_envs=2)
    try:
        zero = np.zeros(envs.action_space.shape)
        with pytest.raises(gym.error.ResetNeeded, match="call reset"):
            envs.step(zero)
        envs.reset(seed=0)
        with pytest.raises(ValueError, match=r"actions must have shape \(2, "):
            envs.step(zero[:1])
        bad = zero.copy()
        bad[1, 3] = np.nan
        with pytest.raises(ValueError, match=r"actions of worlds \[1\] have NaN or infinite values"):
            envs.step(bad)
        with pytest.raises(ValueError, match="a list of num_envs=2 seeds expected, got 3"):
            envs.reset(seed=[1, 2, 3])
    finally:
        envs.close()


def _assert_same_step_autoreset(native_out: tuple, sync_out: tuple, step: int) -> None:
    """As :func:`_assert_same_step`, the masked info values only (the unmasked ones are fill)."""
    names = ("obs", "reward", "terminated", "truncated")
    for name, a, b in zip(names, native_out[:4], sync_out[:4], strict=True):
        assert np.array_equal(a, b), f"step {step}: {name} differs"

    def same(mine: dict, theirs: dict, where: str) -> None:
        assert set(mine) == set(theirs), f"step {step}: {where} keys"
        for key, value in theirs.items():
            if key.startswith("_") or key == "final_info":
                continue
            mask = theirs[f"_{key}"]
            assert np.array_equal(mine[f"_{key}"], mask), f"step {step}: {where}[_{key}]"
            for i in np.flatnonzero(mask):
                assert np.array_equal(mine[key][i], value[i]), f"step {step}: {where}[{key!r}][{i}]"

    native_info, sync_info = native_out[4], sync_out[4]
    same(native_info, sync_info, "info")
    if "final_info" in sync_info:
        same(native_info["final_info"], sync_info["final_info"], "final_info")


def test_native_vector_env_resets_in_the_same_step_like_sync_vector_env_when_asked():
    kwargs = {"random_start": True, "max_object_drift": 0.02}
    native = gym.make_vec(
        REPLAY,
        num_envs=3,
        vectorization_mode="vector_entry_point",
        autoreset_mode=AutoresetMode.SAME_STEP,
        **kwargs,
    )
    sync = gym.make_vec(
        REPLAY,
        num_envs=3,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP},
        **kwargs,
    )
    try:
        assert native.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
        native.reset(seed=3)
        sync.reset(seed=3)
        rng = np.random.default_rng(3)
        ended = 0
        for step in range(150):
            actions = rng.uniform(-1.2, 1.2, native.action_space.shape).astype(np.float32)
            out_a, out_b = native.step(actions), sync.step(actions)
            _assert_same_step_autoreset(out_a, out_b, step)
            done = out_a[2] | out_a[3]
            ended += int(done.sum())
            if done.any():  # the ended worlds' final observation is the step's, the returned one the reset's
                assert out_a[4]["_final_obs"].tolist() == done.tolist()
                assert not any(
                    np.array_equal(out_a[4]["final_obs"][i], out_a[0][i]) for i in np.flatnonzero(done)
                )
        assert ended >= 2
    finally:
        native.close()
        sync.close()


def test_native_vector_env_refuses_an_unknown_autoreset_mode():
    with pytest.raises(
        ValueError, match=r"autoreset_mode must be one of \['NextStep', 'SameStep'\], got 'Disabled'"
    ):
        ReplayVectorEnv(1, autoreset_mode="Disabled")
