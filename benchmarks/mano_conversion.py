"""Benchmark: MANO parameters → hinge-angle trajectory, 10,000 frames (target < 1 s).

Run: python benchmarks/mano_conversion.py
Prints the median wall time of :func:`handsim.io.arctic.mano_pose.mano_pose_to_trajectory` (axis-angle →
Rodrigues →
Z·Y·X decomposition → residual check → root pose) for 10,000 random frames on the bundled mean-shape right
hand, the largest decomposition residual, and for reference the time of reading an ARCTIC-layout
``.mano.npy`` of the same length with the restricted unpickler.
"""

from __future__ import annotations

import re
import sys
import tempfile
from pathlib import Path

import numpy as np
from timing import median_seconds  # benchmarks/timing.py (scripts run from benchmarks/)

from handsim.builders.mano_hand import mano_hand_skeleton
from handsim.io.arctic.mano_pose import MANOSequence, mano_pose_to_trajectory
from handsim.io.arctic.sequence import read_arctic_mano

NFRAMES = 10_000
TARGET_S = 1.0


def random_sequence(n: int, seed: int = 0) -> MANOSequence:
    """Random MANO parameters: rot ~ N(0, 1) rad, pose ~ N(0, 0.5) rad, trans within ±0.5 m."""
    rng = np.random.default_rng(seed)
    return MANOSequence(
        rot=rng.normal(size=(n, 3)),
        pose=rng.normal(scale=0.5, size=(n, 45)),
        trans=rng.uniform(-0.5, 0.5, size=(n, 3)),
        shape=np.zeros(10),
    )


def main() -> int:
    skeleton = mano_hand_skeleton()
    seq = random_sequence(NFRAMES)
    convert = lambda: mano_pose_to_trajectory(seq, skeleton, flat_hand_mean=True)  # noqa: E731
    seconds = median_seconds(convert, 7)
    residual = next(n for n in convert().notes if "residual" in n)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.mano.npy"
        hands = {}
        for side, x in (("right", 0.2), ("left", -0.2)):  # ARCTIC's layout: both hands, fitting_err a list
            t = np.arange(NFRAMES) / 30.0
            wrist = np.column_stack([x + 0.05 * np.sin(t), 0.05 * np.cos(t), 1.0 + 0.0 * t])
            hand = {k: np.asarray(getattr(seq, k), dtype=np.float32) for k in ("rot", "pose", "shape")}
            hands[side] = {**hand, "trans": wrist.astype(np.float32), "fitting_err": [0.005] * NFRAMES}
        np.save(path, hands, allow_pickle=True)
        read_s = median_seconds(lambda: read_arctic_mano(path, "right"), 7)
    print(f"mano_conversion_{NFRAMES}_frames_s={seconds:.3f} (target < {TARGET_S:g})")
    print(f"per_frame_us={seconds / NFRAMES * 1e6:.1f}")
    worst = re.search(r"residual (\S+) rad", residual).group(1)
    print(f"max_decomposition_residual_rad={worst}")
    print(f"read_arctic_mano_{NFRAMES}_frames_s={read_s:.3f}")
    return 0 if seconds < TARGET_S else 1


if __name__ == "__main__":
    sys.exit(main())
