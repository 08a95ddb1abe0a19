"""The reward of ``handsim/Grasp-v0``: its weights, its terms, and which sides of the hand hold the object.

:class:`GraspReward` computes a step's terms from the observation once
:meth:`~handsim.envs.grasp_observation.GraspObservation.features` has filled it, and from what the task
judged of the step (lifted, held to the end).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from handsim.datatypes.fingers import finger_of
from handsim.envs._checks import nonnegative, set_checked
from handsim.envs.grasp_observation import GraspObservation

CONTACT_LINKS = 3
"""``reward_contact`` is full when this many hand links touch the object."""
HOLD_SIDES = ("thumb", "fingers", "palm")
"""The sides a hand can press an object from (:func:`contact_sides`); ``reward_lift`` pays only while the
object is touched from at least two of them, so a lift is paid when the hand holds the object, not when a
stray knock sends it up."""
REACH_SCALE = 10.0
"""1/m: ``reward_reach = reach_weight · (1 − tanh(REACH_SCALE · distance))``."""


def contact_sides(link_names: tuple[str, ...] | list[str]) -> tuple[np.ndarray, ...]:
    """Indices of the hand links on each side of :data:`HOLD_SIDES` (thumb, the other fingers, palm).

    An object touched from two of these sides is squeezed between them, so the hand can carry it; links of
    one side alone (say the index and the middle finger) only push it.

    Args:
        link_names: The hand's link names, in the order of the per-link contact forces.

    Returns:
        One index array per side, in :data:`HOLD_SIDES` order (:func:`handsim.datatypes.fingers.finger_of`
        decides each link's finger; every finger but the thumb is on the ``"fingers"`` side).
    """
    fingers = [finger_of(name) for name in link_names]
    thumb = [i for i, f in enumerate(fingers) if f == "thumb"]
    palm = [i for i, f in enumerate(fingers) if f == "palm"]
    others = [i for i, f in enumerate(fingers) if f not in ("thumb", "palm")]
    return tuple(np.array(side, dtype=np.int64) for side in (thumb, others, palm))


def held_from_two_sides(link_forces: np.ndarray, sides: tuple[np.ndarray, ...]) -> bool:
    """Whether the object is touched from at least two sides (:func:`contact_sides`).

    Args:
        link_forces: Normal force on the object per hand link, N.
        sides: The link indices of each side, from :func:`contact_sides`.

    Returns:
        True when links of two or more sides push on the object: the hand holds it.
    """
    return sum(bool(np.any(link_forces[side] > 0.0)) for side in sides) >= 2


@dataclasses.dataclass(frozen=True)
class GraspRewardWeights:
    """The reward's weights, checked.

    Each attribute is the :class:`~handsim.envs.grasp_env.GraspEnv` keyword of the same name
    (``penetration_weight`` per mm, ``hold_weight`` per step, ``success_weight`` once).

    Raises:
        ValueError: A weight is not a finite number ≥ 0.
    """

    reach_weight: float
    contact_weight: float
    lift_weight: float
    hold_weight: float
    success_weight: float
    penetration_weight: float

    def __post_init__(self) -> None:
        set_checked(self, {field.name: nonnegative for field in dataclasses.fields(self)})


class GraspReward:
    """The reward of a grasping world: the sum of its terms, in :meth:`__call__`'s order.

    The terms are those :class:`~handsim.envs.grasp_env.GraspEnv` documents.

    Args:
        weights: The weights.
        lift_height: Height above its start the object must reach, m (the lift term is full there).
        observation: The observation (its object-to-grasp vector and contact forces are read).
    """

    def __init__(
        self, weights: GraspRewardWeights, lift_height: float, observation: GraspObservation
    ) -> None:
        self._w_reach = weights.reach_weight
        self._w_contact = weights.contact_weight / CONTACT_LINKS
        self._w_lift = weights.lift_weight / lift_height
        self._w_hold = weights.hold_weight
        self._w_success = weights.success_weight
        self._w_pen = weights.penetration_weight * 1000.0  # per m
        self._lift_height = lift_height
        self._rel = observation.rel_slice
        self._force = observation.force_slice
        self._sides = contact_sides(observation.contacts.link_names)

    def __call__(
        self,
        obs: np.ndarray,
        lift: float,
        penetration: float,
        touching: int,
        lifted: bool,
        held_at_end: bool,
    ) -> dict[str, float]:
        """The reward terms, by name, in the order they are summed (see the class).

        Whether the object is held from two sides (:func:`held_from_two_sides`) gates ``reward_lift``:
        without it, random actions that knock the object upward would be paid for a lift the hand does
        not hold.

        Args:
            obs: The observation, features filled.
            lift: The object's rise above its start, m.
            penetration: The deepest hand–object penetration, m.
            touching: How many hand links touch the object.
            lifted: Whether the object is up and touched (``reward_hold``).
            held_at_end: Whether the episode ends now with the object held (``reward_success``).
        """
        grasped = held_from_two_sides(obs[self._force], self._sides)
        rel = obs[self._rel]
        distance = math.sqrt(float(np.dot(rel, rel)))
        return {
            "reward_reach": self._w_reach * (1.0 - math.tanh(REACH_SCALE * distance)),
            "reward_contact": self._w_contact * min(touching, CONTACT_LINKS),
            "reward_lift": self._w_lift * min(max(lift, 0.0), self._lift_height) if grasped else 0.0,
            "reward_hold": self._w_hold if lifted else 0.0,
            "reward_penetration": -self._w_pen * penetration,
            "reward_success": self._w_success if held_at_end else 0.0,
        }
