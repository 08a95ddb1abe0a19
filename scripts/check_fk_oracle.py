"""Compare handsim's forward kinematics with a GraspDB14 MATLAB ``*_w_traj.mat`` file.

Usage:
    python scripts/check_fk_oracle.py SKELETON.xmlskel MOTION.txt MOTION.txt_w_traj.mat

Prints the largest joint-position difference (mm) over all joints and frames, for the numpy FK and for
MuJoCo's mj_kinematics on the built hand. Exits 1 if either exceeds 0.1 mm.
"""

from __future__ import annotations

import argparse
import sys

import mujoco
import numpy as np
import scipy.io

from handsim.builders import build_hand
from handsim.datatypes.skeleton import mj_name
from handsim.io import read_skeleton, read_trajectory
from handsim.sim import compile_spec

TOLERANCE_MM = 0.1


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("skeleton")
    parser.add_argument("motion")
    parser.add_argument("oracle")
    args = parser.parse_args()

    skeleton = read_skeleton(args.skeleton)
    traj = read_trajectory(args.motion, skeleton=skeleton)
    mot = scipy.io.loadmat(args.oracle, squeeze_me=True, struct_as_record=False)["motion"]
    truth = np.stack([np.asarray(t, dtype=float).T for t in mot.jointtrajectories], axis=1)

    numpy_mm = skeleton.forward_kinematics(traj.targets).positions * 1000.0
    model = compile_spec(build_hand(skeleton))
    data = mujoco.MjData(model)
    qadr = [model.joint(name).qposadr[0] for name in skeleton.dof_names]
    sites = [model.site(mj_name(j.name)).id for j in skeleton.joints]
    mujoco_mm = np.empty_like(numpy_mm)
    for t, q in enumerate(traj.targets):
        data.qpos[qadr] = q
        mujoco.mj_kinematics(model, data)
        mujoco_mm[t] = data.site_xpos[sites] * 1000.0

    numpy_err = float(np.abs(numpy_mm - truth).max())
    mujoco_err = float(np.abs(mujoco_mm - truth).max())
    print(f"frames {traj.nframes}, joints {skeleton.njoints}")
    print(f"numpy FK  max |error| = {numpy_err:.3e} mm")
    print(f"MuJoCo FK max |error| = {mujoco_err:.3e} mm")
    return 0 if max(numpy_err, mujoco_err) <= TOLERANCE_MM else 1


if __name__ == "__main__":
    sys.exit(main())
