"""Corrected trials export to Minari: ``handsim report`` over a folder of ``.corrected.npz``, then the export.

A corrected glove grasp (the bundled scripted tennis-ball grasp, corrected with a few samples over a short
horizon) is a trial of its own (kind ``corrected``): a dataset run records it like any other, and
``handsim export minari`` of that run writes one episode whose actions are the corrected motion's joint
targets, frame by frame (the control schedule the committed simulation was driven with).
"""

from __future__ import annotations

import numpy as np
import pytest

from handsim.assets import ASSETS_DIR
from handsim.cli import main
from handsim.correct import CorrectionConfig, correct, write_corrected
from handsim.sim.control import control_schedule
from handsim.trials import load_trial

FAST = CorrectionConfig(samples=3, iterations=1, horizon=10)


def test_a_folder_of_corrected_trials_exports_to_minari(tmp_path, monkeypatch, capsys):
    minari = pytest.importorskip("minari")
    data, run = tmp_path / "data", tmp_path / "run"
    path = data / "ball.corrected.npz"
    ball = load_trial(ASSETS_DIR / "demo" / "tennis_ball.grasp.json")
    write_corrected(path, correct(ball, FAST, threads=1))
    assert main(["report", str(data), "-o", str(run), "--workers", "1", "--frames", "0"]) == 0
    assert "1 trials: 1 ok" in capsys.readouterr().out
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    assert main(["export", "minari", str(run), "--dataset-id", "handsim/corrected-v0", "--workers", "1"]) == 0
    assert "episodes    1" in capsys.readouterr().out
    episode = next(iter(minari.load_dataset("handsim/corrected-v0").iterate_episodes()))
    loaded = load_trial(path)
    schedule = control_schedule(loaded.scene, loaded.trajectory, FAST.control_rate)
    assert np.array_equal(episode.actions, schedule.ctrl[1:])
