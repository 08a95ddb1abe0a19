"""What both environments share: a stepper on a private model copy, checks, rendering, pickling.

The stepper is :class:`~handsim.sim.stepper.Stepper`, the one stepping loop of the replay core. A subclass
hands the base what it needs through two calls and one method, never through attributes the base would
look up by name: :meth:`HandEnv._setup_sim` (the scene and stepper), :meth:`HandEnv._setup_observation`
(where the state goes in the observation, an :class:`ObservedState`) and :meth:`HandEnv._action_description`
(for the message of a wrong action).
"""

from __future__ import annotations

import abc
import copy
import dataclasses
from typing import Any, NamedTuple, Protocol

import gymnasium as gym
import mujoco
import numpy as np
import numpy.typing as npt

from handsim.envs._observation import ContactSummary
from handsim.envs._render import OffscreenRenderer
from handsim.sim.scene.compiled import SimScene
from handsim.sim.stepper import Stepper

RENDER_MODES = ("rgb_array",)
DEFAULT_SIZE = 480
"""Rendered image width and height, pixels."""
DEFAULT_CAMERA = "hand_cam"


class ObservedState(Protocol):
    """Where an observation holds the state the base gathers (:meth:`HandEnv._observe_state`).

    Attributes:
        pos_slice: The positions' slice; ``obs[pos_slice] = qpos[qpos_adr]``.
        qpos_adr: The positions' qpos addresses.
        vel_slice: The velocities' slice; ``obs[vel_slice] = qvel[qvel_adr]``.
        qvel_adr: The velocities' qvel addresses.
        contacts: The contact summary whose forces and penetration fill ``force_slice`` and ``pen_index``.
        force_slice: The per-link contact forces' slice.
        pen_index: The penetration's index.
    """

    pos_slice: slice
    qpos_adr: np.ndarray
    vel_slice: slice
    qvel_adr: np.ndarray
    contacts: ContactSummary
    force_slice: slice
    pen_index: int


class DataViews(NamedTuple):
    """Views into the simulation data and the observation buffer, made once per (un)pickled environment.

    Views unpickle as copies, so they are never pickled: :meth:`HandEnv.__setstate__` makes them again.
    """

    qpos: np.ndarray
    qvel: np.ndarray
    sensordata: np.ndarray
    ctrl: np.ndarray
    obs_pos: np.ndarray
    obs_vel: np.ndarray
    obs_force: np.ndarray


class HandEnv(gym.Env[np.ndarray, np.ndarray], abc.ABC):
    """Base of the handsim environments (not registered).

    Subclasses call :meth:`_setup_sim` and then :meth:`_setup_observation` in ``__init__`` (again for
    another scene), and describe their action in :meth:`_action_description`. The base pickles every
    attribute but its views (:class:`DataViews`), which it makes again after unpickling: a subclass keeps
    no views of its own.
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
    def _setup_observation(self, observed: ObservedState, size: int) -> None:
        """Allocate the observation buffer (``self._obs``, zeros) and the views into it and the data.

        Args:
            observed: Where the state the base gathers goes in the observation.
            size: Number of observation elements.
        """
        self._observed = observed
        self._obs = np.zeros(size)
        self._views = self._make_views()

    def _make_views(self) -> DataViews:
        data, obs, observed = self._stepper.data, self._obs, self._observed
        return DataViews(
            qpos=data.qpos,
            qvel=data.qvel,
            sensordata=data.sensordata,
            ctrl=data.ctrl,
            obs_pos=obs[observed.pos_slice],
            obs_vel=obs[observed.vel_slice],
            obs_force=obs[observed.force_slice],
        )

    def _observe_state(self) -> float:
        """Fill the observation's state, contact forces and penetration; returns the penetration, m.

        Gathers by the index arrays of :func:`~handsim.envs._observation.add_state` into the places the
        :class:`ObservedState` of :meth:`_setup_observation` gives.
        """
        views, observed = self._views, self._observed
        views.obs_pos[:] = views.qpos[observed.qpos_adr]
        views.obs_vel[:] = views.qvel[observed.qvel_adr]
        observed.contacts.link_forces(views.sensordata, views.obs_force)
        penetration = observed.contacts.penetration(views.sensordata)
        self._obs[observed.pen_index] = penetration
        return penetration

    @abc.abstractmethod
    def _action_description(self) -> str:
        """What an action holds, for the message of an action of the wrong shape."""

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
                f"({self._action_description()}), got shape {a.shape}"
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
        """Every attribute but the views, which would unpickle as copies of what they view.

        The stepper pickles with its data (the whole state, the warnings seen) and the private model with
        whatever was changed in it (domain randomisation, a scenario's contact switch), so a copy goes on
        bitwise like the original.
        """
        state = self.__dict__.copy()
        del state["_views"]
        return state

    def __setstate__(self, state: dict) -> None:
        """Restore the attributes and make the views into the restored data and buffer again."""
        self.__dict__.update(state)
        self._views = self._make_views()
