"""Test helpers shared by several test modules."""

from __future__ import annotations

import mujoco
import numpy as np

from handsim.datatypes.skeleton import Skeleton, mj_name


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


def glove_switch_inputs():
    """A short glove scene whose replay switches contacts on mid-run and releases the support before the end.

    The default hand makes a fist first (the fingers curl through where the ball will be), opens, then
    closes on the tennis ball; 100 frames at 64 Hz.

    Returns:
        The scene and its trajectory.
    """
    from handsim.builders import build_object, build_scene, default_hand
    from handsim.builders.catalog import get
    from handsim.datatypes.trajectory import Phase, Trajectory
    from handsim.sim.scenarios import glove_scene
    from handsim.sim.scene.compiled import compile_scene

    hand, ball = default_hand(), build_object(get("tennis_ball"))
    layout = compile_scene(build_scene(hand, ball)).layout
    t = np.arange(100) / 64.0
    flex = np.array(["flex" in n and not n.startswith("root") for n in layout.dof_names])
    closing = np.where(t < 0.2, 1.0, np.clip((t - 0.4) / 0.6, 0, 0.6 / 0.95)) * 0.95
    targets = closing[:, None] * np.where(flex, layout.ctrl_range[:, 1], 0.0)
    grasp = (Phase("grasp", int(np.searchsorted(t, 0.8)), 100),)
    trajectory = Trajectory(t, layout.dof_names, targets, np.ones_like(targets, bool), phases=grasp)
    return glove_scene(hand, trajectory, ball), trajectory
