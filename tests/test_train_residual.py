"""A smoke run of scripts/train_residual.py: a few hundred PPO steps and its outputs (no real training)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

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
