"""Benchmark: judging every grasp episode of a whole glove session, on 2 cores, cold and warm caches.

Run: python benchmarks/episodes.py [--session PATH] [--workers 2]

The shared session (``../shared/data/graspdb14/sessions/01_11_ex03-rad-004-grasp-su04.txt``: 51 complete
tennis-ball grasps in 195 s) is put alone in a dataset folder and run by ``handsim report``'s runner
(``run_dataset``: one trial per complete episode, no frames rendered, each trial on one thread as in a
pool worker) in a fresh process, twice: with an empty cache folder (``HANDSIM_CACHE_DIR``: every episode
pays its placement search; ``cold``) and again with the cache the first run left (``warm``). Printed:
episodes judged (held or not held) and replayed, wall time, ``episodes_per_minute_2_cores=`` (replayed
episodes per minute of wall time), the CPU time inside the trial function per episode (load = read,
segmentation, scene and placement; replay = the winner, the grip check, the robustness ensemble, the
release test), and, for one episode in this process, its replay against a raw ``mj_step`` loop on the same
model with the same controls (``replay_vs_raw_one_episode=``: raw loop time ÷ ``replay()`` without the
ensemble, 1.0 would be no overhead at all). The machine's load average is printed before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TREE = Path(__file__).resolve().parents[1]
SESSION = TREE.parent / "shared" / "data" / "graspdb14" / "sessions" / "01_11_ex03-rad-004-grasp-su04.txt"
_RUN = """
import sys, time
start = time.perf_counter()
from handsim.trials import discover
from handsim.runner.execute import run_dataset
run_dataset(discover(sys.argv[1]), sys.argv[2], workers=int(sys.argv[3]), frames=0, progress=False,
            command=["benchmark"])
print(time.perf_counter() - start)
"""


def run(dataset: Path, out: Path, workers: int, cache: Path) -> tuple[float, list[dict]]:
    """One dataset run in a fresh process with the given cache folder; wall time and records."""
    env = {**os.environ, "HANDSIM_CACHE_DIR": str(cache), "HANDSIM_THREADS": "1"}
    done = subprocess.run(
        [sys.executable, "-c", _RUN, str(dataset), str(out), str(workers)],
        check=True, capture_output=True, text=True, env=env, cwd=TREE,
    )  # fmt: skip
    lines = (out / "records.jsonl").read_text(encoding="utf-8").splitlines()
    return float(done.stdout.split()[-1]), [json.loads(line) for line in lines if line.strip()]


def replay_vs_raw(session: Path) -> float:
    """Raw ``mj_step`` loop ÷ ``replay()`` (no ensemble) for the session's first complete episode."""
    import mujoco

    from handsim.sim.control import control_schedule
    from handsim.sim.drive import ScheduleDriver, scenario_switches
    from handsim.sim.replay import ReplayConfig, replay
    from handsim.sim.stepper import Stepper
    from handsim.trials.registry import find_trial, grasp_episodes, load_trial

    first = grasp_episodes(find_trial(session)).complete[0].index
    loaded = load_trial(session, grasp=first)
    scene, trajectory = loaded.scene, loaded.trajectory
    config = ReplayConfig(ensemble=False)
    schedule = control_schedule(scene, trajectory, config.control_rate)
    raw, full = [], []
    for _ in range(5):
        driver = ScheduleDriver(
            Stepper(scene, schedule.substeps), schedule, scenario_switches(scene, schedule, 0.1)
        )
        driver.reset()
        data, model = driver.stepper.data, driver.stepper.model
        start = time.perf_counter()
        for i in range(1, schedule.frames):
            data.ctrl[:] = schedule.ctrl[i]
            mujoco.mj_step(model, data, nstep=schedule.substeps)
        raw.append(time.perf_counter() - start)
        start = time.perf_counter()
        replay(scene, trajectory, config)
        full.append(time.perf_counter() - start)
    return statistics.median(raw) / statistics.median(full)


def report(label: str, wall: float, records: list[dict]) -> None:
    """Print one run's figures."""
    replayed = [r for r in records if r["status"] in ("ok", "diverged")]
    judged = [r for r in replayed if (r["summary"] or {}).get("held") is not None]
    load = statistics.fmean(r["timing"]["load_s"] for r in replayed) if replayed else float("nan")
    replay = statistics.fmean(r["timing"]["replay_s"] for r in replayed) if replayed else float("nan")
    print(
        f"{label}: {len(records)} episodes, {len(replayed)} replayed, {len(judged)} judged (held or not held)"
    )
    print(f"{label}: wall {wall:.1f} s; per episode, in the trial: load {load:.2f} s, replay {replay:.2f} s")
    print(f"{label}_episodes_per_minute_2_cores={len(replayed) / wall * 60.0:.1f}")


def main() -> None:
    """Run the session cold and warm, and one episode against raw ``mj_step``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--session", type=Path, default=SESSION, help="a glove recording of many grasps")
    parser.add_argument("--workers", type=int, default=2, help="pool workers (2: the 2-core figure)")
    args = parser.parse_args()
    if not args.session.is_file():
        sys.exit(f"benchmarks/episodes.py: {args.session} not found (it needs ../shared/data)")
    print(f"load average before: {os.getloadavg()}")
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        dataset = root / "dataset"
        dataset.mkdir()
        (dataset / args.session.name).symlink_to(args.session.resolve())
        cache = root / "cache"
        for label in ("cold", "warm"):
            wall, records = run(dataset, root / label, args.workers, cache)
            report(label, wall, records)
            if label == "cold":
                print(f"episodes_per_minute_2_cores={len(records) / wall * 60.0:.1f}")
    print(f"replay_vs_raw_one_episode={replay_vs_raw(args.session):.3f}")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
