"""``handsim/Replay-v0`` as a native vector environment: N worlds stepped on MuJoCo's threads.

``gymnasium.make_vec("handsim/Replay-v0", num_envs=N, vectorization_mode="vector_entry_point")`` gives a
:class:`ReplayVectorEnv`. Its N worlds are the rows of one :class:`mujoco.batch.Batch` (MuJoCo ≥ 4.0):
each world's whole integration state (``mjSTATE_INTEGRATION``: time, qpos, qvel, the solver's warm start,
controls, mocap targets, active equalities) is a row, and one ``Batch.step`` call advances every world by
``frame_skip`` MuJoCo steps on a pool of native threads with the GIL released — bit-identical to stepping
each world's own ``MjData`` with ``mj_step`` (MuJoCo's promise, pinned by this package's tests against N
single environments). A world's per-frame control law is the single environment's: the residual on the
recorded targets (:meth:`ReplayTask.controls <handsim.envs.replay_task.ReplayTask.controls>`, elementwise
over all worlds at once), the recorded root pose on the mocap target, the glove scenario's contact switch
(per-world ``geom_contype``/``geom_conaffinity``) and support release (per-world ``eq_active``) at the
frames :func:`~handsim.sim.drive.scenario_switches` gives. Observations and rewards come from the same
:class:`~handsim.envs.replay_task.ReplayTask` the single environment computes with (:attr:`ReplayEnv.task`),
world by world, and episodes end by the same rule, so the vector environment returns exactly what N
:class:`ReplayEnv` would.

Autoreset follows gymnasium ≥ 1.0's default, ``AutoresetMode.NEXT_STEP``: a world that terminated or was
truncated is reset by the next ``step`` call (its action ignored, reward 0, not terminated, not
truncated, its info the reset's ``frame`` and ``time``). ``reset(seed=s)`` seeds world i with ``s + i``
(or ``seed[i]`` for a list), as :class:`gymnasium.vector.SyncVectorEnv` does.

With ``autoreset_mode=AutoresetMode.SAME_STEP`` (or its value ``"SameStep"``) a world that ended is reset
within the same ``step``: its row of the returned observation is the reset's, and ``info["final_obs"]`` /
``info["final_info"]`` (with their ``_`` masks) hold the observation and the step's info it ended with, as
:class:`~gymnasium.vector.SyncVectorEnv` gives in that mode (what Stable-Baselines3's ``VecEnv`` expects).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import numpy.typing as npt
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space
from mujoco import batch as mjbatch

from handsim.envs.recordings import RecordingError
from handsim.envs.replay_env import ReplayEnv
from handsim.envs.replay_reward import DRIFT, STEP_NUMBERS
from handsim.sim.parallel import available_cores
from handsim.sim.stepper import warning_events

_INTEGRATION = int(mujoco.mjtState.mjSTATE_INTEGRATION)


def _threads(num_envs: int, nthread: int | None) -> int:
    if nthread is None:
        return max(1, min(num_envs, available_cores()))
    if int(nthread) < 1:
        raise ValueError(f"nthread must be ≥ 1 (or None: one per core, at most one per world), got {nthread}")
    return int(nthread)


class ReplayVectorEnv(gym.vector.VectorEnv):
    """N ``handsim/Replay-v0`` worlds stepped together on MuJoCo's native threads.

    Args:
        num_envs: Number of worlds (≥ 1).
        nthread: Threads stepping the worlds (the caller's included); None: one per available core, at
            most one per world.
        render_mode: Only None: render a single :class:`ReplayEnv` instead.
        max_episode_steps: Only None (``make_vec`` passes the registration's, which is None): episodes end
            at the schedule's last frame.
        **kwargs: :class:`ReplayEnv`'s keyword arguments (scene, trajectory, control rate, reward weights,
            ``random_start`` …), the same for every world.

    Raises:
        ValueError: ``num_envs`` < 1, a bad ``nthread``, a ``render_mode`` or ``max_episode_steps``, or a
            bad :class:`ReplayEnv` argument.
    """

    metadata: dict[str, Any] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}  # noqa: RUF012

    def __init__(
        self,
        num_envs: int = 1,
        *,
        nthread: int | None = None,
        render_mode: str | None = None,
        max_episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **kwargs: Any,
    ) -> None:
        modes = {m.value: m for m in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP)}
        mode = modes.get(
            autoreset_mode.value if isinstance(autoreset_mode, AutoresetMode) else autoreset_mode
        )
        if mode is None:
            raise ValueError(f"autoreset_mode must be one of {sorted(modes)}, got {autoreset_mode!r}")
        if int(num_envs) < 1:
            raise ValueError(f"num_envs must be ≥ 1, got {num_envs}")
        if render_mode is not None:
            raise ValueError(
                f"ReplayVectorEnv does not render (render_mode={render_mode!r}); render one ReplayEnv instead"
            )
        if max_episode_steps is not None:
            raise ValueError(
                f"ReplayVectorEnv episodes end at the schedule's last frame; max_episode_steps must be None, "
                f"got {max_episode_steps}"
            )
        self.num_envs = int(num_envs)
        # one ReplayEnv holds the configuration and the reset states; its task the per-world functions
        self._env = ReplayEnv(**kwargs)
        env = self._env
        if env.recordings > 1:
            raise RecordingError(
                f"ReplayVectorEnv steps every world on one model and so follows one recording; for "
                f"{env.recordings} recordings use vectorization_mode='sync' or 'async' (each world samples)"
            )
        self.single_observation_space = env.observation_space
        self.single_action_space = env.action_space
        self.observation_space = batch_space(env.observation_space, self.num_envs)
        self.action_space = batch_space(env.action_space, self.num_envs)
        self.metadata = {
            **type(self).metadata,
            "render_fps": env.metadata["render_fps"],
            "autoreset_mode": mode,
        }
        self._same_step = mode == AutoresetMode.SAME_STEP
        self.render_mode = None
        self.observation_names = env.observation_names
        self.observation_slices = env.observation_slices

        model = env.model
        self._batch = mjbatch.Batch(model, self.num_envs, _threads(self.num_envs, nthread))
        batch = self._batch
        self._state = batch.state
        self._ctrl = batch.bind("ctrl")
        self._qpos, self._qvel = batch.bind("qpos"), batch.bind("qvel")
        self._sensordata = batch.bind("sensordata")
        self._time = batch.bind("time")
        self._row = np.empty(batch.nstate)
        task = self._task = env.task
        self._observation = task.observation
        driver = self._driver = task.driver
        switches = driver.switches
        self._release = switches.release_frame
        self._contact = switches.contact_frame
        # the frames at whose start something switches (release ≥ 0; contacts switched only when > 0)
        self._switches = {f for f, first in ((self._release, 0), (self._contact, 1)) if f >= first}
        self._supports = driver.targets.supports
        self._eq_active = batch.bind("eq_active") if model.neq else None
        self._mocap = driver.targets.mocap
        self._root_pos, self._root_quat = driver.targets.root_pos, driver.targets.root_quat
        if self._root_pos is not None:
            self._mocap_pos, self._mocap_quat = batch.bind("mocap_pos"), batch.bind("mocap_quat")
        self._geoms = driver.targets.geoms
        if self._contact > 0:  # the glove scenario switches contacts: per-world collision filters
            self._contype = batch.expand("geom_contype")
            self._conaffinity = batch.expand("geom_conaffinity")
        # warning counters per world: (worlds, warnings, [lastinfo, number])
        self._warning = batch.warning
        self._seen = np.zeros(self._warning.shape[:2], dtype=self._warning.dtype)
        self._substeps, self._timestep = env.frame_skip, float(model.opt.timestep)
        self._last = task.last
        self._times = task.times
        self._frames = np.zeros(self.num_envs, dtype=np.int64)
        self._everyone = np.arange(self.num_envs)
        self._started = False
        self._pending = False  # some world ended on the last step and is reset on the next
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._all_mocap = driver.targets.all_mocap
        self._obs = np.zeros((self.num_envs, *env.observation_space.shape))
        self._actions = np.zeros((self.num_envs, len(env.dof_names)))
        self._world_rng: list[np.random.Generator | None] = [None] * self.num_envs
        self._qpos_adr, self._qvel_adr = self._observation.qpos_adr, self._observation.qvel_adr

    # ---- facts --------------------------------------------------------------------------------------------
    @property
    def frame_skip(self) -> int:
        """MuJoCo steps per environment step."""
        return self._substeps

    def set_max_object_drift(self, value: float | None) -> None:
        """Set every world's :attr:`ReplayEnv.max_object_drift` (m; None: never), e.g. for a curriculum."""
        self._env.max_object_drift = value

    @property
    def nthread(self) -> int:
        """Threads stepping the worlds."""
        return self._batch.nthread

    @property
    def frames(self) -> np.ndarray:
        """The control frame each world is at (a copy)."""
        return self._frames.copy()

    # ---- gymnasium API ------------------------------------------------------------------------------------
    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every world (see :meth:`ReplayEnv.reset`; ``options`` apply to every world).

        Raises:
            TypeError: ``options`` is not a dict, or an option is not a whole number.
            ValueError: A seed list of the wrong length, an unknown option, or a bad ``options["frame"]``.
        """
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif isinstance(seed, int):
            seeds = [seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed: a list of num_envs={self.num_envs} seeds expected, got {len(seeds)}")
        if seed is not None:
            self._np_random, self._np_random_seed = seeding.np_random(seeds[0])
        for i, s in enumerate(seeds):
            if s is not None or self._world_rng[i] is None:
                self._world_rng[i] = seeding.np_random(s)[0]
        frames = np.empty(self.num_envs, dtype=np.int64)
        numbers = np.empty((self.num_envs, len(STEP_NUMBERS)))
        for i in range(self.num_envs):
            frames[i], numbers[i] = self._reset_world(i, options)
        self._autoreset[:] = False
        self._started, self._pending = True, False
        everyone = np.ones(self.num_envs, bool)
        infos: dict[str, Any] = {
            "frame": frames,
            "_frame": everyone,
            "time": self._times[frames],
            "_time": everyone.copy(),
            "recording": np.zeros(self.num_envs, np.int64),  # one recording (several are refused)
            "_recording": everyone.copy(),
        }
        for key, column in zip(STEP_NUMBERS, numbers.T, strict=True):
            infos[key], infos[f"_{key}"] = column.copy(), everyone.copy()
        return self._obs.copy(), infos

    def step(
        self, actions: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Advance every running world one control frame; reset the worlds that ended on the last call.

        Args:
            actions: (num_envs, nu) residuals in [-1, 1] (values outside are clipped, as by
                :class:`ReplayEnv`; ``info["action_clipped"]`` counts them per world).

        Raises:
            ValueError: ``actions`` has the wrong shape or a non-finite value.
            ResetNeeded: ``reset()`` was never called.
        """
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != self.action_space.shape:
            raise ValueError(
                f"ReplayVectorEnv: actions must have shape {self.action_space.shape} "
                f"(one residual in [-1, 1] per hand DoF per world), got shape {a.shape}"
            )
        inside = (a >= -1.0) & (a <= 1.0)  # NaN fails both tests
        in_range = bool(inside.all())
        if not in_range and not np.isfinite(a).all():
            bad = sorted({int(i) for i in np.nonzero(~np.isfinite(a))[0]})
            raise ValueError(f"ReplayVectorEnv: actions of worlds {bad} have NaN or infinite values")
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        n = self.num_envs
        terminated = np.zeros(n, bool)
        infos: dict[str, Any] = {}
        if self._pending:  # worlds that ended on the last call are reset now, the others step
            reset_ids = np.flatnonzero(self._autoreset)
            ids = np.flatnonzero(~self._autoreset)
            sel: slice | np.ndarray = ids
            reset_numbers = {i: self._reset_world(i, None)[1] for i in reset_ids.tolist()}
        else:
            ids, sel = self._everyone, slice(None)
            reset_ids = None
        if ids.size:
            if in_range:
                clipped = np.zeros(n, np.int64)
                self._actions[:] = a
            else:
                clipped = (~inside).sum(axis=1)
                np.minimum(np.maximum(a, -1.0, out=self._actions), 1.0, out=self._actions)
            self._advance(ids, sel)
            penetration = self._observe(ids, sel)
            warnings = self._warnings(ids)
            reward_of, actions, obs, frames = self._task.reward, self._actions, self._obs, self._frames
            table = []  # per stepped world: the reward, its terms and the info numbers
            for i in ids.tolist():
                action = actions[i]
                depth = float(penetration[i])
                reward, numbers = reward_of(obs[i], int(frames[i]), float(np.dot(action, action)), depth)
                table.append((reward, *numbers))
            if self._pending:
                columns = np.zeros((len(STEP_NUMBERS) + 1, n))
                columns[:, ids] = np.array(table).T
                mask = np.zeros(n, bool)
                mask[ids] = True
                clipped[~mask] = 0
            else:
                columns = np.array(table).T
                mask = self._everyone >= 0
            diverged = np.zeros(n, bool)
            for i, events in warnings.items():
                diverged[i] = any(e.diverged for e in events)
            limit = self._env.max_object_drift
            terminated[sel] = diverged[sel] | (
                columns[1 + DRIFT][sel] > (math.inf if limit is None else limit)
            )
            for key, column in zip(STEP_NUMBERS, columns[1:], strict=True):
                infos[key], infos[f"_{key}"] = column, mask
            infos["diverged"], infos["_diverged"] = diverged, mask
            infos["action_clipped"], infos["_action_clipped"] = clipped, mask
            if warnings:
                described = np.full(n, None, dtype=object)
                for i, events in warnings.items():
                    described[i] = tuple(e.describe() for e in events)
                infos["warnings"] = described
                infos["_warnings"] = np.array([w is not None for w in described])
            rewards = columns[0]
        else:
            rewards = np.zeros(n)
        if reset_ids is not None:
            self._put_reset_numbers(infos, reset_numbers)
        frame_info = self._frames.copy()  # a reset world's start frame is before the last: not truncated
        truncated = (frame_info >= self._last) & ~terminated
        everyone = np.ones(n, bool)
        infos["frame"], infos["_frame"] = frame_info, everyone
        infos["time"], infos["_time"] = self._times[frame_info], everyone
        if reset_ids is not None:  # the reset worlds' info has the reset's recording
            infos["recording"], infos["_recording"] = np.zeros(n, np.int64), self._autoreset.copy()
        ended = terminated | truncated
        if self._same_step:
            if ended.any():
                infos = self._reset_ended(ended, infos)
            return self._obs.copy(), rewards, terminated, truncated, infos
        self._autoreset = ended
        self._pending = bool(ended.any())
        return self._obs.copy(), rewards, terminated, truncated, infos

    def _reset_ended(self, ended: np.ndarray, infos: dict[str, Any]) -> dict[str, Any]:
        """Same-step autoreset: the ended worlds' final observation and info aside, then their reset.

        Returns:
            The step's info with ``final_obs``/``final_info`` (masked to the ended worlds) and, for those
            worlds, the reset's numbers, frame, time and recording in place of the step's (the step-only
            keys masked off), as :class:`gymnasium.vector.SyncVectorEnv` gives in ``SAME_STEP`` mode.
        """
        n = self.num_envs
        final_obs = np.full(n, None, dtype=object)
        final_info: dict[str, Any] = {}
        for key, value in infos.items():
            if key.startswith("_"):
                continue
            mask = infos[f"_{key}"] & ended
            if not mask.any():
                continue
            column = np.array(value, copy=True)
            column[~mask] = None if column.dtype == object else 0
            final_info[key], final_info[f"_{key}"] = column, mask
        reset_numbers = {}
        for i in np.flatnonzero(ended).tolist():
            final_obs[i] = self._obs[i].copy()
            frame, reset_numbers[i] = self._reset_world(i, None)
            infos["frame"][i], infos["time"][i] = frame, self._times[frame]
        self._put_reset_numbers(infos, reset_numbers)
        for key in ("diverged", "action_clipped", "warnings"):  # not in a reset's info
            if key in infos:
                infos[f"_{key}"] = infos[f"_{key}"] & ~ended
        infos["recording"], infos["_recording"] = np.zeros(n, np.int64), ended.copy()
        infos["final_obs"], infos["_final_obs"] = final_obs, ended.copy()
        infos["final_info"], infos["_final_info"] = final_info, ended.copy()
        return infos

    def _put_reset_numbers(self, infos: dict[str, Any], reset_numbers: dict[int, tuple[float, ...]]) -> None:
        """Give each reset world's info the reset's :data:`STEP_NUMBERS` (as ``SyncVectorEnv`` gives them).

        Args:
            infos: The step's info, changed in place (a missing key is added, masked to the reset worlds).
            reset_numbers: World → the numbers its reset returned.
        """
        n = self.num_envs
        for column, key in enumerate(STEP_NUMBERS):
            if key not in infos:
                infos[key], infos[f"_{key}"] = np.zeros(n), np.zeros(n, bool)
            values, mask = infos[key], infos[f"_{key}"].copy()
            for i, numbers in reset_numbers.items():
                values[i], mask[i] = numbers[column], True
            infos[f"_{key}"] = mask

    def close_extras(self, **kwargs: Any) -> None:
        """Free the template environment's renderer."""
        self._env.close()

    # ---- worlds -------------------------------------------------------------------------------------------
    def _reset_world(self, i: int, options: dict | None) -> tuple[int, tuple[float, ...]]:
        """Put world ``i`` in the recorded state of its start frame; its observation in row ``i``.

        Returns:
            The start frame and the reset's values of :data:`STEP_NUMBERS`.
        """
        env = self._env
        env.np_random = self._world_rng[i]
        obs, info = env.reset(options=options)
        self._world_rng[i] = env.np_random
        mujoco.mj_getState(env.model, env.data, self._row, _INTEGRATION)
        self._state[i] = self._row
        if self._contact > 0:
            self._contype[i] = env.model.geom_contype
            self._conaffinity[i] = env.model.geom_conaffinity
        self._seen[i] = self._warning[i, :, 1]
        self._obs[i] = obs
        self._frames[i] = info["frame"]
        return int(info["frame"]), tuple(info[key] for key in STEP_NUMBERS)

    def _advance(self, ids: np.ndarray, sel: slice | np.ndarray) -> None:
        """One control frame of worlds ``ids`` (``sel``: the same, or ``slice(None)`` for every world).

        The switches of their frame, the root targets and controls of the next, then ``frame_skip`` steps.
        """
        k = self._frames[sel]
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
            self._task.controls(self._actions, n, self._ctrl)
            self._batch.step(None, nstep=self._substeps)
        else:
            controls = np.empty((ids.size, self._ctrl.shape[1]))
            self._task.controls(self._actions[ids], n, controls)
            self._ctrl[ids] = controls
            self._batch.step(ids, nstep=self._substeps)
        self._frames[sel] = n

    def _observe(self, ids: np.ndarray, sel: slice | np.ndarray) -> np.ndarray:
        """Fill the observation rows of worlds ``ids`` from their state; returns each world's penetration."""
        observation, obs = self._observation, self._obs
        rows = sel if isinstance(sel, slice) else ids[:, None]
        obs[sel, observation.pos_slice] = self._qpos[rows, self._qpos_adr]
        obs[sel, observation.vel_slice] = self._qvel[rows, self._qvel_adr]
        penetration = np.zeros(self.num_envs)
        contacts, force_slice, sensordata = observation.contacts, observation.force_slice, self._sensordata
        frames = self._frames
        for i in ids.tolist():
            row = obs[i]
            contacts.link_forces(sensordata[i], row[force_slice])
            penetration[i] = row[observation.pen_index] = contacts.penetration(sensordata[i])
            observation.features(row, int(frames[i]), sensordata[i])  # the single environment's own
        obs[sel, observation.progress_index] = frames[sel] / self._last
        return penetration

    def _warnings(self, ids: np.ndarray) -> dict[int, tuple]:
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
                frame=int(self._frames[i]) - 1,
                substeps=self._substeps,
                steps_since_reset=round(float(self._time[i]) / self._timestep),
            )
            self._seen[i] = counts[i]
        return events
