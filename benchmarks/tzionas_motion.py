"""Benchmark: reading + fitting the Tzionas sequence 20 motion (hand 186 frames, cube track).

Run: python benchmarks/tzionas_motion.py
Prints the median time of reading the hand skeleton alone, of fit_tzionas_motion (which reads the skeleton
too), of the cube track and of the whole sequence, and how many times faster than the recording's real time
(186 frames at 30 Hz = 6.2 s) the whole sequence reads.
"""

from __future__ import annotations

import sys
from pathlib import Path

from timing import median_seconds  # benchmarks/timing.py (scripts run from benchmarks/)

from handsim.io.tzionas.motion import fit_tzionas_motion, read_tzionas_object_motion
from handsim.io.tzionas.sequence import read_tzionas_sequence
from handsim.io.tzionas.skeleton import read_tzionas_skeleton

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "tzionas_ijcv16"
BUNDLED = Path(__file__).resolve().parents[1] / "handsim" / "assets" / "tzionas_ijcv16"


def main() -> int:
    root = SHARED if SHARED.exists() else BUNDLED
    models = root / "Models" / "20"
    hand = models / "Model_Hand_R.SKEL"
    if not hand.exists():
        print(f"no sample data at {models}", file=sys.stderr)
        return 1
    trajectory, fit = fit_tzionas_motion(hand)
    cases = {
        "read_tzionas_skeleton (hand)": lambda: read_tzionas_skeleton(hand),
        "fit_tzionas_motion (hand)": lambda: fit_tzionas_motion(hand),
        "read_tzionas_object_motion (cube)": lambda: read_tzionas_object_motion(
            models / "Model_Object_Cube.SKEL"
        ),
        "read_tzionas_sequence (20)": lambda: read_tzionas_sequence(models),
    }
    print(f"data: {models}; {trajectory.nframes} frames, {len(trajectory.dof_names)} DoFs")
    print(f"{'step':36s} {'median s':>9s}")
    seconds = {}
    for name, call in cases.items():
        seconds[name] = median_seconds(call)
        print(f"{name:36s} {seconds[name]:9.3f}")
    real_time = trajectory.duration + 1.0 / trajectory.mean_rate
    print(
        f"whole sequence reads {real_time / seconds['read_tzionas_sequence (20)']:.1f}x faster than real time"
    )
    print(f"max joint position error {1e3 * fit.position_error.max():.3f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
