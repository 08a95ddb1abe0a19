"""Dataset runs end to end: the real sample data (in-process, pool, Ray) and ``handsim report``."""

from __future__ import annotations

import hashlib
import json
import multiprocessing
import subprocess
import sys
from pathlib import Path

import pytest

from handsim.assets import TZIONAS_DIR
from handsim.cli import main
from handsim.datatypes.fingers import FINGER_GROUPS
from handsim.runner.execute import run_dataset
from handsim.runner.records import read_records
from handsim.runner.worker import run_parameters
from handsim.trials import discover
from tests.conftest import SHARED_DATA
from tests.processes import ROOT, child_env, ray_head
from tests.runner_fixtures import (
    CONFIG,
    GRASPDB_IDS,
    SESSION_IDS,
    TZIONAS_ID,
    dataset_in,
    tzionas_copies,
    without_timing,
)

FRAMES = 4
RECORD_KEYS = [
    "schema", "id", "kind", "status", "meta", "trial", "inputs", "parameters", "metric_spec_version",
    "versions", "model_sha256", "scenario", "summary", "episode", "hold", "grip", "robustness",
    "release_stability", "stability", "warnings", "diverged", "flags", "notes",
    "trajectory_quality", "curves", "renders", "error", "timing",
]  # fmt: skip
FAST_IDS = [GRASPDB_IDS[0], TZIONAS_ID]  # the two quickest to load (no long placement search)


# --------------------------------------------------------------------------------------------------
# The real sample data, run once in-process (GraspDB14 loading takes seconds: its placement search)


_REAL_RUN = """
import dataclasses, json, sys
from handsim.trials import discover
from handsim.runner.execute import run_dataset
from handsim.sim.replay import ReplayConfig
summary = run_dataset(
    discover(sys.argv[1]), sys.argv[2], workers=1, config=ReplayConfig(stability_at="grasp"),
    frames=int(sys.argv[3]), progress=False,
)
print(json.dumps(dataclasses.asdict(summary)))
"""


@pytest.fixture(scope="module")
def real_run(tmp_path_factory):
    """The sample data run once with workers=1, in a fresh interpreter.

    Fresh, because MuJoCo picks its OpenGL backend when first imported: a test module that imports
    ``mujoco`` before ``handsim`` leaves this process without offscreen rendering (its records would then
    carry a note instead of frames), while pool and Ray workers always start clean.
    """
    if not (SHARED_DATA / "graspdb14").exists() or not (SHARED_DATA / "tzionas_ijcv16").exists():
        pytest.skip(f"needs the real sample data in ../shared/data: {SHARED_DATA} is absent")
    out = tmp_path_factory.mktemp("real_run")
    done = subprocess.run(
        [sys.executable, "-c", _REAL_RUN, str(SHARED_DATA), str(out), str(FRAMES)],
        capture_output=True, text=True, check=False, cwd=Path(__file__).resolve().parents[1],
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    return discover(SHARED_DATA), out, summary, read_records(out)


@pytest.mark.slow
def test_the_real_data_run_records_every_trial(real_run):
    discovery, out, summary, records = real_run
    assert sorted(r["id"] for r in records) == sorted([*GRASPDB_IDS, *SESSION_IDS, TZIONAS_ID])
    assert [summary[k] for k in ("trials", "skipped", "failed", "hold_trials")] == [55, 0, 0, 29]
    assert [u.path for u in discovery.unknown] == ["mano/mano_right_mean_joints.json"]
    run = json.loads((out / "run.json").read_text())
    assert run["discovery"]["trials"] == 55 and run["parameters"] == run_parameters(CONFIG, FRAMES)
    for record in records:
        assert list(record) == RECORD_KEYS
        assert record["status"] in ("ok", "diverged") and record["error"] is None
        assert record["parameters"] == run_parameters(CONFIG, FRAMES)
        assert set(record["versions"]) == {"handsim", "mujoco", "numpy", "python", "platform"}
        assert len(record["model_sha256"]) == 64
        for item in record["inputs"]:
            assert item["sha256"] == hashlib.sha256((SHARED_DATA / item["path"]).read_bytes()).hexdigest()
        curves = record["curves"]
        n = len(curves["time_s"])
        assert n <= 600 and n == -(-record["summary"]["frames"] // curves["stride"])
        assert list(curves["contacts_per_finger"]) == list(FINGER_GROUPS)
        assert all(len(v) == n for v in curves["contacts_per_finger"].values())
        assert len(curves["penetration_mm"]) == len(curves["tracking_error_deg"]) == n
        frames = [r["frame"] for r in record["renders"]]
        assert frames[0] == 0 and frames[-1] == record["summary"]["frames"] - 1 and len(frames) <= FRAMES
        for render in record["renders"]:
            assert hashlib.sha256((out / render["path"]).read_bytes()).hexdigest() == render["sha256"]
        quality = record["trajectory_quality"]
        # the whole session has dropped samples (SOURCES.md); the single trials have none
        assert quality["limit_violations"] >= 0 and quality["gaps_filled"] == (
            (record["id"] in SESSION_IDS) * (record["trajectory_quality"]["gaps_filled"] > 0)
        )
    for record in records:  # no hold stands on a link deeper in the object than the grip's limit
        if record["summary"].get("held") is True:
            grip = record["grip"]
            assert grip["max_depth_mm"] <= grip["depth_limit_mm"] and grip["opposition"] >= 0.5
    by_id = {r["id"]: r for r in records}
    glove, recorded = by_id[GRASPDB_IDS[2]], by_id[TZIONAS_ID]
    assert glove["meta"]["grasp"] == "Power sphere" and glove["scenario"] == "glove"
    assert glove["curves"]["drift_mm"] is None and glove["stability"] is not None
    assert [i["role"] for i in glove["inputs"]] == ["trajectory", "annotation"]
    assert recorded["scenario"] == "recorded" and recorded["stability"] is None
    assert len(recorded["curves"]["drift_mm"]) == len(recorded["curves"]["time_s"])
    assert not any(n.startswith("stability tests") for n in recorded["notes"])  # no hold window by nature
    assert max(recorded["curves"]["contacts_per_finger"]["thumb"]) > 0  # the thumb pushes the cube


@pytest.mark.slow
def test_a_process_pool_gives_the_in_process_records_and_resumes_after_an_interrupt(real_run, tmp_path):
    discovery, _, _, records = real_run
    entries = tuple(e for e in discovery.entries if e.id in FAST_IDS)

    def stop(record: dict) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_dataset(
            entries, tmp_path, workers=2, config=CONFIG, frames=FRAMES, progress=False, on_record=stop
        )
    assert multiprocessing.active_children() == []  # the workers were stopped
    first = [r["id"] for r in read_records(tmp_path)]
    assert len(first) == 1
    resumed = run_dataset(entries, tmp_path, workers=2, config=CONFIG, frames=FRAMES, progress=False)
    assert sorted([*first, *resumed.ran]) == sorted(FAST_IDS)
    expected = {k: v for k, v in without_timing(records).items() if k in FAST_IDS}
    assert without_timing(read_records(tmp_path)) == expected


@pytest.mark.slow
def test_the_ray_backend_gives_bitwise_the_records_of_the_local_backend(real_run, tmp_path, ray_home):
    ray = pytest.importorskip("ray")
    discovery, _, _, records = real_run
    entries = tuple(e for e in discovery.entries if e.id in FAST_IDS)
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        summary = run_dataset(entries, tmp_path, backend="ray", config=CONFIG, frames=FRAMES, progress=False)
    finally:
        ray.shutdown()
    assert sorted(summary.ran) == sorted(FAST_IDS)
    expected = {k: v for k, v in without_timing(records).items() if k in FAST_IDS}
    assert without_timing(read_records(tmp_path)) == expected


# --------------------------------------------------------------------------------------------------
# The command


def test_handsim_report_runs_renders_and_re_renders(tmp_path, capsys):
    pytest.importorskip("handsim.report")
    data = tzionas_copies(tmp_path / "data", [20])
    out = tmp_path / "out"
    assert main(["report", str(data), "-o", str(out), "--workers", "1", "--frames", "1", "--rate", "50"]) == 0
    printed = capsys.readouterr().out
    assert "1 trials: 1 ok, 0 diverged, 0 failed" in printed
    assert f"records     {out / 'records.jsonl'} (1 run now, 0 resumed)" in printed
    assert (out / "run.json").is_file() and len(read_records(out)) == 1
    assert main(["report", "--render-only", str(out)]) == 0
    assert "1 trials: 1 ok" in capsys.readouterr().out


@pytest.mark.slow
def test_handsim_report_runs_on_a_ray_cluster_given_its_address_and_leaves_it_running(
    tmp_path, capsys, ray_home
):
    pytest.importorskip("ray")
    data = dataset_in(tmp_path / "data")
    options = ["--frames", "1", "--rate", "50"]
    assert main(["report", str(data), "-o", str(tmp_path / "ref"), "--workers", "1", *options]) == 0
    capsys.readouterr()
    env = {
        **child_env(),
        "RAY_AUTH_MODE": "token",
    }  # the cluster's token authentication (ray start's default)
    with ray_head(2, tmp_path / "ray.log") as (address, head):
        ray = ["--backend", "ray", "--address", address, *options]
        done = subprocess.run(
            [sys.executable, "-m", "handsim.cli", "report", str(data), "-o", str(tmp_path / "out"), *ray],
            capture_output=True, text=True, env=env, cwd=ROOT, check=False,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert head.poll() is None  # the cluster is the user's: still running
        tzionas = [e for e in discover(data).entries if e.id == "Models/20"]  # no address: a Ray of its own
        local = run_dataset(tzionas, tmp_path / "local", backend="ray", workers=1, frames=0, progress=False)
    assert "2 trials: 1 ok, 0 diverged, 1 failed" in done.stdout
    assert without_timing(read_records(tmp_path / "out")) == without_timing(read_records(tmp_path / "ref"))
    assert local.ran == ("Models/20",) and read_records(tmp_path / "local")[0]["status"] == "ok"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([], "give DATASET and -o OUT (or --render-only OUT)"),
        (["--only", "nothing*"], "no trial matching 'nothing*' in"),
        (["--render-only", "{tmp}/none"], "--render-only needs a run's folder with records.jsonl"),
    ],
)
def test_handsim_report_exits_2_on_a_usage_error(tmp_path, capsys, args, message):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    if args[:1] == ["--only"]:
        args = [str(TZIONAS_DIR), "-o", str(tmp_path / "out"), *args]
    assert main(["report", *args]) == 2
    assert message in capsys.readouterr().err
