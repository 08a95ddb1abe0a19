"""What a ``handsim/Grasp-v0`` episode is: its start, its control law, how it is judged and how it ends.

A :class:`GraspTask` runs on the environment's stepper: it resets the scene (the open hand above the
object, the object at a seeded offset), turns an action into the hand's controls and the root's target
(:class:`~handsim.envs.grasp_action.HandCommand`, :class:`~handsim.envs.grasp_action.RootTarget`), steps,
and judges the step (:class:`GraspOutcome`: lifted, held long enough, fallen, penetrated, diverged).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import mujoco
import numpy as np

from handsim.envs._checks import nonnegative, positive, set_checked
from handsim.envs.grasp_action import HandCommand, HandConfig, RootConfig, RootTarget
from handsim.envs.grasp_scene import GraspScene
from handsim.sim.stepper import Stepper, WarningEvent

FALL_HEIGHT = -0.05
"""m: the episode terminates when the object's origin drops below this height (off the table)."""

_EPISODE_CHECKS = {
    "duration": positive,
    "hand_clearance": nonnegative,
    "object_xy_noise": nonnegative,
    "lift_height": positive,
    "hold_time": nonnegative,
}


@dataclasses.dataclass(frozen=True)
class EpisodeConfig:
    """How an episode starts, is judged and ends, checked.

    Each attribute is the :class:`~handsim.envs.grasp_env.GraspEnv` keyword of the same name.

    Raises:
        ValueError: A length, height or time out of range (``duration``, ``lift_height`` and
            ``max_penetration`` must be > 0, the others ≥ 0).
    """

    duration: float
    hand_clearance: float
    object_xy_noise: float
    lift_height: float
    hold_time: float
    terminate_on_success: bool
    max_penetration: float | None

    def __post_init__(self) -> None:
        set_checked(self, _EPISODE_CHECKS)
        object.__setattr__(self, "terminate_on_success", bool(self.terminate_on_success))
        if self.max_penetration is not None:
            object.__setattr__(self, "max_penetration", positive("max_penetration", self.max_penetration))


class GraspOutcome(NamedTuple):
    """What a step came to (the :class:`~handsim.envs.grasp_env.GraspEnv` step's ``info`` keys)."""

    lifted: bool  # the object is lift_height up and touched
    success: bool  # ... and has been for hold_time
    fell: bool  # the object dropped off the table
    penetrated: bool  # the hand went deeper into the object than max_penetration
    diverged: bool  # MuJoCo diverged
    terminated: bool
    truncated: bool
    held_at_end: bool  # the episode ends now, the object held


class GraspTask:
    """The per-step functions of a grasping episode on an environment's stepper.

    Args:
        stepper: The environment's stepper (its scene holds the environment's own model).
        built: The grasping scene the stepper's scene was compiled from (its grasp geometry).
        dt: Seconds per environment step.
        hand: How the hand's part of an action acts.
        root: How the root moves.
        episode: How an episode starts, is judged and ends.

    Attributes:
        steps: Steps per episode.
        hold_steps: Steps the object must be held for success.
        hand: The hand command.
        root: The root's target.
        action_names: One name per action element.
        grasp_offset: World offset from the hand root to the grasp point, m.
        step_count: Steps taken in the episode.
        held: Steps the object has been held up so far.
    """

    def __init__(
        self,
        stepper: Stepper,
        built: GraspScene,
        dt: float,
        hand: HandConfig,
        root: RootConfig,
        episode: EpisodeConfig,
    ) -> None:
        self._stepper = stepper
        scene = stepper.scene
        layout = scene.layout
        self.steps = max(1, round(episode.duration / dt))
        self._lift_height = episode.lift_height
        self.hold_steps = max(1, math.ceil(episode.hold_time / dt - 1e-9))
        self._noise = episode.object_xy_noise
        self._terminate_on_success = episode.terminate_on_success
        self._pen_limit = math.inf if episode.max_penetration is None else episode.max_penetration
        self.hand = HandCommand(layout, hand, dt)
        self.root = RootTarget(
            scene.model,
            layout.mocap,
            built.root_floor,
            root,
            dt,
            self.steps,
            episode.hand_clearance,
            episode.lift_height,
        )
        self.action_names = self.hand.names + self.root.names
        self._object_qpos = layout.objects[0].free_qpos  # x y z qw qx qy qz
        self.grasp_offset = np.asarray(built.grasp_offset, dtype=float)
        self._object_start_z = float(scene.model.qpos0[self._object_qpos + 2])
        self.step_count = 0
        self.held = 0

    def action_description(self) -> str:
        """What an action holds (for the message of a wrong action)."""
        root = " then 3 root velocities" if self.root.names else ""
        return self.hand.action_description() + root + " in [-1, 1]"

    def reset(self, rng: np.random.Generator) -> None:
        """The open hand at its start pose above the object; the object moved by a seeded offset.

        Args:
            rng: The environment's ``np_random`` (the object's offset).
        """
        stepper, layout = self._stepper, self._stepper.scene.layout
        stepper.reset()
        data = stepper.data
        rest = np.clip(0.0, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
        data.qpos[layout.dof_qpos] = rest
        data.ctrl[:] = rest
        if self._noise > 0:
            xy = self._object_qpos
            data.qpos[xy : xy + 2] += rng.uniform(-self._noise, self._noise, 2)
        self.root.reset(data.mocap_pos)
        self.hand.reset()
        mujoco.mj_forward(stepper.scene.model, data)
        self.step_count = 0
        self.held = 0

    def step(self, action: np.ndarray) -> tuple[WarningEvent, ...]:
        """Set the hand's controls and the root's target from ``action``, then advance one control frame.

        Args:
            action: The action, clipped to the action space.

        Returns:
            MuJoCo's warnings of the frame (empty almost always).
        """
        data = self._stepper.data
        self.hand.apply(action, data.ctrl)
        n = self.step_count + 1
        self.root.move(action[self.hand.size :], n, data.mocap_pos)
        events = self._stepper.step()  # the controls are in data.ctrl already
        self.step_count = n
        return events

    def lift(self) -> float:
        """The object's rise above its start, m."""
        return float(self._stepper.data.qpos[self._object_qpos + 2]) - self._object_start_z

    @property
    def progress(self) -> float:
        """Step / steps per episode."""
        return self.step_count / self.steps

    @property
    def hold_fraction(self) -> float:
        """Time held so far / the time to hold, at most 1."""
        return min(1.0, self.held / self.hold_steps)

    def judge(
        self, lift: float, touching: int, penetration: float, events: tuple[WarningEvent, ...]
    ) -> GraspOutcome:
        """Count the step as held or not and say how the episode stands after it.

        Args:
            lift: The object's rise above its start, m.
            touching: How many hand links touch the object.
            penetration: The deepest hand–object penetration, m.
            events: The step's MuJoCo warnings.
        """
        lifted = lift >= self._lift_height and touching > 0
        self.held = self.held + 1 if lifted else 0
        success = self.held >= self.hold_steps
        diverged = any(e.diverged for e in events) if events else False
        fell = float(self._stepper.data.qpos[self._object_qpos + 2]) < FALL_HEIGHT
        penetrated = penetration > self._pen_limit
        failed = diverged or fell or penetrated
        terminated = failed or (success and self._terminate_on_success)
        truncated = self.step_count >= self.steps and not terminated
        held_at_end = success and not failed and (terminated or truncated)
        return GraspOutcome(lifted, success, fell, penetrated, diverged, terminated, truncated, held_at_end)
