"""``handsim/Replay-v0``: follow a recorded trajectory; the policy corrects the recorded joint targets.

One environment step is one control frame of :func:`handsim.sim.control.control_schedule`: the hand's
actuators hold the recorded targets of the next frame plus the policy's residual, the mocap root (a
recorded root pose) moves to the next frame's pose, and MuJoCo runs ``frame_skip`` steps in one
``mj_step`` call of :class:`~handsim.sim.stepper.Stepper` — the same stepping, targets and sensors as
:func:`handsim.sim.replay.replay`. With zero actions the environment reproduces ``replay`` bitwise.

Default scene: the bundled Tzionas et al. sequence 20 (MIT): the right hand following its recorded root
pose through a mocap weld, the 53 mm cube free on the table
(:func:`~handsim.envs.recordings.default_replay_inputs`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import numpy.typing as npt
from gymnasium import spaces

from handsim.datatypes.trajectory import Trajectory
from handsim.envs._base import DEFAULT_CAMERA, DEFAULT_SIZE, HandEnv
from handsim.envs._checks import nonnegative, positive, reset_options, whole_option
from handsim.envs.recordings import RecordingError, recordings_from_keywords
from handsim.envs.replay_reward import DRIFT, STEP_NUMBERS, RewardWeights
from handsim.envs.replay_task import ReplayTask
from handsim.sim.control import DEFAULT_CONTROL_RATE, ControlSchedule, control_schedule
from handsim.sim.scene.compiled import SimScene
from handsim.sim.specs import MetricSpec


def _layout_mismatch(recordings: Sequence, names: tuple[str, ...], other: tuple[str, ...]) -> str:
    """Why recordings cannot share one environment: their observations differ (the first difference)."""
    first = next(
        (i for i, (a, b) in enumerate(zip(names, other, strict=False)) if a != b), min(len(names), len(other))
    )
    a = names[first] if first < len(names) else "(end)"
    b = other[first] if first < len(other) else "(end)"
    return (
        f"the {len(recordings)} recordings do not share one observation layout ({len(other)} and "
        f"{len(names)} elements; element {first} is {b!r} in one and {a!r} in another): sample only "
        "recordings of the same hand and objects in one environment"
    )


RESET_OPTIONS = {
    "frame": "the start frame, a whole number before the last frame",
    "recording": "which recording, a whole number from 0",
}
"""The options :meth:`ReplayEnv.reset` takes, with what each is (for the message of an unknown one)."""


class ReplayEnv(HandEnv):
    """Follow a recorded hand trajectory in a scene with free objects (``handsim/Replay-v0``).

    **Action** ``Box(-1, 1, (nu,), float32)``: a residual per hand DoF (actuator order,
    :attr:`dof_names`). The actuators get ``clip(ref + residual_scale · clip(action, -1, 1), ctrl range)``
    where ``ref`` is the recorded target of the frame the step drives towards.

    **Observation** ``Box(-inf, inf, (n,), float64)``, named element by element in
    :attr:`observation_names` and group by group in :attr:`observation_slices`:

    * ``hand_qpos`` (nu, rad), then ``root_pose`` (7: position m, quaternion w x y z; scenes whose hand
      root follows a recorded pose), then per object ``<prefix>pose`` (7) and ``<prefix>hinge`` (rad,
      articulated objects);
    * ``hand_qvel`` (nu, rad/s), ``root_velocity`` (6), per object ``<prefix>velocity`` (6: linear m/s in
      the world frame, angular rad/s in the body frame) and ``<prefix>hinge_velocity``;
    * the references of the next step: ``ref_ctrl`` (nu, the recorded targets clipped to the joint
      ranges), ``ref_root_pose`` (7), per recorded object ``ref_<prefix>pose`` (7) and
      ``ref_<prefix>hinge``; with ``reference_window=K`` the same groups for the K − 1 frames after it
      (``ref2_ctrl`` …);
    * errors to the reference of the frame reached: ``err_hand_qpos`` (nu, rad), ``err_fingertips`` (3 per
      fingertip, m), per recorded object ``err_<prefix>position`` (3, m), ``err_<prefix>rotation`` (3: the
      rotation vector of ``q_ref ⊗ q⁻¹``, rad) and ``err_<prefix>hinge`` (rad);
    * ``contact_force`` (one per hand link with collision geometry: the total contact normal force on
      every object part, N), ``penetration`` (the deepest hand–object penetration, m),
      ``contact_state`` (fraction of links touching; ``held``: 1 when at least 2 links touch);
    * ``progress``: frame index / last frame index, in [0, 1].

    **Reward** = the sum of the terms in ``info`` (errors measured at the frame reached):

    * ``reward_tracking = tracking_weight · exp(−mean((q − ref)²) / tracking_sigma²)``;
    * ``reward_object = object_weight · mean over recorded objects of exp(−d² / object_sigma²)``, d the
      distance of the object's origin from its recording (0 on frames where no track is valid);
    * ``reward_rotation = rotation_weight · mean over recorded objects of exp(−θ² / rotation_sigma²)``;
    * ``reward_articulation = articulation_weight · mean over articulated ones of exp(−e² / sigma²)``;
    * ``reward_held = held_weight · held`` in scenes without recorded object tracks (glove scenes);
    * ``reward_penetration = −penetration_weight · penetration in mm``;
    * ``reward_action = −action_weight · mean(action²)``.

    ``reset`` info carries the reset state's values of :data:`STEP_NUMBERS` too.

    **Episode**: starts at frame 0 (or a random frame with ``random_start``, or ``options={"frame": k}``),
    the hand joints moved by seeded noise with ``reset_noise_scale``;
    truncated at the schedule's last frame; terminated when MuJoCo diverges (``info["diverged"]``) or a
    recorded object ends up more than ``max_object_drift`` from its recording (``info["object_drift"]``).

    Args:
        scene: A compiled scene (:mod:`handsim.sim.scenarios`), or None with ``trajectory`` None for the
            bundled Tzionas sequence 20 (:func:`~handsim.envs.recordings.default_replay_inputs`).
        trajectory: The trajectory the scene replays; or, without a scene, a recording path or a list of
            them (any trial kind, :mod:`handsim.envs.recordings`): each episode follows one, drawn from
            the seeded ``np_random`` at reset (or ``options={"recording": i}``).
        control_rate: Control frames (environment steps) per second; rounded to whole MuJoCo steps.
        residual_scale: Largest residual, rad: a number or one per DoF.
        tracking_weight: Weight of the joint tracking term.
        tracking_sigma: Joint error scale of the tracking term, rad.
        object_weight: Weight of the object term.
        object_sigma: Distance scale of the object term, m.
        penetration_weight: Penalty per millimetre of penetration.
        action_weight: Penalty on the mean squared action.
        rotation_weight: Weight of the object rotation term.
        rotation_sigma: Angle scale of the rotation term, rad.
        articulation_weight: Weight of the articulation term.
        articulation_sigma: Angle scale of the articulation term, rad.
        held_weight: Weight of the held term (scenes without recorded object tracks).
        max_object_drift: Terminate when a recorded object is farther than this from its recording, m;
            None never terminates for it (settable later: :meth:`set_max_object_drift`).
        release_delay: Scenes with supports (glove scenario): they are switched off this long after the
            scene's ``release_time``, s (:attr:`handsim.sim.specs.MetricSpec.release_delay`).
        random_start: Reset to a frame drawn from the environment's seeded ``np_random``.
        reference_window: How many future frames of references the observation holds (≥ 1).
        reset_noise_scale: Half-width of the uniform noise on each hand joint at reset, rad.
        render_mode: None or ``"rgb_array"``.
        width: Rendered image width, pixels.
        height: Rendered image height, pixels.
        camera: Scene camera to render from (``"hand_cam"``, ``"overview"``) or None (free camera).
        **trial_options: With recording paths: :func:`handsim.trials.find_trial`'s keywords.

    Raises:
        ValueError: A parameter is out of range, or only one of ``scene`` and ``trajectory`` is given.
        RecordingError: A bad recording keyword (unknown option, empty list, a two-hand scene, recordings
            whose observations differ).
        HandsimError: A recording cannot be found, read or built (the subclass says why).
        TrajectoryError: The trajectory does not fit the scene (see
            :func:`~handsim.sim.control.control_schedule`).
    """

    def __init__(
        self,
        scene: SimScene | None = None,
        trajectory: Trajectory | None = None,
        *,
        control_rate: float = DEFAULT_CONTROL_RATE,
        residual_scale: float | npt.ArrayLike = 0.1,
        tracking_weight: float = 1.0,
        tracking_sigma: float = 0.05,
        object_weight: float = 1.0,
        object_sigma: float = 0.01,
        penetration_weight: float = 0.1,
        action_weight: float = 0.01,
        rotation_weight: float = 0.5,
        rotation_sigma: float = 0.2,
        articulation_weight: float = 0.5,
        articulation_sigma: float = 0.1,
        held_weight: float = 0.5,
        max_object_drift: float | None = 0.1,
        release_delay: float = MetricSpec.release_delay,
        random_start: bool = False,
        reference_window: int = 1,
        reset_noise_scale: float = 0.0,
        render_mode: str | None = None,
        width: int = DEFAULT_SIZE,
        height: int = DEFAULT_SIZE,
        camera: str | None = DEFAULT_CAMERA,
        **trial_options: Any,
    ) -> None:
        recordings = recordings_from_keywords(scene, trajectory, trial_options)
        self._control_rate = float(control_rate)
        self._render_args = {"render_mode": render_mode, "width": width, "height": height, "camera": camera}
        self._weights = RewardWeights(
            tracking_weight=tracking_weight,
            tracking_sigma=tracking_sigma,
            object_weight=object_weight,
            object_sigma=object_sigma,
            penetration_weight=penetration_weight,
            rotation_weight=rotation_weight,
            rotation_sigma=rotation_sigma,
            articulation_weight=articulation_weight,
            articulation_sigma=articulation_sigma,
            held_weight=held_weight,
            action_weight=action_weight,
        )
        self.max_object_drift = max_object_drift
        if (
            isinstance(reference_window, bool)
            or int(reference_window) != reference_window
            or reference_window < 1
        ):
            raise ValueError(f"reference_window must be a whole number ≥ 1, got {reference_window!r}")
        self._window = int(reference_window)
        self._noise = nonnegative("reset_noise_scale", reset_noise_scale)
        self._random_start = bool(random_start)
        self._residual_scale = residual_scale
        self._release_delay = nonnegative("release_delay", release_delay)
        self._recordings = recordings
        self._recording = -1
        names = None
        # every recording is configured once here: its errors surface now, and all must observe alike
        for index in reversed(range(len(recordings))):
            self._configure(index)
            if names is not None and names != self.observation_names:
                raise RecordingError(_layout_mismatch(recordings, names, self.observation_names))
            names = self.observation_names

    def _configure(self, index: int) -> None:
        """Build the simulation, references and observation layout of recording ``index``."""
        if index == self._recording:
            return
        if self._recording >= 0:
            self.close()
        scene, trajectory = self._recordings[index]
        schedule = control_schedule(scene, trajectory, self._control_rate)
        if schedule.frames < 2:
            raise ValueError(f"the trajectory gives {schedule.frames} control frame; an episode needs ≥ 2")
        self._setup_sim(scene, schedule.substeps, **self._render_args)
        self._recording = index
        task = ReplayTask(
            self._stepper, schedule, self._release_delay, self._window, self._residual_scale, self._weights
        )
        self._task = task
        self._driver, self._last, self._times = task.driver, task.last, task.times
        observation = task.observation
        # the recorded targets and fingertip positions of every frame (the observation's references)
        self._ref_ctrl, self._ref_tips = task.ref_ctrl, observation.ref_tips
        self.observation_names = observation.names
        self.observation_slices = observation.slices
        self.observation_space = spaces.Box(-np.inf, np.inf, (observation.size,), np.float64)
        self.action_space = spaces.Box(-1.0, 1.0, (len(self.dof_names),), np.float32)
        self._setup_observation(observation, observation.size)
        self._started = False

    def _action_description(self) -> str:
        return "one residual in [-1, 1] per hand DoF"

    # ---- public facts -----------------------------------------------------------------------------------
    @property
    def schedule(self) -> ControlSchedule:
        """The control frames the episode follows."""
        return self._task.schedule

    @property
    def task(self) -> ReplayTask:
        """The recording's control law, observation and reward (the vector environment's too)."""
        return self._task

    @property
    def max_object_drift(self) -> float | None:
        """The drift that terminates an episode, m (None: never); settable between episodes.

        A curriculum: ``vec_env.env_method("set_max_object_drift", d)`` in Stable-Baselines3, or
        :meth:`ReplayVectorEnv.set_max_object_drift`.
        """
        return None if math.isinf(self._max_drift) else self._max_drift

    @max_object_drift.setter
    def max_object_drift(self, value: float | None) -> None:
        self._max_drift = math.inf if value is None else positive("max_object_drift", value)

    def set_max_object_drift(self, value: float | None) -> None:
        """Set :attr:`max_object_drift` (a method, for ``env_method`` calls of vectorised training)."""
        self.max_object_drift = value

    @property
    def recording(self) -> int:
        """Index of the recording the episode follows (in the order given; 0 with one)."""
        return self._recording

    @property
    def recordings(self) -> int:
        """How many recordings the environment samples from."""
        return len(self._recordings)

    @property
    def frame(self) -> int:
        """Index of the control frame the simulation is at."""
        return self._driver.frame

    # ---- gymnasium API ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Put the scene at its recorded state of frame 0 (or of ``options["frame"]``, or a random frame).

        Args:
            seed: Seeds ``np_random`` (the random start frame and recording, the reset noise).
            options: None, or a dict of :data:`RESET_OPTIONS`: ``"frame"`` (the start frame) and
                ``"recording"`` (which recording), whole numbers.

        Raises:
            TypeError: ``options`` is not a dict, or an option is not a whole number (2.7 is not rounded,
                True is not 1).
            ValueError: An unknown option, ``options["frame"]`` not a frame before the last, or
                ``options["recording"]`` not one of the recordings.
        """
        options = reset_options(options, RESET_OPTIONS, type(self).__name__)
        chosen = {name: whole_option(options, name) for name in RESET_OPTIONS if name in options}
        super().reset(seed=seed)
        count = len(self._recordings)
        if "recording" in chosen:
            index = chosen["recording"]
            if not 0 <= index < count:
                raise ValueError(f"options['recording'] must be in [0, {count - 1}], got {index}")
        else:
            index = int(self.np_random.integers(0, count)) if count > 1 else 0
        self._configure(index)
        if "frame" in chosen:
            start = chosen["frame"]
            if not 0 <= start < self._last:
                raise ValueError(f"options['frame'] must be a frame in [0, {self._last - 1}], got {start}")
        elif self._random_start:
            start = int(self.np_random.integers(0, self._last))
        else:
            start = 0
        self._driver.reset(start)
        if self._noise > 0.0:
            self._perturb()
        self._started = True
        penetration = self._observe()
        _, numbers = self._task.reward(self._obs, start, 0.0, penetration)
        info = {"frame": start, "time": float(self._times[start]), "recording": index}
        info.update(zip(STEP_NUMBERS, numbers, strict=True))
        return self._obs.copy(), info

    def _perturb(self) -> None:
        """Reset noise: each hand joint moved by U(−s, s) rad (within its range), from ``np_random``."""
        layout = self._scene.layout
        data = self._stepper.data
        noise = self.np_random.uniform(-self._noise, self._noise, len(layout.dof_names))
        q = data.qpos[layout.dof_qpos] + noise
        data.qpos[layout.dof_qpos] = np.clip(q, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
        mujoco.mj_forward(self.model, data)

    def step(self, action: npt.ArrayLike) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Advance one control frame with the recorded targets plus the residual ``action``.

        Raises:
            ValueError: ``action`` has the wrong shape or a non-finite value.
            ResetNeeded: The episode is over (or was never started).
        """
        a, squares, clipped = self._action(action)
        k = self._driver.frame
        if k >= self._last or not self._started:
            raise gym.error.ResetNeeded(
                "the episode is over (last frame reached or terminated): call reset()"
                if self._started
                else "call reset() before step()"
            )
        n = k + 1
        self._task.controls(a, n, self._views.ctrl)
        events = self._driver.advance()  # the controls are in data.ctrl already
        penetration = self._observe()
        reward, numbers = self._task.reward(self._obs, n, squares, penetration)
        drift = numbers[DRIFT]
        diverged = any(e.diverged for e in events) if events else False
        terminated = diverged or drift > self._max_drift
        truncated = n >= self._last and not terminated
        if terminated:
            self._started = False
        info = {"frame": n, "time": float(self._times[n])}
        info.update(zip(STEP_NUMBERS, numbers, strict=True))
        info["diverged"] = diverged
        info["action_clipped"] = clipped
        if events:
            info["warnings"] = tuple(e.describe() for e in events)
        return self._obs.copy(), reward, terminated, truncated, info

    def _observe(self) -> float:
        """Fill the observation buffer from the state; returns the penetration, m."""
        obs, observation = self._obs, self._task.observation
        penetration = self._observe_state()
        frame = self._driver.frame
        observation.features(obs, frame, self._views.sensordata)
        obs[observation.progress_index] = frame / self._last
        return penetration
