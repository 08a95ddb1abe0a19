"""Objects become MuJoCo bodies: hull collision geoms, a visual mesh, mass and inertia from the mesh.

An object is described by plain data (:class:`ObjectModel`: one or two :class:`ObjectPart`, an optional
:class:`Hinge`, a density or a total mass) and built in two steps:

* :func:`prepare_object` decomposes every part that needs it (cached CoACD, see
  :mod:`handsim.builders.decompose`) and computes each part's mass properties from its watertight mesh;
* :func:`object_spec` turns the prepared object into a :class:`mujoco.MjSpec`.

:func:`build_object` does both. The spec has one body per part, named after the part (``body`` for a
rigid object); the root part carries a free joint ``free``, the second part a hinge ``hinge``. Body frames
are the object frame: a recorded object pose is the root body's pose, and the child part's frame coincides
with the root's at articulation 0. A hinge with ``parts_collide`` gets explicit contact pairs
``pair_<i>_<j>`` between the two parts' collision geoms (MuJoCo never collides a body with its parent, and
a global flag would change every parent–child pair of the hand too). Collision geoms are ``hull_<i>``
(``<part>_hull_<i>`` for parts of an articulated object) or exact primitives ``prim_<i>``; the visual mesh is
``visual`` (``<part>_visual``).

Mass and inertia are set explicitly on each body (``explicitinertial``) from the repaired watertight mesh
and the density — summing overlapping hulls would over-count the mass — and every geom has density 0.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

from handsim.builders.decompose import decompose
from handsim.builders.decomposition_types import Decomposition, DecompositionParams
from handsim.builders.geom_classes import add_geom_classes
from handsim.builders.surfaces import CONTACT_CONDIM, OBJECT, Surface
from handsim.datatypes.mesh import Mesh
from handsim.datatypes.mesh_mass import mesh_mass
from handsim.datatypes.object_model import Hinge, ObjectModel, ObjectPart, Primitive
from handsim.datatypes.physical_ranges import DENSITY, OBJECT_MASS
from handsim.datatypes.rotations import quat_to_matrix
from handsim.errors import ModelError

OBJECT_RGBA = (0.55, 0.60, 0.68, 1.0)
HULL_RGBA = (0.9, 0.5, 0.2, 0.4)
HINGE_DAMPING = 1e-3  # N·m·s/rad: a little viscous loss so a free hinge settles
HOLD_SOLREF_FRICTION = (0.004, 1.0)
HOLD_SOLIMP_FRICTION = (0.99, 0.999, 0.001, 0.5, 2.0)
"""A hinge that holds its pose: its dry friction is made nearly hard (time constant 2 steps, impedance
0.99–0.999). MuJoCo's friction constraint is soft, so with its defaults (0.02 s; 0.9–0.95) a lid held by
friction creeps shut at 6–17°/s; with these, ≤ 0.3°/s (measured on the synthetic ARCTIC templates,
``docs/objects.md``)."""
HINGE_STOP_SOLREF = (0.005, 1.0)
"""Time constant and damping ratio of a hinge's range limit and of the contact pairs between the parts: a lid
dropped shut sinks ≤ 0.2° past its closed pose at impact (0.6–2.9° with MuJoCo's default 0.02 s)."""


@dataclass(frozen=True)
class MassProperties:
    """Mass properties of one part in the object frame.

    Attributes:
        mass: kg.
        com: Centre of mass, metres, shape (3,).
        inertia: Inertia tensor about the centre of mass, kg·m², shape (3, 3).
        volume: The volume the mass was computed from, m³.
    """

    mass: float
    com: np.ndarray
    inertia: np.ndarray
    volume: float


@dataclass(frozen=True)
class PreparedObject:
    """An object with its collision hulls and mass properties computed, ready for :func:`object_spec`.

    Attributes:
        model: The object.
        decompositions: Part name → decomposition (parts with primitives have none).
        mass_properties: Part name → mass properties.
        notes: What was decided while preparing (mass distribution, skipped decompositions …).
    """

    model: ObjectModel
    decompositions: dict[str, Decomposition]
    mass_properties: dict[str, MassProperties]
    notes: tuple[str, ...] = field(default=())

    @property
    def total_mass(self) -> float:
        """Total mass in kg."""
        return float(sum(p.mass for p in self.mass_properties.values()))


def prepare_object(
    model: ObjectModel,
    params: DecompositionParams | None = None,
    *,
    cache_dir: str | None = None,
    use_cache: bool = True,
    progress: bool = False,
    force: bool = False,
) -> PreparedObject:
    """Compute the object's mass properties, check its mass, and decompose its parts (cached).

    Args:
        model: The object.
        params: CoACD parameters (defaults of :class:`DecompositionParams`).
        cache_dir: Decomposition cache directory (default: ``default_cache_dir()``).
        use_cache: Read and write the decomposition cache.
        progress: Show a progress bar while CoACD runs.
        force: Accept a density or total mass outside :data:`handsim.datatypes.physical_ranges.DENSITY` /
            :data:`~handsim.datatypes.physical_ranges.OBJECT_MASS`.

    Returns:
        The prepared object.

    Raises:
        OutOfRangeError: The density or the total mass (mesh volume × density) is outside its documented
            range and ``force`` is False; checked before any decomposition.
        DecompositionError: CoACD failed or timed out on a part (the message names the mesh).
    """
    params = params or DecompositionParams()
    masses, notes = _mass_properties(model)
    _check_mass(model, masses, force)
    decompositions = {
        part.name: decompose(part.mesh, params, cache_dir=cache_dir, use_cache=use_cache, progress=progress)
        for part in model.parts
        if not part.primitives
    }
    return PreparedObject(model, decompositions, masses, tuple(notes))


def _mass_properties(model: ObjectModel) -> tuple[dict[str, MassProperties], list[str]]:
    """Each part's mass properties from its mesh and the density (or the total mass), with notes."""
    notes: list[str] = []
    if model.density is not None:
        masses = {p.name: _mesh_mass_properties(p.mesh, model.density) for p in model.parts}
    else:
        solids = {p.name: p.mesh if p.mesh.watertight else _convex_hull(p.mesh) for p in model.parts}
        volume = sum(s.volume for s in solids.values())
        density = model.mass / volume
        masses = {name: _mesh_mass_properties(solid, density) for name, solid in solids.items()}
        hulled = [p.name for p in model.parts if not p.mesh.watertight]
        if hulled:
            notes.append(
                f"mass {model.mass:g} kg given; parts {hulled} are open, so their volume and inertia come "
                "from their convex hulls"
            )
    return masses, notes


def _convex_hull(mesh: Mesh) -> Mesh:
    """The convex hull of an open mesh (its solid for the mass, when the total mass is given)."""
    hull = mesh.to_trimesh().convex_hull
    return Mesh(
        np.asarray(hull.vertices, dtype=float),
        np.asarray(hull.faces, dtype=np.int64),
        source=f"convex hull of {mesh.source}",
    )


def _check_mass(model: ObjectModel, masses: dict[str, MassProperties], force: bool) -> None:
    """Refuse a density or total mass outside its documented range, unless forced.

    The density checked is the given one, or the given mass over the volume the mass was spread over.
    """
    subject = f"object {model.name!r} "
    volume = sum(p.volume for p in masses.values())
    total = sum(p.mass for p in masses.values())
    cm3 = f"{volume * 1e6:.4g} cm³"
    if model.density is not None:
        DENSITY.check(model.density, force=force, subject=subject)
        OBJECT_MASS.check(total, force=force, subject=subject, context=f" ({cm3} at {model.density:g} kg/m³)")
    else:
        OBJECT_MASS.check(total, force=force, subject=subject)
        DENSITY.check(total / volume, force=force, subject=subject, context=f" ({total:g} kg over {cm3})")


def hinge_friction(hinge: Hinge, child: MassProperties, gravity: float = 9.81) -> float:
    """Dry friction torque (N·m) that holds the child part still against gravity, or 0.

    The largest gravity torque about the hinge is m·g·r, r the distance of the child's centre of mass from
    the axis; 1.5 times that holds the part in any orientation of the object.
    """
    if not hinge.holds_pose:
        return 0.0
    axis = np.asarray(hinge.axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    offset = child.com - np.asarray(hinge.pos, dtype=float)
    lever = float(np.linalg.norm(offset - (offset @ axis) * axis))
    return 1.5 * child.mass * gravity * lever


def _mesh_mass_properties(mesh: Mesh, density: float) -> MassProperties:
    """Mass, centre of mass and inertia of a closed mesh of uniform density."""
    props = mesh_mass(mesh.vertices, mesh.faces, density)
    if not props.volume > 0:
        raise ModelError(f"{mesh.source or 'mesh'}: volume {props.volume} m³ is not positive")
    return MassProperties(mass=props.mass, com=props.center_mass, inertia=props.inertia, volume=props.volume)


def object_spec(
    prepared: PreparedObject,
    *,
    free: bool = True,
    surface: Surface = OBJECT,
    rgba: Sequence[float] = OBJECT_RGBA,
) -> mujoco.MjSpec:
    """The MuJoCo spec of a prepared object.

    Args:
        prepared: The object from :func:`prepare_object`.
        free: Give the root body a free joint (False: the object is fixed to its parent frame).
        surface: Contact parameters of the collision geoms (:mod:`handsim.builders.surfaces`; skin and the
            table have priority over them, so they act between objects, and between two parts).
        rgba: Colour of the visual mesh.

    Returns:
        The spec; it is not compiled.
    """
    model = prepared.model
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.modelname = model.name
    visual, collision = add_geom_classes(
        spec, surface=surface, visual_rgba=rgba, collision_rgba=HULL_RGBA, density=0.0
    )

    single = len(model.parts) == 1
    parent = spec.worldbody
    for index, part in enumerate(model.parts):
        body = parent.add_body(name=part.name)
        if index == 0:
            if free:
                body.add_freejoint(name="free")
        else:
            hinge = model.hinge
            assert hinge is not None  # guaranteed by ObjectModel
            _add_hinge(body, hinge, prepared.mass_properties[part.name])
        _set_inertia(body, prepared.mass_properties[part.name])
        prefix = "" if single else f"{part.name}_"
        _add_visual(spec, body, visual, part.mesh, f"{prefix}visual")
        _add_collision(spec, body, collision, prepared, part, prefix)
        parent = body
    if not single:
        spec.add_exclude(bodyname1=model.parts[0].name, bodyname2=model.parts[1].name)
        if model.hinge is not None and model.hinge.parts_collide:
            _add_part_pairs(spec, model.parts[0].name, model.parts[1].name, surface)
    return spec


def _add_hinge(body: mujoco.MjsBody, hinge: Hinge, child: MassProperties) -> None:
    """The hinge of an articulated object's second part: damped, with friction that holds it, its stops."""
    joint = body.add_joint(
        name="hinge",
        type=mujoco.mjtJoint.mjJNT_HINGE,
        axis=list(hinge.axis),
        pos=list(hinge.pos),
        damping=HINGE_DAMPING,
        frictionloss=hinge_friction(hinge, child),
    )
    if hinge.holds_pose:
        joint.solref_friction = list(HOLD_SOLREF_FRICTION)
        joint.solimp_friction = list(HOLD_SOLIMP_FRICTION)
    if hinge.range is not None:
        joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
        joint.range = list(hinge.range)
        joint.solref_limit = list(HINGE_STOP_SOLREF)


def _set_inertia(body: mujoco.MjsBody, props: MassProperties) -> None:
    """Set a part's mass, centre of mass and full inertia explicitly (not summed from overlapping hulls)."""
    body.explicitinertial = True
    body.mass = props.mass
    body.ipos = props.com.tolist()
    i = props.inertia
    body.fullinertia = [i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]]


def _add_collision(
    spec: mujoco.MjSpec,
    body: mujoco.MjsBody,
    collision: mujoco.MjsDefault,
    prepared: PreparedObject,
    part: ObjectPart,
    prefix: str,
) -> None:
    """A part's collision geoms: its primitives when it has them, else its convex hulls as meshes."""
    if part.primitives:
        for k, prim in enumerate(part.primitives):
            body.add_geom(
                collision,
                name=f"{prefix}prim_{k}",
                type=_PRIMITIVE_TYPES[prim.kind],
                size=_geom_size(prim),
                pos=list(prim.pos),
                quat=list(prim.quat),
            )
        return
    for k, hull in enumerate(prepared.decompositions[part.name].hulls):
        name = f"{prefix}hull_{k}"
        spec.add_mesh(
            name=name, uservert=hull.vertices.ravel().tolist(), userface=hull.faces.ravel().tolist()
        )
        body.add_geom(collision, name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name)


def _add_part_pairs(spec: mujoco.MjSpec, parent: str, child: str, surface: Surface) -> None:
    """Explicit contact pairs between every collision geom of two parts (``pair_<i>_<j>``).

    A pair takes no parameters from its geoms: condim and friction are set to the geoms' own (sliding,
    sliding, torsional, rolling, rolling), solref to :data:`HINGE_STOP_SOLREF`, solimp stays MuJoCo's default.
    """
    geoms = {parent: [], child: []}
    for geom in spec.geoms:
        body = geom.parent.name
        if body in geoms and not (geom.contype == 0 and geom.conaffinity == 0):
            geoms[body].append(geom.name)
    slide, torsion = surface.sliding, surface.torsional
    for i, a in enumerate(geoms[parent]):
        for j, b in enumerate(geoms[child]):
            spec.add_pair(
                name=f"pair_{i}_{j}", geomname1=a, geomname2=b, condim=CONTACT_CONDIM,
                friction=[slide, slide, torsion, 0.0, 0.0], solref=list(HINGE_STOP_SOLREF),
            )  # fmt: skip


_PRIMITIVE_TYPES = {
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
    "box": mujoco.mjtGeom.mjGEOM_BOX,
    "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
}


def _geom_size(prim: Primitive) -> list[float]:
    size = [*prim.size, 0.0, 0.0][:3]
    return [float(s) for s in size]


def _add_visual(
    spec: mujoco.MjSpec, body: mujoco.MjsBody, cls: mujoco.MjsDefault, mesh: Mesh, name: str
) -> None:
    vis = spec.add_mesh(
        name=name, uservert=mesh.vertices.ravel().tolist(), userface=mesh.faces.ravel().tolist()
    )
    if not mesh.watertight:
        vis.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
    body.add_geom(cls, name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name)


def build_object(
    model: ObjectModel,
    params: DecompositionParams | None = None,
    *,
    cache_dir: str | None = None,
    use_cache: bool = True,
    progress: bool = False,
    free: bool = True,
    surface: Surface = OBJECT,
    force: bool = False,
) -> mujoco.MjSpec:
    """Build an object's MuJoCo spec: :func:`prepare_object` then :func:`object_spec`.

    Args:
        model: The object.
        params: CoACD parameters.
        cache_dir: Decomposition cache directory.
        use_cache: Read and write the decomposition cache.
        progress: Show a progress bar while CoACD runs.
        free: Give the root body a free joint.
        surface: Contact parameters of the collision geoms (:mod:`handsim.builders.surfaces`).
        force: Accept a density or mass outside the documented ranges (see :func:`prepare_object`).

    Returns:
        The spec; it is not compiled.

    Raises:
        OutOfRangeError: The density or total mass is implausible and ``force`` is False.
        DecompositionError: CoACD failed or timed out on a part.
    """
    prepared = prepare_object(
        model, params, cache_dir=cache_dir, use_cache=use_cache, progress=progress, force=force
    )
    return object_spec(prepared, free=free, surface=surface)


def object_bounds(spec: mujoco.MjSpec) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned bounds of an object spec's collision geometry in its object frame (articulation 0).

    Args:
        spec: A spec made by :func:`object_spec`.

    Returns:
        Lower and upper corners, metres.
    """
    allp = object_points(spec)
    return allp.min(axis=0), allp.max(axis=0)


def object_points(spec: mujoco.MjSpec) -> np.ndarray:
    """Points whose convex hull bounds the object's collision geometry, in its object frame.

    Hull vertices and primitive bounding-box corners at articulation 0, shape (n, 3), metres.

    Raises:
        ModelError: The spec has no collision geometry.
    """
    points: list[np.ndarray] = []
    meshes = {m.name: np.asarray(m.uservert).reshape(-1, 3) for m in spec.meshes}
    for geom in spec.geoms:
        if geom.contype == 0 and geom.conaffinity == 0:
            continue
        if int(geom.type) == int(mujoco.mjtGeom.mjGEOM_MESH):
            points.append(meshes[geom.meshname])
            continue
        points.append(_primitive_corners(geom))
    if not points:
        raise ModelError(f"object spec {spec.modelname!r} has no collision geometry")
    return np.vstack(points)


def _primitive_corners(geom: mujoco.MjsGeom) -> np.ndarray:
    """Corners of a primitive geom's bounding box in its body frame."""
    s = np.asarray(geom.size, dtype=float)
    kind = int(geom.type)
    if kind == int(mujoco.mjtGeom.mjGEOM_SPHERE):
        half = np.full(3, s[0])
    elif kind == int(mujoco.mjtGeom.mjGEOM_BOX):
        half = s[:3]
    elif kind == int(mujoco.mjtGeom.mjGEOM_CYLINDER):
        half = np.array([s[0], s[0], s[1]])
    elif kind == int(mujoco.mjtGeom.mjGEOM_CAPSULE):
        half = np.array([s[0], s[0], s[0] + s[1]])
    else:
        raise ModelError(f"geom {geom.name!r}: unsupported primitive type {kind}")
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    return corners @ quat_to_matrix(geom.quat).T + np.asarray(geom.pos, dtype=float)
