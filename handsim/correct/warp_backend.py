"""Batched rollouts on MuJoCo Warp: the sampler's candidates as the worlds of one batch, on a GPU or the CPU.

An optional backend (``pip install 'handsim[warp]'``: ``warp-lang`` and ``mujoco-warp``; never a required
dependency). :class:`WarpRollout` answers :meth:`~handsim.correct.backend.RolloutBackend.rollout` as
:class:`~handsim.correct.backend.CpuRollout` does, with every candidate a world of one MuJoCo Warp batch:

* the start (the full physics state, the warm-start accelerations, every mocap pose and equality flag) is
  copied into every world; each step, small kernels write that step's controls of every world (actuator
  targets, mocap poses, equality flags, the guidance's ``xfrc_applied``) and, after ``mujoco_warp.step``,
  copy out the state in :data:`~handsim.correct.backend.STATE`'s layout (and the sensor data);
* on a CUDA device the whole rollout is one captured CUDA graph per batch shape, replayed for each call
  with new inputs; on the CPU device (for checking, slow) the kernels run in a loop;
* MuJoCo Warp filters the colliding geom pairs when a model is copied to the device, so a scene whose
  contacts switch on during the run (the planner's private model, :mod:`handsim.correct.planner`) gets a
  device model per contact setting;
* one batch per model, candidate count and control spec: a rollout shorter than the batch (a planning step
  near the recording's end) runs in it with its last controls held, and the extra steps are dropped;
* contact and constraint buffers per world start at 4 contacts per geom pair that may collide; a batch that
  overflowed them (MuJoCo Warp's flags for the constraint rows, the broad and narrow phase and CCD) is run
  again with buffers twice as large, up to :data:`MAX_GROWTH` times, then refused; any other overflow (a
  contact sensor's match limit, EPA, height fields; the solver's iteration caps excepted, which cap it as
  on the CPU) is refused at once, naming the flags.

MuJoCo Warp computes in float32 and sums some quantities with atomics on a GPU, so a plan found on it may
differ from the CPU backend's and from run to run: the candidates are *scored* approximately. What the
correction commits is simulated by handsim's replay core on the CPU either way
(:mod:`handsim.correct.planner`), so a corrected file replays bit for bit whatever backend planned it; its
provenance names the backend.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.correct.backend import STATE, Start
from handsim.correct.config import CorrectionError

MAX_GROWTH = 3
"""How many times a batch whose contact or constraint buffers overflowed is rerun with them doubled."""
CONTACTS_PER_PAIR = 4
"""Contacts per world allocated per geom pair that may collide (a box on a plane makes 4)."""
DEVICE_ENV = "HANDSIM_WARP_DEVICE"
"""Environment variable naming the Warp device (``cuda:0``, ``cpu``); default: the first CUDA device, else
the CPU."""

_ORDER = (
    mujoco.mjtState.mjSTATE_CTRL,
    mujoco.mjtState.mjSTATE_QFRC_APPLIED,
    mujoco.mjtState.mjSTATE_XFRC_APPLIED,
    mujoco.mjtState.mjSTATE_EQ_ACTIVE,
    mujoco.mjtState.mjSTATE_MOCAP_POS,
    mujoco.mjtState.mjSTATE_MOCAP_QUAT,
)
"""The control elements this backend sets, in MuJoCo's state order (the order of a control vector)."""
_STATE_PARTS = (
    mujoco.mjtState.mjSTATE_TIME,
    mujoco.mjtState.mjSTATE_QPOS,
    mujoco.mjtState.mjSTATE_QVEL,
    mujoco.mjtState.mjSTATE_ACT,
)
"""The parts of :data:`STATE` this backend returns (a model with history or plugin state is refused)."""


_BUFFER_FLAGS = ("NEFC", "NJMAX_NNZ", "BROADPHASE", "NARROWPHASE", "CCD")
"""MuJoCo Warp's overflow flags that larger contact and constraint buffers cure (the others do not)."""


def _flags(mjw, names: tuple[str, ...]) -> int:
    """The overflow bits of the flags named (those this MuJoCo Warp has)."""
    return sum(int(getattr(mjw.OverflowType, n)) for n in names if hasattr(mjw.OverflowType, n))


def _names(mjw, overflow: int) -> str:
    """The names of the overflow flags set in ``overflow``."""
    named = [f.name for f in mjw.OverflowType if f.value and f.value & overflow and f.name != "ALL"]
    return ", ".join(named) or f"{overflow:#x}"


def import_warp():
    """``warp`` and ``mujoco_warp``, or a :class:`CorrectionError` that says how to install them."""
    try:
        import mujoco_warp
        import warp
    except ImportError as exc:
        raise CorrectionError(
            f"the warp rollout backend needs MuJoCo Warp ({exc}); install it with pip install 'handsim[warp]'"
        ) from exc
    warp.config.quiet = True  # no banner; and no line per kernel module compiled or loaded
    warp.config.log_level = getattr(warp, "LOG_WARNING", warp.config.log_level)
    return warp, mujoco_warp


def control_layout(model: mujoco.MjModel, spec: int) -> dict[int, slice]:
    """Where each element of a control vector lies: ``{mjtState bit: slice}`` for the bits of ``spec``.

    Raises:
        CorrectionError: ``spec`` names an element this backend does not set (user data, plugin state).
    """
    known = 0
    layout, start = {}, 0
    for bit in _ORDER:
        known |= int(bit)
        if spec & int(bit):
            size = mujoco.mj_stateSize(model, bit)
            layout[int(bit)] = slice(start, start + size)
            start += size
    if spec & ~known:
        raise CorrectionError(
            f"the warp rollout backend does not set the control elements {spec & ~known:#x}"
        )
    return layout


@dataclass
class _Batch:
    """One batch shape's device data, input and output buffers, and (on CUDA) its captured graph."""

    data: object
    inputs: dict[int, object]
    states: object
    sensors: object
    graph: object = None


class WarpRollout:
    """Rollouts as the worlds of a MuJoCo Warp batch (module docstring).

    Args:
        threads: Unused (a batch runs every candidate at once); accepted so that backends are made alike.
        device: The Warp device; None: ``$HANDSIM_WARP_DEVICE``, else the first CUDA device, else the CPU.

    Raises:
        CorrectionError: MuJoCo Warp is not installed.
    """

    name = "warp"

    def __init__(self, threads: int | None = None, device: str | None = None) -> None:
        self._wp, self._mjw = import_warp()
        wp = self._wp
        wp.init()
        chosen = device or os.environ.get(DEVICE_ENV) or ("cuda:0" if wp.is_cuda_available() else "cpu")
        try:
            self.device = wp.get_device(chosen)
        except (RuntimeError, ValueError) as exc:
            raise CorrectionError(f"the warp rollout backend: no Warp device {chosen!r} ({exc})") from exc
        self.threads = 1
        self._models: dict[bytes, object] = {}
        self._batches: dict[tuple, _Batch] = {}
        self._growth = 0
        self._kernels = _kernels(wp)

    def _device_model(self, model: mujoco.MjModel):
        """The device copy of ``model`` for its current contact setting (a switch needs another copy)."""
        key = (
            b"".join(
                np.ascontiguousarray(a).tobytes()
                for a in (model.geom_contype, model.geom_conaffinity, model.opt.disableflags)
            )
            + str(id(model)).encode()
        )
        if key not in self._models:
            with self._wp.ScopedDevice(self.device):
                self._models[key] = self._mjw.put_model(model)
        return key, self._models[key]

    def _sizes(self, device_model, model: mujoco.MjModel) -> tuple[int, int]:
        """Contacts and constraint rows per world, doubled for each overflow seen."""
        pairs = max(1, int(device_model.nxn_geom_pair_filtered.shape[0]))
        nconmax = CONTACTS_PER_PAIR * pairs * 2**self._growth
        rows = 6 * nconmax + 6 * model.neq + 2 * model.njnt + model.nv
        return nconmax, rows

    def rollout(
        self, model: mujoco.MjModel, start: Start, controls: np.ndarray, spec: int, sensors: bool = False
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """States (and sensor data) after every step of every sequence (:meth:`RolloutBackend.rollout`).

        Raises:
            CorrectionError: The model has state this backend does not simulate (history, plugins), the
                batch still overflowed its contact buffers after :data:`MAX_GROWTH` enlargements, or it
                overflowed something larger buffers do not cure (the flags are named).
        """
        parts = sum(mujoco.mj_stateSize(model, p) for p in _STATE_PARTS)
        if parts != mujoco.mj_stateSize(model, STATE):
            raise CorrectionError(
                "the warp rollout backend simulates time, qpos, qvel and act; this model has more state "
                "(history or plugins): use the cpu backend"
            )
        layout = control_layout(model, spec)
        buffers = _flags(self._mjw, _BUFFER_FLAGS)
        while True:
            states, data, overflow = self._run(model, start, controls, spec, layout, sensors)
            if not overflow:
                return states, data
            if overflow & ~buffers or self._growth >= MAX_GROWTH:
                grown = f" with buffers {2**self._growth}× the default" if overflow & buffers else ""
                raise CorrectionError(
                    f"MuJoCo Warp overflowed ({_names(self._mjw, overflow)}){grown}: its results would be "
                    "wrong; use the cpu backend"
                )
            self._growth += 1
            self._batches.clear()

    def _run(self, model, start: Start, controls: np.ndarray, spec: int, layout: dict, sensors: bool):
        wp, mjw = self._wp, self._mjw
        count, nstep = controls.shape[:2]
        key, device_model = self._device_model(model)
        with wp.ScopedDevice(self.device):
            batch, steps = self._batch(key, device_model, model, count, nstep, spec, layout)
            self._set_start(batch.data, model, start, count)
            # a shorter rollout runs in a longer batch: its last controls held, the extra steps dropped
            padded = np.concatenate([controls, np.repeat(controls[:, -1:], steps - nstep, axis=1)], axis=1)
            for bit, part in layout.items():
                batch.inputs[bit].assign(np.ascontiguousarray(padded[:, :, part], dtype=np.float32))
            if batch.graph is not None:
                wp.capture_launch(batch.graph)
            else:
                self._steps(device_model, batch, steps, layout)
            caps = int(mjw.OverflowType.ITERATIONS | mjw.OverflowType.LS_ITERATIONS)
            overflow = int(np.bitwise_or.reduce(batch.data.overflow.numpy())) & ~caps
            states = batch.states.numpy()[:, :nstep].astype(np.float64)
            data = None
            if sensors:
                data = batch.sensors.numpy()[:, :nstep, : model.nsensordata].astype(np.float64)
        return states, data, overflow

    def _batch(self, key, device_model, model, count: int, nstep: int, spec: int, layout: dict):
        """The buffers (and graph) of a batch of at least ``nstep`` steps, and its steps; made on first use.

        One batch per model, candidates and control spec: a planning step near the recording's end asks for
        fewer steps and runs in the longer batch (a new batch, and on CUDA a new graph, per length would
        grow the device's memory with every planning step there).
        """
        wp, mjw = self._wp, self._mjw
        shape = (key, count, spec)
        batch = self._batches.get(shape)
        if batch is not None and batch.states.shape[1] >= nstep:
            return batch, batch.states.shape[1]
        host = mujoco.MjData(model)
        nconmax, njmax = self._sizes(device_model, model)
        data = mjw.put_data(model, host, nworld=count, nconmax=nconmax, njmax=njmax)
        inputs = {
            bit: wp.zeros((count, nstep, part.stop - part.start), dtype=wp.float32)
            for bit, part in layout.items()
        }
        states = wp.zeros((count, nstep, mujoco.mj_stateSize(model, STATE)), dtype=wp.float32)
        sensors = wp.zeros((count, nstep, max(1, model.nsensordata)), dtype=wp.float32)
        batch = _Batch(data, inputs, states, sensors)
        if self.device.is_cuda:  # the inputs are copied into these buffers before each launch
            with wp.ScopedCapture() as capture:
                self._steps(device_model, batch, nstep, layout)
            batch.graph = capture.graph
        self._batches[shape] = batch
        return batch, nstep

    def _set_start(self, data, model: mujoco.MjModel, start: Start, count: int) -> None:
        """Every world at the start: its state, warm start, mocap poses, equality flags; no applied force."""
        host = mujoco.MjData(model)
        mujoco.mj_setState(model, host, start.state, STATE)
        host.mocap_pos[:], host.mocap_quat[:] = start.mocap[:, :3], start.mocap[:, 3:]
        host.eq_active[:] = start.eq_active != 0
        # MuJoCo Warp reads the bodies' velocities (cvel) of the step before within a step: left from
        # another batch they would make a rollout depend on what ran before, so they are the start's own
        mujoco.mj_forward(model, host)
        tile = lambda a: np.ascontiguousarray(np.broadcast_to(a, (count, *np.shape(a))), dtype=np.float32)  # noqa: E731
        data.time.assign(np.full(count, host.time, dtype=np.float32))
        for name, value in (
            ("qpos", host.qpos),
            ("qvel", host.qvel),
            ("qacc_warmstart", start.warmstart),
            ("cvel", host.cvel),
        ):
            getattr(data, name).assign(tile(value))
        if model.na:
            data.act.assign(tile(host.act))
        if model.nmocap:
            data.mocap_pos.assign(tile(host.mocap_pos))
            data.mocap_quat.assign(tile(host.mocap_quat))
        if model.neq:
            data.eq_active.assign(np.broadcast_to(host.eq_active != 0, (count, model.neq)).copy())
        data.ctrl.zero_()
        data.qfrc_applied.zero_()
        data.xfrc_applied.zero_()
        data.overflow.zero_()

    def _steps(self, device_model, batch: _Batch, nstep: int, layout: dict) -> None:
        """A rollout's kernels: per step its controls in, one MuJoCo Warp step, its state and sensors out."""
        wp, mjw, k = self._wp, self._mjw, self._kernels
        data = batch.data
        count = data.nworld
        setters = {
            int(mujoco.mjtState.mjSTATE_CTRL): (k.floats, data.ctrl),
            int(mujoco.mjtState.mjSTATE_QFRC_APPLIED): (k.floats, data.qfrc_applied),
            int(mujoco.mjtState.mjSTATE_XFRC_APPLIED): (k.spatial, data.xfrc_applied),
            int(mujoco.mjtState.mjSTATE_EQ_ACTIVE): (k.flags, data.eq_active),
            int(mujoco.mjtState.mjSTATE_MOCAP_POS): (k.vec3, data.mocap_pos),
            int(mujoco.mjtState.mjSTATE_MOCAP_QUAT): (k.quat, data.mocap_quat),
        }
        nq, nv = data.qpos.shape[1], data.qvel.shape[1]
        for step in range(nstep):
            for bit in layout:
                kernel, target = setters[bit]
                wp.launch(kernel, dim=target.shape, inputs=[step, batch.inputs[bit], target])
            mjw.step(device_model, data)
            wp.launch(k.time, dim=count, inputs=[step, data.time, batch.states])
            wp.launch(k.take, dim=data.qpos.shape, inputs=[step, 1, data.qpos, batch.states])
            wp.launch(k.take, dim=data.qvel.shape, inputs=[step, 1 + nq, data.qvel, batch.states])
            if data.act.shape[1]:
                wp.launch(k.take, dim=data.act.shape, inputs=[step, 1 + nq + nv, data.act, batch.states])
            if data.sensordata.shape[1]:
                wp.launch(k.take, dim=data.sensordata.shape, inputs=[step, 0, data.sensordata, batch.sensors])

    def close(self) -> None:
        """Drop the device models and buffers."""
        self._models.clear()
        self._batches.clear()


@dataclass(frozen=True)
class _Kernels:
    floats: object
    flags: object
    vec3: object
    quat: object
    spatial: object
    time: object
    take: object


def _kernels(wp) -> _Kernels:
    """The per-step copy kernels (defined once Warp is imported: it is an optional dependency)."""

    @wp.kernel
    def floats(step: int, src: wp.array3d(dtype=float), dst: wp.array2d(dtype=float)):
        w, j = wp.tid()
        dst[w, j] = src[w, step, j]

    @wp.kernel
    def flags(step: int, src: wp.array3d(dtype=float), dst: wp.array2d(dtype=bool)):
        w, j = wp.tid()
        dst[w, j] = src[w, step, j] != 0.0

    @wp.kernel
    def vec3(step: int, src: wp.array3d(dtype=float), dst: wp.array2d(dtype=wp.vec3)):
        w, b = wp.tid()
        i = 3 * b
        dst[w, b] = wp.vec3(src[w, step, i], src[w, step, i + 1], src[w, step, i + 2])

    @wp.kernel
    def quat(step: int, src: wp.array3d(dtype=float), dst: wp.array2d(dtype=wp.quat)):
        w, b = wp.tid()
        i = 4 * b  # MuJoCo's (w, x, y, z), stored as MuJoCo Warp stores it: the components in that order
        dst[w, b] = wp.quat(src[w, step, i], src[w, step, i + 1], src[w, step, i + 2], src[w, step, i + 3])

    @wp.kernel
    def spatial(step: int, src: wp.array3d(dtype=float), dst: wp.array2d(dtype=wp.spatial_vector)):
        w, b = wp.tid()
        i = 6 * b
        dst[w, b] = wp.spatial_vector(
            src[w, step, i],
            src[w, step, i + 1],
            src[w, step, i + 2],
            src[w, step, i + 3],
            src[w, step, i + 4],
            src[w, step, i + 5],
        )

    @wp.kernel
    def time(step: int, src: wp.array(dtype=float), out: wp.array3d(dtype=float)):
        w = wp.tid()
        out[w, step, 0] = src[w]

    @wp.kernel
    def take(step: int, offset: int, src: wp.array2d(dtype=float), out: wp.array3d(dtype=float)):
        w, j = wp.tid()
        out[w, step, offset + j] = src[w, j]

    return _Kernels(floats, flags, vec3, quat, spatial, time, take)
