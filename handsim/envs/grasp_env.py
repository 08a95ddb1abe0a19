"""``handsim/Grasp-v0``: a hand above a catalogue object on the table; lift the object and hold it.

The hand is handsim's parametric default hand without its wrist DoFs, palm down, its root welded to a
mocap target (:mod:`handsim.envs.grasp_scene`). The environment puts together four parts, each in its own
module: the scene (:func:`~handsim.envs.grasp_scene.grasp_scene`), the task (:mod:`handsim.envs.grasp_task`:
the episode's start, control law and end, with the action's meaning in :mod:`handsim.envs.grasp_action`),
the observation (:mod:`handsim.envs.grasp_observation`) and the reward (:mod:`handsim.envs.grasp_reward`).

Two ways to move the root (``root_control``):

* ``"velocity"`` (default): the last 3 action elements command the root target's velocity (x, y, z, at
  most ``root_speed`` m/s each); the target is integrated every step, kept within ``root_range`` of its
  start (x, y either way, z up; down to the palm touching the table), and its orientation is held.
* ``"scripted"``: the action holds joint targets only; the root target goes down by ``hand_clearance``
  (the palm onto the object) in the first :data:`SCRIPT_DESCEND` s, waits until :data:`SCRIPT_LIFT_START`
  s and then rises at :data:`SCRIPT_LIFT_SPEED` m/s by ``lift_height`` + 5 cm: a finger-only task.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from gymnasium import spaces

from handsim.envs._base import DEFAULT_CAMERA, DEFAULT_SIZE, HandEnv
from handsim.envs._checks import reset_options
from handsim.envs.grasp_action import (
    DEFAULT_HAND_RATE,
    FINGERS,
    HAND_ACTIONS,
    HAND_CONTROLS,
    ROOT_CONTROLS,
    SCRIPT_DESCEND,
    SCRIPT_LIFT_SPEED,
    SCRIPT_LIFT_START,
    ZERO_ACTIONS,
    HandConfig,
    RootConfig,
    finger_coupling,
)
from handsim.envs.grasp_observation import GraspObservation
from handsim.envs.grasp_reward import (
    CONTACT_LINKS,
    HOLD_SIDES,
    REACH_SCALE,
    GraspReward,
    GraspRewardWeights,
    contact_sides,
    held_from_two_sides,
)
from handsim.envs.grasp_scene import GRASP_AHEAD, GraspScene, grasp_scene
from handsim.envs.grasp_task import FALL_HEIGHT, EpisodeConfig, GraspOutcome, GraspTask
from handsim.sim.control import DEFAULT_CONTROL_RATE, substeps_for

__all__ = [
    "CONTACT_LINKS",
    "DEFAULT_HAND_RATE",
    "FALL_HEIGHT",
    "FINGERS",
    "GRASP_AHEAD",
    "HAND_ACTIONS",
    "HAND_CONTROLS",
    "HOLD_SIDES",
    "REACH_SCALE",
    "ROOT_CONTROLS",
    "SCRIPT_DESCEND",
    "SCRIPT_LIFT_SPEED",
    "SCRIPT_LIFT_START",
    "ZERO_ACTIONS",
    "GraspEnv",
    "GraspScene",
    "contact_sides",
    "finger_coupling",
    "grasp_scene",
    "held_from_two_sides",
]


class GraspEnv(HandEnv):
    """Lift a catalogue object off the table and hold it (``handsim/Grasp-v0``).

    **Action** ``Box(-1, 1, (nu + 3,), float32)`` (``root_control="velocity"``) or ``(nu,)``
    (``"scripted"``): per hand DoF (actuator order, :attr:`dof_names`) a joint target; then the root
    target's velocity along world x, y, z as a fraction of ``root_speed``. Values are clipped to [−1, 1].
    ``zero_action="open"`` (default): 0 is the open hand of the reset (each DoF at 0 rad or its nearest
    limit), 0 … 1 goes linearly to the joint's upper limit and 0 … −1 to its lower one, so a policy's
    initial mean action holds the hand open; ``"mid"``: −1 … 1 mapped linearly onto the joint's range.
    ``hand_action="fingers"``: the hand's part is 6 values (:data:`FINGERS`: thumb opposition, thumb
    flexion, index, middle, ring, little), each given to every DoF of its group and mapped as above; the
    other DoFs get 0. :attr:`action_names` names the elements. ``hand_control="rate"``: the hand's part is
    the rate of change of that command instead (the **hand command**, the values above, starts at 0, the
    open hand, and moves by ``action · hand_rate · dt`` per step, kept in [−1, 1]; :attr:`hand_command`):
    a zero action holds the hand still, and exploration noise moves the fingers' targets smoothly rather
    than jolting them every step.

    **Observation** ``Box(-inf, inf, (n,), float64)``, named in :attr:`observation_names` and
    :attr:`observation_slices`: ``hand_qpos`` (nu, rad), ``root_pose`` (7), ``obj/pose`` (7: position m,
    quaternion w x y z); ``hand_qvel``, ``root_velocity`` (6), ``obj/velocity`` (6); ``root_target`` (3,
    the mocap target's position, m); ``object_to_grasp`` (3: the object's origin minus the grasp point
    under the palm, m); ``contact_force`` (per hand link, total normal force on the object, N);
    ``penetration`` (deepest, m); ``lift`` (the object's rise above its start, m); ``hold`` (time held
    so far / ``hold_time``, ≤ 1); ``progress`` (step / steps per episode); with ``hand_control="rate"``
    also ``hand_command`` (the hand command after the step's action, action units).

    **Reward** = the sum of the terms in ``info``:

    * ``reward_reach = reach_weight · (1 − tanh(10 · |object_to_grasp|))``;
    * ``reward_contact = contact_weight · min(links touching, 3) / 3``;
    * ``reward_lift = lift_weight · clip(lift / lift_height, 0, 1)`` while the hand holds the object
      (touched from two of :data:`HOLD_SIDES`: thumb, other fingers, palm), else 0;
    * ``reward_hold = hold_weight`` while the object is ``lift_height`` up and touched, else 0;
    * ``reward_penetration = −penetration_weight · penetration in mm`` (the deepest hand–object one);
    * ``reward_success = success_weight`` on the episode's last step (truncated at ``duration``, or ended
      by ``terminate_on_success``) when the object is held then (``success``), else 0: pays holding *to the
      end*, where ``reward_hold`` pays every step held (so lifting earlier earns more of it).

    **Success** (``info["success"]``, also ``info["is_success"]``): the object has been ``lift_height``
    above its start, touched by the hand, for the last ``hold_time`` seconds.

    **Episode**: the object starts at a seeded random offset (±``object_xy_noise``) on the table;
    truncated after ``duration`` seconds; terminated when MuJoCo diverges, the object falls off the table,
    or on success with ``terminate_on_success``, or (with ``max_penetration``) when the hand penetrates the
    object deeper than that: ``info["penetrated"]``.

    Args:
        object_name: Catalogue object (:func:`handsim.builders.catalog.names`).
        control_rate: Environment steps per second; rounded to whole MuJoCo steps.
        duration: Episode length, s.
        root_control: ``"velocity"`` or ``"scripted"`` (see the module).
        root_speed: Largest root target speed per axis, m/s (``"velocity"``).
        root_range: How far the root target may move from its start along x and y (either way) and up
            along z, m; down, it goes as far as the palm touching the table top.
        hand_clearance: Palm-to-object gap at the start, m.
        object_xy_noise: Half-width of the uniform random object offset at reset, m.
        lift_height: Height above its start the object must reach, m.
        hold_time: How long it must stay there, s.
        reach_weight: Weight of the reach term.
        contact_weight: Weight of the contact term.
        lift_weight: Weight of the lift term.
        hold_weight: Reward per step while holding.
        success_weight: Reward once, at the episode's last step, when the object is held then.
        penetration_weight: Penalty per millimetre of hand–object penetration.
        zero_action: What a zero joint action means, one of :data:`ZERO_ACTIONS`.
        hand_action: ``"joints"`` (a target per DoF) or ``"fingers"`` (a target per finger group,
            :data:`FINGERS`), one of :data:`HAND_ACTIONS`.
        hand_control: ``"position"`` (the action is the hand command) or ``"rate"`` (its rate of change),
            one of :data:`HAND_CONTROLS`.
        hand_rate: ``hand_control="rate"``: the command's largest change per second, action units.
        terminate_on_success: End the episode at success.
        max_penetration: None (default: never), or end the episode when the deepest hand–object
            penetration exceeds this, m: a hard constraint on physical plausibility, where the penalty
            (``penetration_weight``) only prices it.
        render_mode: None or ``"rgb_array"``.
        width: Rendered image width, pixels.
        height: Rendered image height, pixels.
        camera: Scene camera (``"hand_cam"``, ``"overview"``) or None (free camera).

    Raises:
        ValueError: A parameter is out of range.
        UnknownObjectError: ``object_name`` is not in the catalogue.
    """

    def __init__(
        self,
        object_name: str = "tennis_ball",
        *,
        control_rate: float = DEFAULT_CONTROL_RATE,
        duration: float = 3.0,
        root_control: str = "velocity",
        root_speed: float = 0.2,
        root_range: tuple[float, float, float] = (0.1, 0.1, 0.15),
        hand_clearance: float = 0.02,
        object_xy_noise: float = 0.01,
        lift_height: float = 0.05,
        hold_time: float = 0.5,
        reach_weight: float = 0.1,
        contact_weight: float = 0.1,
        lift_weight: float = 1.0,
        hold_weight: float = 1.0,
        success_weight: float = 0.0,
        penetration_weight: float = 0.2,
        zero_action: str = "open",
        hand_action: str = "joints",
        hand_control: str = "position",
        hand_rate: float = DEFAULT_HAND_RATE,
        terminate_on_success: bool = False,
        max_penetration: float | None = None,
        render_mode: str | None = None,
        width: int = DEFAULT_SIZE,
        height: int = DEFAULT_SIZE,
        camera: str | None = DEFAULT_CAMERA,
    ) -> None:
        root = RootConfig(root_control, root_speed, root_range)
        hand = HandConfig(zero_action, hand_action, hand_control, hand_rate)
        episode = EpisodeConfig(
            duration,
            hand_clearance,
            object_xy_noise,
            lift_height,
            hold_time,
            terminate_on_success,
            max_penetration,
        )
        weights = GraspRewardWeights(
            reach_weight, contact_weight, lift_weight, hold_weight, success_weight, penetration_weight
        )
        built = grasp_scene(object_name, episode.hand_clearance)
        substeps = substeps_for(control_rate, built.scene.timestep)
        self._setup_sim(
            built.scene, substeps, render_mode=render_mode, width=width, height=height, camera=camera
        )
        self._task = task = GraspTask(self._stepper, built, self.dt, hand, root, episode)
        observation = GraspObservation(self._scene, task.hand.names if task.hand.rate else None)
        self._observation = observation
        self._reward = GraspReward(weights, episode.lift_height, observation)
        self._setup_observation(observation, observation.size)
        self._started = False
        self.object_name = object_name
        self.zero_action, self.hand_action, self.hand_control = zero_action, hand_action, hand_control
        self.hand_rate, self.root_control = hand.hand_rate, root_control
        self.max_penetration = episode.max_penetration
        self.action_names = task.action_names
        self.observation_names = observation.names
        self.observation_slices = observation.slices
        self.observation_space = spaces.Box(-np.inf, np.inf, (observation.size,), np.float64)
        self.action_space = spaces.Box(-1.0, 1.0, (len(task.action_names),), np.float32)

    def _action_description(self) -> str:
        return self._task.action_description()

    @property
    def task(self) -> GraspTask:
        """The episode's control law, judgement and end."""
        return self._task

    @property
    def max_steps(self) -> int:
        """Steps per episode."""
        return self._task.steps

    @property
    def hand_command(self) -> np.ndarray:
        """The hand command (a copy, action units).

        The last action's hand part, or with ``hand_control="rate"`` the command its rates have moved to
        (0 after a reset).
        """
        return self._task.hand.command.copy()

    # ---- gymnasium API ----------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Open hand at its start pose above the object; the object at a seeded random offset.

        Args:
            seed: Seeds ``np_random`` (the object's offset).
            options: None or an empty dict: every episode starts the same way, so there is nothing to
                choose (an option is refused rather than ignored).

        Raises:
            TypeError: ``options`` is not a dict.
            ValueError: ``options`` holds any key.
        """
        reset_options(options, {}, type(self).__name__)
        super().reset(seed=seed)
        self._task.reset(self.np_random)
        self._started = True
        lift = self._task.lift()
        penetration, touching = self._observe(lift)
        terms = self._reward(self._obs, lift, penetration, touching, lifted=False, held_at_end=False)
        return self._obs.copy(), {
            **terms,
            "success": False,
            "is_success": False,
            "lift": lift,
            "links_touching": touching,
            "penetration": penetration,
        }

    def step(self, action: npt.ArrayLike) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Set the joint targets (and move the root target), then advance one control frame.

        Raises:
            ValueError: ``action`` has the wrong shape or a non-finite value.
            ResetNeeded: The episode is over (or was never started).
        """
        a, _, clipped = self._action(action)  # clipped to the action space
        if not self._started:
            raise gym.error.ResetNeeded("the episode is over or was never started: call reset()")
        task = self._task
        events = task.step(a)
        lift = task.lift()
        penetration, touching = self._observe(lift)
        outcome = task.judge(lift, touching, penetration, events)
        self._obs[self._observation.hold_index] = task.hold_fraction
        terms = self._reward(self._obs, lift, penetration, touching, outcome.lifted, outcome.held_at_end)
        reward = sum(terms.values())
        if outcome.terminated or outcome.truncated:
            self._started = False
        info = {**terms, **_step_info(outcome, lift, touching, penetration), "action_clipped": clipped}
        if events:
            info["warnings"] = tuple(e.describe() for e in events)
        return self._obs.copy(), reward, outcome.terminated, outcome.truncated, info

    def _observe(self, lift: float) -> tuple[float, int]:
        """Fill the observation buffer (``hold`` as the task counts it before this step's judgement).

        Returns:
            The penetration (m) and the number of hand links touching the object.
        """
        task = self._task
        penetration = self._observe_state()
        touching = self._observation.features(
            self._obs, task.root.target, task.grasp_offset, lift, task.progress, task.hand.command
        )
        self._obs[self._observation.hold_index] = task.hold_fraction
        return penetration, touching


def _step_info(outcome: GraspOutcome, lift: float, touching: int, penetration: float) -> dict:
    """A step's ``info`` besides the reward terms, ``action_clipped`` and ``warnings``."""
    return {
        "success": outcome.success,
        "is_success": outcome.success,
        "lift": lift,
        "links_touching": touching,
        "penetration": penetration,
        "fell": outcome.fell,
        "penetrated": outcome.penetrated,
        "diverged": outcome.diverged,
    }
