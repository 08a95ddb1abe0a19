"""Test helpers shared by several test modules."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

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


def write_short_grasp(folder: str | Path, name: str = "cube") -> Path:
    """A scripted grasp of the default hand (27 DoFs) on catalogue object ``name``, 0.8 s: a quick trial.

    Returns:
        The file, ``FOLDER/NAME.grasp.json``.
    """
    grasp = {
        "format": "handsim-scripted-grasp", "version": 1, "description": "a short test grasp",
        "object": name, "hand_length": 0.19, "rate_hz": 60, "rest_s": 0.1, "close_s": 0.3,
        "hold_s": 0.3, "open_s": 0.1, "closure": 0.7,
    }  # fmt: skip
    path = Path(folder) / f"{name}.grasp.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(grasp))
    return path


def load_script(name: str):
    """The module of ``scripts/NAME.py``, loaded from its file (the scripts are no package).

    Returns:
        The module, its code run (its ``main`` not called).
    """
    path = Path(__file__).resolve().parents[1] / "scripts" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
