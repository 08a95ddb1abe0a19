"""One recording as a ``handsim/Replay-v0`` world follows it: its driver, control law, observation, reward.

A :class:`ReplayTask` is what both :class:`~handsim.envs.replay_env.ReplayEnv` and
:class:`~handsim.envs.replay_vector_env.ReplayVectorEnv` compute with, so that N worlds of the vector
environment return exactly what N single environments would: the control law (:meth:`ReplayTask.controls`,
elementwise over any number of worlds), the observation's layout and features
(:class:`~handsim.envs.replay_observation.ReplayObservation`) and the reward
(:class:`~handsim.envs.replay_reward.ReplayReward`).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from handsim.envs.replay_observation import ReplayObservation
from handsim.envs.replay_reward import ReplayReward, RewardWeights
from handsim.sim.control import ControlSchedule
from handsim.sim.drive import ScheduleDriver, scenario_switches
from handsim.sim.stepper import Stepper


class ReplayTask:
    """The per-frame functions of one recording on an environment's stepper.

    Args:
        stepper: The environment's stepper (its scene holds the environment's own model).
        schedule: The control frames the recording gives.
        release_delay: Seconds after the scene's release time at which its supports go off.
        window: How many future frames of references the observation holds (≥ 1).
        residual_scale: Largest residual, rad: a number or one per DoF.
        weights: The reward's weights.

    Attributes:
        schedule: The control frames.
        driver: Steps the stepper through the schedule (switches, root targets).
        last: The last frame's index.
        times: Each frame's time, s.
        ref_ctrl: The recorded targets clipped to the joint ranges (frames, nu), rad.
        observation: The observation's layout and features.
        reward: The reward.

    Raises:
        ValueError: ``residual_scale`` is not a number ≥ 0 nor one per DoF.
    """

    def __init__(
        self,
        stepper: Stepper,
        schedule: ControlSchedule,
        release_delay: float,
        window: int,
        residual_scale: float | npt.ArrayLike,
        weights: RewardWeights,
    ) -> None:
        scene = stepper.scene
        layout = scene.layout
        nu = len(layout.dof_names)
        scale = np.asarray(residual_scale, dtype=float)
        if scale.shape not in ((), (nu,)) or not np.all(np.isfinite(scale)) or np.any(scale < 0):
            raise ValueError(
                f"residual_scale must be a number ≥ 0 or {nu} of them (one per DoF), got {scale.tolist()}"
            )
        self._scale = np.broadcast_to(scale, (nu,)).copy()
        self.schedule = schedule

        # per frame: the recorded targets, and the bounds that clip(ref + residual) stays within
        lo, hi = layout.ctrl_range[:, 0], layout.ctrl_range[:, 1]
        ctrl = np.ascontiguousarray(schedule.ctrl, dtype=float)
        self.ref_ctrl = np.clip(ctrl, lo, hi)
        self._ctrl_lo = np.clip(ctrl - self._scale, lo, hi)
        self._ctrl_hi = np.clip(ctrl + self._scale, lo, hi)
        self._ctrl_ref = ctrl
        self.last = schedule.frames - 1
        self.times = schedule.times
        switches = scenario_switches(scene, schedule, release_delay)
        self.driver = ScheduleDriver(stepper, schedule, switches)
        self.observation = ReplayObservation(scene, schedule, self.driver, self.ref_ctrl, window)
        self.reward = ReplayReward(weights, self.observation)

    def controls(self, action: np.ndarray, frame: int | np.ndarray, out: np.ndarray) -> None:
        """The actuator controls towards ``frame``: ``clip(ref + residual_scale · action, ctrl range)``.

        Elementwise, so one world (``action`` (nu,), ``frame`` an int) and many (``action`` (worlds, nu),
        ``frame`` (worlds,)) give bitwise the same controls.

        Args:
            action: Actions already clipped to the action space.
            frame: The frame each world steps towards.
            out: Where the controls go (``data.ctrl``, or a batch's controls).
        """
        np.multiply(action, self._scale, out=out)
        out += self._ctrl_ref[frame]
        np.maximum(out, self._ctrl_lo[frame], out=out)
        np.minimum(out, self._ctrl_hi[frame], out=out)
