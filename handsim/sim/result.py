"""What a replay returns: :class:`ReplayResult`, its typed summary, and the summary's judged sections.

The per-frame sections of the summary are built in :mod:`handsim.sim.summary`; the glove hold's and the
stability tests' are built here from their typed outcomes (:func:`hold_section`, :func:`stability_numbers`),
so that :class:`~handsim.sim.sections.ReplaySummary` holds every number once and writes the record's
``summary`` in one place.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from handsim.datatypes.flags import Flag
from handsim.datatypes.trajectory import Trajectory
from handsim.sim.drive import ScenarioSwitches
from handsim.sim.grip_check import GripCheck
from handsim.sim.metrics import FrameMetrics
from handsim.sim.placement.robustness import HoldRobustness
from handsim.sim.scene.compiled import SimScene
from handsim.sim.sections import (
    Closure,
    GripNumbers,
    HoldNumbers,
    HoldSection,
    ReplaySummary,
    Robustness,
    StabilityNumbers,
)
from handsim.sim.stability.gravity import StabilityResult
from handsim.sim.stepper import WarningEvent
from handsim.sim.summary import HoldOutcome


@dataclass(frozen=True)
class ReplayResult:
    """What a replay measured.

    Attributes:
        frames: Per-frame metrics of the frames simulated.
        measured: The per-trial numbers by section (typed); ``summary`` is their record dict.
        warnings: MuJoCo warnings with the step they happened at.
        diverged: The divergence that stopped the run, or None.
        hold: Glove scenario: the hold outcome, else None.
        robustness: Glove scenario with ``config.ensemble``: the hold over the robustness ensemble, else None.
        release_stability: Glove scenario with ``config.ensemble``: the stability tests on the state at the
            release (six gravity directions: the verdict does not rest on one), else None.
        stability: The grasp stability tests (``config.stability_at``), else None.
        states: qpos per frame when ``config.keep_states``, else None.
        frame_dt: Seconds per control frame.
        substeps: Steps per control frame.
        steps: MuJoCo steps simulated.
        config: The configuration (JSON-ready).
        scene: Scene facts (model hash, scenario, setup notes) (JSON-ready).
        trajectory: Source file and SHA-256 of the trajectory.
        notes: Decisions made while replaying.
        flags: Plausibility flags (:func:`~handsim.sim.plausibility.replay_flags`); ``summary["valid"]`` is
            false when one of them makes the replay invalid.
        grip: Glove scenario with a judged hold: what the grip looked like over the hold window (its links,
            opposition, deepest link, force against the servos' bound), else None.
        summary: Per-trial numbers (JSON-ready): ``measured.to_dict()``, made once with the result.
    """

    frames: FrameMetrics
    measured: ReplaySummary
    warnings: tuple[WarningEvent, ...]
    diverged: WarningEvent | None
    hold: HoldOutcome | None
    robustness: HoldRobustness | None
    release_stability: StabilityResult | None
    stability: StabilityResult | None
    states: np.ndarray | None
    frame_dt: float
    substeps: int
    steps: int
    config: dict
    scene: dict
    trajectory: dict
    notes: tuple[str, ...]
    flags: tuple[Flag, ...] = ()
    grip: GripCheck | None = None
    summary: dict = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "summary", self.measured.to_dict())

    def to_dict(self) -> dict:
        """JSON-ready result without per-frame arrays (those are in ``frames``)."""
        return {
            "summary": self.summary,
            "diverged": None if self.diverged is None else asdict(self.diverged),
            "warnings": [asdict(w) for w in self.warnings],
            "hold": None if self.hold is None else self.hold.to_dict(),
            "grip": None if self.grip is None else self.grip.to_dict(),
            "robustness": None if self.robustness is None else self.robustness.to_dict(),
            "release_stability": None if self.release_stability is None else self.release_stability.to_dict(),
            "stability": None if self.stability is None else self.stability.to_dict(),
            "frame_dt": self.frame_dt,
            "substeps": self.substeps,
            "steps": self.steps,
            "config": self.config,
            "scene": self.scene,
            "trajectory": self.trajectory,
            "notes": list(self.notes),
            "flags": [f.to_dict() for f in self.flags],
        }


def hold_section(
    hold: HoldOutcome | None,
    grip: GripCheck | None,
    placement: dict,
    robustness: HoldRobustness | None,
    release_stability: StabilityResult | None,
) -> HoldSection | None:
    """The glove scenario's hold section: outcome, grip, placement quality, robustness, release test.

    Args:
        hold: The hold outcome (None where the replay judges no hold: then no section).
        grip: The grip over the hold window (None when no hold was judged).
        placement: The scene's placement facts (``scene.setup.placement``).
        robustness: The hold over the robustness ensemble (None when not run).
        release_stability: The stability tests on the state at the release (None when not run).
    """
    if hold is None:
        return None
    return HoldSection(
        hold=HoldNumbers(
            held=hold.held,
            hold_reason=hold.reason,
            time_held_s=hold.time_held,
            max_slip_mm=hold.max_slip * 1000.0,
            drop_mm=hold.drop * 1000.0,
        ),
        grip=grip_numbers(grip),
        closure=closure(placement),
        robustness=Robustness(
            hold_robustness=None if robustness is None else robustness.fraction,
            hold_robustness_factors=None if robustness is None else robustness.factors(),
            release_directions_held=None
            if release_stability is None
            else sum(d.success for d in release_stability.directions),
        ),
    )


def grip_numbers(grip: GripCheck | None) -> GripNumbers:
    """The grip's numbers in a replay summary (each None when no hold was judged)."""
    if grip is None:
        return GripNumbers()
    return GripNumbers(
        grip_links=tuple(grip.links),
        grip_opposition=grip.opposition,
        grip_opposing_links=None if grip.opposing_links is None else tuple(grip.opposing_links),
        deepest_link=grip.deepest_link,
        deepest_link_mm=grip.max_depth * 1000.0,
        grip_force_n=grip.grip_force,
        grip_force_limit_n=grip.force_limit,
    )


def closure(placement: dict) -> Closure:
    """A glove placement's recording-quality numbers for the summary.

    How far the recorded closing passes the object (the flexion fraction at which it fits), the grip it then
    makes, and the hand through itself at the closed frame.
    """
    grip = placement.get("grip") or {}
    self_penetration = placement.get("self_penetration_at_closure") or {}
    depth = self_penetration.get("depth_m")
    return Closure(
        fit_fraction=placement.get("fit_fraction"),
        grip_normal_force_n=grip.get("normal_force_n"),
        grip_servo_torque_nm=grip.get("servo_torque_nm"),
        grip_directions_held=grip.get("directions_held"),
        self_penetration_at_closure_mm=None if depth is None else depth * 1000.0,
    )


def stability_numbers(stability: StabilityResult | None) -> StabilityNumbers | None:
    """The stability tests' verdict and displacement for the summary (None when none ran)."""
    if stability is None:
        return None
    displacement = stability.simulation_displacement
    return StabilityNumbers(
        stable=stability.success,
        simulation_displacement_mm=None if displacement is None else displacement * 1000.0,
    )


def scene_facts(scene: SimScene, switches: ScenarioSwitches) -> dict:
    """The scene's facts in a result (JSON-ready): model hash, scenario, names, placement, switches, notes."""
    setup = scene.setup
    return {
        "model_sha256": scene.model_sha256,
        "scenario": setup.scenario,
        "links": list(scene.layout.link_names),
        "parts": list(scene.layout.part_labels),
        "tips": list(scene.layout.tip_names),
        "placement": setup.placement,
        "contact_frame": switches.contact_frame,
        "release_frame": switches.release_frame,
        "notes": list(setup.notes),
    }


def trajectory_facts(trajectory: Trajectory) -> dict:
    """The trajectory's source, SHA-256 and sample count in a result (JSON-ready)."""
    return {
        "source": trajectory.source,
        "sha256": trajectory.sha256,
        "frames": int(trajectory.times.shape[0]),
    }
