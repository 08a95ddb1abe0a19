"""The ARCTIC scene: two MANO hands following their recorded wrists, one articulated object, free.

ARCTIC's world is z-up (its capture studio's floor frame), so, unlike
:func:`handsim.sim.scenarios.recorded_scene` (camera-frame recordings have no "up"), the scene keeps the
recording's axes: gravity is world −z and nothing is snapped to an object axis. The recording is only
shifted: the object's origin at frame 0 goes above the scene's origin and its lowest collision point at
frame 0 onto the support plane (the table top, z = 0), so the object starts resting on a support wherever it
was recorded.

Each hand is attached under ``hand/<side>/`` (DoFs ``<side>/<dof>``), its wrist freed and welded to a mocap
body ``hand_target/<side>`` that follows the trajectory's ``hand_roots[side]``; the object is attached under
``obj/`` at its recorded pose, its hinge at the recorded articulation (clamped into the hinge's range: ARCTIC
fits may start a few degrees below the closed pose, and the notes say so).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import mujoco
import numpy as np

from handsim.builders.scene import build_scene
from handsim.datatypes.poses import compose
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import TrajectoryError
from handsim.sim.scenarios import attach_welded_hands
from handsim.sim.scene.compiled import SceneSetup, SimScene, compile_scene
from handsim.sim.scene.model import compile_spec


def lowest_point(obj: mujoco.MjSpec, pose: np.ndarray, articulation: float | None) -> tuple[float, float]:
    """The lowest world z of an object's collision geometry at a pose and articulation.

    Args:
        obj: The object (:func:`handsim.builders.build_object`).
        pose: Its root's pose (x, y, z, qw, qx, qy, qz), metres.
        articulation: Its hinge angle, radians (clamped into the hinge's range), or None for none.

    Returns:
        The lowest z, metres, and the hinge angle used (the clamped articulation; NaN without a hinge).
    """
    model = compile_spec(obj)
    data = mujoco.MjData(model)
    data.qpos[:7] = pose
    angle = math.nan
    hinges = [j for j in range(model.njnt) if int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)]
    if hinges and articulation is not None:
        joint = hinges[0]
        angle = float(articulation)
        if model.jnt_limited[joint]:
            angle = float(np.clip(angle, *model.jnt_range[joint]))
        data.qpos[model.jnt_qposadr[joint]] = angle
    mujoco.mj_kinematics(model, data)
    lowest = math.inf
    for g in range(model.ngeom):
        if not (model.geom_contype[g] or model.geom_conaffinity[g]):
            continue
        rotation = data.geom_xmat[g].reshape(3, 3)
        if int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_MESH):
            mesh = int(model.geom_dataid[g])
            start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
            vertices = model.mesh_vert[start : start + count].astype(float)
            lowest = min(lowest, float((vertices @ rotation.T + data.geom_xpos[g])[:, 2].min()))
        else:
            lowest = min(lowest, float(data.geom_xpos[g, 2] - model.geom_rbound[g]))
    return lowest, angle


def arctic_scene(
    hands: Mapping[str, mujoco.MjSpec],
    trajectory: Trajectory,
    obj: mujoco.MjSpec,
    track: str,
    *,
    table: bool = True,
) -> SimScene:
    """Scene for a two-hand recording in a z-up world with one recorded object (ARCTIC).

    Args:
        hands: Hand specs by name (``"right"``, ``"left"``), their root bodies without DoFs (their world pose
            is the trajectory's ``hand_roots[name]``).
        trajectory: DoF columns ``<name>/<dof>``, a root pose per hand in ``hand_roots``, the object's track.
        obj: The object (:func:`handsim.builders.build_object`).
        track: The object's track in ``trajectory.objects``.
        table: Add the table under the support plane.

    Returns:
        The compiled scene (scenario ``recorded``).

    Raises:
        TrajectoryError: A hand without a root pose, or the object's track missing.
    """
    if track not in trajectory.objects:
        raise TrajectoryError(
            f"{trajectory.source or 'trajectory'}: no object track {track!r}; "
            f"it has {list(trajectory.objects)}"
        )
    recorded = trajectory.objects[track]
    start = np.asarray(recorded.pose[0], dtype=float)
    first = None if recorded.articulation is None else float(recorded.articulation[0])
    lowest, angle = lowest_point(obj, start, first)
    world = np.array([-start[0], -start[1], -lowest, 1.0, 0.0, 0.0, 0.0])
    spec = build_scene(None, [obj], object_poses=[compose(world, start)], table=table)
    attach_welded_hands(spec, hands, trajectory)
    notes = [
        "gravity = world −z (ARCTIC's world is z-up; no axis snapped); the recording is shifted by "
        f"{(world[:3] * 1000).round(1).tolist()} mm: the object's origin at frame 0 above the origin, the "
        "support plane (table top, z = 0) under its lowest point at frame 0",
    ]
    if first is not None and not math.isnan(angle) and angle != first:
        notes.append(
            f"the recorded articulation at frame 0 ({math.degrees(first):.1f}°) is outside the hinge's "
            f"range: the object starts at {math.degrees(angle):.1f}°, its stop (drift is still measured "
            "against the recording)"
        )
    setup = SceneSetup(
        scenario="recorded",
        world_from_recording=tuple(world.tolist()),
        object_tracks=(track,),
        notes=tuple(notes),
    )
    return compile_scene(spec, setup)
