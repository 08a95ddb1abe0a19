"""The reward of ``handsim/Replay-v0``: its weights, its terms and the numbers a step reports.

:class:`ReplayReward` computes one world's reward from its observation once
:meth:`~handsim.envs.replay_observation.ReplayObservation.features` has filled the errors to the reference;
:class:`~handsim.envs.replay_env.ReplayEnv` and :class:`~handsim.envs.replay_vector_env.ReplayVectorEnv`
both call it, world by world.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from handsim.envs._checks import nonnegative, positive, set_checked
from handsim.envs.replay_observation import ReplayObservation

STEP_NUMBERS = (
    "reward_tracking",
    "reward_object",
    "reward_rotation",
    "reward_articulation",
    "reward_held",
    "reward_penetration",
    "reward_action",
    "tracking_error",
    "object_drift",
    "object_rotation_error",
    "penetration",
)
"""The numbers a step (and a reset) puts in ``info`` besides ``frame``, ``time``, ``diverged``,
``action_clipped`` (and the reset's ``recording``); the ``reward_*`` ones sum to the reward."""
DRIFT = STEP_NUMBERS.index("object_drift")
"""Where ``object_drift`` (m) is in :data:`STEP_NUMBERS`: an episode ends when it passes the limit."""
REWARD_TERMS = tuple(key for key in STEP_NUMBERS if key.startswith("reward_"))
"""The reward's terms, in the order they are summed."""


@dataclasses.dataclass(frozen=True)
class RewardWeights:
    """The reward's weights and scales, checked: :class:`~handsim.envs.replay_env.ReplayEnv`'s keywords.

    Each attribute is the keyword of the same name (see :class:`~handsim.envs.replay_env.ReplayEnv`): the
    ``*_weight`` ones are weights (``penetration_weight`` per mm), the ``*_sigma`` ones the error scales
    of their terms (rad, or m for ``object_sigma``).

    Raises:
        ValueError: A weight is not a finite number ≥ 0, or a scale (``*_sigma``) not one > 0.
    """

    tracking_weight: float
    tracking_sigma: float
    object_weight: float
    object_sigma: float
    penetration_weight: float
    rotation_weight: float
    rotation_sigma: float
    articulation_weight: float
    articulation_sigma: float
    held_weight: float
    action_weight: float

    def __post_init__(self) -> None:
        names = [field.name for field in dataclasses.fields(self)]
        set_checked(self, {name: positive if name.endswith("_sigma") else nonnegative for name in names})


class ReplayReward:
    """The reward of a world of one recording: the sum of the terms in :data:`REWARD_TERMS`.

    The terms are those :class:`~handsim.envs.replay_env.ReplayEnv` documents (errors measured at the
    frame reached), each read from the observation's errors and contact state.

    Args:
        weights: The weights and scales.
        observation: The recording's observation (its errors and contact state are read).
    """

    def __init__(self, weights: RewardWeights, observation: ReplayObservation) -> None:
        self._w_track = weights.tracking_weight
        self._inv_sigma2_track = 1.0 / weights.tracking_sigma**2
        self._w_object = weights.object_weight
        self._inv_sigma2_object = 1.0 / weights.object_sigma**2
        self._w_pen = weights.penetration_weight * 1000.0  # per m
        self._w_rot = weights.rotation_weight
        self._inv_sigma2_rot = 1.0 / weights.rotation_sigma**2
        self._w_art = weights.articulation_weight
        self._inv_sigma2_art = 1.0 / weights.articulation_sigma**2
        self._w_held = weights.held_weight
        nu = observation.err_hand.stop - observation.err_hand.start
        self._w_action = weights.action_weight / max(nu, 1)
        self._err_hand = observation.err_hand
        self._tracks = observation.tracks
        self._held_index = observation.contact_index + 1
        self._hold_term = not self._tracks  # scenes without recorded objects: the held term

    def __call__(
        self, obs: np.ndarray, frame: int, squares: float, penetration: float
    ) -> tuple[float, tuple[float, ...]]:
        """The reward of one world that reached ``frame`` with observation ``obs`` (features filled).

        Args:
            obs: The world's observation (obs_size,).
            frame: The frame reached.
            squares: Sum of squares of the (clipped) action.
            penetration: Deepest hand–object penetration, m.

        Returns:
            The reward (its terms summed in :data:`REWARD_TERMS` order) and the values of
            :data:`STEP_NUMBERS`.
        """
        err = obs[self._err_hand]
        mean_sq = float(np.dot(err, err)) / err.size if err.size else 0.0
        r_track = self._w_track * math.exp(-mean_sq * self._inv_sigma2_track)
        r_object = r_rot = r_art = drift = turn = 0.0
        tracked = hinged = 0
        for t in self._tracks:
            if not t.valid[frame]:
                continue
            delta = obs[t.position_error : t.position_error + 3]
            d2 = float(np.dot(delta, delta))
            r_object += math.exp(-d2 * self._inv_sigma2_object)
            drift = max(drift, math.sqrt(d2))
            rot = obs[t.rotation_error : t.rotation_error + 3]
            a2 = float(np.dot(rot, rot))
            r_rot += math.exp(-a2 * self._inv_sigma2_rot)
            turn = max(turn, math.sqrt(a2))
            tracked += 1
            if t.hinge_error >= 0:
                e = float(obs[t.hinge_error])
                r_art += math.exp(-e * e * self._inv_sigma2_art)
                hinged += 1
        if tracked:
            r_object *= self._w_object / tracked
            r_rot *= self._w_rot / tracked
        if hinged:
            r_art *= self._w_art / hinged
        r_held = self._w_held * float(obs[self._held_index]) if self._hold_term else 0.0
        r_pen = -self._w_pen * penetration
        r_action = -self._w_action * squares
        reward = r_track + r_object + r_rot + r_art + r_held + r_pen + r_action
        numbers = (r_track, r_object, r_rot, r_art, r_held, r_pen, r_action, math.sqrt(mean_sq), drift, turn)
        return reward, (*numbers, penetration)
