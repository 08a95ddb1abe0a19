"""A smoke run of scripts/train_residual.py: a few hundred PPO steps and its outputs (no real training)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

pytest.importorskip("stable_baselines3")
pytest.importorskip("matplotlib")


def _script():
    spec = importlib.util.spec_from_file_location("train_residual", ROOT / "scripts" / "train_residual.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_a_smoke_run_writes_the_curve_the_table_and_evaluates_the_whole_recording(tmp_path):
    record = _script().main(["--timesteps", "256", "--eval-every", "128", "--out", str(tmp_path)])
    for name in ("learning_curve.png", "evaluation.json", "evaluation.md", "policy.zip"):
        assert (tmp_path / name).is_file()
    saved = json.loads((tmp_path / "evaluation.json").read_text())
    assert saved["replay"] == record["replay"]
    # the whole recording, deterministically: sequence 20 has 617 frames, 616 steps
    assert record["replay"]["frames"] == record["policy_eval"]["frames"] == 616
    assert [c["timesteps"] for c in record["curve"][:3]] == [2, 128, 256]
    table = (tmp_path / "evaluation.md").read_text().splitlines()
    assert table[2].startswith("| pure replay (zero residual) | ")
    assert table[3].startswith("| PPO residual (256 steps, ")


def test_pure_replay_evaluation_is_deterministic():
    module = _script()
    kwargs = dict(module.ENV_KWARGS, max_object_drift=0.05)
    assert module.evaluate(kwargs) == module.evaluate(kwargs)


@pytest.mark.slow
def test_a_smoke_run_on_the_native_vector_env_trains_and_evaluates(tmp_path):
    record = _script().main(
        ["--vec", "native", "--timesteps", "256", "--eval-every", "128", "--out", str(tmp_path)]
    )
    assert record["n_envs"] == 2
    assert record["policy_eval"]["frames"] == 616
    assert [c["timesteps"] for c in record["curve"][:3]] == [2, 128, 256]


def test_the_native_sb3_adapter_returns_the_reset_observation_and_the_terminal_one():
    module = _script()
    venv = module.native_vec_env(dict(module.ENV_KWARGS, max_object_drift=1e-6), n_envs=2, seed=0).venv
    obs = venv.reset()
    zero = np.zeros((2, *venv.action_space.shape), np.float32)
    venv.step_async(zero)
    after, _, dones, infos = venv.step_wait()
    assert dones.tolist() == [True, True]  # a 1 µm drift limit ends every episode at once
    for i in range(2):
        assert infos[i]["TimeLimit.truncated"] is False
        assert infos[i]["terminal_observation"].shape == obs[i].shape
        assert not np.array_equal(
            infos[i]["terminal_observation"], after[i]
        )  # the returned one is the reset's
    venv.close()
