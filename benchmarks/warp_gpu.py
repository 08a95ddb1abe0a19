"""Benchmark: the replay and the stability batch on MuJoCo Warp (a GPU), against MuJoCo on the CPU.

Measurement only: handsim does not depend on a GPU or on ``mujoco-warp`` (the correction's optional Warp
rollouts, ``handsim correct --rollouts warp``, are measured by ``benchmarks/correct.py --warp``, on a machine
with handsim installed). Two steps, because the GPU machine has neither handsim's dependencies nor the
recordings:

1. ``python benchmarks/warp_gpu.py export DIR`` (here, with ``../shared``): builds the scenes of
   ``benchmarks/replay.py`` (glove + ball on the GraspDB14 power-sphere trial, Tzionas hand + cube,
   ARCTIC-shaped two hands + box) and writes into DIR, per scene, the compiled model (``.mjb``), the replay's
   inputs (start state, controls per frame, mocap root per frame, the contact switch and support release
   frames, 100 Hz control as in ``benchmarks/replay.py``) and the CPU replay's trajectory as the reference;
   for the glove scene also the stability batch of its release state (the frozen model, the start state
   and the seven gravity vectors of :func:`handsim.sim.stability.gravity.stability_test`) with handsim's own
   results.
2. ``python benchmarks/warp_gpu.py run DIR`` (on the GPU machine; needs only ``mujoco``, ``numpy``,
   ``warp-lang`` and ``mujoco-warp``) measures, on that machine, with the same inputs:

   * CPU, one thread: the replay as ``benchmarks/replay.py``'s raw loop (``mj_step`` with only the inputs
     set), steps/s; CPU, every core: one replay per thread (``mj_step`` releases the GIL), worlds × steps/s;
   * GPU: the same replay in ``nworld`` worlds at once (every world the same inputs), one CUDA graph per
     control frame (its ``substeps`` steps), the frame's inputs written by a kernel; worlds × steps/s for
     each ``nworld``, and the first call's kernel compilation apart;
   * fidelity (Warp computes in float32, MuJoCo in float64): world 0's trajectory against the CPU's — the
     hand's joint error, the object's position error, and the object's slip in the hand's frame over the
     hold window (from each frame's final state: handsim's verdict reads it from sensors one step earlier),
     GPU against CPU;
   * the stability batch: the six gravity directions (1 s) from the release state as the worlds of one
     batch, then ObMan's run (35/240 s) as another, each repeated K times (as a dataset's trials would
     be); each direction's displacement and verdict (< ``max_displacement``) against the CPU's; the
     contact-at-end part of the verdict is not compared (it reads handsim's contact sensors).

   Results go to ``--out`` (JSON, written after each part so a run stopped by its time limit keeps what
   it measured) and print as lines; the last lines are ``warp_<scene>_worlds_steps_per_s=`` (the best
   ``nworld``) and ``warp_<scene>_vs_cpu_cores=`` (that over all CPU cores of the same machine).

Run from the repository root: ``PYTHONPATH=. python benchmarks/warp_gpu.py export /tmp/warp_export``, then
on the GPU machine ``python benchmarks/warp_gpu.py run /tmp/warp_export --out results.json``.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import copy
import json
import os
import platform
import time
from pathlib import Path

import mujoco
import numpy as np
from replay_inputs import ReplayInputs  # benchmarks/replay_inputs.py (scripts run from benchmarks/)

CONTROL_RATE = 100.0
"""Control frames per second, as in ``benchmarks/replay.py``."""
WORLDS = (1, 64, 512, 2048, 8192)
"""GPU world counts tried, in order (a count stops the list once one replay of it takes over
:data:`LONGEST_S`)."""
LONGEST_S = 60.0
STABILITY_REPEATS = (1, 64, 512)
"""The stability batch (7 worlds) repeated K times in one GPU batch."""


# --------------------------------------------------------------------------------------------- export


def export(folder: Path) -> None:
    """Write the scenes, inputs, CPU references and the glove stability batch into ``folder``."""
    from replay import arctic_case, driver_at_start, glove_case, tzionas_case

    from handsim.sim.control import control_schedule
    from handsim.sim.replay import run_schedule
    from handsim.sim.specs import MetricSpec, StabilitySpec
    from handsim.sim.stability.gravity import DIRECTIONS, frozen_model, stability_test

    folder.mkdir(parents=True, exist_ok=True)
    index = {}
    for key, build in (("glove", glove_case), ("tzionas", tzionas_case), ("arctic", arctic_case)):
        name, scene, trajectory, *_ = build()
        schedule = control_schedule(scene, trajectory, CONTROL_RATE)
        driver = driver_at_start(scene, schedule, own_model=True)
        switches, inputs = driver.switches, ReplayInputs.from_driver(driver)
        model, data = driver.stepper.model, driver.stepper.data
        state_spec = mujoco.mjtState.mjSTATE_INTEGRATION
        start = np.empty(mujoco.mj_stateSize(model, state_spec))
        mujoco.mj_getState(model, data, start, state_spec)
        qpos, _, warnings, diverged = run_schedule(driver)
        if diverged is not None:
            raise RuntimeError(f"{name}: the CPU replay diverged ({diverged.describe()})")
        ncon, nefc = _contact_sizes(scene.model, start, inputs)
        layout = scene.layout
        obj = layout.objects[0] if layout.objects else None
        arrays = {
            "start": start,
            **inputs.arrays(),
            "reference_qpos": qpos,
            "dof_qpos": np.asarray(layout.dof_qpos),
        }
        info = {
            "name": name,
            **inputs.info(),
            "timestep": float(model.opt.timestep),
            "max_ncon": ncon,
            "max_nefc": nefc,
            "cpu_warnings": len(warnings),
            "nq": model.nq,
            "nv": model.nv,
            "nu": model.nu,
            "ngeom": model.ngeom,
            "object_body": -1 if obj is None else obj.root_body,
            "hand_body": layout.hands[0].root_body,
        }
        mujoco.mj_saveModel(scene.model, str(folder / f"{key}.mjb"), None)
        if key == "glove" and scene.setup.hold_window is not None and switches.release_frame >= 0:
            window_end = int(np.searchsorted(schedule.times, scene.setup.hold_window[1] + 1e-9)) - 1
            info["window_end_frame"] = min(window_end, schedule.frames - 1)
            info["slip_limit"] = MetricSpec().slip_limit
            release = switches.release_frame
            stability_spec = StabilitySpec()
            result = stability_test(scene, qpos[release], schedule.ctrl[release], spec=stability_spec)
            frozen = frozen_model(scene.model, stability_spec)
            mujoco.mj_saveModel(frozen, str(folder / f"{key}_frozen.mjb"), None)
            weighted = np.array([b for o in layout.objects for b in o.part_bodies], dtype=np.int64)
            obman = np.asarray(stability_spec.obman_direction) / np.linalg.norm(
                stability_spec.obman_direction
            )
            units = [np.asarray(u, dtype=float) for u in DIRECTIONS.values()] + [obman]
            xfrc = np.zeros((len(units), model.nbody, 6))
            for i, unit in enumerate(units):
                xfrc[i, weighted, :3] = frozen.body_mass[weighted, None] * stability_spec.gravity * unit
            arrays.update(
                stability_qpos=qpos[release],
                stability_ctrl=schedule.ctrl[release],
                stability_mocap_pos=qpos[release, layout.root_free_qpos : layout.root_free_qpos + 3]
                if layout.mocap >= 0
                else np.zeros(0),
                stability_mocap_quat=qpos[release, layout.root_free_qpos + 3 : layout.root_free_qpos + 7]
                if layout.mocap >= 0
                else np.zeros(0),
                stability_xfrc=xfrc,
            )
            info["stability"] = {
                "labels": [*DIRECTIONS, "obman"],
                "steps": [round(stability_spec.duration / frozen.opt.timestep)] * len(DIRECTIONS)
                + [round(stability_spec.obman_duration / frozen.opt.timestep)],
                "max_displacement": stability_spec.max_displacement,
                "mocap": int(layout.mocap),
                "handsim": {
                    d.direction: {"displacement": d.displacement, "success": d.success}
                    for d in (*result.directions, result.obman)
                },
            }
        np.savez(folder / f"{key}.npz", **arrays)
        index[key] = info
        print(f"exported {key}: {name}, {schedule.frames} frames × {schedule.substeps} steps")
    (folder / "scenes.json").write_text(json.dumps(index, indent=1))


def _contact_sizes(model: mujoco.MjModel, start: np.ndarray, inputs: ReplayInputs) -> tuple[int, int]:
    """Most contacts and constraints in any step of the CPU replay (to size the GPU's buffers)."""
    model, data = copy.deepcopy(model), mujoco.MjData(model)
    _restore(model, data, start)
    ncon = nefc = 0

    def watch() -> None:
        nonlocal ncon, nefc
        ncon, nefc = max(ncon, data.ncon), max(nefc, data.nefc)

    inputs.run(model, data, after_step=watch)
    return ncon, nefc


def _restore(model: mujoco.MjModel, data: mujoco.MjData, state: np.ndarray) -> None:
    mujoco.mj_resetData(model, data)
    mujoco.mj_setState(model, data, state, mujoco.mjtState.mjSTATE_INTEGRATION)
    mujoco.mj_forward(model, data)


# ------------------------------------------------------------------------------------------ CPU side


def cpu_rates(model: mujoco.MjModel, start: np.ndarray, inputs: ReplayInputs, threads: int) -> dict:
    """One replay on one thread (best of 3), and one replay per thread on ``threads`` threads (wall)."""
    steps = (inputs.frames - 1) * inputs.substeps
    qpos = np.empty((inputs.frames, model.nq))
    best = np.inf
    for _ in range(3):
        m, d = copy.deepcopy(model), mujoco.MjData(model)
        _restore(m, d, start)
        t0 = time.perf_counter()
        inputs.run(m, d, qpos_out=qpos)
        best = min(best, time.perf_counter() - t0)
    worlds = [(copy.deepcopy(model), mujoco.MjData(model)) for _ in range(threads)]
    for m, d in worlds:
        _restore(m, d, start)
    with concurrent.futures.ThreadPoolExecutor(threads) as pool:
        t0 = time.perf_counter()
        list(pool.map(lambda w: inputs.run(*w), worlds))
        wall = time.perf_counter() - t0
    return {
        "steps": steps,
        "one_thread_steps_per_s": steps / best,
        "threads": threads,
        "all_threads_worlds_steps_per_s": threads * steps / wall,
        "qpos": qpos,
    }


# ------------------------------------------------------------------------------------------ GPU side


class _Gpu:
    """MuJoCo Warp replays of one scene: models (contacts off/on), frame inputs on the device."""

    def __init__(self, model: mujoco.MjModel, start: np.ndarray, inputs: ReplayInputs, info: dict) -> None:
        import mujoco_warp as mjw
        import warp as wp

        self.wp, self.mjw = wp, mjw
        self.inputs, self.info = inputs, info
        self.host_model = model
        self.start = start
        off = inputs.contacts_off(model) if inputs.contact > 0 else model
        self.m_on = mjw.put_model(model)
        self.m_off = mjw.put_model(off) if inputs.contact > 0 else self.m_on
        self.ctrl = wp.array(inputs.ctrl.astype(np.float32), dtype=wp.float32)
        self.hands = int(inputs.root_pos.shape[1])  # welded roots with a recorded pose
        self.mocap = wp.array(inputs.mocap.astype(np.int32), dtype=wp.int32)
        self.root_pos = wp.array(inputs.root_pos.reshape(-1, 3).astype(np.float32), dtype=wp.vec3)
        self.root_quat = wp.array(inputs.root_quat.reshape(-1, 4).astype(np.float32), dtype=wp.quat)
        self.supports = wp.array(inputs.supports.astype(np.int32), dtype=wp.int32)
        self.nconmax, self.njmax = _buffer_sizes(self.m_on, info)

    def data(self, nworld: int):
        """``nworld`` copies of the start state on the device."""
        host = mujoco.MjData(self.host_model)
        _restore(self.host_model, host, self.start)
        return self.mjw.put_data(self.host_model, host, nworld=nworld, nconmax=self.nconmax, njmax=self.njmax)

    def frame_steppers(self, d) -> dict:
        """A frame's ``substeps`` steps of ``d`` with the contacts off and on (CUDA graphs on a GPU)."""
        on = _stepper(self.wp, self.mjw, self.m_on, d, self.inputs.substeps)
        if self.m_off is self.m_on:
            return {"on": on, "off": on}
        return {"on": on, "off": _stepper(self.wp, self.mjw, self.m_off, d, self.inputs.substeps)}

    def replay(self, d, steppers: dict, qpos_out=None, world: int = 0) -> None:
        """The replay of every world of ``d`` (at the start state), world ``world``'s qpos per frame."""
        wp = self.wp
        inputs = self.inputs
        nworld = d.nworld
        for i in range(1, inputs.frames):
            if i - 1 == inputs.release and inputs.supports.size:
                wp.launch(
                    _release_kernel, dim=(nworld, inputs.supports.size), inputs=[self.supports, d.eq_active]
                )
            wp.launch(_ctrl_kernel, dim=(nworld, inputs.ctrl.shape[1]), inputs=[i, self.ctrl, d.ctrl])
            if self.hands:
                wp.launch(
                    _mocap_kernel,
                    dim=(nworld, self.hands),
                    inputs=[
                        i,
                        self.hands,
                        self.mocap,
                        self.root_pos,
                        self.root_quat,
                        d.mocap_pos,
                        d.mocap_quat,
                    ],
                )
            steppers["on" if i - 1 >= inputs.contact else "off"]()
            if qpos_out is not None:
                qpos_out[i] = d.qpos.numpy()[world]


def _unlike(q: np.ndarray) -> dict:
    """Where the worlds differ most from world 0 (``q``: qpos per world at the end of a replay), and how many
    worlds differ from it by more than 0.1 (m or rad) in any entry."""
    diff = np.abs(q - q[0])
    world, entry = np.unravel_index(int(np.argmax(diff)), diff.shape)
    return {
        "worlds_alike_at": {"world": int(world), "qpos": int(entry), "value": float(q[world, entry])},
        "worlds_over_0.1": int((diff.max(axis=1) > 0.1).sum()),
    }


def _buffer_sizes(m, info: dict) -> tuple[int, int]:
    """Contacts and constraints per world: at least the number of geom pairs that can collide (the
    broadphase's candidates fill the contact buffer) and 4× the CPU replay's most. Whether anything was
    dropped is what the overflow check says (:func:`_overflow`)."""
    pairs = int(m.nxn_geom_pair_filtered.shape[0])
    return max(pairs, 4 * int(info["max_ncon"])), max(64, 4 * int(info["max_nefc"]))


def _stepper(wp, mjw, m, d, steps: int):
    """``steps`` steps of ``d``: one CUDA graph launch on a GPU (captured, not run), else a loop."""
    if not wp.get_device().is_cuda:
        return lambda: [mjw.step(m, d) for _ in range(steps)]
    with wp.ScopedCapture() as capture:
        for _ in range(steps):
            mjw.step(m, d)
    graph = capture.graph
    return lambda: wp.capture_launch(graph)


def _kernels() -> None:
    """Define the frame-input kernels (module globals: warp is imported only on the machine that runs)."""
    import warp as wp

    global _ctrl_kernel, _mocap_kernel, _release_kernel

    @wp.kernel
    def _ctrl_kernel(frame: int, ctrl: wp.array2d(dtype=wp.float32), out: wp.array2d(dtype=wp.float32)):
        w, j = wp.tid()
        out[w, j] = ctrl[frame, j]

    @wp.kernel
    def _mocap_kernel(
        frame: int,
        hands: int,
        ids: wp.array(dtype=wp.int32),
        pos: wp.array(dtype=wp.vec3),
        quat: wp.array(dtype=wp.quat),
        out_pos: wp.array2d(dtype=wp.vec3),
        out_quat: wp.array2d(dtype=wp.quat),
    ):
        w, h = wp.tid()
        out_pos[w, ids[h]] = pos[frame * hands + h]
        out_quat[w, ids[h]] = quat[frame * hands + h]

    @wp.kernel
    def _release_kernel(ids: wp.array(dtype=wp.int32), eq_active: wp.array2d(dtype=bool)):
        w, k = wp.tid()
        eq_active[w, ids[k]] = False


def _overflow(d) -> int:
    """The overflow bits of any world, less the solver's iteration caps (ITERATIONS, LS_ITERATIONS): those
    cap the solver as on the CPU; the others mean a contact or a constraint was dropped."""
    import mujoco_warp as mjw

    caps = int(mjw.OverflowType.ITERATIONS | mjw.OverflowType.LS_ITERATIONS)
    return int(np.bitwise_or.reduce(d.overflow.numpy())) & ~caps


def gpu_replays(gpu: _Gpu, worlds: tuple[int, ...], deadline: float, report) -> dict:
    """Compile, then time the replay at each world count; world 0's trajectory of the single-world run."""
    wp = gpu.wp
    inputs = gpu.inputs
    steps = (inputs.frames - 1) * inputs.substeps
    t0 = time.perf_counter()
    d = gpu.data(1)
    for m in (gpu.m_off, gpu.m_on):
        gpu.mjw.step(m, d)  # compiles every kernel of a step of this model (a throwaway data)
    wp.synchronize()
    compile_s = time.perf_counter() - t0
    report("compile_s", compile_s)
    out: dict = {"compile_s": compile_s, "steps": steps, "worlds": {}}
    for nworld in worlds:
        if time.perf_counter() > deadline:
            out["stopped"] = f"time budget spent before nworld={nworld}"
            break
        d = gpu.data(nworld)
        steppers = gpu.frame_steppers(d)  # a capture records the steps, it does not run them
        wp.synchronize()
        t0 = time.perf_counter()
        gpu.replay(d, steppers)
        wp.synchronize()
        seconds = time.perf_counter() - t0
        q = d.qpos.numpy()
        entry = {
            "seconds": seconds,
            "worlds_steps_per_s": nworld * steps / seconds,
            "overflow": _overflow(d),
            "finite": bool(np.isfinite(q).all()),
            "worlds_alike": float(np.abs(q - q[0]).max()),
            **_unlike(q),
        }
        out["worlds"][nworld] = entry
        if nworld == 1:  # world 0's trajectory, read back each frame: a run of its own, not timed
            d = gpu.data(1)
            out["qpos"] = np.empty((inputs.frames, gpu.host_model.nq))
            gpu.replay(d, gpu.frame_steppers(d), qpos_out=out["qpos"])
        report(f"nworld={nworld}", entry)
        if seconds > LONGEST_S:
            break
    return out


# ------------------------------------------------------------------------------------------ fidelity


def fidelity(model: mujoco.MjModel, reference: np.ndarray, other: np.ndarray, arrays, info: dict) -> dict:
    """``other`` (a run's qpos per frame) against the CPU's ``reference``: joint and object errors, slip.

    The slip is the object's largest move in the hand root's frame over the hold window after the release,
    for both runs, from each frame's final state. handsim's hold verdict reads the same slip from sensors,
    which MuJoCo evaluates before a frame's last step (4.858 mm on the glove trial against 4.874 mm here):
    the two runs are compared the same way, but this is not handsim's own number.
    """
    dof = np.asarray(arrays["dof_qpos"])
    n = min(reference.shape[0], other.shape[0])
    result = {"hand_joint_err_max_rad": float(np.abs(reference[1:n, dof] - other[1:n, dof]).max())}
    body = int(info["object_body"])
    if body < 0:
        return result
    ref_pos, ref_in_hand = _object_tracks(model, reference[1:n], body, int(info["hand_body"]))
    pos, in_hand = _object_tracks(model, other[1:n], body, int(info["hand_body"]))
    err = np.linalg.norm(ref_pos - pos, axis=1)
    result["object_pos_err_max_mm"] = float(err.max() * 1000)
    result["object_pos_err_end_mm"] = float(err[-1] * 1000)
    over = np.flatnonzero(err > 1e-3)
    result["object_err_first_frame_over_1mm"] = int(over[0]) + 1 if over.size else None
    if "window_end_frame" in info:
        # rows start at frame 1 (row 0 is the start state, left out)
        r, end = max(int(info["release_frame"]) - 1, 0), int(info["window_end_frame"]) - 1
        for label, track in (("reference", ref_in_hand), ("run", in_hand)):
            slip = np.linalg.norm(track[r : end + 1] - track[r], axis=1)
            result[f"{label}_hold_slip_max_mm"] = float(slip.max() * 1000)
            result[f"{label}_slip_within_limit"] = bool(slip.max() <= info["slip_limit"])
    return result


def float32_start_run(model: mujoco.MjModel, start: np.ndarray, inputs: ReplayInputs) -> np.ndarray:
    """The CPU replay from the start state rounded to float32: the model's own sensitivity to a rounding
    of the size Warp makes, the yardstick for the GPU's differences from the CPU."""
    m, d = copy.deepcopy(model), mujoco.MjData(model)
    _restore(m, d, start.astype(np.float32).astype(np.float64))
    qpos = np.empty((inputs.frames, model.nq))
    inputs.run(m, d, qpos_out=qpos)
    return qpos


def _object_tracks(model, qpos: np.ndarray, body: int, hand: int) -> tuple[np.ndarray, np.ndarray]:
    """The object's world position and its position in the hand root's frame per row of ``qpos``."""
    data = mujoco.MjData(model)
    world = np.empty((qpos.shape[0], 3))
    in_hand = np.empty((qpos.shape[0], 3))
    for k, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        world[k] = data.xpos[body]
        in_hand[k] = data.xmat[hand].reshape(3, 3).T @ (data.xpos[body] - data.xpos[hand])
    return world, in_hand


# ------------------------------------------------------------------------------------------ stability


def stability_batch(
    folder: Path, arrays, info: dict, repeats_list: tuple[int, ...], deadline: float, report
) -> dict:
    """The seven stability runs on the CPU (one thread) and as GPU worlds, K batches at once."""
    import mujoco_warp as mjw
    import warp as wp

    spec = info["stability"]
    frozen = mujoco.MjModel.from_binary_path(str(folder / "glove_frozen.mjb"))
    labels, steps = spec["labels"], spec["steps"]
    body = int(info["object_body"])

    def start(data: mujoco.MjData, xfrc: np.ndarray) -> None:
        mujoco.mj_resetData(frozen, data)
        data.qpos[:] = arrays["stability_qpos"]
        data.ctrl[:] = arrays["stability_ctrl"]
        if spec["mocap"] >= 0:
            data.mocap_pos[spec["mocap"]] = arrays["stability_mocap_pos"]
            quat = np.asarray(arrays["stability_mocap_quat"])
            data.mocap_quat[spec["mocap"]] = quat / np.linalg.norm(quat)
        data.eq_active[:] = 0  # the glove scene's only equality is the object's support
        data.xfrc_applied[:] = xfrc
        mujoco.mj_forward(frozen, data)

    xfrc = np.asarray(arrays["stability_xfrc"])
    cpu, cpu_steps = {}, 0
    data = mujoco.MjData(frozen)
    t0 = time.perf_counter()
    for i, label in enumerate(labels):
        start(data, xfrc[i])
        com0 = data.subtree_com[body].copy()
        mujoco.mj_step(frozen, data, nstep=steps[i])
        mujoco.mj_forward(frozen, data)
        cpu[label] = float(np.linalg.norm(data.subtree_com[body] - com0))
        cpu_steps += steps[i]
    cpu_s = time.perf_counter() - t0
    out = {"cpu_one_thread_steps_per_s": cpu_steps / cpu_s, "directions": {}, "batches": {}}
    limit = spec["max_displacement"]
    # GPU: worlds = K copies of the six directions (1 s) and, apart, K ObMan runs (35/240 s)
    host = mujoco.MjData(frozen)
    start(host, xfrc[0])
    com0 = host.subtree_com[body].copy()
    m = mjw.put_model(frozen)
    nconmax, njmax = _buffer_sizes(m, info)
    for repeats in repeats_list:
        if time.perf_counter() > deadline:
            out["stopped"] = f"time budget spent before K={repeats}"
            break
        displacement = {}
        seconds = 0.0
        for group, rows in (("directions", list(range(6))), ("obman", [6])):
            nworld = repeats * len(rows)
            forces = wp.array(
                np.tile(xfrc[rows], (repeats, 1, 1)).astype(np.float32), dtype=wp.spatial_vector
            )
            d = mjw.put_data(frozen, host, nworld=nworld, nconmax=nconmax, njmax=njmax)
            mjw.step(m, d)  # compiles (the first time) on a throwaway data
            d = mjw.put_data(frozen, host, nworld=nworld, nconmax=nconmax, njmax=njmax)
            wp.copy(d.xfrc_applied, forces)
            step = _stepper(wp, mjw, m, d, 1)
            wp.synchronize()
            t0 = time.perf_counter()
            for _ in range(steps[rows[0]]):
                step()
            mjw.forward(m, d)
            wp.synchronize()
            seconds += time.perf_counter() - t0
            com = d.subtree_com.numpy()[:, body]
            moved = np.linalg.norm(com - com0, axis=1).reshape(repeats, len(rows))
            for j, row in enumerate(rows):
                displacement[labels[row]] = (float(moved[:, j].min()), float(moved[:, j].max()))
            if _overflow(d):
                out.setdefault("overflow", {})[f"K={repeats} {group}"] = _overflow(d)
        batch_steps = repeats * sum(steps)
        out["batches"][repeats] = {"seconds": seconds, "worlds_steps_per_s": batch_steps / seconds}
        report(f"stability K={repeats}", out["batches"][repeats])
        if repeats == repeats_list[0]:
            for label in labels:
                gpu = displacement[label][0]
                out["directions"][label] = {
                    "cpu_mm": cpu[label] * 1000,
                    "handsim_mm": None
                    if spec["handsim"][label]["displacement"] is None
                    else spec["handsim"][label]["displacement"] * 1000,
                    "gpu_mm": gpu * 1000,
                    "cpu_moved_less": cpu[label] < limit,
                    "gpu_moved_less": gpu < limit,
                }
            report("stability directions", out["directions"])
        out["batches"][repeats]["repeats_alike_mm"] = max(
            (hi - lo) * 1000 for lo, hi in displacement.values()
        )
    return out


# ------------------------------------------------------------------------------------------ run


def run(
    folder: Path,
    out_path: Path,
    scenes: list[str],
    budget_s: float,
    threads: int,
    worlds: tuple[int, ...] = WORLDS,
    repeats: tuple[int, ...] = STABILITY_REPEATS,
) -> None:
    """Measure every exported scene (in ``scenes`` order); no new part starts after ``budget_s`` seconds."""
    import mujoco_warp as mjw
    import warp as wp

    deadline = time.perf_counter() + budget_s
    wp.config.quiet = True
    wp.init()
    _kernels()
    index = json.loads((folder / "scenes.json").read_text())
    results: dict = {
        "machine": {
            "gpu": wp.get_device().name,
            "cpu": platform.processor() or platform.machine(),
            "cpu_count": os.cpu_count(),
            "mujoco": mujoco.__version__,
            "mujoco_warp": getattr(mjw, "__version__", "?"),
            "warp": wp.config.version,
        },
        "scenes": {},
    }

    def save() -> None:
        out_path.write_text(json.dumps(results, indent=1, default=_plain))

    for key in scenes:
        info = index[key]
        arrays = dict(np.load(folder / f"{key}.npz"))
        model = mujoco.MjModel.from_binary_path(str(folder / f"{key}.mjb"))
        inputs = ReplayInputs.from_arrays(arrays, info)
        scene: dict = {"name": info["name"], "frames": info["frames"], "substeps": info["substeps"]}
        results["scenes"][key] = scene

        def report(label, value, key=key) -> None:
            print(f"{key} {label}: {json.dumps(value, default=_plain)}", flush=True)
            save()

        cpu = cpu_rates(model, arrays["start"], inputs, threads)
        cpu_qpos = cpu.pop("qpos")
        cpu["same_as_export_max"] = float(np.abs(cpu_qpos - arrays["reference_qpos"]).max())
        scene["cpu"] = cpu
        report("cpu", cpu)
        gpu = _Gpu(model, arrays["start"], inputs, info)
        try:
            replays = gpu_replays(gpu, worlds, deadline, report)
        except Exception as exc:  # a feature mujoco_warp lacks: say so, go on with the next scene
            scene["gpu_error"] = f"{type(exc).__name__}: {exc}"
            report("gpu_error", scene["gpu_error"])
            continue
        gpu_qpos = replays.pop("qpos", None)
        scene["gpu"] = replays
        if gpu_qpos is not None:
            gpu_qpos[0] = cpu_qpos[0]
            rounded = float32_start_run(model, arrays["start"], inputs)
            scene["fidelity"] = {
                "gpu_vs_cpu": fidelity(model, cpu_qpos, gpu_qpos, arrays, info),
                "cpu_float32_start_vs_cpu": fidelity(model, cpu_qpos, rounded, arrays, info),
            }
            report("fidelity", scene["fidelity"])
        if "stability" in info and time.perf_counter() < deadline:
            try:
                scene["stability"] = stability_batch(folder, arrays, info, repeats, deadline, report)
            except Exception as exc:
                scene["stability_error"] = f"{type(exc).__name__}: {exc}"
                report("stability_error", scene["stability_error"])
        save()
        if time.perf_counter() > deadline:
            break
    for key, scene in results["scenes"].items():
        worlds = scene.get("gpu", {}).get("worlds", {})
        if worlds:
            best = max(w["worlds_steps_per_s"] for w in worlds.values())
            print(f"warp_{key}_worlds_steps_per_s={best:.0f}")
            print(f"warp_{key}_vs_cpu_cores={best / scene['cpu']['all_threads_worlds_steps_per_s']:.3g}")


def _plain(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(type(value))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    exporter = sub.add_parser("export", help="build the scenes here and write them with their inputs")
    exporter.add_argument("folder", type=Path)
    runner = sub.add_parser("run", help="measure the exported scenes on this machine's GPU and CPU")
    runner.add_argument("folder", type=Path)
    runner.add_argument("--out", type=Path, default=Path("warp_results.json"))
    runner.add_argument("--scenes", default="glove,tzionas,arctic", help="comma-separated, in order")
    runner.add_argument("--budget", type=float, default=420.0, help="seconds before no new part starts")
    runner.add_argument("--threads", type=int, default=os.cpu_count(), help="CPU threads for the batch")
    runner.add_argument("--worlds", default=",".join(map(str, WORLDS)), help="GPU world counts, in order")
    runner.add_argument(
        "--stability-repeats", default=",".join(map(str, STABILITY_REPEATS)), help="stability batches K"
    )
    runner.add_argument("--device", default=None, help="warp device (default: warp's, a GPU if present)")
    args = parser.parse_args()
    if args.command == "export":
        export(args.folder)
        return
    if args.device:
        import warp as wp

        wp.set_device(args.device)
    worlds = tuple(int(x) for x in args.worlds.split(","))
    repeats = tuple(int(x) for x in args.stability_repeats.split(","))
    run(args.folder, args.out, args.scenes.split(","), args.budget, args.threads, worlds, repeats)


if __name__ == "__main__":
    main()
