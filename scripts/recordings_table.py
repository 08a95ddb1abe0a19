"""The verdict table of every real GraspDB14 recording in ``../shared/data/graspdb14``, on both hands.

Runs ``python -m handsim.cli replay FILE --json OUT`` (this tree's handsim) on the three GraspDB14 trials and
the two ``fk_oracle`` motions, with the parametric default hand and with ``--skeleton default.xmlskel``, and
prints the Markdown table of ``docs/replay.md`` ("Measured: every real recording"): the outcome (held / not
held / not judged, with the reason), ``hold_robustness``, the grip directions the placement's grip test
resisted, p95 penetration, MuJoCo warnings, ``fit_fraction``, the grip's normal force and the hand's
self-penetration at closure; then the acceptance rate (judged recordings held with robustness ≥ 0.8).

Usage::

    python scripts/recordings_table.py [--data ../shared/data/graspdb14]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "graspdb14"
RECORDINGS = (
    "r_01_11_ex03-rad-004-grasp-su04.txt",
    "01_ex01-rad-002-grasp-su01.txt",
    "04_ex01-rad-045-grasp-su03.txt",
    "fk_oracle/01_11_ex03-rad-004-grasp-su04.txt",
    "fk_oracle/16_14_ex01-rad-004-grasp-su06",
)
TRIALS = RECORDINGS[:3]
"""The three GraspDB14 trials (the ``fk_oracle`` motions are not GraspDB14 recordings)."""
ROBUST = 0.8
OUTCOMES = {True: "held", False: "not held", None: "not judged"}
"""A replay summary's ``held`` in words."""


def verdict(summary: dict) -> dict:
    """A glove replay summary's verdict: held, reason, robustness, grip directions, fit fraction.

    Args:
        summary: ``ReplayResult.summary`` of a glove replay.
    """
    return {
        "held": summary.get("held"),
        "reason": summary.get("hold_reason"),
        "robustness": summary.get("hold_robustness"),
        "directions": summary.get("grip_directions_held"),
        "fit_fraction": summary.get("fit_fraction"),
    }


def replay_json(data: Path, name: str, skeleton: bool, out: Path) -> dict:
    """``handsim replay`` of one recording as its ``--json`` record."""
    command = [sys.executable, "-m", "handsim.cli", "replay", str(data / name), "--json", str(out)]
    if skeleton:
        command += ["--skeleton", str(data / "default.xmlskel")]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=False)
    if done.returncode not in (0, 4):
        raise RuntimeError(f"{' '.join(command)} exited {done.returncode}: {done.stderr.strip()}")
    return json.loads(out.read_text(encoding="utf-8"))


def _num(value: float | None, fmt: str) -> str:
    return "–" if value is None else format(value, fmt)


def row(name: str, hand: str, record: dict) -> tuple[str, bool | None, float | None]:
    """One table row and the record's held and robustness."""
    s = record["summary"]
    held = s.get("held")
    outcome = f"**{OUTCOMES[held]}**" if held else OUTCOMES[held]
    reason = s.get("hold_reason")
    if reason:
        outcome += f": {reason.removeprefix('not judged: ')}"
    cells = [
        name,
        hand,
        outcome,
        _num(s.get("hold_robustness"), ".2f"),
        _num(s.get("grip_directions_held"), "d") + "/6",
        _num(s.get("p95_penetration_mm"), ".2f"),
        str(s.get("warnings")),
        _num(s.get("fit_fraction"), ".2f"),
        _num(s.get("grip_normal_force_n"), ".1f"),
        _num(s.get("self_penetration_at_closure_mm"), ".2f"),
    ]
    return "| " + " | ".join(cells) + " |", held, s.get("hold_robustness")


def main() -> None:
    """Replay every recording on both hands and print the table and the rate."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA, help="the GraspDB14 folder")
    args = parser.parse_args()
    header = [
        "recording",
        "hand",
        "outcome",
        "hold_robustness",
        "grip directions",
        "p95 pen. mm",
        "warnings",
        "fit_fraction",
        "grip force N",
        "self-pen. mm",
    ]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    rates = {}
    with tempfile.TemporaryDirectory() as folder:
        for hand, skeleton in (("default", False), ("xmlskel", True)):
            judged = robust = 0
            for name in RECORDINGS:
                record = replay_json(args.data, name, skeleton, Path(folder) / "out.json")
                line, held, robustness = row(name, hand, record)
                print(line)
                if held is not None:
                    judged += 1
                    robust += bool(held and robustness is not None and robustness >= ROBUST)
            rates[hand] = (robust, judged)
    print()
    for hand, (robust, judged) in rates.items():
        print(f"- {hand}: {robust} of {judged} judged recordings held with robustness ≥ {ROBUST:g}")


if __name__ == "__main__":
    main()
