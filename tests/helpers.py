"""Test helpers shared by several test modules."""

from __future__ import annotations

import mujoco
import numpy as np

from handsim.skeleton import Skeleton, mj_name


def set_pose(model: mujoco.MjModel, data: mujoco.MjData, skeleton: Skeleton, q: np.ndarray) -> None:
    """Write skeleton DoF angles into ``data.qpos`` by joint name and run kinematics."""
    for k, name in enumerate(skeleton.dof_names):
        data.qpos[model.joint(name).qposadr[0]] = q[k]
    mujoco.mj_kinematics(model, data)


def site_positions(model: mujoco.MjModel, data: mujoco.MjData, skeleton: Skeleton) -> np.ndarray:
    """World positions of the sites named after every skeleton joint, shape (njoints, 3)."""
    return np.array([data.site(mj_name(j.name)).xpos for j in skeleton.joints])


def random_in_limits(skeleton: Skeleton, n: int, seed: int) -> np.ndarray:
    """``n`` random poses inside the DoF limits, shape (n, ndof)."""
    rng = np.random.default_rng(seed)
    lim = skeleton.limits
    return rng.uniform(lim[:, 0], lim[:, 1], size=(n, skeleton.ndof))
