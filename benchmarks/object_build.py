"""Benchmark: object and scene building, cold (CoACD) vs warm (cached hulls), and the scene's mj_step rate.

Run: python benchmarks/object_build.py [--skip-cold]
Prints, for every catalogue object, its hull count and the CoACD time that produced the hulls; then the
mug (concave: 16 hulls) built cold (CoACD in a fresh cache, about a minute) and warm (cached hulls) as a
scene with the default hand, with the warm scene build + compile time (target < 0.2 s), and the raw
mj_step rate of that scene next to the bare hand's (same run).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time

import mujoco
import numpy as np

from handsim.builders import build_object, build_scene, catalog, default_hand, prepare_object


def step_rate(model: mujoco.MjModel, seconds: float = 1.0) -> float:
    """Raw mj_step calls per second over ``seconds`` of simulated time, median of 3."""
    rates = []
    for _ in range(3):
        data = mujoco.MjData(model)
        nstep = round(seconds / model.opt.timestep)
        start = time.perf_counter()
        mujoco.mj_step(model, data, nstep)
        rates.append(nstep / (time.perf_counter() - start))
    return statistics.median(rates)


def scene_build(cache_dir: str | None) -> float:
    start = time.perf_counter()
    build_scene(default_hand(), [build_object(catalog.get("mug"), cache_dir=cache_dir)]).compile()
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--skip-cold", action="store_true", help="skip the cold (CoACD) mug build")
    args = parser.parse_args()

    print(f"{'object':16s} {'hulls':>5s} {'CoACD s':>8s}  collision")
    for entry in catalog.entries():
        prepared = prepare_object(entry.load())
        for part in prepared.model.parts:
            d = prepared.decompositions.get(part.name)
            if d is None:
                print(f"{entry.name:16s} {'-':>5s} {'-':>8s}  {len(part.primitives)} primitives")
            else:
                how = d.skipped or ("cached" if d.from_cache else "computed now")
                print(
                    f"{entry.name:16s} {len(d.hulls):5d} {d.coacd_seconds:8.1f}  hulls ({part.name}, {how})"
                )

    with tempfile.TemporaryDirectory() as tmp:
        if not args.skip_cold:
            mug = catalog.get("mug").parts[0].mesh
            from handsim.builders.decompose import decompose

            start = time.perf_counter()
            cold = decompose(mug, cache_dir=tmp, use_cache=False)
            print(f"\nmug cold: CoACD {time.perf_counter() - start:.1f} s, {len(cold.hulls)} hulls")
        warm = [scene_build(tmp) for _ in range(10)]
    print(
        f"mug scene (default hand + mug) warm build + compile: "
        f"median {statistics.median(warm) * 1000:.0f} ms (target < 200 ms)"
    )

    scene = build_scene(default_hand(), [build_object(catalog.get("mug"))]).compile()
    hand = default_hand().compile()
    scene_rate, hand_rate = step_rate(scene), step_rate(hand)
    print(
        f"raw mj_step: hand + mug scene {scene_rate:,.0f} steps/s "
        f"({scene_rate * scene.opt.timestep:.0f}× real time); bare hand {hand_rate:,.0f} steps/s; "
        f"scene/hand {scene_rate / hand_rate:.2f}"
    )
    data = mujoco.MjData(scene)
    mujoco.mj_step(scene, data, 500)
    assert not np.any([w.number for w in data.warning]), "warnings in the benchmark scene"
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
