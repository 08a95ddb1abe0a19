"""Benchmark: dataset-run throughput with 1 and 2 workers, the runner's own overhead, a projection.

Run: python benchmarks/runner.py [--copies N] [--frames N]

The dataset is synthesised by repeating the real GraspDB14 recordings of ``../shared/data/graspdb14``
(each copy renamed to another trial number, its annotation file copied alongside); without ``../shared``
the bundled Tzionas sequence is used. A first, untimed run warms the hull cache on disk.

Each run is a fresh process (imports and in-memory caches cold, as for a user's command), timed from
its start to the last record. Printed, per worker count: wall time, trials per minute and the scaling
2 vs 1 worker; then the per-trial time split from the records (load = read + build + compile + glove
placement search; replay; render) and the runner's own overhead: wall ÷ trials (1 worker) minus the
mean time spent inside the trial function (imports, process start, record writing, progress).
``mj_step``'s share of ``replay()`` is measured in the same run on one trial (a raw ``mj_step`` loop with
the same inputs). Last, the time a GraspDB14-sized dataset (2,200 trials of ~300 frames) would take at
the measured 2-worker rate.
"""

from __future__ import annotations

import argparse
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from handsim.assets import TZIONAS_DIR
from handsim.runner.records import load_records
from handsim.trials import discover

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "graspdb14"
GRASPDB_SIZE = 2200
_TRIAL_NUMBER = re.compile(r"-(\d{3})-grasp-")


def synthesise(root: Path, copies: int) -> Path:
    """A dataset folder of ``copies`` renamed copies of each real recording (and the Tzionas sample)."""
    data = root / "dataset"
    data.mkdir()
    if SHARED.is_dir():
        for path in sorted(SHARED.glob("*.txt")):
            if "_annot-" in path.name:
                continue
            annotation = SHARED / (path.name.removeprefix("r_").removesuffix(".txt") + "_annot-.txt")
            for c in range(copies):
                number = 100 + c
                name = _TRIAL_NUMBER.sub(f"-{number:03d}-grasp-", path.name)
                shutil.copy(path, data / name)
                if annotation.is_file():
                    target = name.removeprefix("r_").removesuffix(".txt") + "_annot-.txt"
                    shutil.copy(annotation, data / target)
    tzionas = root / "tzionas"
    shutil.copytree(TZIONAS_DIR, tzionas)
    return data if SHARED.is_dir() else tzionas


_RUN = """
import sys, time
start = time.perf_counter()
from handsim.trials import discover
from handsim.runner.execute import run_dataset
run_dataset(discover(sys.argv[1]), sys.argv[2], workers=int(sys.argv[3]), frames=int(sys.argv[4]),
            progress=False, command=["benchmark"])
print(time.perf_counter() - start)
"""


def run(dataset: Path, out: Path, workers: int, frames: int) -> tuple[float, list[dict]]:
    """One dataset run in a fresh process (imports and in-memory caches cold for every worker count)."""
    done = subprocess.run(
        [sys.executable, "-c", _RUN, str(dataset), str(out), str(workers), str(frames)],
        check=True,
        capture_output=True,
        text=True,
    )
    return float(done.stdout.split()[-1]), load_records(out).records


def mj_step_share() -> float:
    """``mj_step``'s share of one ``replay()`` of the bundled Tzionas trial (raw loop ÷ replay)."""
    import mujoco

    from handsim.sim.control import control_schedule
    from handsim.sim.drive import ScheduleDriver, scenario_switches
    from handsim.sim.replay import replay
    from handsim.sim.stepper import Stepper
    from handsim.trials import load_trial

    loaded = load_trial(TZIONAS_DIR / "Models" / "20")
    scene, trajectory = loaded.scene, loaded.trajectory
    schedule = control_schedule(scene, trajectory, 100.0)
    raw, full = [], []
    for _ in range(3):
        driver = ScheduleDriver(
            Stepper(scene, schedule.substeps), schedule, scenario_switches(scene, schedule, 0.1)
        )
        driver.reset()
        data, model = driver.stepper.data, scene.model
        start = time.perf_counter()
        for i in range(1, schedule.frames):
            data.mocap_pos[0], data.mocap_quat[0] = schedule.root_pose[i, :3], schedule.root_pose[i, 3:]
            data.ctrl[:] = schedule.ctrl[i]
            mujoco.mj_step(model, data, nstep=schedule.substeps)
        raw.append(time.perf_counter() - start)
        start = time.perf_counter()
        replay(scene, trajectory)
        full.append(time.perf_counter() - start)
    return statistics.median(raw) / statistics.median(full)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--copies", type=int, default=6, help="copies of each real recording")
    parser.add_argument("--frames", type=int, default=4, help="frames rendered per trial")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        dataset = synthesise(root, args.copies)
        trials = len(discover(dataset).entries)
        run(dataset, root / "warm", 1, 0)  # warms the hull cache on disk and the file system; not timed
        results = {}
        for workers in (1, 2):
            wall, records = run(dataset, root / f"out{workers}", workers, args.frames)
            results[workers] = (wall, records)
            rate = trials / wall * 60
            print(f"{workers} worker(s): {trials} trials in {wall:.1f} s = {rate:.1f} trials/min")
        scaling = results[1][0] / results[2][0]
        print(f"scaling 2 vs 1 worker: {scaling:.2f}×")
        for workers, (wall, records) in results.items():
            inside = sum(r["timing"]["total_s"] for r in records)
            print(
                f"  {workers} worker(s): {inside / len(records):.3f} s per trial inside the trial function; "
                f"workers busy {inside / (workers * wall):.1%} of the wall time"
            )
        wall, records = results[1]
        timing = [r["timing"] for r in records]
        mean = {
            k: statistics.fmean(t[k] for t in timing) for k in ("load_s", "replay_s", "render_s", "total_s")
        }
        overhead = wall / trials - mean["total_s"]
        print(
            f"per trial (1 worker): load {mean['load_s']:.3f} s, replay {mean['replay_s']:.3f} s, "
            f"render {mean['render_s']:.3f} s, inside the trial function {mean['total_s']:.3f} s"
        )
        print(
            f"runner overhead per trial: {overhead * 1000:.1f} ms = {overhead / (wall / trials):.1%} of the "
            "trial's wall time"
        )
        share = mj_step_share()
        print(f"mj_step share of replay() (Tzionas seq 20, same run): {share:.1%}")
        frames = statistics.fmean(
            r["trajectory_quality"]["frames"] for r in records if r.get("trajectory_quality")
        )
        projected = GRASPDB_SIZE / (trials / results[2][0]) / 3600
        print(
            f"projection: {GRASPDB_SIZE} trials (~300 frames; these average {frames:.0f}) at the 2-worker "
            f"rate ≈ {projected:.1f} h"
        )
        print(f"scaling_2_workers={scaling:.3f}")
        print(f"runner_overhead={overhead / (wall / trials):.4f}")


if __name__ == "__main__":
    main()
