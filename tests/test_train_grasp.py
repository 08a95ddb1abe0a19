"""scripts/train_grasp.py: its scripted demonstrator, its evaluation and a smoke run (no real training)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

pytest.importorskip("stable_baselines3")
pytest.importorskip("matplotlib")


@pytest.fixture(scope="module")
def script():
    sys.path.insert(0, str(ROOT / "scripts"))  # it imports train_residual's PPO plumbing
    try:
        spec = importlib.util.spec_from_file_location("train_grasp", ROOT / "scripts" / "train_grasp.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.path.remove(str(ROOT / "scripts"))


def test_the_scripted_grasp_lifts_and_holds_the_ball(script):
    """The demonstrator: most evaluation episodes end held, at the scripted policy's 5–6 mm."""
    env = script.GraspEnv(**script.ENV_KWARGS)
    act = script.scripted_policy(env)
    held, deepest = [], 0.0
    for episode in range(script.EVAL_EPISODES):
        env.reset(seed=script.EVAL_SEED + episode)
        for step in range(env.max_steps):
            _, _, terminated, truncated, info = env.step(act(step))
            deepest = max(deepest, info["penetration"])
            if terminated or truncated:
                break
        held.append(info["success"] and not terminated)
    assert np.mean(held) >= 0.5
    assert 0.003 < deepest < 0.008


def test_zero_action_evaluation_is_deterministic_and_holds_nothing(script):
    first = script.evaluate(script.ENV_KWARGS)
    assert first == script.evaluate(script.ENV_KWARGS)
    assert first["held"] == 0.0 and first["episodes"] == script.EVAL_EPISODES
    assert not script.passes(first)


@pytest.mark.slow
def test_a_smoke_run_from_demonstrations_writes_the_table_and_the_curves(script, tmp_path, monkeypatch):
    monkeypatch.setattr(script, "DEMO_EPISODES", 2)
    monkeypatch.setattr(script, "BC_STEPS", 20)
    monkeypatch.setattr(script, "EVAL_EPISODES", 2)
    record = script.main(
        ["--timesteps", "256", "--eval-every", "128", "--seeds", "0", "--demo", "--out", str(tmp_path)]
    )
    for name in ("learning_curve.png", "evaluation.json", "evaluation.md", "seed0/policy.zip"):
        assert (tmp_path / name).is_file()
    assert json.loads((tmp_path / "evaluation.json").read_text())["zero_action"] == record["zero_action"]
    (seed,) = record["seeds"]
    assert [c["timesteps"] for c in seed["curve"]][-1] == 256
    table = (tmp_path / "evaluation.md").read_text().splitlines()
    assert table[2].startswith("| zero action (open hand) | 0 % |")
    assert table[3].startswith("| PPO seed 0 (256 steps, ")
    assert table[-1] in (
        "0 of 1 seeds pass (every episode held, ≤ 5 mm).",
        "1 of 1 seeds pass (every episode held, ≤ 5 mm).",
    )
