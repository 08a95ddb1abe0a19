"""A grasping scene: the hand and objects attached under prefixes, a table, a floor, lights and cameras.

World frame: z up, the origin on the table top's centre. The table top is the plane z = 0 (a box of
``table_size`` whose top face is at z = 0), the floor is z = −``table_height``. Names: the hand's elements
are prefixed ``hand/``; a single object's ``obj/``; several objects' ``obj0/``, ``obj1/`` … in the order
given. Cameras: ``hand_cam`` looks at the hand from the front-right and above, ``overview`` at the table.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.builders.objects import object_points
from handsim.builders.surfaces import CONTACT_CONDIM, ENVIRONMENT
from handsim.datatypes.rotations import matrix_to_quat, quat_multiply, quat_rotate, quat_to_matrix
from handsim.errors import ModelError

HAND_PREFIX = "hand/"
OBJECT_PREFIX = "obj/"
HAND_ROOT_OPTIONS = ("fixed", "weld")
"""``build_scene(hand_root=…)``: the hand's root fixed where attached, or free and welded to a mocap body."""
HAND_TARGET = "hand_target"
"""Name of the mocap body the hand's root is welded to (``hand_root="weld"``)."""
HAND_WELD = "hand_weld"
"""Name of the weld between :data:`HAND_TARGET` and the hand's root body."""
SUPPORT_SUFFIX = "support"
"""An object's support weld is named ``<prefix>support`` (e.g. ``obj/support``)."""
SUPPORT_SOLREF = (0.005, 1.0)
"""Support weld: stiff (2.5 steps of 2 ms), so a held object sags well under a millimetre."""
HAND_WELD_SOLREF = (0.01, 1.0)
"""Weld time constant (s) and damping ratio: the root follows its target within ~10 ms; contacts push back."""
FLOOR = "floor"
"""Name of the floor plane (:func:`add_floor`)."""
STAND = "stand"
"""Name of a stand under an object (:func:`add_stand`) and of its mesh."""
TABLE_RGBA = (0.62, 0.52, 0.42, 1.0)
FLOOR_RGBA = (0.35, 0.37, 0.40, 1.0)


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


def resting_position(
    obj: mujoco.MjSpec,
    xy: Sequence[float] = (0.0, 0.0),
    gap: float = 0.0,
    quat: npt.ArrayLike = (1.0, 0.0, 0.0, 0.0),
) -> np.ndarray:
    """Position of an object's frame that rests it, turned by ``quat``, on the table top at ``xy``.

    Args:
        obj: An object spec from :func:`handsim.builders.build_object`.
        xy: Table-top position, metres.
        gap: Height of the object's lowest point above the table, metres.
        quat: The object's orientation (w, x, y, z); identity by default.

    Returns:
        Position (x, y, z), metres.
    """
    rot = quat_to_matrix(_vector(quat, 4, "quat"))
    lowest = float((object_points(obj) @ rot.T)[:, 2].min())
    return np.array([xy[0], xy[1], gap - lowest], dtype=float)


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
    hand_root: str = "fixed",
    object_support: bool = False,
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
        hand_root: ``"fixed"``: the hand's root body stays where it is attached (glove data; wrist DoFs
            stay hinges). ``"weld"``: the root body gets a free joint and is welded (:data:`HAND_WELD`) to
            the mocap body :data:`HAND_TARGET`, which starts at the root's pose; writing a recorded root
            pose into ``data.mocap_pos``/``mocap_quat`` drives the hand while contacts still push back.
        object_support: Weld each object's root body to the world where it is placed (``<prefix>support``,
            active); switching the equality off (``data.eq_active``) releases the object.
        options: Simulation options (default :class:`SceneOptions`).
        name: Model name.

    Returns:
        The scene spec; it is not compiled.

    Raises:
        ModelError: ``object_poses`` does not match the objects, a pose is malformed, ``hand_root`` is
            unknown, or ``"weld"`` is asked for a hand whose root body has joints of its own.
    """
    if hand_root not in HAND_ROOT_OPTIONS:
        raise ModelError(f"unknown hand_root {hand_root!r}; expected one of {list(HAND_ROOT_OPTIONS)}")
    opts = options or SceneOptions()
    objs = [objects] if isinstance(objects, mujoco.MjSpec) else list(objects)
    spec = _new_scene_spec(name, opts)
    if table:
        _add_table(spec, table_size, table_height)
    _add_lights(spec.worldbody)
    if hand is not None:
        attach_hand(spec, hand, pos=hand_pos, quat=hand_quat, root=hand_root, options=opts)
    _attach_objects(spec, objs, _object_poses(objs, object_poses), object_support)
    target = np.asarray(hand_pos, dtype=float) if hand is not None else np.zeros(3)
    _add_look_at_camera(spec, "hand_cam", target, eye=target + np.array([0.35, -0.35, 0.25]))
    _add_look_at_camera(spec, "overview", np.zeros(3), eye=np.array([0.0, -0.9, 0.6]))
    return spec


def _new_scene_spec(name: str, opts: SceneOptions) -> mujoco.MjSpec:
    """An empty scene in radians with the simulation options and an offscreen buffer for 1280 × 960 frames."""
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.modelname = name
    _apply_options(spec, opts)
    spec.visual.global_.offwidth = 1280
    spec.visual.global_.offheight = 960
    spec.visual.headlight.ambient = [0.3, 0.3, 0.3]
    spec.visual.headlight.diffuse = [0.4, 0.4, 0.4]
    return spec


def _add_table(spec: mujoco.MjSpec, table_size: tuple[float, float], table_height: float) -> None:
    """The table, its top at z = 0, and the floor ``table_height`` below it."""
    half = [table_size[0] / 2, table_size[1] / 2, 0.02]
    spec.worldbody.add_geom(
        name="table", type=mujoco.mjtGeom.mjGEOM_BOX, size=half, pos=[0, 0, -half[2]],
        rgba=list(TABLE_RGBA), friction=ENVIRONMENT.friction, priority=ENVIRONMENT.priority,
        condim=CONTACT_CONDIM,
    )  # fmt: skip
    add_floor(spec, -table_height)


def _add_lights(world: mujoco.MjsBody) -> None:
    """A key light casting shadows from the front right and a fill light from the back left."""
    world.add_light(name="key", pos=[0.4, -0.4, 1.2], dir=[-0.35, 0.35, -1.0], castshadow=True)
    world.add_light(name="fill", pos=[-0.5, 0.3, 1.0], dir=[0.5, -0.3, -1.0], castshadow=False)


def _attach_objects(
    spec: mujoco.MjSpec, objs: list[mujoco.MjSpec], poses: list[np.ndarray], object_support: bool
) -> None:
    """Copies of the objects under their prefixes at their poses; welded in place if ``object_support``."""
    for prefix, obj, pose in zip(object_prefixes(len(objs)), objs, poses, strict=True):
        frame = spec.worldbody.add_frame(pos=pose[:3].tolist(), quat=pose[3:].tolist())
        root_name = prefix + obj.worldbody.first_body().name
        spec.attach(obj.copy(), prefix=prefix, frame=frame)
        if object_support:
            spec.add_equality(
                name=prefix + SUPPORT_SUFFIX, type=mujoco.mjtEq.mjEQ_WELD, objtype=mujoco.mjtObj.mjOBJ_BODY,
                name1=root_name, data=[*pose[:3].tolist(), *_AS_COMPILED_WELD[3:]],
                solref=list(SUPPORT_SOLREF),
            )  # fmt: skip


def add_floor(spec: mujoco.MjSpec, height: float) -> None:
    """Add the floor: the plane z = ``height`` (m), named :data:`FLOOR`, with the environment's surface.

    Args:
        spec: The scene (changed in place).
        height: The floor's height in the world, m.
    """
    spec.worldbody.add_geom(
        name=FLOOR, type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05], pos=[0, 0, float(height)],
        rgba=list(FLOOR_RGBA), friction=ENVIRONMENT.friction, priority=ENVIRONMENT.priority,
        condim=CONTACT_CONDIM,
    )  # fmt: skip


def add_stand(spec: mujoco.MjSpec, outline: npt.ArrayLike, bottom: float, name: str = STAND) -> None:
    """Add a stand: a vertical prism whose top is the convex polygon ``outline`` at z = 0, down to ``bottom``.

    The stand stands for whatever an object rested on during a capture (a small table or pedestal): a
    column from the support plane (the table top's plane, z = 0) down to the floor, with the environment's
    surface, collided as the convex mesh it is.

    Args:
        spec: The scene (changed in place).
        outline: The top's corners (x, y), m, shape (k, 3 ≤ k), counter-clockwise, convex.
        bottom: Height of the stand's foot, m (< 0).
        name: The geom's (and its mesh's) name.

    Raises:
        ModelError: The outline is not at least three finite (x, y) corners, or ``bottom`` is not below 0.
    """
    corners = np.asarray(outline, dtype=float)
    if corners.ndim != 2 or corners.shape[0] < 3 or corners.shape[1] != 2 or not np.isfinite(corners).all():
        raise ModelError(
            f"a stand's outline must be at least 3 finite (x, y) corners, got shape {corners.shape}"
        )
    if not (math.isfinite(bottom) and bottom < 0.0):
        raise ModelError(f"a stand's foot must lie below its top (z = 0), got {bottom}")
    k = corners.shape[0]
    top, foot = np.column_stack([corners, np.zeros(k)]), np.column_stack([corners, np.full(k, bottom)])
    vertices = np.vstack([top, foot])
    faces = [[0, i, i + 1] for i in range(1, k - 1)]  # top (counter-clockwise seen from above)
    faces += [[k, k + i + 1, k + i] for i in range(1, k - 1)]  # foot (facing down)
    for i in range(k):  # sides, facing out
        j = (i + 1) % k
        faces += [[i, k + i, k + j], [i, k + j, j]]
    spec.add_mesh(name=name, uservert=vertices.ravel().tolist(), userface=np.ravel(faces).tolist())
    spec.worldbody.add_geom(
        name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name, rgba=list(TABLE_RGBA),
        friction=ENVIRONMENT.friction, priority=ENVIRONMENT.priority, condim=CONTACT_CONDIM,
    )  # fmt: skip


def hand_prefix(name: str = "") -> str:
    """Name prefix of a scene's hand: ``hand/`` for the only hand, ``hand/<name>/`` for one of several."""
    return f"{HAND_PREFIX}{name}/" if name else HAND_PREFIX


def hand_target_name(name: str = "") -> str:
    """The mocap body a welded hand root follows: :data:`HAND_TARGET`, or ``hand_target/<name>``."""
    return f"{HAND_TARGET}/{name}" if name else HAND_TARGET


def hand_weld_name(name: str = "") -> str:
    """The weld holding a hand root on its mocap body: :data:`HAND_WELD`, or ``hand_weld/<name>``."""
    return f"{HAND_WELD}/{name}" if name else HAND_WELD


def attach_hand(
    spec: mujoco.MjSpec,
    hand: mujoco.MjSpec,
    *,
    name: str = "",
    pos: npt.ArrayLike = (0.0, 0.0, 0.0),
    quat: npt.ArrayLike = (1.0, 0.0, 0.0, 0.0),
    root: str = "fixed",
    options: SceneOptions | None = None,
) -> None:
    """Attach a copy of a hand to a scene under :func:`hand_prefix` ``(name)``.

    Args:
        spec: The scene (changed in place).
        hand: The hand spec (left unchanged).
        name: "" for a scene's only hand; a scene with several names each (``"right"``, ``"left"``).
        pos: Position of the hand's root frame, metres.
        quat: Orientation of the hand's root frame (w, x, y, z).
        root: ``"fixed"`` or ``"weld"`` (see :func:`build_scene`'s ``hand_root``): a weld frees the root body
            and holds it on the mocap body :func:`hand_target_name` ``(name)``.
        options: Simulation options the hand's own are replaced by (default :class:`SceneOptions`).

    Raises:
        ModelError: ``root`` is unknown, a pose is malformed, or ``"weld"`` is asked for a hand whose root
            body has joints of its own.
    """
    if root not in HAND_ROOT_OPTIONS:
        raise ModelError(f"unknown hand_root {root!r}; expected one of {list(HAND_ROOT_OPTIONS)}")
    child = hand.copy()
    _apply_options(child, options or SceneOptions())
    frame = spec.worldbody.add_frame(pos=_vector(pos, 3, "hand_pos"), quat=_vector(quat, 4, "hand_quat"))
    prefix = hand_prefix(name)
    root_name = prefix + child.worldbody.first_body().name
    spec.attach(child, prefix=prefix, frame=frame)
    if root == "weld":
        _weld_to_mocap(spec, root_name, pos, quat, name)


_IDENTITY_WELD = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
"""Weld ``data``: anchor (3), relative position (3), relative quaternion (4), torque scale, unused.

An identity relative pose holds the two bodies' frames together (the hand's root on its mocap target)."""
_AS_COMPILED_WELD = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]
"""A zero relative quaternion makes MuJoCo take the relative pose at ``qpos0``: the body stays where placed
(``name2`` left empty is the world). The anchor (in ``name2``'s frame) goes on the object's origin: anchored
at the world origin, the weld's position rows hold that point and only its soft rotation rows resist the
object swinging about it."""


def _weld_to_mocap(
    spec: mujoco.MjSpec, root_name: str, pos: npt.ArrayLike, quat: npt.ArrayLike, name: str = ""
) -> None:
    """Free the hand's root body and weld it to a mocap body at the root's initial world pose."""
    root = spec.body(root_name)
    if root.first_joint() is not None:
        raise ModelError(
            f"hand_root='weld': the hand's root body {root_name!r} has joints of its own "
            f"({root.first_joint().name!r}); a recorded root pose replaces them, so build the hand without "
            "root DoFs or use hand_root='fixed'"
        )
    hand_quat = _vector(quat, 4, "hand_quat")
    world_pos = np.asarray(_vector(pos, 3, "hand_pos")) + quat_rotate(hand_quat, root.pos)
    world_quat = quat_multiply(hand_quat, root.quat)
    root.add_freejoint(name=f"root_free/{name}" if name else "root_free")
    target_name = hand_target_name(name)
    target = spec.worldbody.add_body(name=target_name, pos=world_pos.tolist(), quat=world_quat.tolist())
    target.mocap = True
    spec.add_equality(
        name=hand_weld_name(name), type=mujoco.mjtEq.mjEQ_WELD, objtype=mujoco.mjtObj.mjOBJ_BODY,
        name1=target_name, name2=root_name, data=_IDENTITY_WELD, solref=list(HAND_WELD_SOLREF),
    )  # fmt: skip


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
    spec.worldbody.add_camera(name=name, pos=eye.tolist(), quat=matrix_to_quat(rot).tolist(), fovy=45.0)
