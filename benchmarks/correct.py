"""Benchmark: the correction's rollouts against raw ``mj_step``, and a whole correction of sequence 20.

Run from the repository root: ``PYTHONPATH=. python benchmarks/correct.py [--repeats N] [--threads N]``
(``--no-full`` skips the whole correction, which takes minutes; ``--arctic`` adds a correction of the
ARCTIC-shaped benchmark scene).

Two numbers, in one run, on the bundled Tzionas sequence 20 (right hand + 53 mm cube, 617 frames at 100 Hz):

* ``rollout_vs_raw_1thread=``: simulated steps per second (wall clock) of one planning step's rollouts as the
  correction runs them (:class:`handsim.correct.backend.CpuRollout` on ``--threads`` threads, default 2:
  ``samples`` residual sequences of ``horizon`` frames of 5 steps, from the committed state at frame 460,
  where the cube is in the hand and the correction works hardest), over raw single-thread ``mj_step`` on the
  same model from the same state with the same controls (set once per frame, ``nstep = 5`` per call: the
  floor any stepping loop can reach). The machine's limit is the number of threads (2.0 on 2 cores);
  ``mujoco.rollout`` runs the rollouts in native threads, so only the hand-over between them costs.
  Interleaved, the least time of ``--repeats`` for each side (``BEST``: the machine is shared, other work
  only ever adds time).
* ``correct_seconds_per_recorded_second=``: the wall time of ``handsim.correct.correct`` on the whole
  sequence with the default (``standard``) parameters on ``--threads`` threads, over the recording's 6.16 s
  (the before and after replays included; loading the trial not).

With ``--arctic``, ``arctic_followed_before=`` and ``arctic_followed_after=``: the fraction of the manipulated
frames in which the ARCTIC-shaped benchmark scene's box follows its recording (the replay's track verdict,
:func:`handsim.sim.track.track_verdict`) in pure replay and after a correction with the ``quick`` budget
(two mean-shape MANO hands carry the box and lift its lid: ``benchmarks/arctic_recording.py``); and
``arctic_wide_followed_before=`` / ``…_after=``, the same with the wrists 4 mm further out in the carry
(:data:`WIDE_GRIP`): a capture error of the kind a correction exists for.

With ``--warp`` (``handsim[warp]``; a GPU, or the device ``$HANDSIM_WARP_DEVICE`` names):
``warp_rollouts_vs_cpu_threads=``, the same planning step's rollouts on MuJoCo Warp (every sequence a world
of one batch, kernels compiled and the CUDA graph captured before timing) over ``CpuRollout`` on
``--threads`` threads (16 on the GPU machine, as the issue asks), and
``warp_correct_seconds_per_recorded_second=``, the whole correction planned on Warp. ``--samples N`` sets the
batch: a GPU pays only for large ones (docs/gpu.md).

The load average is printed beside them: on a machine shared with other work the wall-clock numbers are
what the machine gave this run.
"""

from __future__ import annotations

import argparse
import os
import time

import mujoco
import numpy as np

from handsim.assets import TZIONAS_DIR
from handsim.correct import CorrectionConfig, correct
from handsim.correct.backend import STATE, CpuRollout, start_of
from handsim.correct.planner import committed_driver
from handsim.correct.reference import build_reference
from handsim.correct.sampler import AnnealedSampler
from handsim.sim.stepper import Stepper
from handsim.trials import LoadedTrial, Trial, load_trial

BEST = min
"""The statistic of the repeats: the least time (other work on a shared machine only adds time)."""
WIDE_GRIP = 0.102
"""``--arctic``'s second case: the benchmark scene with its wrists 4 mm further out in the carry (m from the
box's mid-plane), a recording pure replay does not carry (the box turns out of the palms)."""
START = 460
"""The frame the rollouts start from: the cube in the hand, just before pure replay lets it slip."""


def _load() -> str:
    one, five, _ = os.getloadavg()
    return f"load average {one:.2f} (1 min), {five:.2f} (5 min) on {os.cpu_count()} cores"


def planning_batch(loaded, config: CorrectionConfig):
    """One planning step's rollouts from frame :data:`START`: (model, start, controls, spec, substeps)."""
    reference = build_reference(loaded.scene, loaded.trajectory, config)
    stepper = Stepper(loaded.scene, reference.schedule.substeps)
    driver = committed_driver(reference, config, np.zeros((reference.frames, reference.size)), stepper)
    driver.reset()
    for k in range(START):
        driver.advance(driver.schedule.ctrl[k + 1])
    model = stepper.model
    begin = start_of(model, stepper.data)
    frames = START + 1 + np.arange(config.horizon)
    rng = np.random.default_rng(0)
    residual = rng.normal(0.0, 0.01, (config.samples, config.horizon, reference.size))
    sampler = AnnealedSampler(reference, config, CpuRollout(1), model, rng)
    controls = sampler.controls(residual, frames, begin)
    return model, begin, controls, sampler.spec(guided=False), reference.schedule.substeps


def rollout_ratio(loaded, config: CorrectionConfig, threads: int, repeats: int) -> float:
    """Rollout steps/s on ``threads`` threads over raw single-thread ``mj_step``'s (module docstring)."""
    model, begin, controls, spec, substeps = planning_batch(loaded, config)
    backend = CpuRollout(threads)
    nu = model.nu
    steps = controls.shape[0] * controls.shape[1]
    raw_data = mujoco.MjData(model)
    rollout_times, raw_times = [], []
    backend.rollout(model, begin, controls, spec)  # warm up: the thread pool and the per-thread data
    for _ in range(repeats):
        start = time.perf_counter()
        backend.rollout(model, begin, controls, spec)
        rollout_times.append(time.perf_counter() - start)
        start = time.perf_counter()
        for sequence in controls:
            mujoco.mj_setState(model, raw_data, begin.state, STATE)
            raw_data.qacc_warmstart[:] = begin.warmstart
            for row in sequence[::substeps]:
                raw_data.ctrl[:] = row[:nu]
                raw_data.mocap_pos[:] = row[nu : nu + 3 * model.nmocap].reshape(-1, 3)
                raw_data.mocap_quat[:] = row[nu + 3 * model.nmocap :].reshape(-1, 4)
                mujoco.mj_step(model, raw_data, nstep=substeps)
        raw_times.append(time.perf_counter() - start)
    backend.close()
    rollout_rate, raw_rate = steps / BEST(rollout_times), steps / BEST(raw_times)
    print(
        f"rollouts: {config.samples} sequences × {config.horizon} frames × {substeps} steps from "
        f"frame {START}: {rollout_rate:.0f} steps/s on {threads} threads, raw mj_step {raw_rate:.0f} steps/s "
        f"(1 thread; least of {repeats})"
    )
    return rollout_rate / raw_rate


def warp_comparison(loaded, config: CorrectionConfig, threads: int, repeats: int) -> tuple[float, float]:
    """MuJoCo Warp against ``threads`` CPU threads: one planning step's rollouts, then the whole correction.

    Returns:
        The rollouts' steps/s on Warp over the CPU threads', and the correction's seconds per recorded second
        on Warp (its kernels compiled before the clock starts).
    """
    from handsim.correct.warp_backend import WarpRollout

    model, begin, controls, spec, _ = planning_batch(loaded, config)
    steps = controls.shape[0] * controls.shape[1]
    rates = {}
    for name, backend in (("cpu", CpuRollout(threads)), ("warp", WarpRollout())):
        backend.rollout(model, begin, controls, spec)  # warm up: threads, or Warp's kernels and graph
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            backend.rollout(model, begin, controls, spec)
            times.append(time.perf_counter() - start)
        rates[name] = steps / BEST(times)
        device = getattr(backend, "device", f"{threads} threads")
        print(f"rollouts on {name} ({device}): {rates[name]:.0f} steps/s ({config.samples} sequences)")
        backend.close()
    start = time.perf_counter()
    correction = correct(loaded, config, backend="warp")
    seconds = time.perf_counter() - start
    recorded = float(correction.reference.schedule.times[-1])
    print(
        f"correction on MuJoCo Warp: {seconds:.1f} s for {recorded:.2f} s recorded; cube within 1 cm "
        f"{correction.score.after.within_1cm * 100:.1f} % ({correction.score.status})"
    )
    return rates["warp"] / rates["cpu"], seconds / recorded


def arctic_correction(threads: int, half_grip: float | None = None) -> tuple[float, float]:
    """The ARCTIC-shaped scene's followed fraction in pure replay and after a ``quick`` correction.

    ``half_grip``: the wrists' distance from the box's mid-plane in the carry, m (default: the benchmark's).
    """
    from arctic_recording import GRIP, arctic_case_scene  # benchmarks/arctic_recording.py

    from handsim.correct.config import BUDGETS

    half_grip = GRIP if half_grip is None else half_grip
    case = arctic_case_scene(half_grip)
    trial = Trial("arctic", "benchmarks/arctic_recording.py", None, ())
    loaded = LoadedTrial(trial, case.scene, case.trajectory, "two mean-shape MANO hands", ())
    budget = BUDGETS["quick"]
    start = time.perf_counter()
    correction = correct(
        loaded, CorrectionConfig(samples=budget.samples, iterations=budget.iterations), threads=threads
    )
    seconds = time.perf_counter() - start
    before, after = (r.summary.get("track_followed_fraction") for r in (correction.before, correction.after))
    score = correction.score
    print(
        f"ARCTIC-shaped scene (wrists {half_grip * 1000:.0f} mm from the box's mid-plane in the carry): "
        f"corrected in {seconds:.1f} s on {threads} threads; {score.status}: "
        f"{score.reason}; fingers {score.finger_rms_deg:.2f}° RMS, wrist "
        f"{score.wrist_position_rms_mm:.1f} mm and {score.wrist_rotation_rms_deg:.2f}° RMS"
    )
    return float("nan") if before is None else before, float("nan") if after is None else after


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--no-full", action="store_true", help="skip the whole correction (minutes)")
    parser.add_argument(
        "--arctic", action="store_true", help="also correct the ARCTIC-shaped scene (minutes)"
    )
    parser.add_argument(
        "--warp",
        action="store_true",
        help="also run the rollouts and the correction on MuJoCo Warp against --threads CPU threads "
        "(handsim[warp]; a GPU, or $HANDSIM_WARP_DEVICE)",
    )
    parser.add_argument("--samples", type=int, default=None, help="samples per round (default: the budget's)")
    args = parser.parse_args()
    print(f"start: {_load()}")
    loaded = load_trial(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION")
    config = CorrectionConfig() if args.samples is None else CorrectionConfig(samples=args.samples)
    ratio = rollout_ratio(loaded, config, args.threads, args.repeats)
    print(f"  ({_load()})")
    per_second = float("nan")
    if not args.no_full:
        start = time.perf_counter()
        correction = correct(loaded, config, threads=args.threads)
        seconds = time.perf_counter() - start
        recorded = float(correction.reference.schedule.times[-1])
        per_second = seconds / recorded
        score = correction.score
        print(
            f"correction: {seconds:.1f} s for {recorded:.2f} s recorded on {args.threads} threads "
            f"({correction.plan.rollouts} rollouts, {correction.plan.steps} steps, "
            f"{correction.plan.steps / correction.plan.seconds:.0f} steps/s in the planner); cube within "
            f"1 cm {score.after.within_1cm * 100:.1f} % (pure replay {score.before.within_1cm * 100:.1f} %)"
        )
        print(f"  ({_load()})")
    print(f"rollout_vs_raw_1thread={ratio:.3f}")
    print(f"correct_seconds_per_recorded_second={per_second:.2f}")
    if args.arctic:
        before, after = arctic_correction(args.threads)
        print(f"  ({_load()})")
        print(f"arctic_followed_before={before:.3f}")
        print(f"arctic_followed_after={after:.3f}")
        before, after = arctic_correction(args.threads, WIDE_GRIP)
        print(f"  ({_load()})")
        print(f"arctic_wide_followed_before={before:.3f}")
        print(f"arctic_wide_followed_after={after:.3f}")
    if args.warp:
        versus, warp_per_second = warp_comparison(loaded, config, args.threads, args.repeats)
        print(f"  ({_load()})")
        print(f"warp_rollouts_vs_cpu_threads={versus:.3f}")
        print(f"warp_correct_seconds_per_recorded_second={warp_per_second:.2f}")


if __name__ == "__main__":
    main()
