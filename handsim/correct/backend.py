"""Batched rollouts for the sampler: a pluggable backend, and the CPU one on ``mujoco.rollout``'s threads.

The sampler asks a backend for one thing: from one state (MuJoCo's full physics state and its warm-start
accelerations), simulate ``N`` open-loop control sequences and return the state after every step. Any
simulator that answers that for the same model can plan a correction; the committed result is always
simulated by handsim's own replay core on the CPU (:mod:`handsim.correct.planner`), so a backend changes
how fast a plan is found, never what a corrected file replays to.

:class:`CpuRollout` uses ``mujoco.rollout.Rollout``: a pool of ``nthread`` native threads, one ``MjData``
each, the rollouts split into chunks. Each rollout sets the whole state it starts from (``mj_setState`` with
``mjSTATE_FULLPHYSICS``, the warm start copied, the warning counters cleared) and its controls at every
step, so its states do not depend on which thread ran it or what that thread ran before: the results are
bitwise the same for any ``nthread`` and chunk size (pinned in ``tests/test_correct.py``), and bitwise those
of :class:`~handsim.sim.drive.ScheduleDriver` stepping the same controls from the same state.

A rollout's controls may also set ``xfrc_applied`` (``mjSTATE_XFRC_APPLIED``: the guidance's virtual force,
:mod:`handsim.correct.guidance`); a rollout whose controls do not set it starts with it zero, whatever the
thread's data held before, so an unguided rollout is exactly that.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from handsim.correct.config import CorrectionError
from handsim.sim.parallel import sim_threads

STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
"""The state a rollout starts from and returns per step."""
CONTROLS = (
    mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_MOCAP_POS | mujoco.mjtState.mjSTATE_MOCAP_QUAT
)
"""What a rollout's controls set before each step: actuator targets, then every mocap body's pose."""
SWITCHED_CONTROLS = CONTROLS | mujoco.mjtState.mjSTATE_EQ_ACTIVE
"""The controls of a scene that releases supports during the run (a glove scene): actuator targets, every
equality's active flag (a support switched off at the release), then every mocap body's pose."""


@dataclass(frozen=True)
class Start:
    """Where a planning step starts: the committed simulation's state at a frame, as the rollouts take it.

    Attributes:
        state: ``mj_getState(…, mjSTATE_FULLPHYSICS)`` (:data:`~handsim.correct.backend.STATE`).
        warmstart: Its ``qacc_warmstart`` (MuJoCo's solver starts from it: part of the state for bitwise
            rollouts).
        mocap: Every mocap body's pose (nmocap, 7).
        eq_active: Every equality's active flag (neq,): a support released or not.
    """

    state: np.ndarray
    warmstart: np.ndarray
    mocap: np.ndarray
    eq_active: np.ndarray


def start_of(model: mujoco.MjModel, data: mujoco.MjData) -> Start:
    """The planning start of the simulation in ``data``."""
    state = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, state, STATE)
    mocap = np.concatenate([data.mocap_pos, data.mocap_quat], axis=1)
    return Start(state, data.qacc_warmstart.copy(), mocap, data.eq_active.astype(float))


class RolloutBackend(Protocol):
    """Simulates open-loop control sequences from one state (see the module docstring).

    Attributes:
        name: The backend's name (:data:`~handsim.correct.rollouts.BACKENDS`), written into a corrected
            file's provenance.
        threads: Threads (or devices' worlds) it runs at once, for people; results never depend on it.
    """

    name: str
    threads: int

    def rollout(
        self, model: mujoco.MjModel, start: Start, controls: np.ndarray, spec: int, sensors: bool
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """The states (and sensor data) after every step of every sequence.

        Args:
            model: The model (not changed).
            start: Where every sequence starts: its ``state`` (``mj_getState(…, mjSTATE_FULLPHYSICS)``) and
                ``warmstart`` (``qacc_warmstart``); the other fields are the controls' business.
            controls: Per sequence and step, the vector of the ``mjtState`` elements ``spec`` names
                (N, nstep, ncontrol).
            spec: What the controls set: :data:`CONTROLS` or :data:`SWITCHED_CONTROLS`, with
                ``mjSTATE_XFRC_APPLIED`` in a guided round. Elements a spec leaves out are zero
                (``xfrc_applied``) or the start's.
            sensors: Return the sensor data too.

        Returns:
            States (N, nstep, nstate) in the layout of :data:`STATE`, and the sensor data after every step
            (N, nstep, nsensordata), or None unless ``sensors``.
        """

    def close(self) -> None:
        """Release threads and buffers (the backend is not used after)."""


class CpuRollout:
    """``mujoco.rollout`` on CPU threads (module docstring).

    Args:
        threads: Native threads; None: :func:`handsim.sim.parallel.sim_threads` (``$HANDSIM_THREADS``, else
            every core this process may use).
    """

    name = "cpu"

    def __init__(self, threads: int | None = None) -> None:
        self.threads = sim_threads() if threads is None else int(threads)
        if self.threads < 1:
            raise CorrectionError(f"threads must be ≥ 1, got {threads!r}")
        self._pool = mj_rollout.Rollout(nthread=self.threads if self.threads > 1 else 0)
        self._data: list[mujoco.MjData] = []
        self._model: mujoco.MjModel | None = None

    def _datas(self, model: mujoco.MjModel) -> list[mujoco.MjData]:
        if self._model is not model:
            self._model = model
            self._data = [mujoco.MjData(model) for _ in range(self.threads)]
        return self._data

    def rollout(
        self, model: mujoco.MjModel, start: Start, controls: np.ndarray, spec: int, sensors: bool = False
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """States (and sensor data) after every step of every sequence (:meth:`RolloutBackend.rollout`)."""
        count = controls.shape[0]
        datas = self._datas(model)
        for data in datas:  # a force a guided rollout left is not part of the next rollout's start
            data.xfrc_applied[:] = 0.0
        starts = np.broadcast_to(start.state, (count, start.state.shape[0]))
        warm = np.broadcast_to(start.warmstart, (count, start.warmstart.shape[0]))
        states, data = self._pool.rollout(
            model,
            datas,
            np.ascontiguousarray(starts),
            np.ascontiguousarray(controls),
            control_spec=int(spec),
            initial_warmstart=np.ascontiguousarray(warm),
            # four chunks per thread: a thread slowed by other work on the machine hands its last chunks to
            # the others (24 rollouts on 2 threads of a loaded 2-core machine: chunks of 3 ran 1.24× as fast
            # as chunks of 12); the results do not depend on it
            chunk_size=max(1, count // (4 * self.threads)),
        )
        return states, data if sensors else None

    def close(self) -> None:
        """Stop the thread pool."""
        self._pool.close()
        self._data = []
        self._model = None
