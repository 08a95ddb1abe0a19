"""Evaluate the gap-filling methods on real GraspDB14 CyberGlove trials.

On every ``*-rad-*.txt`` trial of ``--data``, runs of known samples are hidden — one gap in one DoF at a
time, lengths 5, 10, 20 and 40 frames as in the thesis' experiment (§4.2.2) — filled by every method of
:mod:`handsim.glove.gaps`, and compared with the hidden values. Gap positions are drawn with
``numpy.random.default_rng(seed)`` (deterministic) among the positions where the hidden stretch moves by at
least ``--min-motion`` degrees (in a static stretch every method is exact), with at least 3 samples before
(the trend methods look back 3 frames) and 1 after (linear interpolates to it).

Trials are read with the GraspDB14 skeleton for the DoF structure but only the glove-driven columns are
kept, so DoFs the glove does not drive (held at 0) never act as references. The DIP columns are not
measured: the 18-sensor glove's software computes them from the finger's other joints; they are reported
in their own group, labelled as computed.

Prints Markdown tables (RMS / max error in degrees per method × gap length, one table per joint group) to
stdout; ``--json`` also writes the numbers.

    python scripts/evaluate_gap_filling.py --seed 0 --json gaps.json
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from handsim.glove.gaps import GAP_METHODS, fill_gaps
from handsim.glove.sensors import computed_dofs
from handsim.io import read_skeleton, read_trajectory

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT.parent / "shared" / "data" / "graspdb14"
FINGERS = ("if", "mf", "rf", "lf")
GROUPS: dict[str, tuple[str, ...]] = {
    "PIP flexion (measured)": tuple(f"{f}_pip_flex" for f in FINGERS),
    "DIP flexion (computed by the glove software, not measured)": computed_dofs(),
    "MCP flexion (measured)": tuple(f"{f}_mcp_flex" for f in FINGERS),
    "thumb MCP and IP flexion (measured)": ("th_mcp_flex", "th_ip_flex"),
    "abduction (measured)": ("th_mcp_abd", "if_mcp_abd", "rf_mcp_abd", "lf_mcp_abd"),
}
LENGTHS = (5, 10, 20, 40)


def trials(data: Path) -> list[Path]:
    return sorted(p for p in data.glob("*-rad-*.txt") if "_annot" not in p.name)


def evaluate(data: Path, seed: int, gaps_per_case: int, lengths: tuple[int, ...], min_motion: float) -> dict:
    skeleton = read_skeleton(data / "default.xmlskel")
    rng = np.random.default_rng(seed)
    # (group, method, length) -> squared errors and max
    sq: dict[tuple[str, str, int], list[float]] = {}
    peak: dict[tuple[str, str, int], float] = {}
    ngaps: dict[tuple[str, int], int] = {}
    changed: dict[tuple[str, str], int] = {}  # gaps where a method's fill differs from previous_difference
    files = trials(data)
    if not files:
        raise SystemExit(f"no GraspDB14 '*-rad-*.txt' trials in {data}")
    for path in files:
        traj = read_trajectory(path)  # glove-driven columns only
        n = traj.nframes
        for group, columns in GROUPS.items():
            for name in columns:
                c = traj.dof_names.index(name)
                truth = traj.targets[:, c]
                for length in lengths:
                    starts = np.arange(3, n - length)  # 3 samples before, >= 1 after
                    moving = [s for s in starts if np.degrees(np.ptp(truth[s : s + length])) >= min_motion]
                    if not moving:
                        continue
                    chosen = rng.choice(moving, size=min(gaps_per_case, len(moving)), replace=False)
                    for s in sorted(int(v) for v in chosen):
                        valid = traj.valid.copy()
                        valid[s : s + length, c] = False
                        hidden = replace(traj, valid=valid, notes=())
                        ngaps[group, length] = ngaps.get((group, length), 0) + 1
                        fills = {
                            m: fill_gaps(hidden, m, skeleton).targets[s : s + length, c] for m in GAP_METHODS
                        }
                        for method, filled in fills.items():
                            err = np.degrees(filled - truth[s : s + length])
                            if not np.array_equal(filled, fills["previous_difference"]):
                                changed[group, method] = changed.get((group, method), 0) + 1
                            key = (group, method, length)
                            sq.setdefault(key, []).extend((err**2).tolist())
                            peak[key] = max(peak.get(key, 0.0), float(np.abs(err).max()))
    rows = []
    for (group, method, length), errs in sq.items():
        rows.append(
            {
                "group": group,
                "method": method,
                "gap_frames": length,
                "gaps": ngaps[group, length],
                "samples": len(errs),
                "rms_deg": float(np.sqrt(np.mean(errs))),
                "max_deg": peak[group, method, length],
            }
        )
    differs = [
        {
            "group": g,
            "method": m,
            "gaps": changed.get((g, m), 0),
            "of": sum(ngaps.get((g, n), 0) for n in lengths),
        }
        for g in GROUPS
        for m in ("interfinger_trend", "intrafinger_trend")
    ]
    return {
        "data": str(data),
        "trials": [p.name for p in files],
        "seed": seed,
        "gaps_per_case": gaps_per_case,
        "min_motion_deg": min_motion,
        "lengths": list(lengths),
        "results": rows,
        "trend_differs_from_previous_difference": differs,
    }


def markdown(result: dict) -> str:
    lengths = result["lengths"]
    by_key = {(r["group"], r["method"], r["gap_frames"]): r for r in result["results"]}
    lines = [
        f"Trials: {', '.join(result['trials'])}; seed {result['seed']}; up to {result['gaps_per_case']} gaps "
        f"per DoF, trial and length, placed where the joint moves >= {result['min_motion_deg']} deg.",
        "",
    ]
    for group in GROUPS:
        counts = [
            next((r["gaps"] for k, r in by_key.items() if k[0] == group and k[2] == n), 0) for n in lengths
        ]
        lines += [
            f"### {group}",
            "",
            "RMS / max error (deg); gaps per length: "
            + ", ".join(f"{n}: {c}" for n, c in zip(lengths, counts, strict=True)),
            "",
            "| method | " + " | ".join(f"{n} frames" for n in lengths) + " |",
            "|---|" + "---|" * len(lengths),
        ]
        for method in GAP_METHODS:
            cells = []
            for n in lengths:
                r = by_key.get((group, method, n))
                cells.append("–" if r is None else f"{r['rms_deg']:.1f} / {r['max_deg']:.1f}")
            lines.append(f"| {method} | " + " | ".join(cells) + " |")
        turned = [d for d in result["trend_differs_from_previous_difference"] if d["group"] == group]
        lines += [
            "",
            "Gaps where a trend method's fill differs from previous_difference (a turn of the reference was "
            "detected): " + ", ".join(f"{d['method']} {d['gaps']} of {d['of']}" for d in turned),
            "",
        ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data", type=Path, default=DEFAULT_DATA, help="GraspDB14 folder (default ../shared/data/graspdb14)"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the gap positions (default 0)")
    parser.add_argument("--gaps", type=int, default=20, help="gaps per DoF, trial and length (default 20)")
    parser.add_argument(
        "--lengths",
        type=int,
        nargs="+",
        default=list(LENGTHS),
        help="gap lengths in frames (default 5 10 20 40)",
    )
    parser.add_argument(
        "--min-motion", type=float, default=1.0, help="least range (deg) of the hidden values (default 1)"
    )
    parser.add_argument("--json", type=Path, help="also write the results as JSON to this file")
    args = parser.parse_args(argv)
    if not args.data.is_dir():
        print(f"error: {args.data} is not a folder", file=sys.stderr)
        return 2
    result = evaluate(args.data, args.seed, args.gaps, tuple(args.lengths), args.min_motion)
    print(markdown(result))
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
