"""Benchmark: the wall-clock figures the test suite used to assert (tests assert no times: they flaked).

Run: python benchmarks/io_and_cache.py [--repeats 5]

Prints the median of ``--repeats`` runs of:

* reading a synthetic 10,000-row GraspDB14 ``rad`` recording and a 10,000-row ``raw`` one (16 ms apart;
  target < 0.5 s each);
* a decomposition cache hit: ``decompose`` of a 128-vertex annulus whose hulls are cached (target < 0.5 s);
* a CoACD run with a 0.01 s time limit: how soon ``decompose`` gives up and raises (target < 2 s).

Needs no data beyond the package (the recordings and the annulus are made here).
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from datetime import datetime, timedelta
from pathlib import Path

import trimesh
from timing import median_seconds  # benchmarks/timing.py (scripts run from benchmarks/)

from handsim.builders.decompose import decompose
from handsim.builders.decomposition_types import DecompositionError, DecompositionParams
from handsim.datatypes.mesh import validate_mesh
from handsim.io.graspdb.glove import read_graspdb_glove, read_graspdb_raw

ROWS = 10_000
PARAMS = DecompositionParams(resolution=500, preprocess_resolution=30, mcts_iterations=60)


def recording(folder: Path, name: str, counts: bool) -> Path:
    """A ``ROWS``-row recording, 16 ms apart: radians, or raw counts."""
    start = datetime(2014, 9, 15, 8, 2, 9, 24000)
    values = " ".join(str(100 + k) if counts else f"{0.01 * k:.5f}" for k in range(23))
    lines = []
    for i in range(ROWS):
        d = start + timedelta(milliseconds=16 * i)
        seconds = d.second + d.microsecond / 1e6
        lines.append(
            f"{d.year} {d.month:02d} {d.day:02d} {d.hour:02d} {d.minute:02d} {seconds:08.5f} 1 {values} \n"
        )
    path = folder / name
    path.write_text("".join(lines))
    return path


def timeout_return(mesh, cache: Path) -> None:
    try:
        decompose(mesh, dataclasses.replace(PARAMS, timeout_s=0.01), cache_dir=cache)
    except DecompositionError:
        return
    raise RuntimeError("CoACD finished within 0.01 s; nothing was timed")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per step (median reported)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        rad = recording(folder, "01_ex01-rad-001-grasp-su01.txt", counts=False)
        raw = recording(folder, "01_ex01-raw-001-grasp-su01.txt", counts=True)
        t = trimesh.creation.annulus(r_min=0.02, r_max=0.04, height=0.02)
        annulus = validate_mesh(t.vertices, t.faces, source="annulus")
        decompose(annulus, PARAMS, cache_dir=folder / "cache")  # fills the cache
        rows = [
            (f"read {ROWS} rad rows", median_seconds(lambda: read_graspdb_glove(rad), args.repeats), 0.5),
            (f"read {ROWS} raw rows", median_seconds(lambda: read_graspdb_raw(raw), args.repeats), 0.5),
            (
                "decompose, cache hit",
                median_seconds(lambda: decompose(annulus, PARAMS, cache_dir=folder / "cache"), args.repeats),
                0.5,
            ),
            (
                "decompose, 0.01 s timeout",
                median_seconds(lambda: timeout_return(annulus, folder / "timeout"), args.repeats),
                2.0,
            ),
        ]
    print(f"{'step':28s} {'median [s]':>10s} {'target [s]':>10s}")
    for name, seconds, target in rows:
        verdict = "" if seconds < target else "  MISSES the target"
        print(f"{name:28s} {seconds:10.3f} {target:10.1f}{verdict}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
