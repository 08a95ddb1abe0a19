"""Sensitivity of the glove scenario's verdicts to skin friction, finger-pad stiffness, gains, torsion.

Runs the three shared GraspDB14 trials (``../shared/data/graspdb14``) on both hands (the parametric default
hand and the GraspDB14 ``default.xmlskel``) with the skin's sliding friction μ ∈ {0.5, 0.8, 1.0, 1.2} and
the pad's stiffness scaled ×0.5, ×1, ×2, and prints a Markdown table of ``held`` and ``hold_robustness``
(the table in ``docs/physics.md``); ``--part gains`` scales the servos' ``kp`` ×0.5 and ×2 instead,
``--part torsional`` the skin's torsional friction ×0 and ×2. Each setting replaces
:data:`handsim.builders.surfaces.SKIN` (and ``JOINT_CLASSES``) where the hand builder reads them, for the
whole trial (placement search, grip tests, replay, robustness ensemble), so the verdict is the one a user
would get with that hand. MuJoCo's contact stiffness is ``1 / (dmax² · timeconst² · dampratio²)``
(``docs/physics.md``), so stiffness ×s is the pad's solref time constant ÷ √s. Deterministic: no
randomness; 72 replays for the skin table, a few minutes on one core.

Usage::

    python scripts/physics_sensitivity.py [--data ../shared/data/graspdb14] [--jobs 2]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from recordings_table import DATA, OUTCOMES, TRIALS, verdict

HANDS = ("default", "xmlskel")
FRICTIONS = (0.5, 0.8, 1.0, 1.2)
STIFFNESS = (0.5, 1.0, 2.0)
FACTORS = {"gains": ("kp", (0.5, 2.0)), "torsional": ("torsional friction", (0.0, 2.0))}
"""The one-factor parts: what is scaled, by which factors (×1 is the skin table's μ 1.0, ×1 cell)."""


def run_case(
    data: Path, name: str, hand: str, mu: float, stiffness: float, gain: float = 1.0, torsion: float = 1.0
) -> dict:
    """Replay one trial with the skin's friction, pad stiffness, servo gains and torsional friction set.

    Args:
        data: The GraspDB14 folder.
        name: The trial's file name.
        hand: ``"default"`` (parametric hand) or ``"xmlskel"`` (``default.xmlskel``).
        mu: Skin sliding friction.
        stiffness: Factor on the pad's contact stiffness.
        gain: Factor on every position servo's stiffness ``kp`` (force ranges unchanged).
        torsion: Factor on the skin's torsional friction.

    Returns:
        The case and its ``held``, ``hold_reason``, ``hold_robustness``, ``grip_directions_held``.
    """
    import handsim.builders.hand as hand_builder
    from handsim.builders.surfaces import SKIN
    from handsim.sim.replay import replay
    from handsim.trials import load_trial

    timeconst, ratio = SKIN.solref
    classes = hand_builder.JOINT_CLASSES
    hand_builder.SKIN = dataclasses.replace(
        SKIN,
        sliding=mu,
        torsional=SKIN.torsional * torsion,
        solref=(timeconst / math.sqrt(stiffness), ratio),
    )
    hand_builder.JOINT_CLASSES = {k: dataclasses.replace(c, kp=c.kp * gain) for k, c in classes.items()}
    try:
        skeleton = str(data / "default.xmlskel") if hand == "xmlskel" else None
        loaded = load_trial(data / name, skeleton=skeleton)
        summary = replay(loaded.scene, loaded.trajectory).summary
    finally:
        hand_builder.SKIN = SKIN
        hand_builder.JOINT_CLASSES = classes
    return {
        "trial": name,
        "hand": hand,
        "mu": mu,
        "stiffness": stiffness,
        "gain": gain,
        "torsion": torsion,
        **verdict(summary),
    }


def _cell(case: dict) -> str:
    held = OUTCOMES[case["held"]]
    robustness = case["robustness"]
    return held if robustness is None else f"{held} {robustness:.2f}"


def main() -> None:
    """Run every case and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA, help="the GraspDB14 folder")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes")
    parser.add_argument(
        "--part",
        choices=("skin", *FACTORS),
        default="skin",
        help="skin friction × pad stiffness, or one factor alone (servo gains, torsional friction)",
    )
    args = parser.parse_args()
    if args.part in FACTORS:
        gains = args.part == "gains"
        cases = [
            (args.data, n, h, 1.0, 1.0, f if gains else 1.0, 1.0 if gains else f)
            for n in TRIALS
            for h in HANDS
            for f in FACTORS[args.part][1]
        ]
    else:
        cases = [
            (args.data, n, h, mu, k, 1.0, 1.0)
            for n in TRIALS
            for h in HANDS
            for mu in FRICTIONS
            for k in STIFFNESS
        ]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(run_case, *zip(*cases, strict=True)))
    if args.part in FACTORS:
        label, factors = FACTORS[args.part]
        key = "gain" if args.part == "gains" else "torsion"
        print("| trial | hand | " + " | ".join(f"{label} ×{f:g}" for f in factors) + " |")
        print("|---|---|" + "---|" * len(factors))
        by_factor = {(r["trial"], r["hand"], r[key]): r for r in results}
        for name in TRIALS:
            for hand in HANDS:
                cells = [_cell(by_factor[(name, hand, f)]) for f in factors]
                print(f"| {name[:14]}… | {hand} | " + " | ".join(cells) + " |")
        return
    by_key = {(r["trial"], r["hand"], r["mu"], r["stiffness"]): r for r in results}
    header = ["trial", "hand", "pad stiffness"] + [f"μ {mu:g}" for mu in FRICTIONS]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for name in TRIALS:
        for hand in HANDS:
            for k in STIFFNESS:
                cells = [_cell(by_key[(name, hand, mu, k)]) for mu in FRICTIONS]
                print(f"| {name[:14]}… | {hand} | ×{k:g} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
