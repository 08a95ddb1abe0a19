"""Benchmark: building + compiling hands, and raw mj_step throughput of the bare hand.

Run: python benchmarks/hand_build.py
Prints the median build + compile time of the default hand (target < 50 ms) and the raw mj_step rate of
each hand, as the reference later replay benchmarks compare against (same model, same run).
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

from handsim.builders import build_hand, default_hand
from handsim.io import read_skeleton

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def time_build(make, repeats: int = 30) -> float:
    """Median seconds to build the spec and compile it."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        make().compile()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def step_rate(model: mujoco.MjModel, seconds: float = 1.0, repeats: int = 5) -> float:
    """Median raw mj_step calls per second over ``seconds`` of simulated time with constant control."""
    rates = []
    for _ in range(repeats):
        data = mujoco.MjData(model)
        low, high = model.actuator_ctrlrange.T
        data.ctrl[:] = 0.5 * (np.clip(0, low, high) + 0.5 * (low + high))
        nstep = round(seconds / model.opt.timestep)
        start = time.perf_counter()
        mujoco.mj_step(model, data, nstep)
        rates.append(nstep / (time.perf_counter() - start))
    return statistics.median(rates)


def main() -> int:
    hands = {"default (0.19 m)": default_hand}
    graspdb = SHARED / "graspdb14" / "default.xmlskel"
    tzionas = SHARED / "tzionas_ijcv16" / "Models" / "20" / "Model_Hand_R.SKEL"
    if graspdb.exists():
        skel = read_skeleton(graspdb)
        hands["graspdb14 default.xmlskel"] = lambda: build_hand(skel)
    if tzionas.exists():
        tz = read_skeleton(tzionas)
        hands["tzionas Model_Hand_R (capsules)"] = lambda: build_hand(tz)
        hands["tzionas Model_Hand_R (mesh hulls)"] = lambda: build_hand(tz, collision="mesh")
    print(f"mujoco {mujoco.__version__}")
    print(f"{'hand':36s} {'build+compile':>14s} {'raw mj_step/s':>14s} {'real-time x':>12s}")
    for label, make in hands.items():
        build_s = time_build(make)
        model = make().compile()
        rate = step_rate(model)
        print(f"{label:36s} {build_s * 1000:11.1f} ms {rate:14.0f} {rate * model.opt.timestep:11.1f}x")
    default_build = time_build(default_hand)
    print(f"default_hand_build_compile_ms={default_build * 1000:.1f} (target < 50)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
