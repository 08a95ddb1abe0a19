"""What both environments share: a stepper on a private model copy, checks, rendering, pickling.

The stepper is :class:`~handsim.sim.stepper.Stepper`, the one stepping loop of the replay core.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import numpy.typing as npt

from handsim.envs._render import OffscreenRenderer
from handsim.sim.scene.compiled import SimScene
from handsim.sim.stepper import Stepper

RENDER_MODES = ("rgb_array",)
DEFAULT_SIZE = 480
"""Rendered image width and height, pixels."""
DEFAULT_CAMERA = "hand_cam"


class HandEnv(gym.Env[np.ndarray, np.ndarray]):
    """Base of the handsim environments (not registered).

    Subclasses call :meth:`_setup_sim` in ``__init__`` and rebuild their views into ``self.data`` and
    the observation buffer in :meth:`_bind` (called again after unpickling).
    """

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 100}  # noqa: RUF012

    def _setup_sim(
        self,
        scene: SimScene,
        substeps: int,
        *,
        render_mode: str | None,
        width: int,
        height: int,
        camera: str | None,
    ) -> None:
        if len(scene.layout.hands) > 1:
            raise ValueError(
                f"the environments drive one hand; this scene has {len(scene.layout.hands)} "
                f"({[h.name for h in scene.layout.hands]}): replay it with handsim.sim.replay"
            )
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"unknown render_mode {render_mode!r}; expected one of {[None, *RENDER_MODES]}")
        # a private model: changing one env's model (e.g. domain randomisation) leaves the others alone
        self._scene = dataclasses.replace(scene, model=copy.deepcopy(scene.model))
        self._substeps = int(substeps)
        self._stepper = Stepper(self._scene, self._substeps)
        self.render_mode = render_mode
        self._renderer = OffscreenRenderer(self._scene.model, width, height, camera)
        self.metadata = {**type(self).metadata, "render_fps": round(1.0 / self.dt)}

    # ---- properties -------------------------------------------------------------------------------------
    @property
    def scene(self) -> SimScene:
        """The simulated scene (its model is this environment's own copy)."""
        return self._scene

    @property
    def model(self) -> mujoco.MjModel:
        """The MuJoCo model."""
        return self._scene.model

    @property
    def data(self) -> mujoco.MjData:
        """The MuJoCo data."""
        return self._stepper.data

    @property
    def dof_names(self) -> tuple[str, ...]:
        """Hand DoFs in action order."""
        return self._scene.layout.dof_names

    @property
    def frame_skip(self) -> int:
        """MuJoCo steps per environment step (the control frame's substeps)."""
        return self._stepper.substeps

    @property
    def dt(self) -> float:
        """Seconds per environment step."""
        return self._stepper.substeps * float(self._scene.model.opt.timestep)

    # ---- helpers ----------------------------------------------------------------------------------------
    def _bind(self) -> None:
        """(Re)create views into ``self.data`` and the observation buffer."""

    def _observe_state(self) -> float:
        """Fill the observation's state, contact forces and penetration; returns the penetration, m.

        Uses the views :meth:`_bind` made (``_obs_pos``/``_obs_vel``/``_obs_force``) and the index arrays
        of :func:`~handsim.envs._observation.add_state`.
        """
        self._obs_pos[:] = self._qpos[self._qpos_adr]
        self._obs_vel[:] = self._qvel[self._qvel_adr]
        self._contacts.link_forces(self._sensordata, self._obs_force)
        penetration = self._contacts.penetration(self._sensordata)
        self._obs[self._pen_index] = penetration
        return penetration

    def _action(self, action: npt.ArrayLike) -> tuple[np.ndarray, float, int]:
        """The action as float64 clipped to the action space, its sum of squares, and how many clipped.

        A value outside the action space (a policy's 1e30) is clipped to its bound, never passed on: the
        step's ``info["action_clipped"]`` says how many elements were. The caller's array is not changed.

        Raises:
            ValueError: Wrong shape, or a value that is NaN or infinite (MuJoCo would silently replace a
                non-finite control by zero).
        """
        a = np.asarray(action, dtype=np.float64)
        if a.shape != self.action_space.shape:
            raise ValueError(
                f"{type(self).__name__}: action must have shape {self.action_space.shape} "
                f"({self._action_doc}), got shape {a.shape}"
            )
        low, high = self.action_space.low, self.action_space.high
        if ((a >= low) & (a <= high)).all():  # the usual case in one reduction (NaN fails both tests)
            return a, float(np.dot(a, a)), 0
        if not np.isfinite(a).all():
            raise ValueError(f"{type(self).__name__}: action has NaN or infinite values: {a.tolist()}")
        outside = (a < low) | (a > high)
        clipped = int(np.count_nonzero(outside))
        if clipped:
            a = np.clip(a, low, high)
        return a, float(np.dot(a, a)), clipped

    _action_doc = ""

    # ---- rendering --------------------------------------------------------------------------------------
    def render(self) -> np.ndarray | None:  # type: ignore[override]
        """An RGB frame (height, width, 3) uint8 when ``render_mode="rgb_array"``, else None (warned).

        Raises:
            RenderError: No offscreen OpenGL context could be created.
        """
        if self.render_mode is None:
            gym.logger.warn(
                f"{type(self).__name__}.render() called without a render_mode: create the env with "
                "render_mode='rgb_array'"
            )
            return None
        return self._renderer.render(self.model, self.data)

    def close(self) -> None:
        """Free the renderer's GL context (idempotent)."""
        self._renderer.close()

    # ---- pickling ---------------------------------------------------------------------------------------
    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        # the stepper pickles with its data (state, warnings seen); views into data and buffers would
        # unpickle as copies: _bind() recreates them
        for name in getattr(self, "_views", ()):
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._bind()
