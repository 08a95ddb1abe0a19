"""Benchmark: the glove placement search against the replay, per trial, on the shared GraspDB14 recordings.

Run: python benchmarks/placement.py [--repeats N] [--data ../shared/data/graspdb14]

For each of the three shared GraspDB14 trials on both hands (the parametric default hand and the GraspDB14
``default.xmlskel``), in one process (median of ``--repeats``):

* placement: :func:`handsim.sim.placement.place.place_object` as :func:`handsim.sim.scenarios.glove_scene`
  calls
  it (candidates, fit frames, grip tests, the robustness perturbations' fit frames), timed by wrapping it,
  with the placement cache off (the search itself); ``cached``: the same call answered by the cache (a
  fresh temporary cache directory, written once, then read);
* load: the whole :func:`handsim.trials.load_trial` (read, build, compile, placement);
* replay: one :func:`handsim.sim.replay.replay` without the robustness ensemble (the replay a user waits
  for once the scene is built), and with it (the winner, its alternatives and perturbations, and the grip
  test at the release; ``handsim replay``'s default).

Prints a table, the load average, ``cached_placement_vs_replay=<ratio>``,
``placement_vs_replay_with_ensemble=<ratio>`` (over the replay a user waits for with ``handsim replay``:
the robustness ensemble and the test at the release included) and, last,
``placement_vs_replay=<ratio>`` (total placement search time over total replay time without the ensemble)
for tracking over time. Skips with a message when the data is absent. Run it from the repository root with
``PYTHONPATH=.`` to time this tree's code rather than an installed handsim.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import handsim.sim.scenarios as scenarios
from handsim.sim.replay import ReplayConfig, replay
from handsim.trials import load_trial

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
from recordings_table import DATA, TRIALS  # the shared recordings, listed once


def _timed_placement(store: list[float], calls: list):
    original = scenarios.place_object

    def timed(*args, **kwargs):
        calls.append((args, kwargs))
        start = time.perf_counter()
        try:
            return original(*args, **kwargs, use_cache=False)
        finally:
            store.append(time.perf_counter() - start)

    return original, timed


def _cached_seconds(place, args: tuple, kwargs: dict, repeats: int) -> float:
    """Median seconds of the placement read from a cache entry (written once beforehand)."""
    with tempfile.TemporaryDirectory() as cache:
        place(*args, **kwargs, cache_dir=cache)
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            place(*args, **kwargs, cache_dir=cache)
            times.append(time.perf_counter() - start)
    return statistics.median(times)


def measure(path: Path, skeleton: Path | None, repeats: int) -> dict:
    """Median seconds of the placement, the load, and the replay without and with the ensemble."""
    placements: list[float] = []
    calls: list = []
    loads, singles, ensembles = [], [], []
    original, timed = _timed_placement(placements, calls)
    scenarios.place_object = timed
    try:
        for _ in range(repeats):
            start = time.perf_counter()
            loaded = load_trial(path, skeleton=None if skeleton is None else str(skeleton))
            loads.append(time.perf_counter() - start)
            start = time.perf_counter()
            replay(loaded.scene, loaded.trajectory, ReplayConfig(ensemble=False))
            singles.append(time.perf_counter() - start)
            start = time.perf_counter()
            result = replay(loaded.scene, loaded.trajectory)
            ensembles.append(time.perf_counter() - start)
    finally:
        scenarios.place_object = original
    placement = loaded.scene.setup.placement
    return {
        "placement": statistics.median(placements),
        "cached": _cached_seconds(original, *calls[-1], repeats),
        "load": statistics.median(loads),
        "replay": statistics.median(singles),
        "ensemble": statistics.median(ensembles),
        "candidates": placement.get("candidates"),
        "grip_tests": placement.get("grip_tests"),
        "held": result.summary.get("held"),
    }


def main() -> int:
    """Time every trial and print the table and the ratio."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--data", type=Path, default=DATA)
    args = parser.parse_args()
    if not all((args.data / name).is_file() for name in TRIALS):
        print(f"skipped: the GraspDB14 recordings are not in {args.data}")
        return 0
    print(f"{'trial':<34} {'hand':<8} {'placement':>10} {'cached':>7} {'load':>7} {'replay':>7} "
          f"{'+ensemble':>10} {'poses':>7} {'grip tests':>10}")  # fmt: skip
    total_placement = total_replay = total_cached = total_full = 0.0
    for name in TRIALS:
        for hand, skeleton in (("default", None), ("xmlskel", args.data / "default.xmlskel")):
            m = measure(args.data / name, skeleton, args.repeats)
            total_placement += m["placement"]
            total_replay += m["replay"]
            total_cached += m["cached"]
            total_full += m["ensemble"]
            print(
                f"{name:<34} {hand:<8} {m['placement']:>9.2f}s {m['cached']:>6.3f}s {m['load']:>6.2f}s "
                f"{m['replay']:>6.2f}s "
                f"{m['ensemble']:>9.2f}s {m['candidates']:>7} {m['grip_tests']:>10}"
            )
    trials = 2 * len(TRIALS)
    per_trial = total_placement / trials, total_replay / trials
    print(f"placement per trial {per_trial[0]:.2f} s, replay per trial {per_trial[1]:.2f} s")
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores")
    print(f"cached_placement_vs_replay={total_cached / total_replay:.3f}")
    print(f"placement_vs_replay_with_ensemble={total_placement / total_full:.2f}")
    print(f"placement_vs_replay={total_placement / total_replay:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
