"""The scripted-grasp sweep: first-contact level × closure, the hold and its robustness per cell.

For each bundled demo grasp (``handsim/assets/demo``: cube, 25 mm cylinder, tennis ball) the first-contact
level (:data:`handsim.io.scripted.CONTACT_LEVEL`, where the ``grasp`` phase starts and the glove scenario
places the object: 0.7, 0.8, 0.9, 1.0 of the closing ramp) is crossed with the file's closure and ±0.1
(capped at 1), and each cell is replayed as ``handsim replay`` would (placement search, replay, robustness
ensemble). Prints a Markdown table per object: ``held``/``not held``/``not judged``, ``hold_robustness``,
the grip directions the placement's grip test resisted, and the flexion fraction where the object fits
(the table in ``docs/stability.md``). Deterministic: no randomness.

Usage::

    python scripts/scripted_sweep.py [--jobs 2]
"""

from __future__ import annotations

import argparse
import json
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from recordings_table import OUTCOMES, verdict

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "handsim" / "assets" / "demo"
GRASPS = ("cube.grasp.json", "cylinder_25mm.grasp.json", "tennis_ball.grasp.json")
LEVELS = (0.7, 0.8, 0.9, 1.0)
CLOSURE_STEPS = (-0.1, 0.0, 0.1)


def run_cell(grasp: str, level: float, closure: float) -> dict:
    """Replay one demo grasp with its first-contact level and closure set; its verdict.

    Args:
        grasp: The demo file's name.
        level: First-contact level (fraction of the closing ramp).
        closure: The closure written into a copy of the file.

    Returns:
        The cell and its ``held``, ``reason``, ``robustness``, ``directions``, ``fit_fraction``.
    """
    import handsim.io.scripted as scripted
    from handsim.sim.replay import replay
    from handsim.trials import load_trial

    fields = json.loads((DEMO / grasp).read_text(encoding="utf-8"))
    fields["closure"] = closure
    default_level = scripted.CONTACT_LEVEL
    scripted.CONTACT_LEVEL = level
    try:
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / grasp
            path.write_text(json.dumps(fields), encoding="utf-8")
            loaded = load_trial(path)
            summary = replay(loaded.scene, loaded.trajectory).summary
    finally:
        scripted.CONTACT_LEVEL = default_level
    return {
        "grasp": grasp,
        "level": level,
        "closure": closure,
        **verdict(summary),
    }


def _cell(result: dict) -> str:
    held = OUTCOMES[result["held"]]
    robustness = "–" if result["robustness"] is None else f"{result['robustness']:.2f}"
    fit = "–" if result["fit_fraction"] is None else f"{result['fit_fraction']:.2f}"
    return f"{held} {robustness} ({result['directions']}/6, fit {fit})"


def main() -> None:
    """Run every cell and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=1, help="worker processes")
    args = parser.parse_args()
    cells = []
    for grasp in GRASPS:
        base = json.loads((DEMO / grasp).read_text(encoding="utf-8"))["closure"]
        closures = sorted({round(min(1.0, base + step), 3) for step in CLOSURE_STEPS})
        cells.extend((grasp, level, closure) for level in LEVELS for closure in closures)
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(run_cell, *zip(*cells, strict=True)))
    for grasp in GRASPS:
        rows = [r for r in results if r["grasp"] == grasp]
        closures = sorted({r["closure"] for r in rows})
        print(f"\n{grasp}: held/not held, hold_robustness (grip directions held, flexion fraction at fit)\n")
        print("| first contact | " + " | ".join(f"closure {c:g}" for c in closures) + " |")
        print("|---|" + "---|" * len(closures))
        for level in LEVELS:
            by_closure = {r["closure"]: r for r in rows if r["level"] == level}
            print(f"| {level:g} | " + " | ".join(_cell(by_closure[c]) for c in closures) + " |")
        for r in rows:
            if r["reason"]:
                print(f"- level {r['level']:g}, closure {r['closure']:g}: {r['reason']}")


if __name__ == "__main__":
    main()
