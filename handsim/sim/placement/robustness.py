"""Hold robustness: the hold outcome over a small deterministic ensemble of placements, not one lucky pose.

A glove scene's setup lists, beside the winning placement, the next-best placements of the search and the
winner moved by ±:attr:`~handsim.sim.specs.MetricSpec.robustness_shift` along each axis and turned by
±:attr:`~handsim.sim.specs.MetricSpec.robustness_turn_deg` about each axis
(:mod:`handsim.sim.placement.place`),
each with its own contact time. Each member is replayed in a private copy of the scene's model with only the
object's starting pose (and its support) changed.

A glove verdict also rests on what the glove does not measure. For a hand whose DoFs the CyberGlove drives
(GraspDB14's names), the ensemble adds members with the winner's placement and other hand targets
(:func:`hand_variants`): each thumb TMC DoF no sensor drives (``th_tmc_abd``, ``th_tmc_flex``) turned by
±:attr:`~handsim.sim.specs.MetricSpec.robustness_undriven_deg`, every other undriven DoF turned together by
as much, and every sensor-driven DoF offset together by
±:attr:`~handsim.sim.specs.MetricSpec.robustness_sensor_deg` (the glove's repeatability between wearings).
``hold_robustness`` is the fraction of judged members, the winner included, whose object was held; the
members' factors (placement, thumb, undriven, sensor) are counted apart too, so a verdict shows what it
hinges on.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from handsim.glove.sensors import driven_dofs
from handsim.glove.thumb_rest import THUMB_REST_DOFS
from handsim.sim.control import ControlSchedule
from handsim.sim.parallel import map_runs
from handsim.sim.placement.grip import object_pose_variant
from handsim.sim.scene.compiled import SimScene
from handsim.sim.specs import MetricSpec
from handsim.sim.summary import HoldOutcome

FACTORS = ("placement", "thumb", "undriven", "sensor")
"""What an ensemble member varies: the object's placement, an undriven thumb DoF, the other undriven DoFs,
the sensors' offset."""


@dataclass(frozen=True)
class EnsembleMember:
    """One replay of the robustness ensemble.

    Attributes:
        label: ``"placement"`` (the winner), ``"alternative 1"`` …, ``"+x 2 mm"``, ``"-z 5°"``,
            ``"th_tmc_abd +5°"``, ``"sensors -3°"`` ….
        held: Its hold outcome (None: not judged).
        reason: Why it was lost or not judged, or None.
        factor: What it varies (one of :data:`FACTORS`).
    """

    label: str
    held: bool | None
    reason: str | None
    factor: str = "placement"


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

    def factors(self) -> dict[str, dict]:
        """Held and judged members of each factor present, with their fraction (None when none judged)."""
        counts = {}
        for factor in FACTORS:
            members = [m for m in self.members if m.factor == factor]
            if members:
                judged = [m for m in members if m.held is not None]
                held = sum(bool(m.held) for m in judged)
                fraction = held / len(judged) if judged else None
                counts[factor] = {"held": held, "judged": len(judged), "fraction": fraction}
        return counts

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {
            "fraction": self.fraction,
            "held": self.held,
            "judged": self.judged,
            "factors": self.factors(),
            "members": [
                {"label": m.label, "factor": m.factor, "held": m.held, "reason": m.reason}
                for m in self.members
            ],
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


def hand_variants(
    scene: SimScene, schedule: ControlSchedule, spec: MetricSpec
) -> list[tuple[str, str, ControlSchedule]]:
    """The ensemble's hand members: the winner's placement driven by other targets (label, factor, schedule).

    Only for a hand the CyberGlove drives (its DoFs named as the glove's sensors map them, see
    :func:`handsim.glove.sensors.driven_dofs`); none for any other. Targets are shifted over every frame and
    kept inside the actuators' control ranges.

    Args:
        scene: The glove scene.
        schedule: The winner's control schedule.
        spec: The ranges (:attr:`~handsim.sim.specs.MetricSpec.robustness_undriven_deg`,
            :attr:`~handsim.sim.specs.MetricSpec.robustness_sensor_deg`); 0 leaves a factor out.
    """
    names = scene.layout.dof_names
    driven = set(driven_dofs())
    if not driven.intersection(names):
        return []
    undriven = [i for i, name in enumerate(names) if name not in driven]
    groups = [
        (names[i], "thumb", [i], spec.robustness_undriven_deg)
        for i in undriven
        if names[i] in THUMB_REST_DOFS
    ]
    others = [i for i in undriven if names[i] not in THUMB_REST_DOFS]
    if others:
        groups.append(("other undriven DoFs", "undriven", others, spec.robustness_undriven_deg))
    sensed = [i for i, name in enumerate(names) if name in driven]
    groups.append(("sensors", "sensor", sensed, spec.robustness_sensor_deg))
    low, high = scene.layout.ctrl_range[:, 0], scene.layout.ctrl_range[:, 1]
    variants = []
    for label, factor, columns, degrees in groups:
        if degrees <= 0:
            continue
        for sign in (1.0, -1.0):
            offset = np.zeros(len(names))
            offset[columns] = sign * math.radians(degrees)
            ctrl = np.clip(schedule.ctrl + offset, low, high)
            variants.append((f"{label} {sign * degrees:+g}°", factor, replace(schedule, ctrl=ctrl)))
    return variants


Outcome = tuple[bool | None, str | None] | None
"""A member's judge's answer: ``(held, reason)``, or None when it has no hold to judge."""

Judge = Callable[[SimScene, ControlSchedule], Outcome]
"""Replays a member (its scene and schedule) and says whether it held
(:func:`handsim.sim.replay.member_verdict`)."""


def member_outcomes(
    scene: SimScene, schedule: ControlSchedule, spec: MetricSpec, judge: Judge
) -> list[tuple[str, str, Outcome]]:
    """Each ensemble member's label, factor and its judge's answer: placements first, then hand members.

    The members are independent replays, each on its own data: they run on
    :func:`~handsim.sim.parallel.sim_threads` threads, so ``judge`` must keep its state (``MjData``) to
    itself. They do not depend on the winner's replay, so they may be judged before or beside it.
    """
    members = [(label, "placement", variant, schedule) for label, variant in ensemble_scenes(scene)]
    members += [
        (label, factor, scene, variant) for label, factor, variant in hand_variants(scene, schedule, spec)
    ]
    outcomes = map_runs(lambda member: judge(member[2], member[3]), members)
    return [
        (label, factor, outcome) for (label, factor, _, _), outcome in zip(members, outcomes, strict=True)
    ]


def hold_robustness(
    scene: SimScene,
    schedule: ControlSchedule,
    spec: MetricSpec,
    winner: HoldOutcome,
    judge: Judge,
    outcomes: list[tuple[str, str, Outcome]] | None = None,
) -> HoldRobustness:
    """Judge the hold of every ensemble member and count.

    Args:
        scene: The glove scene (its winner already replayed).
        schedule: The winner's control schedule.
        spec: The metric parameters (the hand members' ranges).
        winner: The winner's hold outcome.
        judge: Replays a member and returns whether it held and why not (None when it has no hold to judge;
            :func:`handsim.sim.replay.member_verdict`); see :func:`member_outcomes`.
        outcomes: The members' answers when already judged (:func:`member_outcomes`); None: judged here.

    Returns:
        The robustness (``fraction`` None when no member was judged).
    """
    members = [EnsembleMember("placement", winner.held, winner.reason)]
    answers = member_outcomes(scene, schedule, spec, judge) if outcomes is None else outcomes
    for label, factor, outcome in answers:
        held, reason = (None, None) if outcome is None else outcome
        members.append(EnsembleMember(label, held, reason, factor))
    judged = [m for m in members if m.held is not None]
    held = sum(bool(m.held) for m in judged)
    return HoldRobustness(
        fraction=held / len(judged) if judged else None,
        held=held,
        judged=len(judged),
        members=tuple(members),
    )
