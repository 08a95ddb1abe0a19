"""A grasping scene: the hand and objects attached under prefixes, a table, a floor, lights and cameras.

World frame: z up, the origin on the table top's centre. The table top is the plane z = 0 (a box of
``table_size`` whose top face is at z = 0), the floor is z = −``table_height``. Names: the hand's elements
are prefixed ``hand/``; a single object's ``obj/``; several objects' ``obj0/``, ``obj1/`` … in the order
given. Cameras: ``hand_cam`` looks at the hand from the front-right and above, ``overview`` at the table.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.builders.objects import object_bounds
from handsim.errors import ModelError

HAND_PREFIX = "hand/"
OBJECT_PREFIX = "obj/"
TABLE_RGBA = (0.62, 0.52, 0.42, 1.0)
FLOOR_RGBA = (0.35, 0.37, 0.40, 1.0)
TABLE_FRICTION = (
    0.6,
    0.005,
    0.0001,
)  # wood/laminate against the object materials; skin friction dominates grasps


@dataclass(frozen=True)
class SceneOptions:
    """Simulation options chosen for grasping (MuJoCo ``<option>``).

    Attributes:
        timestep: Seconds per step. 2 ms resolves finger–object contact of a ~0.5 kg hand with ~10 g objects.
        integrator: ``implicitfast`` — stable with the hand's joint damping at this step.
        cone: Elliptic friction cones: isotropic friction, no pyramid bias in torsional grasps.
        impratio: Ratio of frictional to normal constraint impedance; > 1 makes contacts stick instead of
            creeping (MuJoCo recommends ~10 for grasping with elliptic cones).
        gravity: m/s².
    """

    timestep: float = 0.002
    integrator: int = int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST)
    cone: int = int(mujoco.mjtCone.mjCONE_ELLIPTIC)
    impratio: float = 10.0
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)


def object_prefixes(count: int) -> list[str]:
    """Prefixes for ``count`` objects in a scene: ``obj/`` for one, ``obj0/``, ``obj1/`` … for several."""
    return [OBJECT_PREFIX] if count == 1 else [f"obj{i}/" for i in range(count)]


def resting_position(obj: mujoco.MjSpec, xy: Sequence[float] = (0.0, 0.0), gap: float = 0.0) -> np.ndarray:
    """Position of an object's frame that rests it (identity orientation) on the table top at ``xy``.

    Args:
        obj: An object spec from :func:`handsim.builders.build_object`.
        xy: Table-top position, metres.
        gap: Height of the object's lowest point above the table, metres.

    Returns:
        Position (x, y, z), metres.
    """
    lower, _ = object_bounds(obj)
    return np.array([xy[0], xy[1], gap - lower[2]], dtype=float)


def build_scene(
    hand: mujoco.MjSpec | None,
    objects: mujoco.MjSpec | Sequence[mujoco.MjSpec] = (),
    *,
    hand_pos: npt.ArrayLike = (0.0, 0.0, 0.12),
    hand_quat: npt.ArrayLike = (1.0, 0.0, 0.0, 0.0),
    object_poses: Sequence[npt.ArrayLike] | None = None,
    table: bool = True,
    table_size: tuple[float, float] = (1.0, 0.7),
    table_height: float = 0.75,
    options: SceneOptions | None = None,
    name: str = "handsim_scene",
) -> mujoco.MjSpec:
    """Assemble a scene from a hand spec and object specs.

    The inputs are copied, not modified.

    Args:
        hand: Hand spec (:func:`handsim.builders.build_hand`), or None for objects only.
        objects: Object specs (:func:`handsim.builders.build_object`).
        hand_pos: Position of the hand's root frame, metres.
        hand_quat: Orientation of the hand's root frame (w, x, y, z).
        object_poses: Per object, a pose (x, y, z, qw, qx, qy, qz) of its frame; default: resting on the
            table, spread along x.
        table: Add the table (its top is z = 0) and the floor.
        table_size: Table top length (x) and width (y), metres.
        table_height: Table height, metres (the floor is at z = −table_height).
        options: Simulation options (default :class:`SceneOptions`).
        name: Model name.

    Returns:
        The scene spec; it is not compiled.

    Raises:
        ModelError: ``object_poses`` does not match the objects, or a pose is malformed.
    """
    opts = options or SceneOptions()
    objs = [objects] if isinstance(objects, mujoco.MjSpec) else list(objects)
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.modelname = name
    _apply_options(spec, opts)
    spec.visual.global_.offwidth = 1280
    spec.visual.global_.offheight = 960
    spec.visual.headlight.ambient = [0.3, 0.3, 0.3]
    spec.visual.headlight.diffuse = [0.4, 0.4, 0.4]
    world = spec.worldbody

    if table:
        half = [table_size[0] / 2, table_size[1] / 2, 0.02]
        world.add_geom(
            name="table", type=mujoco.mjtGeom.mjGEOM_BOX, size=half, pos=[0, 0, -half[2]],
            rgba=list(TABLE_RGBA), friction=list(TABLE_FRICTION),
        )  # fmt: skip
        world.add_geom(
            name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05], pos=[0, 0, -table_height],
            rgba=list(FLOOR_RGBA),
        )  # fmt: skip
    world.add_light(name="key", pos=[0.4, -0.4, 1.2], dir=[-0.35, 0.35, -1.0], castshadow=True)
    world.add_light(name="fill", pos=[-0.5, 0.3, 1.0], dir=[0.5, -0.3, -1.0], castshadow=False)

    if hand is not None:
        child = hand.copy()
        _apply_options(child, opts)
        frame = world.add_frame(pos=_vector(hand_pos, 3, "hand_pos"), quat=_vector(hand_quat, 4, "hand_quat"))
        spec.attach(child, prefix=HAND_PREFIX, frame=frame)

    poses = _object_poses(objs, object_poses)
    for prefix, obj, pose in zip(object_prefixes(len(objs)), objs, poses, strict=True):
        frame = world.add_frame(pos=pose[:3].tolist(), quat=pose[3:].tolist())
        spec.attach(obj.copy(), prefix=prefix, frame=frame)

    target = np.asarray(hand_pos, dtype=float) if hand is not None else np.zeros(3)
    _add_look_at_camera(spec, "hand_cam", target, eye=target + np.array([0.35, -0.35, 0.25]))
    _add_look_at_camera(spec, "overview", np.zeros(3), eye=np.array([0.0, -0.9, 0.6]))
    return spec


def _apply_options(spec: mujoco.MjSpec, opts: SceneOptions) -> None:
    spec.option.timestep = opts.timestep
    spec.option.integrator = opts.integrator
    spec.option.cone = opts.cone
    spec.option.impratio = opts.impratio
    spec.option.gravity = list(opts.gravity)


def _vector(value: npt.ArrayLike, n: int, what: str) -> list[float]:
    v = np.asarray(value, dtype=float)
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ModelError(f"{what} must be {n} finite numbers, got {np.asarray(value).tolist()}")
    if n == 4:
        norm = np.linalg.norm(v)
        if not norm > 0:
            raise ModelError(f"{what} must be a non-zero quaternion (w, x, y, z)")
        v = v / norm
    return v.tolist()


def _object_poses(objs: list[mujoco.MjSpec], poses: Sequence[npt.ArrayLike] | None) -> list[np.ndarray]:
    if poses is None:
        spacing = 0.15
        xs = (np.arange(len(objs)) - (len(objs) - 1) / 2) * spacing
        return [
            np.concatenate([resting_position(o, (x, 0.0)), [1.0, 0.0, 0.0, 0.0]])
            for o, x in zip(objs, xs, strict=True)
        ]
    if len(poses) != len(objs):
        raise ModelError(f"{len(poses)} object poses for {len(objs)} objects")
    result = []
    for i, pose in enumerate(poses):
        p = np.asarray(pose, dtype=float)
        if p.shape != (7,):
            raise ModelError(f"object pose {i} must be (x, y, z, qw, qx, qy, qz), got shape {p.shape}")
        result.append(
            np.concatenate(
                [
                    _vector(p[:3], 3, f"object pose {i} position"),
                    _vector(p[3:], 4, f"object pose {i} quaternion"),
                ]
            )
        )
    return result


def _add_look_at_camera(spec: mujoco.MjSpec, name: str, target: np.ndarray, eye: np.ndarray) -> None:
    """A fixed camera at ``eye`` looking at ``target`` with the world z axis up in the image."""
    forward = target - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    # MuJoCo cameras look along their -z axis, with x to the right and y up in the image.
    rot = np.column_stack([right, up, -forward])
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, rot.ravel())
    spec.worldbody.add_camera(name=name, pos=eye.tolist(), quat=quat.tolist(), fovy=45.0)
