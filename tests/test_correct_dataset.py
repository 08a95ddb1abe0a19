"""``handsim correct DATASET -o OUT``: every trial corrected by the dataset runner, its records, its report.

A tiny dataset: the bundled scripted tennis-ball grasp (corrected: a glove hold) and a hand-only copy of the
bundled Tzionas sequence 20 (not correctable: listed with its reason, not a failure), corrected with a few
samples over a short horizon. What is pinned: one record per trial with the correction's score and curves;
the corrected file streamed to ``OUT/corrected/`` replays to the committed simulation; a second run resumes
and corrects nothing twice; the local pool and Ray give bitwise the same records; the HTML report ranks the
trials and says "implausible" with the numbers for a large correction.
"""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import numpy as np
import pytest

from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.cli import main
from handsim.correct import CorrectionConfig
from handsim.io.corrected import read_corrected
from handsim.report.correction import REPORT_FILE, correction_html
from handsim.runner.correction_job import NOT_CORRECTABLE, CorrectionJob
from handsim.runner.execute import run_dataset
from handsim.runner.records import read_records
from handsim.trials import discover

FAST = CorrectionConfig(samples=3, iterations=1, horizon=10)
"""The smallest correction worth running: 3 candidates, one round, 0.1 s ahead."""
BALL_FILE = "tennis_ball.grasp.json"
BALL_ID = f"{BALL_FILE}#1"
"""Its trial: the grasp file's first (only) episode."""


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("dataset")
    shutil.copy(ASSETS_DIR / "demo" / "tennis_ball.grasp.json", root / BALL_FILE)
    shutil.copytree(TZIONAS_DIR, root / "tzionas")
    (root / "tzionas" / "Configs" / "20" / "MODELS_INFO.txt").write_text("1\nModel_Hand_R\n")  # hand only
    return root


@pytest.fixture(scope="module")
def local_run(dataset, tmp_path_factory):
    out = tmp_path_factory.mktemp("local")
    summary = run_dataset(discover(dataset), out, workers=2, job=CorrectionJob(FAST), progress=False)
    return out, summary, {r["id"]: r for r in read_records(out)}


def _without_timing(records) -> dict:
    return {r["id"]: {k: v for k, v in r.items() if k != "timing"} for r in records}


def test_one_record_per_trial_with_the_score_or_the_reason(local_run):
    _, summary, records = local_run
    assert summary.trials == 2 and summary.failed == 0 and summary.ok == 2
    ball = records[BALL_ID]
    assert ball["status"] == "ok" and ball["correction"]["objective"] == "hold"
    assert ball["correction"]["before"]["track"] == "held" and ball["correction"]["size"] >= 0
    assert ball["parameters"] == {"correction": FAST.to_dict()}
    assert len(ball["curves"]["time_s"]) == len(ball["curves"]["after_mm"]) > 10
    (hand_only,) = (r for i, r in records.items() if i != BALL_ID)
    assert hand_only["status"] == "ok" and hand_only["correction"]["status"] == NOT_CORRECTABLE
    assert "the scene has no object" in hand_only["correction"]["reason"]


def test_the_corrected_file_is_streamed_and_replays_to_the_committed_simulation(local_run):
    from handsim.sim.replay import ReplayConfig, replay
    from handsim.trials import load_trial

    out, _, records = local_run
    entry = records[BALL_ID]["corrected_file"]
    path = out / entry["path"]
    assert hashlib.sha256(path.read_bytes()).hexdigest() == entry["sha256"]
    loaded = load_trial(path)
    result = replay(loaded.scene, loaded.trajectory, ReplayConfig(keep_states=True, ensemble=False))
    assert np.array_equal(result.states, read_corrected(path).arrays["simulated_qpos"])


def test_a_second_run_resumes_and_corrects_nothing_twice(dataset, local_run):
    out, _, records = local_run
    again = run_dataset(discover(dataset), out, workers=2, job=CorrectionJob(FAST), progress=False)
    assert again.skipped == 2 and again.ran == ()
    assert _without_timing(read_records(out)) == _without_timing(records.values())


def test_an_in_process_run_gives_the_pools_records(dataset, local_run, tmp_path):
    _, _, records = local_run
    run_dataset(discover(dataset), tmp_path, workers=1, job=CorrectionJob(FAST), progress=False)
    assert _without_timing(read_records(tmp_path)) == _without_timing(records.values())


def test_the_report_ranks_the_trials_and_says_implausible_with_the_numbers(local_run):
    out, _, records = local_run
    pytest.importorskip("matplotlib")
    from handsim.report.correction import write_correction_report

    page = write_correction_report(out).read_text()
    assert (out / REPORT_FILE).is_file() and "data:image/png;base64," in page
    assert "not correctable" in page and "1 trials corrected" in page
    large = dict(records[BALL_ID], id="large")
    large["correction"] = dict(large["correction"], size=3.0, implausible="the recording needs a large X")
    page = correction_html([records[BALL_ID], large], plots=False)
    assert page.index(">large<") < page.index(f">{BALL_ID}<")  # ranked by size, largest first
    assert "implausible: the recording needs a large X" in page
    assert records[BALL_ID]["correction"]["unsupported"] == []  # a glove grasp has no recorded track
    large["correction"]["unsupported"] = [{"text": "the recording holds the cube in the air from 5.26 s"}]
    page = correction_html([large], plots=False)
    assert "<b>in the air</b>: the recording holds the cube in the air from 5.26 s" in page


def test_the_cli_corrects_a_dataset_and_writes_the_report(dataset, tmp_path, capsys):
    out = tmp_path / "out"
    args = ["--samples", "3", "--iterations", "1", "--horizon", "10", "--workers", "1", "--only", "tennis*"]
    assert main(["correct", str(dataset), "-o", str(out), *args]) == 0
    printed = capsys.readouterr().out
    assert f"{BALL_ID}: corrected; fingers" in printed
    assert (out / "corrected").is_dir() and len(read_records(out)) == 1


@pytest.mark.slow
def test_the_ray_backend_gives_bitwise_the_records_of_the_local_pool(dataset, local_run, tmp_path, ray_home):
    ray = pytest.importorskip("ray")
    _, _, records = local_run
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        run_dataset(discover(dataset), tmp_path, backend="ray", job=CorrectionJob(FAST), progress=False)
    finally:
        ray.shutdown()
    assert _without_timing(read_records(tmp_path)) == _without_timing(records.values())
    ball = read_records(tmp_path)
    assert {r["id"] for r in ball} == set(records)


def test_options_of_one_trial_are_refused_for_a_dataset_run(dataset, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["correct", str(dataset), "-o", str(out), "--density", "500", "--grasp", "1"]) == 2
    assert capsys.readouterr().err.splitlines()[0] == (
        "handsim correct: error: --density, --grasp: options of one trial's correction, not of a dataset run "
        "(each worker corrects on one thread; a dataset's trials take only --mano-dir and --templates)"
    )
    assert not out.exists()
    assert main(["correct", str(dataset), "-o", str(out), "--rollouts", "warp"]) == 2
    assert capsys.readouterr().err.startswith("handsim correct: error: --rollouts: options of one trial's")
    assert not out.exists()
