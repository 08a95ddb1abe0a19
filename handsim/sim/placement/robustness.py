"""Hold robustness: the hold outcome over a small deterministic ensemble of placements, not one lucky pose.

A glove scene's setup lists, beside the winning placement, the next-best placements of the search and the
winner moved by ±:attr:`~handsim.sim.specs.MetricSpec.robustness_shift` along each axis and turned by
±:attr:`~handsim.sim.specs.MetricSpec.robustness_turn_deg` about each axis
(:mod:`handsim.sim.placement.place`),
each with its own contact time. Each member is replayed in a private copy of the scene's model with only the
object's starting pose (and its support) changed; ``hold_robustness`` is the fraction of judged members,
the winner included, whose object was held.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from handsim.sim.parallel import map_runs
from handsim.sim.placement.grip import object_pose_variant
from handsim.sim.scene.compiled import SimScene
from handsim.sim.summary import HoldOutcome


@dataclass(frozen=True)
class EnsembleMember:
    """One replay of the robustness ensemble.

    Attributes:
        label: ``"placement"`` (the winner), ``"alternative 1"`` …, ``"+x 2 mm"``, ``"-z 5°"`` ….
        held: Its hold outcome (None: not judged).
        reason: Why it was lost or not judged, or None.
    """

    label: str
    held: bool | None
    reason: str | None


@dataclass(frozen=True)
class HoldRobustness:
    """The ensemble's hold outcomes.

    Attributes:
        fraction: Held members over judged members (the winner included), or None when none was judged.
        held: Members held.
        judged: Members judged.
        members: Every member's outcome, the winner first.
    """

    fraction: float | None
    held: int
    judged: int
    members: tuple[EnsembleMember, ...]

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {
            "fraction": self.fraction,
            "held": self.held,
            "judged": self.judged,
            "members": [{"label": m.label, "held": m.held, "reason": m.reason} for m in self.members],
        }


def ensemble_scenes(scene: SimScene) -> list[tuple[str, SimScene]]:
    """The ensemble's scenes (without the winner's own): each member's model copy and contact time.

    Args:
        scene: A glove scene whose ``setup.placement`` holds an ``ensemble`` list (label, pose in the
            scene's world, contact time).
    """
    members = []
    for member in scene.setup.placement.get("ensemble", ()):
        model = object_pose_variant(scene, member["pose"])
        setup = replace(scene.setup, contact_time=float(member["contact_time"]))
        members.append((member["label"], replace(scene, model=model, setup=setup)))
    return members


Outcome = tuple[bool | None, str | None] | None
"""A member's judge's answer: ``(held, reason)``, or None when it has no hold to judge."""


def member_outcomes(scene: SimScene, judge: Callable[[SimScene], Outcome]) -> list[tuple[str, Outcome]]:
    """Each ensemble member's label and its judge's answer, in the setup's order.

    The members are independent replays, each on its own data: they run on
    :func:`~handsim.sim.parallel.sim_threads` threads, so ``judge`` must keep its state (``MjData``) to
    itself. They do not depend on the winner's replay, so they may be judged before or beside it.
    """
    variants = ensemble_scenes(scene)
    outcomes = map_runs(judge, [variant for _, variant in variants])
    return [(label, outcome) for (label, _), outcome in zip(variants, outcomes, strict=True)]


def hold_robustness(
    scene: SimScene,
    winner: HoldOutcome,
    judge: Callable[[SimScene], Outcome],
    outcomes: list[tuple[str, Outcome]] | None = None,
) -> HoldRobustness:
    """Judge the hold of every ensemble member and count.

    Args:
        scene: The glove scene (its winner already replayed).
        winner: The winner's hold outcome.
        judge: Replays a member's scene and returns whether it held and why not (None when it has no hold
            to judge; :func:`handsim.sim.replay.member_verdict`); see :func:`member_outcomes`.
        outcomes: The members' answers when already judged (:func:`member_outcomes`); None: judged here.

    Returns:
        The robustness (``fraction`` None when no member was judged).
    """
    members = [EnsembleMember("placement", winner.held, winner.reason)]
    for label, outcome in member_outcomes(scene, judge) if outcomes is None else outcomes:
        held, reason = (None, None) if outcome is None else outcome
        members.append(EnsembleMember(label, held, reason))
    judged = [m for m in members if m.held is not None]
    held = sum(bool(m.held) for m in judged)
    return HoldRobustness(
        fraction=held / len(judged) if judged else None,
        held=held,
        judged=len(judged),
        members=tuple(members),
    )
