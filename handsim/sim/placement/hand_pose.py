"""The hand's posture at a recorded frame, and the orientation the glove scenario attaches it with."""

from __future__ import annotations

import mujoco
import numpy as np

from handsim.datatypes.rotations import matrix_to_quat
from handsim.datatypes.trajectory import Trajectory
from handsim.sim.scene.compiled import SimScene


def targets_qpos(scene: SimScene, trajectory: Trajectory, frame: int) -> np.ndarray:
    """The scene's ``qpos0`` with the hand at the trajectory's targets of ``frame`` (clipped to the ranges).

    Hand DoFs the trajectory has no column for are at 0 (or their nearest limit).
    """
    layout = scene.layout
    qpos = scene.model.qpos0.copy()
    column = {n: i for i, n in enumerate(trajectory.dof_names)}
    values = np.array(
        [trajectory.targets[frame, column[n]] if n in column else 0.0 for n in layout.dof_names]
    )
    qpos[layout.dof_qpos] = np.clip(values, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
    return qpos


def hand_frame(scene: SimScene) -> np.ndarray:
    """Orientation (w, x, y, z) to attach the hand with: fingers along +x, palm facing −z (palm down).

    The palm normal is where the fingertips move when every finger flexion DoF goes to half its upper
    limit, so it does not depend on the hand being left or right.

    Args:
        scene: A scene with the hand attached with the identity orientation.
    """
    model, layout = scene.model, scene.layout
    data = mujoco.MjData(model)
    flex = np.array(["flex" in n and not n.startswith("root") for n in layout.dof_names])
    rest = np.clip(0.0, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
    data.qpos[layout.dof_qpos] = rest
    mujoco.mj_kinematics(model, data)
    tips0 = data.site_xpos[layout.tip_sites].copy()
    root = data.xpos[layout.root_body].copy()
    data.qpos[layout.dof_qpos] = np.where(flex, 0.5 * layout.ctrl_range[:, 1], rest)
    mujoco.mj_kinematics(model, data)
    tips1 = data.site_xpos[layout.tip_sites]
    fingers = tips0.mean(axis=0) - root
    fingers /= np.linalg.norm(fingers)
    palm = (tips1 - tips0).mean(axis=0)
    palm -= fingers * (palm @ fingers)
    palm /= np.linalg.norm(palm)
    hand = np.column_stack([fingers, palm, np.cross(fingers, palm)])
    world = np.column_stack([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    return matrix_to_quat(world @ hand.T)
