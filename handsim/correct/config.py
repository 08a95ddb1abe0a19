"""What a correction optimises and how hard it searches: :class:`CorrectionConfig`, each parameter's reason.

The numbers are scales of the quantities the correction is judged by (docs/correct.md): the object's drift is
judged in centimetres (the replay's 1 cm "on track" tolerance), a finger correction against pure replay's
joint tracking error (≈ 10 mrad RMS on the bundled Tzionas sequence 20), a wrist correction in millimetres
and degrees. The search's sizes (samples, iterations, horizon) are budgets: the presets of
:data:`BUDGETS` trade time for a better optimum; nothing in the result depends on the machine's threads.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from handsim.errors import HandsimError

CORRECTION_METHOD = "annealed-mppi-receding-horizon"
"""The method's name in a corrected file's provenance (:mod:`handsim.correct.sampler`)."""

CORRECTION_CONFIG_VERSION = "2"
"""Bumped whenever a parameter's meaning or a default changes (written into every corrected file)."""


class CorrectionError(HandsimError):
    """A trial cannot be corrected as asked (no recorded object to follow, a parameter out of range …)."""


@dataclass(frozen=True)
class Budget:
    """How many rollouts one planning step spends: ``samples`` candidates in each of ``iterations`` rounds.

    Attributes:
        samples: Candidate residual sequences per round (the noise-free mean among them).
        iterations: Rounds per planning step, the noise annealed from one to the next.
    """

    samples: int
    iterations: int


BUDGETS: dict[str, Budget] = {
    "quick": Budget(samples=12, iterations=2),
    "standard": Budget(samples=24, iterations=3),
    "thorough": Budget(samples=48, iterations=4),
}
"""Named search budgets (``handsim correct --budget``): rollouts per planning step before any rescue pass,
``quick`` a third of ``standard``'s, ``thorough`` 2.7 times. ``standard`` corrected the bundled Tzionas
sequence 20 in 26–42 s per recorded second on 2 shared cores, depending on the other work there
(docs/correct.md, "Speed")."""


_POSITIVE = (
    "control_rate", "finger_noise", "wrist_position_noise", "wrist_rotation_noise", "temperature",
    "finger_bound", "wrist_position_bound", "wrist_rotation_bound", "position_scale", "rotation_scale",
    "articulation_scale", "finger_scale", "wrist_position_scale", "wrist_rotation_scale", "opposition_force",
)  # fmt: skip
_WEIGHTS = (
    "rotation_weight",
    "articulation_weight",
    "finger_weight",
    "wrist_weight",
    "guidance",
    "opposition_weight",
)
_CHECKS = (
    (_POSITIVE, lambda v: v > 0, "be a positive number"),
    (("anneal", "near_noise"), lambda v: 0 < v <= 1, "lie in (0, 1]"),
    (_WEIGHTS, lambda v: v >= 0, "be a number ≥ 0"),
)
"""The number parameters' checks: (names, test, what the message says they must do)."""


@dataclass(frozen=True)
class CorrectionConfig:
    """Parameters of a correction (defaults: docs/correct.md, "Parameters").

    Attributes:
        control_rate: Control frames per second, Hz: the replay's own default (100 Hz), so that
            ``handsim replay`` of the corrected file at its default rate is the committed simulation.
        samples: Candidates per round (:data:`BUDGETS`).
        iterations: Rounds per planning step (:data:`BUDGETS`).
        horizon: Frames each candidate looks ahead (0.5 s at 100 Hz): a slip of the bundled cube develops
            over ~20 frames (docs/rl.md: 25 mm over recorded frames 139–145) and the plan must see it coming;
            on sequence 20 a 30-frame horizon lost the cube 0.34 s earlier at otherwise equal settings
            (docs/correct.md, "Results").
        knot: Frames between the knots of a residual sequence (50 ms), linearly interpolated between: about
            the recordings' own sample period (Tzionas 33 ms, GraspDB14 16 ms, ARCTIC 33 ms), so the
            correction adds no motion faster than the recording has.
        commit: Frames applied after each planning step (one knot) before planning again from the new
            state: the receding horizon.
        finger_noise: Standard deviation of the first round's finger knot perturbations, rad (≈ 2.9°):
            between pure replay's joint tracking error (≈ 10 mrad) and the finger bound's quarter.
        wrist_position_noise: The same for the wrist's position residual, m (5 mm: a quarter of its bound).
        wrist_rotation_noise: The same for the wrist's rotation residual (a rotation vector), rad (2.9°, a
            third of its bound).
        anneal: Factor on the noise from one round to the next (DIAL-MPC's and SPIDER's annealing: wide
            exploration first, local refinement after); 0.5 halves it.
        rescue: Extra passes of ``iterations`` rounds, the noise annealed again from its full scale, while the
            best plan lets an object leave its track (by more than ``position_scale``) that is on it now
            (:mod:`handsim.correct.sampler`): effort where a loss may still be prevented.
        near_noise: The noise on the plan's first free knot relative to its last (rising linearly along
            the horizon, as DIAL-MPC's horizon annealing): near knots were refined by the previous planning
            steps already, far ones were not.
        temperature: MPPI temperature relative to the round's cost spread (the median minus the best cost):
            0.1 gives the best candidates nearly all the weight while still averaging near-ties.
        finger_bound: Largest finger correction per joint, rad (0.2 rad ≈ 11.5°; docs/rl.md found 0.1 rad
            enough to keep the cube through its slip and 0.2 rad needed for its last frames).
        wrist_position_bound: Largest wrist position correction, m (2 cm: twice the acceptance's RMS).
        wrist_rotation_bound: Largest wrist rotation correction, rad (10°: twice the acceptance's RMS).
        position_scale: Object position error at which the position term costs 1, m (the 1 cm "on track"
            tolerance of :class:`~handsim.sim.specs.MetricSpec`).
        rotation_scale: Object rotation error at which the rotation term costs ``rotation_weight``, rad
            (0.2 rad, the Replay-v0 reward's scale: pure replay sits at a median 0.12 rad on sequence 20).
        rotation_weight: Weight of the rotation term (0.5: position first, as the acceptance).
        articulation_scale: Articulated objects' angle error at which its term costs
            ``articulation_weight``, rad (≈ 6°, the Replay-v0 reward's scale).
        articulation_weight: Weight of the articulation term.
        finger_scale: Mean squared finger correction at which the finger term costs ``finger_weight``, rad
            (20 mrad: 2× pure replay's joint tracking RMS on sequence 20, the acceptance's bound).
        finger_weight: Weight of the finger term (0.05). On sequence 20 a weight of 0.25 kept the correction
            within pure replay's joint tracking error but the cube within 1 cm in 81 % of frames; 0.05 gave
            83–91 % for 1.5–3× that error (docs/correct.md, "Results"): the object first, the size reported.
        wrist_position_scale: Wrist position correction at which its term costs ``wrist_weight``, m (the
            acceptance's 10 mm RMS).
        wrist_rotation_scale: Wrist rotation correction at which its term costs ``wrist_weight``, rad (the
            acceptance's 5° RMS).
        wrist_weight: Weight of each wrist term (0.01): the wrist is the lever the acceptance allows most
            of (10 mm, 5° RMS); on sequence 20 it then moved 2.7–4.3 mm and 1.2–3.1° RMS, within those.
        guidance: Contact guidance's gain in the first planning round (SPIDER's virtual contact guidance,
            :mod:`handsim.correct.guidance`): the share of the force that carries each free object along its
            goal (its weight, its recorded acceleration and a pull back from where it starts) applied to it
            in the guided rounds' rollouts; 0 turns guidance off. Annealed to exactly zero by
            ``guidance_rounds``; the plan committed is chosen among unguided rollouts only, so no virtual
            force is in the result. Off by default: at 1 it helped the synthetic two-hand carry (smaller
            drift and correction in both seeds measured) but not Tzionas sequence 20 (three seeds: within
            1 cm 76.6 % against 78.3 % on average; docs/correct.md, "Contact guidance").
        guidance_rounds: Rounds of a planning pass that apply guidance, its gain falling linearly from
            ``guidance`` in the first to zero (SPIDER removes its virtual contact by the last iterations);
            the rounds after are unguided, and at least the last always is: at most ``iterations − 1``
            rounds are guided (SPIDER's own cap), none with a single round.
        opposition_weight: Weight of a glove hold's opposition term (:mod:`handsim.correct.grip`): per frame
            of the hold, 1 where no opposing pair of the hand's sides (thumb and fingers, or fingers and
            palm) presses on the object, falling to 0 as the weaker side's push reaches ``opposition_force``
            of the object's weight: the grip the replay's grip check asks for. 1: a frame without
            opposition costs what 1 cm of slip does.
        opposition_force: The weaker opposing side's push on the object, as a share of its weight, at which
            the opposition term vanishes (0.5: a clear contact on both sides, not a graze).
        wrist: Correct the wrist (its mocap target) where a root pose is recorded; False: fingers only.
        seed: Seed of the perturbations (a NumPy ``Generator``).
    """

    control_rate: float = 100.0
    samples: int = BUDGETS["standard"].samples
    iterations: int = BUDGETS["standard"].iterations
    horizon: int = 50
    knot: int = 5
    commit: int = 5
    finger_noise: float = 0.05
    wrist_position_noise: float = 0.005
    wrist_rotation_noise: float = 0.05
    anneal: float = 0.5
    near_noise: float = 0.5
    rescue: int = 2
    temperature: float = 0.1
    finger_bound: float = 0.2
    wrist_position_bound: float = 0.02
    wrist_rotation_bound: float = math.radians(10.0)
    position_scale: float = 0.01
    rotation_scale: float = 0.2
    rotation_weight: float = 0.5
    articulation_scale: float = 0.1
    articulation_weight: float = 0.5
    finger_scale: float = 0.02
    finger_weight: float = 0.05
    wrist_position_scale: float = 0.01
    wrist_rotation_scale: float = math.radians(5.0)
    wrist_weight: float = 0.01
    guidance: float = 0.0
    guidance_rounds: int = 1
    opposition_weight: float = 1.0
    opposition_force: float = 0.5
    wrist: bool = True
    seed: int = 0

    def __post_init__(self) -> None:
        counts = {
            "samples": 3,
            "iterations": 1,
            "horizon": 1,
            "knot": 1,
            "commit": 1,
            "rescue": 0,
            "seed": 0,
            "guidance_rounds": 0,
        }
        for name, least in counts.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise CorrectionError(f"{name} must be an integer ≥ {least}, got {value!r}")
        if self.commit > self.horizon:
            raise CorrectionError(
                f"commit ({self.commit} frames) must not exceed the horizon ({self.horizon} frames)"
            )
        for names, ok, what in _CHECKS:
            for name in names:
                value = getattr(self, name)
                number = (
                    isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
                )
                if not (number and ok(value)):
                    raise CorrectionError(f"{name} must {what}, got {value!r}")

    def to_dict(self) -> dict:
        """JSON-ready parameters, with the method and the parameters' version."""
        return {"method": CORRECTION_METHOD, "version": CORRECTION_CONFIG_VERSION, **asdict(self)}
