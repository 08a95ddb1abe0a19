"""Benchmark: dataset-run throughput with 1 and 2 workers and on a Ray cluster, a GraspDB-sized projection.

Run: python benchmarks/runner.py [--copies N] [--frames N] [--ray-rounds N]

The dataset is synthesised by repeating the real GraspDB14 recordings of ``../shared/data/graspdb14``
(each copy renamed to another trial number, its annotation file copied alongside); without ``../shared``
the bundled Tzionas sequence is used. A first, untimed run of one copy of each recording warms the hull
cache on disk (a cache folder of the benchmark's own, ``HANDSIM_CACHE_DIR``).

The placement search is content-cached (:mod:`handsim.sim.placement.cache`): byte-identical copies would
share one search, which a real dataset, whose recordings all differ, never does. So every copy differs
from the others in one sample (the first row's last sensor value moved by ``copy × 1e-5`` rad, far below
the glove's resolution), and every timed run starts with no placement cache (the hulls kept): each trial
pays its own placement search, as in a first run over GraspDB14.

Each run is a fresh process (imports and in-memory caches cold, as for a user's command), timed from
its start to the last record, with each trial on one thread (``HANDSIM_THREADS=1``, as in a pool worker:
the 1-worker run is one core's throughput). Printed, per worker count: wall time, trials per minute and
the scaling 2 vs 1 worker; then the per-trial time split from the records (load = read + build +
compile + glove placement search; replay; render) and the runner's own overhead: wall ÷ trials (1
worker) minus the mean time spent inside the trial function (imports, process start, record writing,
progress).
``mj_step``'s share of ``replay()`` is measured in the same run on one trial (a raw ``mj_step`` loop with
the same inputs).

Ray: a local cluster of 2 CPUs (``ray start --head --block``, token authentication as ``ray start``
enables it) runs the same dataset through ``run_dataset(backend="ray", address=…)`` from a fresh process;
its throughput over the 2-worker pool's, timed back to back, is one ratio (1.0: the same; ≥ 0.9: within
10 %), and its records must equal the pool's bitwise (``timing`` aside). One pair of runs moves by ±8 %
on a shared 2-core machine, so ``--ray-rounds`` pairs are timed (the
first pool run is the 2-worker run above; each further pair a fresh pool run, then a fresh Ray run, each
on a fresh cluster) and ``ray_vs_pool`` is the median of their ratios, every ratio printed. Only that
cluster is stopped after each run (not every Ray of the machine, as ``ray stop`` would).

Run length (``--copies``, default 12: 36 trials, ~40 s per 2-worker run; ~6 min for all the runs). A Ray
run pays ~2 s that a pool run does not, whatever its length (the driver's ``import ray`` and connection,
the cluster's daemons beside two busy workers, the disconnection): at 18 trials that fixed cost alone moved
``ray_vs_pool`` below 0.9. A GraspDB-sized run lasts ~45 min, where such seconds vanish, so the longer runs
are the closer measure of it. Measured runs: ``docs/measurements.md`` ("Dataset runs").

Projection (``graspdb_projection_min``): 2,200 glove trials of 300 frames on 2 cores = 2,200 × the
1-worker wall time per trial (overheads included), with its replay part scaled from these recordings'
mean frame count to 300 frames, ÷ the measured 2-vs-1-worker scaling. The machine's load average
(``os.getloadavg``) is printed before and after: on a shared machine the figures are only as good as it
is quiet.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import handsim
from handsim.assets import TZIONAS_DIR
from handsim.runner.records import load_records
from handsim.thread_setting import THREADS_ENV
from handsim.trials import discover

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "graspdb14"
GRASPDB_SIZE = 2200
TREE = Path(handsim.__file__).resolve().parents[1]
"""The folder holding the ``handsim`` this benchmark imported: every run it starts imports that one too (its
working folder and the head of ``PYTHONPATH``; a ``python -c`` child would otherwise import the ``handsim``
of its working folder first, whatever ``PYTHONPATH`` says)."""
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
                (data / name).write_text(_perturbed(path.read_text(), c))
                if annotation.is_file():
                    target = name.removeprefix("r_").removesuffix(".txt") + "_annot-.txt"
                    shutil.copy(annotation, data / target)
    tzionas = root / "tzionas"
    shutil.copytree(TZIONAS_DIR, tzionas)
    return data if SHARED.is_dir() else tzionas


def _perturbed(text: str, copy: int) -> str:
    """The recording with its first row's last value moved by ``copy × 1e-5`` rad (copy 0: unchanged)."""
    if copy == 0:
        return text
    first, rest = text.split("\n", 1)
    head, last = first.rstrip().rsplit(" ", 1)
    return f"{head} {float(last) + copy * 1e-5:.5f} \n{rest}"


def _without_placements() -> None:
    """Remove the benchmark cache's placement entries (the hull entries stay)."""
    shutil.rmtree(Path(os.environ["HANDSIM_CACHE_DIR"]) / "placement", ignore_errors=True)


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
    """One dataset run in a fresh process (imports and in-memory caches cold for every worker count).

    Every trial runs on one thread (``HANDSIM_THREADS=1``), as in the pool's worker processes: with one
    worker the trials run in this fresh process, which would otherwise spread a trial's independent
    simulation runs (the ensemble, the stability tests) over every core, and the 2-vs-1-worker scaling
    would compare two cores with two cores.
    """
    done = subprocess.run(
        [sys.executable, "-c", _RUN, str(dataset), str(out), str(workers), str(frames)],
        check=True,
        capture_output=True,
        text=True,
        env={**os.environ, THREADS_ENV: "1"},
        cwd=TREE,
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


RAY_RUN = """
import sys, time
start = time.perf_counter()
from handsim.trials import discover
from handsim.runner.execute import run_dataset
run_dataset(discover(sys.argv[1]), sys.argv[2], backend="ray", address=sys.argv[3], frames=int(sys.argv[4]),
            progress=False, command=["benchmark"])
print(time.perf_counter() - start)
"""
PROJECTED_FRAMES = 300


def ray_run(dataset: Path, out: Path, frames: int, log: Path) -> tuple[float, list[dict]]:
    """The dataset run on a local 2-CPU Ray cluster by address, in a fresh process; the cluster stopped
    after."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from tests.processes import ray_head

    env = {**os.environ, "RAY_AUTH_MODE": "token"}  # the cluster's token authentication (ray start default)
    with ray_head(2, log) as (address, _):
        done = subprocess.run(
            [sys.executable, "-c", RAY_RUN, str(dataset), str(out), address, str(frames)],
            check=True, capture_output=True, text=True, env=env, cwd=TREE,
        )  # fmt: skip
    return float(done.stdout.split()[-1]), load_records(out).records


def _without_timing(records: list[dict]) -> dict[str, dict]:
    return {r["id"]: {k: v for k, v in r.items() if k != "timing"} for r in records}


def _load() -> str:
    return " ".join(f"{v:.2f}" for v in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--copies", type=int, default=12, help="copies of each real recording")
    parser.add_argument("--frames", type=int, default=4, help="frames rendered per trial")
    parser.add_argument(
        "--ray-rounds",
        type=int,
        default=3,
        help="pool and Ray runs timed in pairs; ray_vs_pool: their median",
    )
    args = parser.parse_args()
    print(f"load average (1, 5, 15 min) at the start: {_load()} on {os.cpu_count()} cores")
    print(f"handsim from {TREE}")
    os.environ["PYTHONPATH"] = os.pathsep.join([str(TREE), *filter(None, [os.environ.get("PYTHONPATH")])])
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        os.environ["HANDSIM_CACHE_DIR"] = str(root / "cache")  # inherited by every run and the Ray cluster
        dataset = synthesise(root, args.copies)
        trials = len(discover(dataset).entries)
        (root / "one").mkdir()
        run(synthesise(root / "one", 1), root / "warm", 1, 0)  # warms the hull cache on disk; not timed
        results = {}
        for workers in (1, 2):
            _without_placements()
            wall, records = run(dataset, root / f"out{workers}", workers, args.frames)
            results[workers] = (wall, records)
            rate = trials / wall * 60
            print(f"{workers} worker(s): {trials} trials in {wall:.1f} s = {rate:.1f} trials/min")
        scaling = results[1][0] / results[2][0]
        print(f"scaling 2 vs 1 worker: {scaling:.2f}×")
        reference = _without_timing(results[2][1])
        ratios, same = [], True
        for round_ in range(max(1, args.ray_rounds)):
            if round_:
                _without_placements()
                pool_wall, pool_records = run(dataset, root / f"pool{round_}", 2, args.frames)
                same = same and _without_timing(pool_records) == reference
            else:
                pool_wall = results[2][0]
            _without_placements()
            ray_wall, ray_records = ray_run(
                dataset, root / f"ray{round_}", args.frames, root / f"ray{round_}.log"
            )
            identical = _without_timing(ray_records) == reference
            same = same and identical
            ratios.append(pool_wall / ray_wall)
            print(
                f"Ray (local cluster, 2 CPUs, by address), pair {round_ + 1}: {trials} trials in "
                f"{ray_wall:.1f} s = {trials / ray_wall * 60:.1f} trials/min against the pool's "
                f"{pool_wall:.1f} s: {ratios[-1]:.3f}; records bitwise the pool's (timing aside): {identical}"
            )
        print(f"Ray over the pool, median of {len(ratios)} pairs: {statistics.median(ratios):.3f}")
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
        per_trial = wall / trials + mean["replay_s"] * (PROJECTED_FRAMES / frames - 1)
        projected = GRASPDB_SIZE * per_trial / scaling / 60
        print(
            f"projection: {GRASPDB_SIZE} trials of {PROJECTED_FRAMES} frames: {per_trial:.3f} s per trial "
            f"on 1 worker (measured {wall / trials:.3f} s at {frames:.0f} frames on average, replay scaled "
            f"to {PROJECTED_FRAMES}) ÷ {scaling:.2f} (2 vs 1 worker) = {projected:.1f} min on 2 cores"
        )
        print(f"load average (1, 5, 15 min) at the end: {_load()}")
        print(f"scaling_2_workers={scaling:.3f}")
        print(f"runner_overhead={overhead / (wall / trials):.4f}")
        print(f"ray_records_identical={same}")
        print(f"graspdb_projection_min={projected:.1f}")
        print(f"ray_vs_pool={statistics.median(ratios):.3f}")


if __name__ == "__main__":
    main()
