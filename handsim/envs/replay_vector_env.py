"""``handsim/Replay-v0`` as a native vector environment: N worlds stepped on MuJoCo's threads.

``gymnasium.make_vec("handsim/Replay-v0", num_envs=N, vectorization_mode="vector_entry_point")`` gives a
:class:`ReplayVectorEnv`. Its N worlds (:class:`~handsim.envs.replay_worlds.ReplayWorlds`) are the rows of one
:class:`mujoco.batch.Batch` (MuJoCo ≥ 4.0): each world's whole integration state (``mjSTATE_INTEGRATION``:
time, qpos, qvel, the solver's warm start, controls, mocap targets, active equalities) is a row, and one
``Batch.step`` call advances every world by ``frame_skip`` MuJoCo steps on a pool of native threads with the
GIL released — bit-identical to stepping each world's own ``MjData`` with ``mj_step`` (MuJoCo's promise,
pinned by this package's tests against N single environments). A world's per-frame control law is the single
environment's: the residual on the recorded targets (:meth:`ReplayTask.controls
<handsim.envs.replay_task.ReplayTask.controls>`, elementwise over all worlds at once), the recorded root pose
on the mocap target, the glove scenario's contact switch (per-world ``geom_contype``/``geom_conaffinity``) and
support release (per-world ``eq_active``) at the frames :func:`~handsim.sim.drive.scenario_switches` gives.
Observations and rewards come from the same :class:`~handsim.envs.replay_task.ReplayTask` the single
environment computes with (:attr:`ReplayEnv.task`), world by world, and episodes end by the same rule, so the
vector environment returns exactly what N :class:`ReplayEnv` would.

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
import numpy as np
import numpy.typing as npt
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from handsim.envs.recordings import RecordingError
from handsim.envs.replay_env import ReplayEnv
from handsim.envs.replay_reward import DRIFT, STEP_NUMBERS
from handsim.envs.replay_vector_info import final_info, put_reset_numbers, put_step_numbers, reset_info
from handsim.envs.replay_worlds import ReplayWorlds


def _autoreset_mode(value: AutoresetMode | str) -> AutoresetMode:
    """The autoreset mode of ``value`` (a mode, or its value: ``"NextStep"``, ``"SameStep"``).

    Raises:
        ValueError: Neither of the two modes.
    """
    modes = {m.value: m for m in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP)}
    mode = modes.get(value.value if isinstance(value, AutoresetMode) else value)
    if mode is None:
        raise ValueError(f"autoreset_mode must be one of {sorted(modes)}, got {value!r}")
    return mode


def _check_vector_arguments(num_envs: int, render_mode: str | None, max_episode_steps: int | None) -> None:
    """Refuse what the vector environment cannot do (see :class:`ReplayVectorEnv`)."""
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


def _template_env(kwargs: dict[str, Any]) -> ReplayEnv:
    """The :class:`ReplayEnv` whose configuration, reset states and task every world shares.

    Raises:
        RecordingError: It samples several recordings (the worlds step on one model).
    """
    env = ReplayEnv(**kwargs)
    if env.recordings > 1:
        raise RecordingError(
            f"ReplayVectorEnv steps every world on one model and so follows one recording; for "
            f"{env.recordings} recordings use vectorization_mode='sync' or 'async' (each world samples)"
        )
    return env


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
        mode = _autoreset_mode(autoreset_mode)
        _check_vector_arguments(num_envs, render_mode, max_episode_steps)
        self.num_envs = int(num_envs)
        # one ReplayEnv holds the configuration and the reset states; its task the per-world functions
        self._env = env = _template_env(kwargs)
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
        self._task = env.task
        self._worlds = ReplayWorlds(env, self.num_envs, nthread)
        self._qvel = self._worlds.qvel  # every world's qvel (worlds, nv)
        self._last = self._task.last
        self._times = self._task.times
        self._everyone = np.arange(self.num_envs)
        self._started = False
        self._pending = False  # some world ended on the last step and is reset on the next
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._obs = np.zeros((self.num_envs, *env.observation_space.shape))
        self._actions = np.zeros((self.num_envs, len(env.dof_names)))
        self._world_rng: list[np.random.Generator | None] = [None] * self.num_envs

    # ---- facts --------------------------------------------------------------------------------------------
    @property
    def frame_skip(self) -> int:
        """MuJoCo steps per environment step."""
        return self._env.frame_skip

    def set_max_object_drift(self, value: float | None) -> None:
        """Set every world's :attr:`ReplayEnv.max_object_drift` (m; None: never), e.g. for a curriculum."""
        self._env.max_object_drift = value

    @property
    def nthread(self) -> int:
        """Threads stepping the worlds."""
        return self._worlds.nthread

    @property
    def frames(self) -> np.ndarray:
        """The control frame each world is at (a copy)."""
        return self._worlds.frames.copy()

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
        return self._obs.copy(), reset_info(frames, self._times, numbers)

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
        a, inside = self._checked_actions(actions)
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        n = self.num_envs
        terminated = np.zeros(n, bool)
        infos: dict[str, Any] = {}
        if self._pending:  # worlds that ended on the last call are reset now, the others step
            ids: np.ndarray = np.flatnonzero(~self._autoreset)
            sel: slice | np.ndarray = ids
            reset_numbers = {
                i: self._reset_world(i, None)[1] for i in np.flatnonzero(self._autoreset).tolist()
            }
        else:
            ids, sel = self._everyone, slice(None)
            reset_numbers = None
        rewards = self._step_worlds(a, inside, ids, sel, terminated, infos) if ids.size else np.zeros(n)
        if reset_numbers is not None:
            put_reset_numbers(infos, reset_numbers, n)
        frame_info = (
            self._worlds.frames.copy()
        )  # a reset world's start frame is before the last: not truncated
        truncated = (frame_info >= self._last) & ~terminated
        everyone = np.ones(n, bool)
        infos["frame"], infos["_frame"] = frame_info, everyone
        infos["time"], infos["_time"] = self._times[frame_info], everyone
        if reset_numbers is not None:  # the reset worlds' info has the reset's recording
            infos["recording"], infos["_recording"] = np.zeros(n, np.int64), self._autoreset.copy()
        ended = terminated | truncated
        if self._same_step:
            if ended.any():
                infos = self._reset_ended(ended, infos)
        else:
            self._autoreset = ended
            self._pending = bool(ended.any())
        return self._obs.copy(), rewards, terminated, truncated, infos

    def _checked_actions(self, actions: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray | None]:
        """The actions as float64, and where they are within [-1, 1] (None: everywhere).

        Raises:
            ValueError: Wrong shape, or a NaN or infinite value (the message names the worlds).
        """
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != self.action_space.shape:
            raise ValueError(
                f"ReplayVectorEnv: actions must have shape {self.action_space.shape} "
                f"(one residual in [-1, 1] per hand DoF per world), got shape {a.shape}"
            )
        inside = (a >= -1.0) & (a <= 1.0)  # NaN fails both tests
        if bool(inside.all()):
            return a, None
        if not np.isfinite(a).all():
            bad = sorted({int(i) for i in np.nonzero(~np.isfinite(a))[0]})
            raise ValueError(f"ReplayVectorEnv: actions of worlds {bad} have NaN or infinite values")
        return a, inside

    def _step_worlds(
        self,
        a: np.ndarray,
        inside: np.ndarray | None,
        ids: np.ndarray,
        sel: slice | np.ndarray,
        terminated: np.ndarray,
        infos: dict[str, Any],
    ) -> np.ndarray:
        """Step worlds ``ids`` with actions ``a`` (clipped here); their numbers into ``infos``.

        Args:
            a: Every world's action.
            inside: Where ``a`` is within [-1, 1], or None where it all is.
            ids: The worlds that step.
            sel: ``ids``, or ``slice(None)`` when every world steps.
            terminated: Set for the worlds that diverged or drifted too far (changed in place).
            infos: The step's info (changed in place).

        Returns:
            Each world's reward (0 for a world that did not step).
        """
        n = self.num_envs
        if inside is None:
            clipped = np.zeros(n, np.int64)
            self._actions[:] = a
        else:
            clipped = (~inside).sum(axis=1)
            np.minimum(np.maximum(a, -1.0, out=self._actions), 1.0, out=self._actions)
        self._worlds.advance(ids, sel, self._actions)
        penetration = self._worlds.observe(ids, sel, self._obs)
        warnings = self._worlds.warnings(ids)
        columns, mask = self._reward_columns(ids, penetration)
        clipped[~mask] = 0
        diverged = np.zeros(n, bool)
        for i, events in warnings.items():
            diverged[i] = any(e.diverged for e in events)
        limit = self._env.max_object_drift
        terminated[sel] = diverged[sel] | (columns[1 + DRIFT][sel] > (math.inf if limit is None else limit))
        put_step_numbers(infos, columns, mask, diverged, clipped, warnings)
        return columns[0]

    def _reward_columns(self, ids: np.ndarray, penetration: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per world, the reward and its :data:`STEP_NUMBERS` (rows), from the single environment's reward.

        Returns:
            The (1 + numbers, num_envs) table (0 for the worlds that did not step) and the mask of those
            that did.
        """
        reward_of, actions, obs, frames = self._task.reward, self._actions, self._obs, self._worlds.frames
        table = []  # per stepped world: the reward, its terms and the info numbers
        for i in ids.tolist():
            action = actions[i]
            depth = float(penetration[i])
            reward, numbers = reward_of(obs[i], int(frames[i]), float(np.dot(action, action)), depth)
            table.append((reward, *numbers))
        if ids.size == self.num_envs:
            return np.array(table).T, self._everyone >= 0
        columns = np.zeros((len(STEP_NUMBERS) + 1, self.num_envs))
        columns[:, ids] = np.array(table).T
        mask = np.zeros(self.num_envs, bool)
        mask[ids] = True
        return columns, mask

    def _reset_ended(self, ended: np.ndarray, infos: dict[str, Any]) -> dict[str, Any]:
        """Same-step autoreset: the ended worlds' final observation and info aside, then their reset.

        Returns:
            The step's info with ``final_obs``/``final_info`` (masked to the ended worlds) and, for those
            worlds, the reset's numbers, frame, time and recording in place of the step's (the step-only
            keys masked off), as :class:`gymnasium.vector.SyncVectorEnv` gives in ``SAME_STEP`` mode.
        """
        n = self.num_envs
        final_obs = np.full(n, None, dtype=object)
        final = final_info(infos, ended)
        reset_numbers = {}
        for i in np.flatnonzero(ended).tolist():
            final_obs[i] = self._obs[i].copy()
            frame, reset_numbers[i] = self._reset_world(i, None)
            infos["frame"][i], infos["time"][i] = frame, self._times[frame]
        put_reset_numbers(infos, reset_numbers, n)
        for key in ("diverged", "action_clipped", "warnings"):  # not in a reset's info
            if key in infos:
                infos[f"_{key}"] = infos[f"_{key}"] & ~ended
        infos["recording"], infos["_recording"] = np.zeros(n, np.int64), ended.copy()
        infos["final_obs"], infos["_final_obs"] = final_obs, ended.copy()
        infos["final_info"], infos["_final_info"] = final, ended.copy()
        return infos

    def close_extras(self, **kwargs: Any) -> None:
        """Free the template environment's renderer."""
        self._env.close()

    def _reset_world(self, i: int, options: dict | None) -> tuple[int, tuple[float, ...]]:
        """Put world ``i`` in the recorded state of its start frame; its observation in row ``i``.

        Returns:
            The start frame and the reset's values of :data:`STEP_NUMBERS`.
        """
        env = self._env
        env.np_random = self._world_rng[i]
        obs, info = env.reset(options=options)
        self._world_rng[i] = env.np_random
        self._worlds.load(i, env, info["frame"])
        self._obs[i] = obs
        return int(info["frame"]), tuple(info[key] for key in STEP_NUMBERS)
