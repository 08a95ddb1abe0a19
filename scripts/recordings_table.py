"""The verdict table of every grasp episode of the real GraspDB14 recordings in ``../shared/data/graspdb14``.

Finds each recording's grasp episodes (``handsim.trials.registry.grasp_episodes``), replays every complete
one as ``handsim replay FILE --grasp K`` does (this tree's handsim, in-process), with the parametric default
hand and with ``--skeleton default.xmlskel``, and prints the Markdown table of ``docs/replay.md``
("Measured: every grasp episode"): the outcome (held / not held / not judged, with the reason),
``hold_robustness`` with its factors (placement, thumb, undriven DoFs, sensors), the grip's opposing pair
and share of the window, the deepest link, the grip force against the servos' bound, the placement's grip
directions and ``fit_fraction``; then the rates: complete episodes judged, and held with robustness ≥ 0.8.

Usage::

    python scripts/recordings_table.py [--data ../shared/data/graspdb14] [--hands default,xmlskel]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from handsim.sim.replay import ReplayConfig, replay
from handsim.trials.registry import find_trial, grasp_episodes, load_trial

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "graspdb14"
RECORDINGS = (
    "r_01_11_ex03-rad-004-grasp-su04.txt",
    "01_ex01-rad-002-grasp-su01.txt",
    "04_ex01-rad-045-grasp-su03.txt",
    "fk_oracle/01_11_ex03-rad-004-grasp-su04.txt",
    "fk_oracle/16_14_ex01-rad-004-grasp-su06",
    "sessions/01_11_ex03-rad-004-grasp-su04.txt",
)
ROBUST = 0.8
OUTCOMES = {True: "held", False: "not held", None: "not judged"}
"""A replay summary's ``held`` in words."""
HEADER = (
    "recording",
    "ep.",
    "hand",
    "outcome",
    "robustness (placement / thumb / undriven / sensor)",
    "grip",
    "deepest mm",
    "grip force N (bound)",
    "grip dirs",
    "fit",
)


def _num(value: float | None, fmt: str) -> str:
    return "–" if value is None else format(value, fmt)


def _factors(summary: dict) -> str:
    factors = summary.get("hold_robustness_factors") or {}
    parts = [f"{f['held']}/{f['judged']}" for f in factors.values()]
    return f"{_num(summary.get('hold_robustness'), '.2f')} ({' / '.join(parts) or '–'})"


def row(name: str, episode: int, hand: str, summary: dict) -> str:
    """One table row of an episode's replay summary."""
    held = summary.get("held")
    outcome = f"**{OUTCOMES[held]}**" if held else OUTCOMES[held]
    reason = summary.get("hold_reason")
    if reason:
        outcome += f": {reason.removeprefix('not judged: ')}"
    pair = summary.get("grip_opposing_links")
    grip = "–"
    if summary.get("grip_opposition") is not None:
        grip = f"{' vs '.join(pair) if pair else 'none'}, {summary['grip_opposition']:.0%}"
    cells = [
        name,
        str(episode),
        hand,
        outcome,
        _factors(summary),
        grip,
        f"{summary.get('deepest_link') or '–'} {_num(summary.get('deepest_link_mm'), '.1f')}",
        f"{_num(summary.get('grip_force_n'), '.1f')} ({_num(summary.get('grip_force_limit_n'), '.0f')})",
        _num(summary.get("grip_directions_held"), "d") + "/6",
        _num(summary.get("fit_fraction"), ".2f"),
    ]
    return "| " + " | ".join(cells) + " |"


def main() -> None:
    """Replay every complete episode on each hand; print the table and the rates."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA, help="the GraspDB14 folder")
    parser.add_argument("--hands", default="default,xmlskel", help="default and/or xmlskel, comma-separated")
    args = parser.parse_args()
    print("| " + " | ".join(HEADER) + " |")
    print("|" + "---|" * len(HEADER))
    rates = {}
    for hand in args.hands.split(","):
        skeleton = args.data / "default.xmlskel" if hand == "xmlskel" else None
        complete = judged = robust = 0
        for name in RECORDINGS:
            path = args.data / name
            segmentation = grasp_episodes(find_trial(path, skeleton=skeleton))
            for episode in segmentation.complete:
                complete += 1
                loaded = load_trial(path, skeleton=skeleton, grasp=episode.index)
                summary = replay(loaded.scene, loaded.trajectory, ReplayConfig()).summary
                print(row(name, episode.index, hand, summary), flush=True)
                if summary.get("held") is not None:
                    judged += 1
                    robust += bool(summary["held"] and (summary.get("hold_robustness") or 0.0) >= ROBUST)
        rates[hand] = (complete, judged, robust)
    print()
    for hand, (complete, judged, robust) in rates.items():
        print(
            f"- {hand}: {complete} complete episodes, {judged} judged, {robust} held with robustness "
            f"≥ {ROBUST:g}" + (f" ({robust / judged:.0%} of the judged)" if judged else "")
        )


if __name__ == "__main__":
    main()
