"""Recordings chosen by keyword: ``gym.make("handsim/Replay-v0", trajectory=PATH_or_LIST, **options)``."""

from __future__ import annotations

import re

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import handsim  # noqa: F401  registers the environments
from handsim.assets import TZIONAS_DIR
from handsim.envs.recordings import RecordingError, cached_recordings, default_replay_inputs, load_recording
from handsim.envs.replay_env import ReplayEnv
from handsim.errors import InputFileError
from handsim.trials import TrialError
from tests.tzionas_fixtures import two_hand_sample

REPLAY = "handsim/Replay-v0"
SEQ20 = TZIONAS_DIR / "Models" / "20"
MOTION20 = SEQ20 / "Model_Hand_R.MOTION"


def test_a_recording_path_gives_the_scene_of_its_trial_and_is_built_once():
    env = gym.make(REPLAY, trajectory=str(SEQ20))
    before = cached_recordings()
    again = gym.make(REPLAY, trajectory=SEQ20)
    assert cached_recordings() == before
    assert env.unwrapped.observation_names == again.unwrapped.observation_names
    assert load_recording(SEQ20) is load_recording(str(SEQ20))
    # the bundled default is the same sequence: the same observation layout
    assert env.unwrapped.observation_names == ReplayEnv().observation_names
    obs, info = env.reset(seed=0)
    assert (info["frame"], info["time"], info["recording"]) == (0, 0.0, 0)
    assert obs.shape == env.observation_space.shape


def test_a_recording_by_keyword_passes_check_env():
    check_env(gym.make(REPLAY, trajectory=SEQ20).unwrapped, skip_render_check=True)


def test_several_recordings_are_sampled_per_episode_from_the_reset_seed():
    def sampled(seed: int) -> list[int]:
        env = gym.make(REPLAY, trajectory=[SEQ20, MOTION20])
        out = [env.reset(seed=seed)[1]["recording"]]
        for _ in range(7):
            out.append(env.reset()[1]["recording"])
        return out

    first = sampled(3)
    assert first == sampled(3)
    assert set(first) == {0, 1}  # both recordings are drawn over 8 episodes
    assert sampled(4) != first


def test_same_seed_with_recordings_sampled_gives_bitwise_identical_rollouts():
    def rollout(seed: int) -> list:
        env = gym.make(REPLAY, trajectory=[SEQ20, MOTION20])
        rng = np.random.default_rng(0)
        obs, info = env.reset(seed=seed)
        out = [obs, info["recording"]]
        for episode in range(3):
            for _ in range(5):
                obs, reward, *_ = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
                out += [obs, reward]
            obs, info = env.reset()
            out += [obs, info["recording"], episode]
        return out

    a, b = rollout(11), rollout(11)
    assert len(a) == len(b)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def test_options_recording_chooses_the_recording():
    env = ReplayEnv(trajectory=[SEQ20, MOTION20])
    assert env.reset(seed=0, options={"recording": 1})[1]["recording"] == 1
    assert env.recording == 1 and env.recordings == 2
    with pytest.raises(ValueError, match=re.escape("options['recording'] must be in [0, 1], got 2")):
        env.reset(options={"recording": 2})


def test_an_unknown_keyword_is_refused_naming_the_trial_options():
    with pytest.raises(
        RecordingError,
        match=re.escape(
            "ReplayEnv: unknown keyword(s) ['sequence']; besides its own, it takes the trial options "
            "['skeleton', 'obj', 'calibration', 'units', 'density', 'mass', 'hand_length', 'collision', "
            "'thumb_rest', 'force', 'mano_dir', 'templates', 'grasp'] (handsim.trials.find_trial)"
        ),
    ):
        gym.make(REPLAY, sequence=SEQ20)


def test_a_missing_recording_is_refused_naming_the_file(tmp_path):
    missing = tmp_path / "nope.txt"
    with pytest.raises(InputFileError, match=re.escape(f"{missing}: file not found")):
        gym.make(REPLAY, trajectory=[SEQ20, missing])


def test_an_empty_list_of_recordings_is_refused():
    with pytest.raises(
        RecordingError, match=re.escape("trajectory: an empty list of recordings; give at least one path")
    ):
        gym.make(REPLAY, trajectory=[])


def test_trial_options_without_recording_paths_are_refused():
    scene, trajectory = default_replay_inputs()
    with pytest.raises(
        RecordingError,
        match=re.escape("trial options ['mass'] need recording paths: trajectory=PATH or a list of paths"),
    ):
        ReplayEnv(scene, trajectory, mass=0.1)


def test_a_scene_with_recording_paths_is_refused():
    scene, _ = default_replay_inputs()
    with pytest.raises(RecordingError, match="give a scene with a Trajectory, or recording paths without"):
        ReplayEnv(scene, SEQ20)


def test_a_trial_option_that_does_not_apply_to_the_kind_is_refused():
    with pytest.raises(TrialError, match="a thumb rest posture does not apply to"):
        gym.make(REPLAY, trajectory=SEQ20, thumb_rest=(10.0, 20.0))


def test_a_two_hand_scene_is_refused_naming_the_reason(tmp_path):
    models = two_hand_sample(tmp_path / "tzionas")
    with pytest.raises(
        RecordingError,
        match=re.escape(
            f"{models}: a scene with 2 hands (['right', 'left']); the environments drive one hand's "
            "actuators with one action vector: replay it with `handsim replay` instead"
        ),
    ):
        gym.make(REPLAY, trajectory=models)


def test_the_native_vector_env_takes_one_recording_and_refuses_several():
    envs = gym.make_vec(REPLAY, num_envs=2, vectorization_mode="vector_entry_point", trajectory=SEQ20)
    obs, _ = envs.reset(seed=0)
    assert obs.shape == (2, *envs.single_observation_space.shape)
    envs.close()
    with pytest.raises(RecordingError, match="for 2 recordings use vectorization_mode='sync' or 'async'"):
        gym.make_vec(
            REPLAY, num_envs=2, vectorization_mode="vector_entry_point", trajectory=[SEQ20, MOTION20]
        )
