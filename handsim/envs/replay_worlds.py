"""The N worlds of :class:`~handsim.envs.replay_vector_env.ReplayVectorEnv`: rows of one MuJoCo batch.

:class:`ReplayWorlds` holds N worlds of one recording as the rows of a :class:`mujoco.batch.Batch`
(MuJoCo ≥ 4.0): each world's whole integration state (``mjSTATE_INTEGRATION``: time, qpos, qvel, the
solver's warm start, controls, mocap targets, active equalities) is a row, and one ``Batch.step`` call
advances every world by ``frame_skip`` MuJoCo steps on a pool of native threads with the GIL released —
bit-identical to stepping each world's own ``MjData`` with ``mj_step``. A world's per-frame control law is
the single environment's (:class:`~handsim.envs.replay_task.ReplayTask`); the glove scenario's contact
switch and support release are per-world ``geom_contype``/``geom_conaffinity`` and ``eq_active``.
"""

from __future__ import annotations

import mujoco
import numpy as np
from mujoco import batch as mjbatch

from handsim.envs.replay_env import ReplayEnv
from handsim.sim.parallel import available_cores
from handsim.sim.stepper import WarningEvent, warning_events

_INTEGRATION = int(mujoco.mjtState.mjSTATE_INTEGRATION)


def _threads(num_envs: int, nthread: int | None) -> int:
    if nthread is None:
        return max(1, min(num_envs, available_cores()))
    if int(nthread) < 1:
        raise ValueError(f"nthread must be ≥ 1 (or None: one per core, at most one per world), got {nthread}")
    return int(nthread)


class ReplayWorlds:
    """N worlds of one recording, stepped, observed and checked for warnings together.

    Args:
        env: The single environment whose model, task and reset states every world shares.
        num_envs: Number of worlds (≥ 1).
        nthread: Threads stepping the worlds; None: one per available core, at most one per world.

    Attributes:
        frames: The control frame each world is at.
        qvel: Every world's ``qvel`` (worlds, nv), a view into the batch.

    Raises:
        ValueError: A bad ``nthread``.
    """

    def __init__(self, env: ReplayEnv, num_envs: int, nthread: int | None) -> None:
        self._num_envs = num_envs
        self._task = env.task
        self._observation = self._task.observation
        self._driver = self._task.driver
        self._substeps, self._timestep = env.frame_skip, float(env.model.opt.timestep)
        self._last = self._task.last
        self._model = env.model
        self._bind_batch(nthread)
        self._bind_switches()
        self.frames = np.zeros(num_envs, dtype=np.int64)
        self._qpos_adr, self._qvel_adr = self._observation.qpos_adr, self._observation.qvel_adr

    def _bind_batch(self, nthread: int | None) -> None:
        """The worlds' batch and the views into its rows: state, controls, positions, sensors, warnings."""
        n = self._num_envs
        self._batch = batch = mjbatch.Batch(self._model, n, _threads(n, nthread))
        self._state = batch.state
        self._ctrl = batch.bind("ctrl")
        self._qpos, self.qvel = batch.bind("qpos"), batch.bind("qvel")
        self._sensordata = batch.bind("sensordata")
        self._time = batch.bind("time")
        self._row = np.empty(batch.nstate)
        # warning counters per world: (worlds, warnings, [lastinfo, number])
        self._warning = batch.warning
        self._seen = np.zeros(self._warning.shape[:2], dtype=self._warning.dtype)

    def _bind_switches(self) -> None:
        """What the schedule's driver switches per world: supports, contacts, the mocap root."""
        batch, targets, switches = self._batch, self._driver.targets, self._driver.switches
        self._release = switches.release_frame
        self._contact = switches.contact_frame
        # the frames at whose start something switches (release ≥ 0; contacts switched only when > 0)
        self._switches = {f for f, first in ((self._release, 0), (self._contact, 1)) if f >= first}
        self._supports = targets.supports
        self._eq_active = batch.bind("eq_active") if self._model.neq else None
        self._mocap = targets.mocap
        self._all_mocap = targets.all_mocap
        self._root_pos, self._root_quat = targets.root_pos, targets.root_quat
        if self._root_pos is not None:
            self._mocap_pos, self._mocap_quat = batch.bind("mocap_pos"), batch.bind("mocap_quat")
        self._geoms = targets.geoms
        if self._contact > 0:  # the glove scenario switches contacts: per-world collision filters
            self._contype = batch.expand("geom_contype")
            self._conaffinity = batch.expand("geom_conaffinity")

    @property
    def nthread(self) -> int:
        """Threads stepping the worlds."""
        return self._batch.nthread

    def load(self, i: int, env: ReplayEnv, frame: int) -> None:
        """Put world ``i`` in the state of ``env`` (just reset to ``frame``): its state, filters, counters."""
        mujoco.mj_getState(env.model, env.data, self._row, _INTEGRATION)
        self._state[i] = self._row
        if self._contact > 0:
            self._contype[i] = env.model.geom_contype
            self._conaffinity[i] = env.model.geom_conaffinity
        self._seen[i] = self._warning[i, :, 1]
        self.frames[i] = frame

    def advance(self, ids: np.ndarray, sel: slice | np.ndarray, actions: np.ndarray) -> None:
        """One control frame of worlds ``ids`` (``sel``: the same, or ``slice(None)`` for every world).

        The switches of their frame, the root targets and controls of the next, then ``frame_skip`` steps.

        Args:
            ids: The worlds that step.
            sel: ``ids``, or ``slice(None)`` when every world steps.
            actions: Every world's action (num_envs, nu), clipped to [-1, 1].
        """
        k = self.frames[sel]
        at = self._switches.intersection(k.tolist())  # usually empty: decided without a numpy reduction
        if self._release in at and self._eq_active is not None:
            release = ids[k == self._release]
            self._eq_active[release[:, None], self._supports] = 0
        if self._contact in at:
            contact = ids[k == self._contact]
            driver = self._driver  # the scene's own collision filters of the objects
            self._contype[contact[:, None], self._geoms] = driver.targets.contype
            self._conaffinity[contact[:, None], self._geoms] = driver.targets.conaffinity
        n = k + 1
        if self._root_pos is not None:
            if self._all_mocap:
                self._mocap_pos[sel] = self._root_pos[n]
                self._mocap_quat[sel] = self._root_quat[n]
            else:
                self._mocap_pos[ids[:, None], self._mocap] = self._root_pos[n]
                self._mocap_quat[ids[:, None], self._mocap] = self._root_quat[n]
        if isinstance(sel, slice):
            self._task.controls(actions, n, self._ctrl)
            self._batch.step(None, nstep=self._substeps)
        else:
            controls = np.empty((ids.size, self._ctrl.shape[1]))
            self._task.controls(actions[ids], n, controls)
            self._ctrl[ids] = controls
            self._batch.step(ids, nstep=self._substeps)
        self.frames[sel] = n

    def observe(self, ids: np.ndarray, sel: slice | np.ndarray, obs: np.ndarray) -> np.ndarray:
        """Fill the observation rows of worlds ``ids`` from their state; returns each world's penetration.

        Args:
            ids: The worlds that stepped.
            sel: ``ids``, or ``slice(None)`` for every world.
            obs: Every world's observation (num_envs, obs_size), rows ``ids`` changed in place.
        """
        observation = self._observation
        rows = sel if isinstance(sel, slice) else ids[:, None]
        obs[sel, observation.pos_slice] = self._qpos[rows, self._qpos_adr]
        obs[sel, observation.vel_slice] = self.qvel[rows, self._qvel_adr]
        penetration = np.zeros(self._num_envs)
        contacts, force_slice, sensordata = observation.contacts, observation.force_slice, self._sensordata
        frames = self.frames
        for i in ids.tolist():
            row = obs[i]
            contacts.link_forces(sensordata[i], row[force_slice])
            penetration[i] = row[observation.pen_index] = contacts.penetration(sensordata[i])
            observation.features(row, int(frames[i]), sensordata[i])  # the single environment's own
        obs[sel, observation.progress_index] = frames[sel] / self._last
        return penetration

    def warnings(self, ids: np.ndarray) -> dict[int, tuple[WarningEvent, ...]]:
        """The MuJoCo warnings of the last frame, by world (empty almost always)."""
        counts = self._warning[:, :, 1]
        if counts.tobytes() == self._seen.tobytes():  # a reset world's counters were taken at its reset
            return {}
        events = {}
        for i in ids:
            if np.array_equal(counts[i], self._seen[i]):
                continue
            events[int(i)] = warning_events(
                counts[i],
                self._seen[i],
                self._warning[i, :, 0],
                frame=int(self.frames[i]) - 1,
                substeps=self._substeps,
                steps_since_reset=round(float(self._time[i]) / self._timestep),
            )
            self._seen[i] = counts[i]
        return events
