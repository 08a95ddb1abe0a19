"""Where things are in a compiled scene: the hand's actuators and links, the objects' parts, the sensors.

A scene from :func:`handsim.builders.build_scene` names its elements by prefix (``hand/``, ``obj/`` or
``obj0/``…); :func:`instrument` adds the sensors the metrics read, and :func:`scene_layout` turns the names
into index arrays once, so that the stepping loop and the metrics only index numpy arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.builders.scene import HAND_PREFIX, SUPPORT_SUFFIX, hand_prefix, hand_target_name, hand_weld_name
from handsim.errors import ModelError

CONTACT_SLOTS = 8
"""Contacts read per hand link × object part and step; more are counted (and reported) but not summed."""
CONTACT_SLOT_SIZE = 5
"""sensordata values per contact slot: found, force (3, in the contact frame: normal first), distance."""
_FOUND, _FORCE, _DIST = 1, 2, 8  # mjtConDataField bits
_REDUCE_NONE, _REDUCE_MINDIST = 0, 1
CONTACT_PREFIX = "contact/"
PENETRATION_PREFIX = "penetration/"
POSITION_PREFIX = "pos/"
ORIENTATION_PREFIX = "quat/"


@dataclass(frozen=True)
class ObjectLayout:
    """One object of the scene.

    Attributes:
        prefix: Its name prefix (``obj/``).
        root_body: Body id of its root part (the one with the free joint).
        free_qpos: qpos address of the free joint (position 3 + quaternion 4).
        free_dof: qvel address of the free joint.
        hinge_qpos: qpos address of the hinge of a two-part object, or -1.
        hinge_dof: qvel address of that hinge, or -1.
        part_bodies: Body ids of its parts (root first).
        part_names: The parts' names without the prefix.
        support_eq: Equality id of its support weld, or -1 without one.
        collision_geoms: Geom ids of its parts' collision geoms.
    """

    prefix: str
    root_body: int
    free_qpos: int
    free_dof: int
    hinge_qpos: int
    hinge_dof: int
    part_bodies: tuple[int, ...]
    part_names: tuple[str, ...]
    support_eq: int
    collision_geoms: tuple[int, ...] = ()


@dataclass(frozen=True)
class HandLayout:
    """One hand of the scene (a scene has one, or several named ones: ARCTIC's right and left).

    Attributes:
        name: "" for a scene's only hand; else its name (``"right"``), its elements prefixed
            ``hand/<name>/`` and its DoFs, links and tips named ``<name>/…`` in :class:`SceneLayout`.
        root_body: Body id of its root.
        root_free_qpos: qpos address of the root's free joint (a welded root), or -1.
        root_free_dof: qvel address of that free joint, or -1.
        mocap: Mocap index of its target body, or -1.
        dofs: Its DoFs: indices into :attr:`SceneLayout.dof_names` (and the actuator arrays).
        links: Its links: indices into :attr:`SceneLayout.link_names` (rows of ``contact_adr``).
        tips: Its fingertips: indices into :attr:`SceneLayout.tip_names`.
        root_pose_adr: sensordata addresses of its root's world position (3) and quaternion (4).
        penetration_adr: (parts,) sensordata address of each object part's ``mindist`` sensor against this
            hand (its root's subtree).
    """

    name: str
    root_body: int
    root_free_qpos: int
    root_free_dof: int
    mocap: int
    dofs: np.ndarray
    links: np.ndarray
    tips: np.ndarray
    root_pose_adr: tuple[int, int]
    penetration_adr: np.ndarray


@dataclass(frozen=True)
class SceneLayout:
    """Index arrays of a compiled, instrumented scene.

    Attributes:
        dof_names: The hand's DoF names (joint names without ``hand/``), in actuator order.
        actuators: Actuator ids, one per DoF.
        dof_qpos: qpos address of each DoF's joint.
        dof_qvel: qvel address of each DoF's joint.
        ctrl_range: (nu, 2) control range of each actuator (radians).
        link_names: Hand bodies (without ``hand/``) that have collision geoms, in body order.
        link_bodies: Their body ids.
        root_body: Body id of the hand's root.
        root_free_qpos: qpos address of the root's free joint (``hand_root="weld"``), or -1.
        root_free_dof: qvel address of that free joint, or -1.
        mocap: Mocap index of :data:`~handsim.builders.scene.HAND_TARGET`, or -1.
        tip_names: Fingertip sites (sites on a link named for a leaf joint), without ``hand/``.
        tip_sites: Their site ids.
        objects: The objects.
        contact_adr: (links, parts) sensordata address of each link × part contact sensor; parts are all
            objects' parts in order.
        penetration_adr: (parts,) sensordata address of each part's whole-hand ``mindist`` sensor.
        tip_adr: (tips,) sensordata address of each fingertip's world position (3).
        root_pose_adr: sensordata addresses of the hand root's world position (3) and quaternion (4).
        object_pose_adr: (objects, 2) addresses of each object root's world position and quaternion.
        hands: Each hand (:class:`HandLayout`); the root, mocap and penetration fields above are the first
            hand's.
    """

    dof_names: tuple[str, ...]
    actuators: np.ndarray
    dof_qpos: np.ndarray
    dof_qvel: np.ndarray
    ctrl_range: np.ndarray
    link_names: tuple[str, ...]
    link_bodies: np.ndarray
    root_body: int
    root_free_qpos: int
    root_free_dof: int
    mocap: int
    tip_names: tuple[str, ...]
    tip_sites: np.ndarray
    objects: tuple[ObjectLayout, ...]
    contact_adr: np.ndarray
    penetration_adr: np.ndarray
    tip_adr: np.ndarray
    root_pose_adr: tuple[int, int]
    object_pose_adr: np.ndarray
    hands: tuple[HandLayout, ...] = ()

    @property
    def part_labels(self) -> tuple[str, ...]:
        """Every object part as ``prefix + part`` (e.g. ``obj/body``), in the order of ``contact_adr``."""
        return tuple(o.prefix + p for o in self.objects for p in o.part_names)


def _hand_links(spec: mujoco.MjSpec) -> list[mujoco.MjsBody]:
    return [
        b
        for b in spec.bodies
        if b.name.startswith(HAND_PREFIX) and any(g.contype or g.conaffinity for g in b.geoms)
    ]


def _object_parts(spec: mujoco.MjSpec) -> list[mujoco.MjsBody]:
    return [b for b in spec.bodies if b.name.startswith("obj") and "/" in b.name]


def _hand_roots(spec: mujoco.MjSpec) -> list[mujoco.MjsBody]:
    return [b for b in spec.worldbody.bodies if b.name.startswith(HAND_PREFIX)]


def hand_name(root_body_name: str) -> str:
    """The hand a root body belongs to: ``hand/right/wrist`` → ``"right"``; a scene's only hand → ""."""
    rest = root_body_name.removeprefix(HAND_PREFIX)
    return rest.split("/")[0] if "/" in rest else ""


def _penetration_sensor(root: str, part: str, several: bool) -> str:
    return f"{PENETRATION_PREFIX}{root}|{part}" if several else f"{PENETRATION_PREFIX}{part}"


def instrument(spec: mujoco.MjSpec) -> mujoco.MjSpec:
    """Add the sensors the metrics read to a scene spec (in place; returned for chaining).

    Per hand link with collision geoms × object part: a contact sensor reporting up to
    :data:`CONTACT_SLOTS` contacts (count, force in the contact frame, distance). Per object part: a
    contact sensor between each whole hand (its root's subtree) and the part, reduced to the minimum
    distance (the deepest penetration when negative). World positions of the fingertip sites, and world
    poses of each hand's root and each object's root body. MuJoCo evaluates them inside ``mj_step`` (in
    the forward pass of its last step, 2 ms before the state it leaves); the loop only copies
    ``sensordata``.

    Args:
        spec: A scene from :func:`handsim.builders.build_scene`, not yet instrumented.

    Returns:
        ``spec``.

    Raises:
        ModelError: The scene is already instrumented.
    """
    if any(s.name.startswith((CONTACT_PREFIX, PENETRATION_PREFIX)) for s in spec.sensors):
        raise ModelError(f"scene {spec.modelname!r} is already instrumented")
    roots = _hand_roots(spec)
    if not roots:
        return spec
    body, subtree = mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_XBODY
    frame_bodies = roots + [b for b in spec.worldbody.bodies if b.name.startswith("obj")]
    for b in frame_bodies:  # xbody: the body frame (body would be its inertial frame)
        for prefix, kind in ((POSITION_PREFIX, mujoco.mjtSensor.mjSENS_FRAMEPOS),
                             (ORIENTATION_PREFIX, mujoco.mjtSensor.mjSENS_FRAMEQUAT)):  # fmt: skip
            spec.add_sensor(name=prefix + b.name, type=kind, objtype=subtree, objname=b.name)
    for site in spec.sites:
        parent = site.parent
        if site.name.startswith(HAND_PREFIX) and site.name != parent.name:
            spec.add_sensor(
                name=POSITION_PREFIX + site.name, type=mujoco.mjtSensor.mjSENS_FRAMEPOS,
                objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site.name,
            )  # fmt: skip
    for part in _object_parts(spec):
        for link in _hand_links(spec):
            spec.add_sensor(
                name=f"{CONTACT_PREFIX}{link.name}|{part.name}",
                type=mujoco.mjtSensor.mjSENS_CONTACT,
                objtype=body,
                objname=link.name,
                reftype=body,
                refname=part.name,
                intprm=[_FOUND | _FORCE | _DIST, _REDUCE_NONE, CONTACT_SLOTS],
            )
        for root in roots:
            spec.add_sensor(
                name=_penetration_sensor(root.name, part.name, len(roots) > 1),
                type=mujoco.mjtSensor.mjSENS_CONTACT,
                objtype=subtree,
                objname=root.name,
                reftype=body,
                refname=part.name,
                intprm=[_FOUND | _DIST, _REDUCE_MINDIST, 1],
            )
    return spec


def _id(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str) -> int:
    return int(mujoco.mj_name2id(model, kind, name))


def scene_layout(model: mujoco.MjModel) -> SceneLayout:
    """Find the hand, objects and metric sensors of a compiled, instrumented scene.

    Raises:
        ModelError: An actuator does not drive a hand joint, or the scene has no hand.
    """
    dof_names, actuators, dof_qpos, dof_qvel = _actuated_dofs(model)
    roots, links = _hand_bodies(model)
    tips = _tip_sites(model)
    objects = _object_layouts(model)
    parts_all = [model.body(c).name for o in objects for c in o.part_bodies]
    link_names = tuple(model.body(b).name.removeprefix(HAND_PREFIX) for b in links)
    tip_names = tuple(model.site(s).name.removeprefix(HAND_PREFIX) for s in tips)
    contact = _contact_adr(model, links, parts_all)
    hands = tuple(
        _hand_layout(model, root, parts_all, len(roots) > 1, dof_names, link_names, tip_names)
        for root in roots
    )
    first = hands[0]
    pose_adr = _object_pose_adr(model, objects)
    return SceneLayout(
        dof_names=dof_names,
        actuators=np.asarray(actuators, dtype=np.int64),
        dof_qpos=np.asarray(dof_qpos, dtype=np.int64),
        dof_qvel=np.asarray(dof_qvel, dtype=np.int64),
        ctrl_range=np.array(model.actuator_ctrlrange, dtype=float),
        link_names=link_names,
        link_bodies=np.asarray(links, dtype=np.int64),
        root_body=first.root_body,
        root_free_qpos=first.root_free_qpos,
        root_free_dof=first.root_free_dof,
        mocap=first.mocap,
        tip_names=tip_names,
        tip_sites=np.asarray(tips, dtype=np.int64),
        objects=objects,
        contact_adr=contact,
        penetration_adr=first.penetration_adr,
        tip_adr=np.array(
            [_sensor_adr(model, POSITION_PREFIX + model.site(s).name) for s in tips], dtype=np.int64
        ),
        root_pose_adr=first.root_pose_adr,
        object_pose_adr=pose_adr,
        hands=hands,
    )


def _actuated_dofs(model: mujoco.MjModel) -> tuple[tuple[str, ...], list[int], list[int], list[int]]:
    """The hand's DoF names, actuator ids, qpos and qvel addresses, in actuator order.

    Raises:
        ModelError: An actuator does not drive a hand joint.
    """
    dof_names, actuators, dof_qpos, dof_qvel = [], [], [], []
    for i in range(model.nu):
        name = model.actuator(i).name
        if not name.startswith(HAND_PREFIX) or int(model.actuator_trntype[i]) != int(
            mujoco.mjtTrn.mjTRN_JOINT
        ):
            raise ModelError(
                f"actuator {name!r} is not a hand joint actuator (expected '{HAND_PREFIX}<dof>_act')"
            )
        joint = int(model.actuator_trnid[i, 0])
        dof_names.append(model.joint(joint).name.removeprefix(HAND_PREFIX))
        actuators.append(i)
        dof_qpos.append(int(model.jnt_qposadr[joint]))
        dof_qvel.append(int(model.jnt_dofadr[joint]))
    return tuple(dof_names), actuators, dof_qpos, dof_qvel


def _hand_bodies(model: mujoco.MjModel) -> tuple[list[int], list[int]]:
    """Body ids of the hands' roots and of their links (hand bodies with collision geoms), in body order.

    Raises:
        ModelError: The scene has no hand.
    """
    hand_bodies = [i for i in range(model.nbody) if model.body(i).name.startswith(HAND_PREFIX)]
    if not hand_bodies:
        raise ModelError(f"the scene has no hand (no body named {HAND_PREFIX}…)")
    roots = [b for b in hand_bodies if int(model.body_parentid[b]) == 0]
    colliding = {
        int(model.geom_bodyid[g])
        for g in range(model.ngeom)
        if model.geom_contype[g] or model.geom_conaffinity[g]
    }
    return roots, [b for b in hand_bodies if b in colliding]


def _tip_sites(model: mujoco.MjModel) -> list[int]:
    """Site ids of the fingertips: hand sites not named for their body."""
    return [
        s
        for s in range(model.nsite)
        if model.site(s).name.startswith(HAND_PREFIX)
        and model.site(s).name != model.body(int(model.site_bodyid[s])).name
    ]


def _object_layouts(model: mujoco.MjModel) -> tuple[ObjectLayout, ...]:
    """The objects: one per world child body named ``obj…/…``, in body order."""
    objects = []
    for b in range(1, model.nbody):
        name = model.body(b).name
        if (name.startswith("obj") and "/" in name) and int(model.body_parentid[b]) == 0:
            objects.append(_object_layout(model, b, name[: name.index("/") + 1]))
    return tuple(objects)


def _object_layout(model: mujoco.MjModel, root: int, prefix: str) -> ObjectLayout:
    """The object whose root body is ``root``, its parts the bodies named ``prefix…``."""
    parts = [c for c in range(model.nbody) if model.body(c).name.startswith(prefix)]
    jnt = int(model.body_jntadr[root])
    hinge = [j for j in range(model.njnt) if model.joint(j).name == prefix + "hinge"]
    return ObjectLayout(
        prefix=prefix,
        root_body=root,
        free_qpos=int(model.jnt_qposadr[jnt]) if jnt >= 0 else -1,
        free_dof=int(model.jnt_dofadr[jnt]) if jnt >= 0 else -1,
        hinge_qpos=int(model.jnt_qposadr[hinge[0]]) if hinge else -1,
        hinge_dof=int(model.jnt_dofadr[hinge[0]]) if hinge else -1,
        part_bodies=tuple(parts),
        part_names=tuple(model.body(c).name.removeprefix(prefix) for c in parts),
        support_eq=_id(model, mujoco.mjtObj.mjOBJ_EQUALITY, prefix + SUPPORT_SUFFIX),
        collision_geoms=tuple(
            int(g)
            for g in range(model.ngeom)
            if int(model.geom_bodyid[g]) in parts and (model.geom_contype[g] or model.geom_conaffinity[g])
        ),
    )


def _contact_adr(model: mujoco.MjModel, links: list[int], parts: list[str]) -> np.ndarray:
    """(links, parts) sensordata address of each link × part contact sensor."""
    contact = np.full((len(links), len(parts)), -1, dtype=np.int64)
    for j, part in enumerate(parts):
        for i, link in enumerate(links):
            contact[i, j] = _sensor_adr(model, f"{CONTACT_PREFIX}{model.body(link).name}|{part}")
    return contact


def _object_pose_adr(model: mujoco.MjModel, objects: tuple[ObjectLayout, ...]) -> np.ndarray:
    """(objects, 2) sensordata addresses of each object root's world position and quaternion."""
    return np.array(
        [[_sensor_adr(model, POSITION_PREFIX + model.body(o.root_body).name),
          _sensor_adr(model, ORIENTATION_PREFIX + model.body(o.root_body).name)] for o in objects],
        dtype=np.int64,
    ).reshape(-1, 2)  # fmt: skip


def _hand_layout(
    model: mujoco.MjModel,
    root: int,
    parts: list[str],
    several: bool,
    dof_names: tuple[str, ...],
    link_names: tuple[str, ...],
    tip_names: tuple[str, ...],
) -> HandLayout:
    """The hand whose root body is ``root`` (its DoFs, links and tips found by its name prefix)."""
    root_name = model.body(root).name
    name = hand_name(root_name)
    own = hand_prefix(name).removeprefix(HAND_PREFIX)

    def mine(names: tuple[str, ...]) -> np.ndarray:
        return np.array([i for i, n in enumerate(names) if n.startswith(own)], dtype=np.int64)

    root_joint = int(model.body_jntadr[root])
    is_free = root_joint >= 0 and int(model.jnt_type[root_joint]) == int(mujoco.mjtJoint.mjJNT_FREE)
    target, weld = hand_target_name(name), hand_weld_name(name)
    target_id = _id(model, mujoco.mjtObj.mjOBJ_BODY, target)
    mocap = int(model.body_mocapid[target_id]) if target_id >= 0 else -1
    if (mocap >= 0) != (_id(model, mujoco.mjtObj.mjOBJ_EQUALITY, weld) >= 0):
        raise ModelError(f"scene has {target!r} without {weld!r} or the reverse")
    return HandLayout(
        name=name,
        root_body=root,
        root_free_qpos=int(model.jnt_qposadr[root_joint]) if is_free else -1,
        root_free_dof=int(model.jnt_dofadr[root_joint]) if is_free else -1,
        mocap=mocap,
        dofs=mine(dof_names),
        links=mine(link_names),
        tips=mine(tip_names),
        root_pose_adr=(
            _sensor_adr(model, POSITION_PREFIX + root_name),
            _sensor_adr(model, ORIENTATION_PREFIX + root_name),
        ),
        penetration_adr=np.array(
            [_sensor_adr(model, _penetration_sensor(root_name, part, several)) for part in parts],
            dtype=np.int64,
        ),
    )


def _sensor_adr(model: mujoco.MjModel, name: str) -> int:
    sensor = _id(model, mujoco.mjtObj.mjOBJ_SENSOR, name)
    if sensor < 0:
        raise ModelError(f"scene has no sensor {name!r}: instrument the spec before compiling")
    return int(model.sensor_adr[sensor])
