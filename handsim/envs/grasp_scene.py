"""The scene of ``handsim/Grasp-v0``: a wristless default hand palm down above a catalogue object.

The hand is handsim's parametric default hand without its wrist DoFs, palm down
(:func:`handsim.sim.placement.hand_pose.hand_frame`: fingers along +x), its root welded to a mocap target
(``hand_root="weld"``): the weld replaces the arm, so the hand can carry the object up while contacts
still push back. The object rests on the table with its centre under a point :data:`GRASP_AHEAD` ahead of
the palm's centre, the palm ``hand_clearance`` above its top.
"""

from __future__ import annotations

import dataclasses
import functools

import mujoco
import numpy as np

from handsim.builders import build_object, build_scene
from handsim.builders.catalog import get
from handsim.builders.hand import build_hand
from handsim.builders.objects import object_bounds
from handsim.builders.scene import resting_position
from handsim.io.graspdb.default_skeleton import DEFAULT_BREADTH_RATIO, DEFAULT_HAND_LENGTH_M, default_skeleton
from handsim.sim.placement.hand_pose import hand_frame
from handsim.sim.scene.compiled import SceneSetup, SimScene, compile_scene

GRASP_AHEAD = 0.03
"""The object's centre starts under the point this far ahead of the palm's centre along the fingers, m."""


@dataclasses.dataclass(frozen=True)
class GraspScene:
    """A grasping scene and where things are in it.

    Attributes:
        scene: The compiled scene: the hand (root welded to a mocap target, palm down) and the object.
        grasp_offset: World offset from the hand root to the grasp point, m: under the palm where the
            object's centre sits when the object touches the palm (the root's orientation is held).
        root_floor: Lowest root height: the palm's lowest point on the table top, m.
        object_name: Catalogue name of the object.
    """

    scene: SimScene
    grasp_offset: np.ndarray
    root_floor: float
    object_name: str


def _wristless_default_hand() -> mujoco.MjSpec:
    """The default hand without its wrist DoFs (the mocap weld moves and turns the root instead)."""
    skeleton = default_skeleton()
    root = skeleton.joints[0].name
    skeleton = dataclasses.replace(skeleton, dofs=tuple(d for d in skeleton.dofs if d.joint != root))
    return build_hand(skeleton, breadth=DEFAULT_BREADTH_RATIO * DEFAULT_HAND_LENGTH_M)


def _palm(scene: SimScene) -> tuple[np.ndarray, float]:
    """Centre of the root's collision geoms, and the height of the palm's lowest point under it.

    Measured with the hand open at rest (every DoF at 0 rad or its nearest limit).
    """
    model, layout = scene.model, scene.layout
    data = mujoco.MjData(model)
    data.qpos[layout.dof_qpos] = np.clip(0.0, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
    mujoco.mj_kinematics(model, data)
    geoms = [
        g
        for g in range(model.ngeom)
        if model.geom_bodyid[g] == layout.root_body and (model.geom_contype[g] or model.geom_conaffinity[g])
    ]
    centre = data.geom_xpos[geoms].mean(axis=0)
    groups = np.zeros(mujoco.mjNGROUP, dtype=np.uint8)
    groups[np.unique(model.geom_group[geoms])] = 1
    hit = np.zeros(1, dtype=np.int32)
    below = 1.0
    dist = mujoco.mj_ray(
        model, data, centre - [0.0, 0.0, below], np.array([0.0, 0.0, 1.0]), groups, 1, -1, hit
    )
    bottom = centre[2] - below + dist if dist >= 0 else centre[2]
    return centre, float(bottom)


@functools.lru_cache(maxsize=8)
def grasp_scene(object_name: str = "tennis_ball", hand_clearance: float = 0.02) -> GraspScene:
    """Build (once per process and arguments) the scene of ``handsim/Grasp-v0``.

    Args:
        object_name: A catalogue object (:func:`handsim.builders.catalog.names`).
        hand_clearance: Gap between the palm's lowest point and the object's top at the start, m.

    Returns:
        The scene and its grasp geometry.

    Raises:
        UnknownObjectError: ``object_name`` is not in the catalogue (the message lists the names).
    """
    obj = build_object(get(object_name))
    hand = _wristless_default_hand()
    quat = hand_frame(compile_scene(build_scene(hand, obj, table=False)))
    probe = compile_scene(build_scene(hand, [], hand_pos=(0.0, 0.0, 0.0), hand_quat=quat, table=False))
    centre, bottom = _palm(probe)
    lower, upper = object_bounds(obj)
    mid = (lower + upper) / 2
    rest = resting_position(obj, xy=(-mid[0], -mid[1]))
    top = rest[2] + upper[2]
    grasp_xy = centre[:2] + np.array([GRASP_AHEAD, 0.0])  # fingers point along +x
    root = np.array([-grasp_xy[0], -grasp_xy[1], top + hand_clearance - bottom])
    spec = build_scene(
        hand,
        obj,
        hand_pos=root,
        hand_quat=quat,
        object_poses=[np.concatenate([rest, [1.0, 0.0, 0.0, 0.0]])],
        table=True,
        hand_root="weld",
    )
    half_height = (upper[2] - lower[2]) / 2
    offset = np.array([grasp_xy[0], grasp_xy[1], bottom - half_height - mid[2]])
    setup = SceneSetup(
        scenario="free",
        notes=(
            f"{object_name} on the table under the palm (centre {GRASP_AHEAD * 100:g} cm ahead of the "
            f"palm's centre), the palm {hand_clearance * 1000:g} mm above its top; "
            "hand root welded to a mocap target",
        ),
    )
    return GraspScene(
        scene=compile_scene(spec, setup), grasp_offset=offset, root_floor=-bottom, object_name=object_name
    )
