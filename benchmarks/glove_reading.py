"""Benchmark: reading a long GraspDB14 glove recording, resampling it to 100 Hz, checking joint limits.

Run: python benchmarks/glove_reading.py [--frames 10000] [--repeats 5] [--profile]

Synthesises a 10,000-frame ``rad`` recording by repeating the rows of the real trial
``../shared/data/graspdb14/r_01_11_ex03-rad-004-grasp-su04.txt`` with time stamps that keep increasing (the
trial's own 15/16/31/32 ms steps, cycled), writes it to a temporary folder, and prints the median time of
``read_trajectory`` (parse + convert to radians targets), ``resample(…, 100)`` and ``limit_violations``.
Target: reading + resampling under 0.5 s. With ``--profile`` (or when reading misses the target) it prints
the functions of the reader where the time goes.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import itertools
import pstats
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np

from handsim.datatypes.trajectory_ops import limit_violations, resample
from handsim.io import read_skeleton, read_trajectory

GRASPDB = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "graspdb14"
TRIAL = GRASPDB / "r_01_11_ex03-rad-004-grasp-su04.txt"
SKELETON = GRASPDB / "default.xmlskel"
TARGET_S = 0.5


def synthesise(trial: Path, frames: int, out: Path) -> Path:
    """Write a ``frames``-row recording made of the trial's rows repeated, with increasing time stamps.

    The time stamps start at the trial's first one and advance by the trial's own steps, cycled (the step
    from its last row back to its first is its median step), rounded to 10 µs as in the files.
    """
    rows = [line.split() for line in trial.read_text().splitlines() if line.strip()]
    stamps = [datetime(*map(int, r[:5])) + timedelta(seconds=float(r[5])) for r in rows]
    steps_us = [round((b - a).total_seconds() * 1e5) * 10 for a, b in itertools.pairwise(stamps)]
    steps_us.append(int(statistics.median(steps_us)))
    start = stamps[0]
    elapsed_us = 0
    lines = []
    for k in range(frames):
        row = rows[k % len(rows)]
        t = start + timedelta(microseconds=elapsed_us)
        seconds = t.second + t.microsecond / 1e6
        stamp = f"{t.year:04d} {t.month:02d} {t.day:02d} {t.hour:02d} {t.minute:02d} {seconds:08.5f}"
        lines.append(f"{stamp} {' '.join(row[6:])} \n")
        elapsed_us += steps_us[k % len(steps_us)]
    path = out / f"r_01_11_ex03-rad-{frames}-grasp-su04.txt"
    path.write_text("".join(lines))
    return path


def median_time(fn: Callable[[], object], repeats: int) -> tuple[float, object]:
    """Median wall time of ``fn()`` over ``repeats`` calls, s, and the last result."""
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def profile_reading(path: Path, skeleton: object, top: int = 15) -> str:
    """cProfile listing (by cumulative and by own time) of one ``read_trajectory`` call."""
    profiler = cProfile.Profile()
    profiler.enable()
    read_trajectory(path, skeleton)
    profiler.disable()
    text = io.StringIO()
    stats = pstats.Stats(profiler, stream=text)
    stats.sort_stats("cumulative").print_stats(top)
    stats.sort_stats("tottime").print_stats(top)
    return text.getvalue()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=10_000, help="rows of the synthetic recording")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per step (median reported)")
    parser.add_argument("--profile", action="store_true", help="profile read_trajectory in any case")
    args = parser.parse_args(argv)
    if not TRIAL.exists() or not SKELETON.exists():
        print(
            f"glove_reading: needs the real GraspDB14 sample data: {TRIAL} and {SKELETON} "
            "(in ../shared/data, present in the project's CI, not in a user's clone); nothing was timed",
            file=sys.stderr,
        )
        return 2
    skeleton = read_skeleton(SKELETON)
    with tempfile.TemporaryDirectory() as tmp:
        path = synthesise(TRIAL, args.frames, Path(tmp))
        size_mb = path.stat().st_size / 1e6
        t_read, traj = median_time(lambda: read_trajectory(path, skeleton), args.repeats)
        t_resample, result = median_time(lambda: resample(traj, 100.0), args.repeats)
        t_limits, report = median_time(lambda: limit_violations(traj, skeleton), args.repeats)
        profile = profile_reading(path, skeleton) if args.profile or t_read > TARGET_S else ""

    steps = np.diff(traj.times)
    print(f"synthetic recording: {traj.nframes} frames, {traj.duration:.2f} s, {size_mb:.2f} MB")
    print(
        f"  input steps {steps.min() * 1e3:.1f}..{steps.max() * 1e3:.1f} ms, "
        f"mean rate {traj.mean_rate:.2f} Hz"
    )
    print(f"{'step':34s} {'median [ms]':>12s}")
    print(f"{'read_trajectory (parse + convert)':34s} {t_read * 1e3:12.1f}")
    print(f"{'resample(…, 100 Hz)':34s} {t_resample * 1e3:12.1f}")
    print(f"{'limit_violations':34s} {t_limits * 1e3:12.1f}")
    total = t_read + t_resample
    verdict = "meets" if total < TARGET_S else "MISSES"
    print(f"{'read + resample':34s} {total * 1e3:12.1f}  ({verdict} the {TARGET_S * 1e3:.0f} ms target)")
    print(
        f"resampled: {result.trajectory.nframes} frames; "
        f"largest input gap {result.largest_gap_s * 1e3:.1f} ms"
    )
    print(
        f"limit violations: {report.total} of {report.checked} valid samples in {len(report.violating)} DoFs"
    )
    if profile:
        print("\nprofile of one read_trajectory call:\n" + profile)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
