"""Build a MuJoCo hand (:class:`mujoco.MjSpec`) from a :class:`~handsim.datatypes.skeleton.Skeleton`.

The model reads like a document (Menagerie style): default classes first (``visual``, ``collision``, one
class per DoF kind carrying armature, damping and actuator gains), then one body per joint that has
children, one hinge per DoF, one position actuator per DoF.

Naming contract (later layers rely on it):

* MuJoCo joint name = DoF name (= the trajectory's ``dof_names``); actuator = DoF name + ``_act``.
* Every skeleton joint J has a site named ``mj_name(J)`` at its origin; fingertips are skeleton joints,
  so they have sites too. Bodies are named like their joint.

Joint ranges are the skeleton's DoF limits, and each actuator's ``ctrlrange`` equals its joint's range:
targets outside the anatomical limits are clamped by MuJoCo, never silently widened (trajectory readers
report how many samples fall outside).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt
from scipy.spatial import ConvexHull, QhullError

from handsim.builders.geom_classes import add_geom_classes
from handsim.builders.hand_geometry import (
    Capsule,
    HandGeometry,
    default_hand_mass,
    finger_chains,
    hand_geometry,
)
from handsim.builders.surfaces import SKIN, Surface
from handsim.datatypes.physical_ranges import HAND_MASS
from handsim.datatypes.rotations import matrix_to_quat
from handsim.datatypes.skeleton import Joint, Skeleton, mj_name
from handsim.errors import ModelError

SKIN_RGBA = (0.87, 0.70, 0.60, 1.0)
COLLISION_RGBA = (0.3, 0.5, 0.9, 0.4)


@dataclass(frozen=True)
class JointClass:
    """Dynamics shared by the DoFs of one kind (sources: ``docs/physics.md``).

    Attributes:
        damping: Joint damping, N·m·s/rad.
        kp: Position-actuator stiffness, N·m/rad.
        force: Actuator torque limit, N·m.
    """

    damping: float
    kp: float
    force: float


ARMATURE = 2e-4
"""Inertia added to every DoF, kg·m² (the links' own about their joints: 1.2e-6 at a DIP to 1.8e-4 at an
MCP). Measured need (``docs/physics.md``): without any, the lightest links ring at the 2 ms step under
random targets (976 rad/s); below 1e-4, fingers closing on a ball resting on the table squeeze it out
(Grasp-v0's scripted grasp launches it at 0.5 m/s); 2e-4 is twice that threshold."""

# Finger flexion: a 1 rad error gives 2 N·m (index MCP flexion strength is a few N·m); ~10 Hz bandwidth.
JOINT_CLASSES: dict[str, JointClass] = {
    "flex": JointClass(damping=0.05, kp=2.0, force=3.0),
    "abd": JointClass(damping=0.05, kp=1.5, force=2.0),
    "pron": JointClass(damping=0.05, kp=1.5, force=2.0),
    "rot": JointClass(damping=0.05, kp=1.5, force=2.0),
    "wrist": JointClass(damping=0.5, kp=20.0, force=15.0),
}


def _add_defaults(spec: mujoco.MjSpec, root_has_dofs: bool, skin: Surface) -> dict[str, mujoco.MjsDefault]:
    main = spec.default
    visual, collision = add_geom_classes(
        spec, surface=skin, visual_rgba=SKIN_RGBA, collision_rgba=COLLISION_RGBA
    )
    classes = {"visual": visual, "collision": collision}
    kinds = [k for k in JOINT_CLASSES if k != "wrist" or root_has_dofs]
    for kind in kinds:
        params = JOINT_CLASSES[kind]
        d = spec.add_default(kind, main)
        d.joint.armature = ARMATURE
        d.joint.damping = [params.damping, 0.0, 0.0]
        d.actuator.set_to_position(kp=params.kp)
        d.actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        d.actuator.forcerange = [-params.force, params.force]
        classes[kind] = d
    return classes


def _capsule_geoms(
    body: mujoco.MjsBody, capsule: Capsule, to_local, mass: float, classes: dict, name: str
) -> None:
    fromto = np.concatenate([to_local(capsule.start), to_local(capsule.end)])
    shape = {"type": mujoco.mjtGeom.mjGEOM_CAPSULE, "fromto": fromto.tolist(), "size": [capsule.radius, 0, 0]}
    # A capsule inside the palm carries its link's mass but does not collide.
    body.add_geom(classes["collision" if capsule.collides else "visual"], name=name, mass=mass, **shape)
    if capsule.collides:
        body.add_geom(classes["visual"], **shape)


def _skinned_hulls(skeleton: Skeleton, min_vertices: int = 8) -> dict[int, ConvexHull]:
    """Per-bone convex hulls from the skinned mesh, by joint index."""
    mesh = skeleton.mesh
    if mesh is None:
        raise ModelError(
            f"skeleton {skeleton.name!r} has no skinned mesh (.OFF + .SKIN); use collision='capsules'"
        )
    owner = np.argmax(mesh.weights, axis=1)
    hulls = {}
    for column, bone in enumerate(mesh.bones):
        verts = mesh.vertices[owner == column]
        if len(verts) < min_vertices:
            continue
        try:
            hull = ConvexHull(verts)
        except QhullError:
            continue  # flat or degenerate part: no hull (it would crash or mislead the collider)
        if hull.volume <= 1e-9:
            continue
        hulls[skeleton.joint_index(bone)] = hull
    return hulls


def build_hand(
    skeleton: Skeleton,
    *,
    mass: float | None = None,
    breadth: float | None = None,
    collision: str = "capsules",
    name: str | None = None,
    timestep: float = 0.002,
    force: bool = False,
    skin: Surface = SKIN,
) -> mujoco.MjSpec:
    """Build a position-controlled MuJoCo hand from a skeleton.

    Args:
        skeleton: The hand skeleton (SI units).
        mass: Whole-hand mass in kg; by default 0.45 kg scaled with the cube of the hand length.
        breadth: Hand breadth in metres for sizing the capsules and palm; estimated when None.
        collision: ``"capsules"`` (capsules per bone and a convex palm) or ``"mesh"`` (a convex hull per
            bone from the skinned ``.OFF`` mesh, each vertex assigned to its highest-weight bone; parts
            whose hulls intersect in the rest pose do not collide with each other).
        name: Model name; the skeleton's name by default.
        timestep: Simulation timestep in seconds.
        force: Accept a ``mass`` outside :data:`handsim.datatypes.physical_ranges.HAND_MASS` (0.1 to 1 kg).
        skin: Contact parameters of the collision geoms: :data:`~handsim.builders.surfaces.SKIN` (the
            geometry is the undeformed finger), or :data:`~handsim.builders.surfaces.FITTED_SKIN` for a
            surface fitted to observed, compressed skin (the Tzionas hands).

    Returns:
        An uncompiled spec. The root body sits at the skeleton's root rest position and frame; DoFs of
        the root joint (a wrist) are hinges of the root body, otherwise the root is fixed to the world.

    Raises:
        ModelError: Unknown ``collision`` option, or ``"mesh"`` without a skinned mesh.
        OutOfRangeError: ``mass`` is not a human hand's and ``force`` is False.
    """
    if mass is not None:
        HAND_MASS.check(mass, force=force)
    if collision not in ("capsules", "mesh"):
        raise ModelError(f"unknown collision option {collision!r}; expected 'capsules' or 'mesh'")
    spec = _new_spec(name or mj_name(skeleton.name), timestep)
    classes = _add_defaults(spec, bool(skeleton.dofs_of(skeleton.joints[0].name)), skin)
    geometry = hand_geometry(skeleton, breadth)
    hulls = _skinned_hulls(skeleton) if collision == "mesh" else {}
    density = _density(skeleton, geometry, hulls, collision, mass)
    bodies = _add_bodies(spec, skeleton, classes)
    if collision == "capsules":
        _add_capsule_collision(spec, skeleton, geometry, bodies, density, classes)
    else:
        _add_hull_collision(spec, skeleton, hulls, bodies, density, classes)
    touching = _overlapping_hulls(hulls) if collision == "mesh" else set()
    touching |= {(0, i) for i in geometry.palm_links if i in bodies}  # palm vs. metacarpal and proximal
    _add_excludes(spec, skeleton, geometry.rigid_to_root, bodies, touching)
    return spec


def _new_spec(name: str, timestep: float) -> mujoco.MjSpec:
    """An empty spec in radians with the hand's solver options: implicitfast, elliptic cones, impratio 10."""
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.modelname = name
    spec.option.timestep = timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 10.0
    return spec


def _density(
    skeleton: Skeleton,
    geometry: HandGeometry,
    hulls: dict[int, ConvexHull],
    collision: str,
    mass: float | None,
) -> float:
    """The one density, kg/m³, that gives the collision geometry the hand's whole mass.

    Raises:
        ModelError: The mass or the collision geometry's volume is not positive.
    """
    if collision == "mesh":
        total_volume = sum(hull.volume for hull in hulls.values())
    else:
        total_volume = sum(c.volume for c in geometry.capsules) + geometry.palm_volume
    total_mass = default_hand_mass(skeleton.hand_length) if mass is None else mass
    if total_mass <= 0 or total_volume <= 0:
        raise ModelError(f"hand {skeleton.name!r}: mass ({total_mass}) and volume must be positive")
    return total_mass / total_volume


def _to_local(skeleton: Skeleton, index: int) -> Callable[[npt.ArrayLike], np.ndarray]:
    """The map from world (rest pose) coordinates to the frame of joint ``index``'s body."""
    frame, origin = skeleton.joints[index].frame, skeleton.joints[index].position
    return lambda p: (np.asarray(p) - origin) @ frame


def _add_bodies(
    spec: mujoco.MjSpec, skeleton: Skeleton, classes: dict[str, mujoco.MjsDefault]
) -> dict[int, mujoco.MjsBody]:
    """One body per joint with children, in skeleton order, with its hinges and their actuators.

    A leaf joint (a fingertip) is a site on its parent's body. Returns the bodies by joint index.
    """
    has_children = {j.parent for j in skeleton.joints}
    bodies: dict[int, mujoco.MjsBody] = {}
    for i, joint in enumerate(skeleton.joints):
        if i not in has_children and joint.parent >= 0:  # a leaf (fingertip): a site on its parent
            site_pos = _to_local(skeleton, joint.parent)(joint.position).tolist()
            bodies[joint.parent].add_site(name=mj_name(joint.name), pos=site_pos, size=[0.003, 0, 0])
            continue
        if joint.parent < 0:
            parent_body, pos, rot = spec.worldbody, joint.position, joint.frame
        else:
            parent = skeleton.joints[joint.parent]
            parent_body = bodies[joint.parent]
            pos = _to_local(skeleton, joint.parent)(joint.position)
            rot = parent.frame.T @ joint.frame
        body = parent_body.add_body(
            name=mj_name(joint.name), pos=pos.tolist(), quat=matrix_to_quat(rot).tolist()
        )
        bodies[i] = body
        body.add_site(name=mj_name(joint.name), pos=[0.0, 0.0, 0.0], size=[0.003, 0, 0])
        _add_hinges(spec, body, skeleton, joint, classes)
    return bodies


def _add_hinges(
    spec: mujoco.MjSpec,
    body: mujoco.MjsBody,
    skeleton: Skeleton,
    joint: Joint,
    classes: dict[str, mujoco.MjsDefault],
) -> None:
    """A hinge per DoF of ``joint`` on its body and a position actuator whose ctrlrange is its range."""
    for dof in skeleton.dofs_of(joint.name):
        cls = classes["wrist" if joint.parent < 0 else dof.kind]
        body.add_joint(
            cls,
            name=dof.name,
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=np.asarray(dof.axis).tolist(),
            range=[dof.lower, dof.upper],
        )
        spec.add_actuator(
            cls,
            name=f"{dof.name}_act",
            target=dof.name,
            trntype=mujoco.mjtTrn.mjTRN_JOINT,
            ctrlrange=[dof.lower, dof.upper],
        )


def _add_capsule_collision(
    spec: mujoco.MjSpec,
    skeleton: Skeleton,
    geometry: HandGeometry,
    bodies: dict[int, mujoco.MjsBody],
    density: float,
    classes: dict[str, mujoco.MjsDefault],
) -> None:
    """Capsules per bone and the convex palm, each with its share of the mass."""
    for capsule in geometry.capsules:
        name_i = mj_name(skeleton.joints[capsule.joint].name)
        _capsule_geoms(
            bodies[capsule.joint],
            capsule,
            _to_local(skeleton, capsule.joint),
            density * capsule.volume,
            classes,
            f"{name_i}_capsule",
        )
    if len(geometry.palm_vertices):
        _add_mesh_geoms(
            spec,
            bodies[0],
            "palm",
            _to_local(skeleton, 0)(geometry.palm_vertices),
            density * geometry.palm_volume,
            classes,
        )


def _add_hull_collision(
    spec: mujoco.MjSpec,
    skeleton: Skeleton,
    hulls: dict[int, ConvexHull],
    bodies: dict[int, mujoco.MjsBody],
    density: float,
    classes: dict[str, mujoco.MjsDefault],
) -> None:
    """The convex hull of each bone's skin vertices, with its share of the mass."""
    for index, hull in hulls.items():
        _add_mesh_geoms(
            spec,
            bodies[index],
            f"{mj_name(skeleton.joints[index].name)}_hull",
            _to_local(skeleton, index)(hull.points[hull.vertices]),
            density * hull.volume,
            classes,
        )


def _add_mesh_geoms(
    spec: mujoco.MjSpec, body: mujoco.MjsBody, name: str, vertices: np.ndarray, mass: float, classes: dict
) -> None:
    spec.add_mesh(name=name, uservert=np.asarray(vertices, dtype=float).ravel().tolist())
    body.add_geom(classes["collision"], name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name, mass=mass)
    body.add_geom(classes["visual"], type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name)


def _overlapping_hulls(hulls: dict[int, ConvexHull]) -> set[tuple[int, int]]:
    """Pairs of joints whose rest-pose hulls intersect (the skinned surface is continuous there).

    Two convex hulls intersect iff some point satisfies both hulls' facet inequalities: a linear
    feasibility problem.
    """
    from scipy.optimize import linprog  # lazy: SciPy's optimisers (60 ms), only where a hull needs one

    equations = {i: hull.equations for i, hull in hulls.items()}
    pairs = set()
    keys = sorted(equations)
    for k, a in enumerate(keys):
        for b in keys[k + 1 :]:
            eq = np.vstack([equations[a], equations[b]])
            result = linprog(np.zeros(3), A_ub=eq[:, :3], b_ub=-eq[:, 3], bounds=[(None, None)] * 3)
            if result.status == 0:
                pairs.add((a, b))
    return pairs


def _add_excludes(
    spec: mujoco.MjSpec,
    skeleton: Skeleton,
    rigid: frozenset[int],
    bodies: dict[int, mujoco.MjsBody],
    touching: set[tuple[int, int]],
) -> None:
    """Exclude contacts between links that touch by construction.

    Every body is excluded with its parent's rigid group (its parent, and up to the root when the parent
    is rigidly attached to it); the bodies rigidly attached to the root are excluded among themselves;
    the links of one finger are excluded among themselves (capsules meet at every joint, and a curled
    rest pose makes non-adjacent phalanges touch); and the ``touching`` pairs (palm vs. each finger's
    first two links, mesh parts whose rest hulls intersect) are excluded.
    """
    pairs: set[tuple[int, int]] = set()
    for i in bodies:
        p = skeleton.joints[i].parent
        while p >= 0:
            pairs.add((p, i))
            if p not in rigid or p == 0:
                break
            p = skeleton.joints[p].parent
    groups = [sorted(i for i in rigid if i in bodies)]
    groups += [sorted(i for i in chain if i in bodies) for chain in finger_chains(skeleton)]
    for group in groups:
        pairs |= {(a, b) for k, a in enumerate(group) for b in group[k + 1 :]}
    pairs |= touching
    for a, b in sorted(pairs):
        spec.add_exclude(bodyname1=bodies[a].name, bodyname2=bodies[b].name)
