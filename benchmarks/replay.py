"""Benchmark: replay and env.step throughput against raw ``mj_step`` on the same compiled scene, same run.

Run: python benchmarks/replay.py [--repeats N]

Scenes: the Tzionas hand + cube (sequence 20, bundled), a glove + ball (the GraspDB14 power-sphere trial
on its skeleton when ``../shared/data`` is present, else the default hand closing on the tennis ball), and
an ARCTIC-shaped scene (:func:`handsim.sim.arctic_scene.arctic_scene` on the synthetic recording of
``benchmarks/arctic_recording.py``: two MANO hands of the bundled mean-shape model, each welded to a moving
wrist, carry a two-part box between their palms, set it down, and one lifts its lid with its fingertips,
10 s at ARCTIC's 30 fps).

Run it from the repository root as ``PYTHONPATH=. python benchmarks/replay.py`` to time this tree's
``handsim`` (a script's own folder comes first on ``sys.path``, so an installed copy would win).

For each scene, in the same process and interleaved (the least of ``--repeats``: :data:`BEST`), in CPU
seconds of this process (:data:`CLOCK`):

* raw: ``mj_step`` from the replay's initial state with only the replay's inputs (controls, mocap root
  pose, the glove contact switch, support release) set once per frame, ``nstep = substeps`` per call —
  the same simulation with nothing recorded or checked: the floor any replay loop can reach on this model;
* loop: :func:`handsim.sim.replay.run_schedule` (the stepping loop: controls, mocap root, support
  release, warning checks, sensor and state copies);
* replay: the whole :func:`handsim.sim.replay.replay` call (schedule, loop, metrics, summary, flags) of
  one simulation of the recording (:data:`ONE_RUN`); for the glove scene the robustness ensemble's extra
  replays are timed on their own line;
* env: ``env.step`` of ``handsim/Replay-v0`` with zero residuals against raw ``mj_step × frame_skip`` on
  the env's own model, from the same state with the same controls and root targets;
* vector env (wall clock): env-steps per second of one unwrapped ``Replay-v0``, of the native vector
  environment (:class:`handsim.envs.replay_vector_env.ReplayVectorEnv`, N worlds on MuJoCo's threads) and
  of ``gymnasium.vector.AsyncVectorEnv`` (N processes) at N = 2, 4, 8.

Where the time goes, measured run by run with cProfile and per-part timers, is in
``docs/measurements.md`` ("Replay against raw mj_step", "Environments"): the stepping loop is at the raw
loop, and ``replay()`` adds a fixed few ms per replay (schedule, a fresh ``MjData``, fingertip targets,
metrics, summary); ``env.step`` adds about 20 numpy calls on preallocated buffers; the vector environment
adds a fixed cost per step and a short per-world loop (the single environment's own code, so its results
are the same bitwise), and its two-world speed-up is capped by how well the machine runs MuJoCo's two
threads.

Prints steps per second, the real-time factor and the ratios, with the load average beside them (the
machine is shared); the last lines are ``replay_vs_raw=<ratio>`` (worst one-hand scene),
``env_vs_raw=<ratio>``, ``vector_env_scaling=<ratio>`` (the native vector environment's env-steps/s over
one environment's, worst N), ``arctic_replay_vs_raw=<ratio>`` (the ARCTIC-shaped scene) and
``arctic_checks_vs_replay=<ratio>`` (the CPU time the ARCTIC scene's checks before the run take, over one
``replay()`` of it: the scene built with its checks less the scene built without them).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import mujoco
import numpy as np
from arctic_recording import arctic_case_scene  # benchmarks/arctic_recording.py
from replay_inputs import ReplayInputs  # benchmarks/replay_inputs.py (scripts run from benchmarks/)

from handsim.assets import TZIONAS_DIR
from handsim.builders import build_hand, build_scene, default_hand
from handsim.builders.catalog import get, get_graspdb
from handsim.builders.objects import build_object
from handsim.datatypes.trajectory import Trajectory
from handsim.io import read_skeleton, read_trajectory
from handsim.io.tzionas.objects import read_tzionas_object
from handsim.io.tzionas.sequence import read_tzionas_sequence
from handsim.sim.arctic_scene import arctic_scene
from handsim.sim.control import control_schedule
from handsim.sim.drive import ScheduleDriver, scenario_switches
from handsim.sim.replay import ReplayConfig, replay, run_schedule
from handsim.sim.scenarios import glove_scene, recorded_scene
from handsim.sim.scene.compiled import compile_scene
from handsim.sim.specs import MetricSpec
from handsim.sim.stepper import Stepper

GRASPDB = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "graspdb14"
CLOCK = time.process_time
"""Single-threaded ratios use this process's CPU time: on a machine shared with other work, wall time
charges the other work's time slices to whichever side ran then; CPU time does not (it equals wall time on
a quiet machine). The vector environment's scaling is wall time (it is about using more cores)."""
BEST = min
"""The statistic of the repeats of the single-threaded ratios: the least time. This machine (a virtual
machine on a shared host) runs the same code 10–35 % slower from one second to the next whatever this
process does (the raw ``mj_step`` loop alone moved from 27 000 to 21 000 steps/s between runs at load
< 0.5); other work only ever adds time, so the least of several runs is the estimate least disturbed by it,
for both sides of a ratio alike (medians of 7 gave the Tzionas replay 0.82 and 0.99 of raw in two runs
an hour apart)."""
ONE_RUN = ReplayConfig(ensemble=False)
"""The replay ratio is one simulation of the recording; a glove trial's robustness ensemble replays
variants of the scene on top (each itself a ``replay``), timed on its own line."""
VECTOR_WORLDS = (2, 4, 8)
REPLAY = "handsim/Replay-v0"


def tzionas_case():
    seq = TZIONAS_DIR / "Models" / "20"
    trajectory = read_tzionas_sequence(seq)
    hand = build_hand(read_skeleton(seq / "Model_Hand_R.SKEL"))
    cube = build_object(read_tzionas_object(seq / "Model_Object_Cube.SKEL"))
    return "Tzionas hand + cube", recorded_scene(hand, trajectory, {"cube": cube}), trajectory


def glove_case():
    if GRASPDB.exists():
        from handsim.io.graspdb.annotations import attach_phases, find_annotation_file

        path = GRASPDB / "r_01_11_ex03-rad-004-grasp-su04.txt"
        skeleton = read_skeleton(GRASPDB / "default.xmlskel")
        trajectory = attach_phases(read_trajectory(path, skeleton=skeleton), find_annotation_file(path))
        scene = glove_scene(build_hand(skeleton), trajectory, build_object(get_graspdb(1)))
        return "glove + ball (GraspDB14)", scene, trajectory
    hand, ball = default_hand(), build_object(get("tennis_ball"))
    layout = compile_scene(build_scene(hand, ball)).layout
    t = np.arange(300) / 64.0
    flex = np.array(["flex" in n and not n.startswith("root") for n in layout.dof_names])
    targets = np.clip(t / 2.0, 0, 1)[:, None] * np.where(flex, 0.6 * layout.ctrl_range[:, 1], 0.0)
    trajectory = Trajectory(t, layout.dof_names, targets, np.ones_like(targets, bool))
    return "glove + ball (default hand, synthetic)", glove_scene(hand, trajectory, ball), trajectory


def arctic_case():
    """Two mean-shape MANO hands carry a box, then one opens its lid (:mod:`arctic_recording`)."""
    case = arctic_case_scene()
    return "ARCTIC-shaped: two MANO hands + box and lid", case.scene, case.trajectory, (case.hands, case.box)


def arctic_check_seconds(hands, trajectory, box, repeats: int) -> tuple[float, float]:
    """CPU seconds of building the ARCTIC-shaped scene with and without its checks before the run.

    The difference is what the checks cost (the hands' recorded paths against the stand and the floor, the
    lid's settled start, the hands' starting penetration, and a second compile where they change the world).
    """
    with_checks, without = [], []
    for _ in range(repeats):
        start = CLOCK()
        arctic_scene(hands, trajectory, box, "box")
        with_checks.append(CLOCK() - start)
        start = CLOCK()
        arctic_scene(hands, trajectory, box, "box", checks=False)
        without.append(CLOCK() - start)
    return BEST(with_checks), BEST(without)


def driver_at_start(scene, schedule, own_model: bool) -> ScheduleDriver:
    """A driver of the replay's scenario, reset to frame 0 (on a private model when ``own_model``)."""
    switches = scenario_switches(scene, schedule, MetricSpec().release_delay)
    stepper = Stepper(scene, schedule.substeps, own_model=own_model or switches.contact_frame > 0)
    driver = ScheduleDriver(stepper, schedule, switches)
    driver.reset()
    return driver


def raw_seconds(scene, schedule) -> float:
    """The same simulation with nothing but the inputs: controls, mocap root, contact switch, release."""
    driver = driver_at_start(scene, schedule, own_model=True)
    inputs = ReplayInputs.from_driver(driver)
    start = CLOCK()
    inputs.run(driver.stepper.model, driver.stepper.data)
    return CLOCK() - start


def loop_seconds(scene, schedule) -> float:
    driver = driver_at_start(scene, schedule, own_model=False)
    start = CLOCK()
    run_schedule(driver)
    return CLOCK() - start


def replay_seconds(scene, trajectory, config: ReplayConfig = ONE_RUN) -> float:
    start = CLOCK()
    replay(scene, trajectory, config)
    return CLOCK() - start


def env_ratio(repeats: int) -> tuple[float, float, float] | None:
    try:
        import gymnasium

        import handsim  # noqa: F401  registers the envs

        env = gymnasium.make("handsim/Replay-v0").unwrapped
    except Exception as exc:  # the env is optional for this benchmark's replay part
        print(f"env: not measured ({type(exc).__name__}: {exc})")
        return None
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
    model, skip = env.model, env.frame_skip
    steps = min(300, env.schedule.frames - 1)
    env_times, raw_times = [], []
    start_state = mujoco.MjData(model)
    env.reset(seed=0)
    mujoco.mj_copyData(start_state, model, env.data)
    # the env's inputs per step (zero residuals: the schedule's targets and the recorded root pose)
    ctrls, mocap_pos, mocap_quat = [], [], []
    for _ in range(steps):
        env.step(action)
        ctrls.append(env.data.ctrl.copy())
        mocap_pos.append(env.data.mocap_pos.copy())
        mocap_quat.append(env.data.mocap_quat.copy())
    data = mujoco.MjData(model)
    for _ in range(repeats):
        env.reset(seed=0)
        start = CLOCK()
        for _ in range(steps):
            env.step(action)
        env_times.append(CLOCK() - start)
        mujoco.mj_copyData(data, model, start_state)
        start = CLOCK()
        for i in range(steps):  # the same physics from the same state, nothing observed
            data.ctrl[:] = ctrls[i]
            data.mocap_pos[:] = mocap_pos[i]
            data.mocap_quat[:] = mocap_quat[i]
            mujoco.mj_step(model, data, nstep=skip)
        raw_times.append(CLOCK() - start)
    env_rate = steps * skip / BEST(env_times)
    raw_rate = steps * skip / BEST(raw_times)
    return env_rate, raw_rate, env_rate / raw_rate


def vector_rates(repeats: int, steps: int = 200) -> tuple[float, dict[int, float], dict[int, float]]:
    """Wall-clock env-steps per second: one ``Replay-v0``, and N worlds native and in ``AsyncVectorEnv``.

    Every environment runs ``steps`` steps with zero residuals from frame 0 of the default scene (Tzionas
    sequence 20), interleaved, median of ``repeats``; the single environment is the unwrapped one (no
    gymnasium wrappers: the fastest single baseline).
    """
    import gymnasium

    import handsim  # noqa: F401  registers the envs

    single = gymnasium.make(REPLAY).unwrapped
    native = {
        n: gymnasium.make_vec(REPLAY, num_envs=n, vectorization_mode="vector_entry_point")
        for n in VECTOR_WORLDS
    }
    pooled = {n: gymnasium.make_vec(REPLAY, num_envs=n, vectorization_mode="async") for n in VECTOR_WORLDS}

    def rate(env, worlds: int) -> float:
        env.reset(seed=0)
        action = np.zeros(env.action_space.shape, np.float32)
        start = time.perf_counter()
        for _ in range(steps):
            env.step(action)
        return worlds * steps / (time.perf_counter() - start)

    one: list[float] = []
    many: dict[int, list[float]] = {n: [] for n in VECTOR_WORLDS}
    processes: dict[int, list[float]] = {n: [] for n in VECTOR_WORLDS}
    for _ in range(repeats):
        one.append(rate(single, 1))
        for n in VECTOR_WORLDS:
            many[n].append(rate(native[n], n))
            processes[n].append(rate(pooled[n], n))
    for env in (*native.values(), *pooled.values()):
        env.close()
    median = statistics.median
    return median(one), {n: median(r) for n, r in many.items()}, {n: median(r) for n, r in processes.items()}


def _load() -> str:
    one, five, _ = os.getloadavg()
    return f"load {one:.2f} {five:.2f} on {os.cpu_count()} cores"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    print(f"start: {_load()}")
    worst_replay, arctic, checks_ratio = np.inf, np.nan, np.nan
    for build in (tzionas_case, glove_case, arctic_case):
        name, scene, trajectory, *inputs = build()
        schedule = control_schedule(scene, trajectory, 100.0)
        steps = (schedule.frames - 1) * schedule.substeps
        raw, loop, full = [], [], []
        replay_seconds(scene, trajectory)  # warm up
        for _ in range(args.repeats):
            raw.append(raw_seconds(scene, schedule))
            loop.append(loop_seconds(scene, schedule))
            full.append(replay_seconds(scene, trajectory))
        raw_s, loop_s, full_s = (BEST(x) for x in (raw, loop, full))
        simulated = steps * scene.timestep
        print(f"{name}: {schedule.frames} frames × {schedule.substeps} steps = {steps} ({simulated:.2f} s)")
        for label, seconds in (("raw mj_step", raw_s), ("replay loop", loop_s), ("replay()", full_s)):
            rate, realtime = steps / seconds, simulated / seconds
            print(
                f"  {label:12s} {rate:9.0f} steps/s  real-time ×{realtime:6.1f}  vs raw {raw_s / seconds:.3f}"
            )
        if scene.setup.hold_window is not None and scene.layout.objects:
            ensemble = replay_seconds(scene, trajectory, ReplayConfig())
            members = len(scene.setup.placement.get("ensemble", ()))
            print(
                f"  replay() with the robustness ensemble ({members} more replays, release stability): "
                f"{ensemble:.2f} s CPU ({ensemble / full_s:.1f}× one replay)"
            )
        print(f"  ({_load()})")
        if build is arctic_case:
            arctic = raw_s / full_s
            hands, box = inputs[0]
            checked, unchecked = arctic_check_seconds(hands, trajectory, box, args.repeats)
            checks_ratio = (checked - unchecked) / full_s
            cost = checked - unchecked
            print(
                f"  scene with its checks before the run {checked * 1000:.1f} ms, without "
                f"{unchecked * 1000:.1f} ms: the checks cost {cost * 1000:.1f} ms = {checks_ratio:.3f} of "
                "one replay()"
            )
        else:
            worst_replay = min(worst_replay, raw_s / full_s)
    env = env_ratio(args.repeats)
    if env is not None:
        print(
            f"Replay-v0 env.step: {env[0]:.0f} steps/s vs raw mj_step×frame_skip {env[1]:.0f} steps/s "
            f"({_load()})"
        )
    one, native, pooled = vector_rates(args.repeats)
    print(f"Replay-v0 env-steps/s (wall clock): one env {one:.0f}")
    for n in VECTOR_WORLDS:
        verdict = "beats" if native[n] > pooled[n] else "does NOT beat"
        print(
            f"  N={n}: native vector env {native[n]:6.0f} (×{native[n] / one:.2f} one env)  "
            f"AsyncVectorEnv {pooled[n]:6.0f} (×{pooled[n] / one:.2f}): native {verdict} async"
        )
    print(f"end: {_load()}")
    print(f"replay_vs_raw={worst_replay:.3f}")
    print(f"env_vs_raw={env[2]:.3f}" if env is not None else "env_vs_raw=nan")
    print(f"vector_env_scaling={min(native[n] / one for n in VECTOR_WORLDS):.3f}")
    print(f"arctic_replay_vs_raw={arctic:.3f}")
    print(f"arctic_checks_vs_replay={checks_ratio:.3f}")


if __name__ == "__main__":
    main()
