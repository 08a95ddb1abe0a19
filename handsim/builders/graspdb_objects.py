"""The GraspDB14 objects (report Table 4.1, ids 1–16) as generated meshes with realistic sizes and masses.

The report gives only a few sizes (tennis ball 64 mm, pen 2 cm, bottle 8 cm and its cap 3 cm, oval jar lid
7 cm, glass 62 mm, notebook 15 mm thick, cylinders 10 and 25 mm, carton 7.6 × 26 × 37.5 cm); every other
dimension and every mass is a typical real-world value, chosen and explained in each object's
``size_note`` and ``notes`` and in ``docs/objects.md``.

Frame of every object: origin at the centre of the mesh's axis-aligned bounding box, z up as the object
stands or lies on the table in the recordings, x along the longest horizontal extent (the mug's handle
points to +x), units metres. Meshes are generated (no files, no randomness), watertight without any repair
by :func:`handsim.mesh.validate_mesh`, and cached per process. Objects whose collision shape is exactly a
set of MuJoCo primitives carry them in ``primitives`` (no convex decomposition needed); the hollow or
waisted ones have ``primitives == ()`` and must be decomposed.

No MuJoCo imports here: plain data, numpy and trimesh.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import trimesh

from handsim.errors import HandsimError, MeshError
from handsim.mesh import Mesh, validate_mesh
from handsim.object_model import ObjectModel, ObjectPart, Primitive

__all__ = [
    "GRASPDB_OBJECTS",
    "GraspDBObject",
    "Primitive",
    "UnknownObjectError",
    "clear_mesh_cache",
    "graspdb_object",
]

MM = 1e-3  # metres per millimetre: all geometry below is written in mm
SECTIONS = 64  # segments around a revolved body; a multiple of 4 puts vertices on the ±x and ±y extremes
SPHERE_RINGS = 32  # meridian segments of a sphere (pole to pole)
_Q_Z_TO_X = (math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0)  # 90° about y: a cylinder's local z along object x


class UnknownObjectError(HandsimError, KeyError):
    """A name or GraspDB id that is not in the catalogue; the message lists the valid ones."""

    def __str__(self) -> str:
        # KeyError would print the message quoted; show it as written.
        return str(self.args[0]) if self.args else ""


@dataclass(frozen=True)
class GraspDBObject:
    """One object of the GraspDB14 catalogue.

    Attributes:
        name: Snake-case name, e.g. ``"tennis_ball"``, ``"carton_standing"``.
        graspdb_id: The object id of report Table 4.1 (first field of a motion file name).
        description: The object as the report names it in Table 4.1.
        mass_kg: Mass in kg (see ``notes`` for the source or the reasoning).
        size_note: The key dimensions in mm and where they come from.
        primitives: The exact collision shape as MuJoCo primitives in the object frame, or ``()`` when the
            mesh must be decomposed into convex hulls.
        notes: Decisions taken for this object (material, fill, what the report leaves open).
    """

    name: str
    graspdb_id: int
    description: str
    mass_kg: float
    size_note: str
    primitives: tuple[Primitive, ...]
    notes: tuple[str, ...]

    def mesh(self) -> Mesh:
        """The object's watertight triangle mesh in metres, in the object frame (cached per process).

        The arrays are read-only: they are shared by every caller.
        """
        return _cached_mesh(self.name)

    @property
    def density_kg_m3(self) -> float:
        """Mass divided by the mesh's enclosed volume, kg/m³ (uniform density giving ``mass_kg``)."""
        return self.mass_kg / self.mesh().volume

    def object_model(self) -> ObjectModel:
        """The object as a one-part :class:`~handsim.object_model.ObjectModel` for the object builder.

        The density is chosen so that mesh volume × density equals ``mass_kg``.
        """
        return ObjectModel(
            name=self.name,
            parts=(ObjectPart("body", self.mesh(), self.primitives),),
            density=self.density_kg_m3,
            source=f"GraspDB14 object {self.graspdb_id} ({self.description}), generated",
            notes=(self.size_note, *self.notes),
        )


def clear_mesh_cache() -> None:
    """Forget the cached meshes (they are regenerated, identically, on the next call)."""
    _cached_mesh.cache_clear()


# --------------------------------------------------------------------------------------------------------
# Mesh generation (all lengths in mm, converted to metres and centred at the end)


def _box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> trimesh.Trimesh:
    lo_a, hi_a = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(
        extents=hi_a - lo_a, transform=trimesh.transformations.translation_matrix((lo_a + hi_a) / 2)
    )


def _box_primitive(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> Primitive:
    """A box primitive (metres) spanning the corners ``lo``..``hi`` given in mm."""
    half = (np.asarray(hi, float) - np.asarray(lo, float)) / 2 * MM
    pos = (np.asarray(hi, float) + np.asarray(lo, float)) / 2 * MM
    return Primitive("box", tuple(map(float, half)), (float(pos[0]), float(pos[1]), float(pos[2])))


def _revolve(profile_mm: list[tuple[float, float]]) -> trimesh.Trimesh:
    """A solid of revolution about z from a closed (r, z) profile running counter-clockwise.

    The profile starts and ends on the axis (r = 0); the segment along the axis closes it.
    """
    mesh = trimesh.creation.revolve(np.asarray(profile_mm, float), sections=SECTIONS)
    if not (mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0):  # pragma: no cover
        raise MeshError("revolved profile is not a closed, outward-wound solid (profile must run CCW)")
    return mesh


def _sphere(radius_mm: float) -> trimesh.Trimesh:
    t = np.linspace(-np.pi / 2, np.pi / 2, SPHERE_RINGS + 1)
    profile = np.column_stack((radius_mm * np.cos(t), radius_mm * np.sin(t)))
    profile[[0, -1], 0] = 0.0  # exactly on the axis
    return _revolve(profile.tolist())


def _cylinder_x(radius_mm: float, length_mm: float) -> trimesh.Trimesh:
    """A cylinder centred at the origin with its axis along x."""
    rot = trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0))
    return trimesh.creation.cylinder(radius=radius_mm, height=length_mm, sections=SECTIONS, transform=rot)


def _tube(path: np.ndarray, normal: np.ndarray, half_width: float, half_thickness: float) -> trimesh.Trimesh:
    """A closed tube of elliptic cross-section swept along ``path``, with planar end caps.

    Args:
        path: Centre line, shape (S, 3), mm.
        normal: Unit in-plane normal of the centre line at each point, shape (S, 3); the cross-section's
            other axis is the path plane's normal (+y here).
        half_width: Cross-section half-size along y, mm.
        half_thickness: Cross-section half-size along ``normal``, mm.
    """
    n_ring = 16
    phi = 2 * np.pi * (np.arange(n_ring) + 0.5) / n_ring  # half-step offset: no vertex on y = 0
    y = np.array([0.0, 1.0, 0.0])
    rings = (
        path[:, None, :]
        + half_thickness * np.sin(phi)[None, :, None] * normal[:, None, :]
        + half_width * np.cos(phi)[None, :, None] * y
    )
    vertices = rings.reshape(-1, 3)
    s, k = np.meshgrid(np.arange(len(path) - 1), np.arange(n_ring), indexing="ij")
    a = s * n_ring + k
    b = s * n_ring + (k + 1) % n_ring
    c, d = a + n_ring, b + n_ring
    sides = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    fan = np.array([[0, i, i + 1] for i in range(1, n_ring - 1)])
    last = (len(path) - 1) * n_ring
    faces = np.concatenate([sides, fan[:, ::-1], fan + last])
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _combine(parts: list[trimesh.Trimesh]) -> tuple[np.ndarray, np.ndarray]:
    """Disjoint watertight components as one vertex/face array pair (no vertex merging)."""
    vertices, faces, offset = [], [], 0
    for part in parts:
        vertices.append(np.asarray(part.vertices, float))
        faces.append(np.asarray(part.faces, np.int64) + offset)
        offset += len(part.vertices)
    return np.concatenate(vertices), np.concatenate(faces)


def _finish(parts: list[trimesh.Trimesh], *, centre: bool) -> tuple[np.ndarray, np.ndarray]:
    """Components in mm → metres, optionally shifted so the bounding box is centred at the origin."""
    vertices, faces = _combine(parts)
    vertices = vertices * MM
    if centre:
        vertices = vertices - (vertices.min(axis=0) + vertices.max(axis=0)) / 2
    return vertices, faces


def _mesh_from_primitives(prims: tuple[Primitive, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Separate mesh components matching boxes, spheres and x-axis cylinders (already centred)."""
    parts = []
    for p in prims:
        centre = np.asarray(p.pos) / MM
        if p.kind == "box":
            half = np.asarray(p.size) / MM
            parts.append(_box(tuple(centre - half), tuple(centre + half)))
        elif p.kind == "sphere":
            parts.append(_sphere(p.size[0] / MM).apply_translation(centre))
        elif p.kind == "cylinder" and p.quat == _Q_Z_TO_X:
            parts.append(_cylinder_x(p.size[0] / MM, 2 * p.size[1] / MM).apply_translation(centre))
        else:  # pragma: no cover - only the kinds used in the catalogue are generated
            raise MeshError(f"no mesh generator for primitive {p}")
    return _finish(parts, centre=False)


# Mug (ceramic): outer radius, height, wall and base thickness; handle half-ellipse and cross-section.
MUG_R, MUG_H, MUG_WALL, MUG_BASE = 41.0, 95.0, 5.0, 7.0
MUG_HANDLE_REACH, MUG_HANDLE_HALF_SPAN, MUG_HANDLE_Z = 28.0, 27.0, 48.0
MUG_HANDLE_W, MUG_HANDLE_T = 6.0, 4.0  # half-width (along y) and half-thickness of the handle


def _mug() -> tuple[np.ndarray, np.ndarray]:
    r, h, ri = MUG_R, MUG_H, MUG_R - MUG_WALL
    body = _revolve(
        [
            (0, 0),
            (r - 2, 0),
            (r - 0.6, 0.6),
            (r, 2),
            (r, h - 1.5),
            (r - 0.6, h - 0.4),
            (r - 1.5, h),
            (ri + 1.5, h),
            (ri + 0.4, h - 0.6),
            (ri, h - 1.5),
            (ri, MUG_BASE + 3),
            (ri - 1, MUG_BASE + 0.8),
            (ri - 3, MUG_BASE),
            (0, MUG_BASE),
        ]
    )
    # The handle: a half-ellipse in the x-z plane whose ends meet the outer wall at right angles. Its end
    # caps lie in the plane x = r, which touches the 64-gon wall only along its vertex line at y = 0, so the
    # handle and the body share no volume (and no vertex).
    theta = np.linspace(-np.pi / 2, np.pi / 2, 41)
    path = np.column_stack(
        (
            r + MUG_HANDLE_REACH * np.cos(theta),
            np.zeros_like(theta),
            MUG_HANDLE_Z + MUG_HANDLE_HALF_SPAN * np.sin(theta),
        )
    )
    tangent = np.column_stack(
        (-MUG_HANDLE_REACH * np.sin(theta), np.zeros_like(theta), MUG_HANDLE_HALF_SPAN * np.cos(theta))
    )
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    tangent[[0, -1]] = ((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0))  # exactly normal to the wall at the ends
    normal = np.column_stack((-tangent[:, 2], np.zeros_like(theta), tangent[:, 0]))
    path[[0, -1], 0] = r  # exactly on the plane x = r
    handle = _tube(path, normal, MUG_HANDLE_W, MUG_HANDLE_T)
    return _finish([body, handle], centre=True)


GLASS_R, GLASS_H, GLASS_WALL, GLASS_BASE = 31.0, 100.0, 2.5, 8.0


def _glass() -> tuple[np.ndarray, np.ndarray]:
    r, h, ri, base = GLASS_R, GLASS_H, GLASS_R - GLASS_WALL, GLASS_BASE
    body = _revolve(
        [
            (0, 0),
            (r - 1.5, 0),
            (r, 1.5),
            (r, h - 0.6),
            (r - 0.6, h),
            (ri + 0.6, h),
            (ri, h - 0.6),
            (ri, base + 2),
            (ri - 2, base),
            (0, base),
        ]
    )
    return _finish([body], centre=True)


BOWL_RIM_R, BOWL_FOOT_R, BOWL_H, BOWL_WALL, BOWL_BASE = 75.0, 40.0, 65.0, 5.0, 7.0


def _bowl() -> tuple[np.ndarray, np.ndarray]:
    # Outer and inner walls: quarter-ellipses from the flat foot (horizontal tangent) to the rim (vertical).
    t = np.linspace(0, np.pi / 2, 13)
    reach = BOWL_RIM_R - BOWL_FOOT_R
    outer = np.column_stack((BOWL_FOOT_R + reach * np.sin(t), BOWL_H - BOWL_H * np.cos(t)))
    inner_reach, inner_depth = reach - BOWL_WALL, BOWL_H - BOWL_BASE
    inner = np.column_stack((BOWL_FOOT_R + inner_reach * np.sin(t), BOWL_H - inner_depth * np.cos(t)))[::-1]
    profile = [(0.0, 0.0), *map(tuple, outer), *map(tuple, inner), (0.0, BOWL_BASE)]
    return _finish([_revolve(profile)], centre=True)


# Bottle: a filled 1.0 l PET water bottle; the outer surface is the (solid) collision and mass shape.
BOTTLE_R, BOTTLE_H, BOTTLE_CAP_R, BOTTLE_CAP_H = 40.0, 280.0, 15.0, 20.0


def _bottle() -> tuple[np.ndarray, np.ndarray]:
    r, h = BOTTLE_R, BOTTLE_H
    neck_r, cap_r, cap_z = 13.5, BOTTLE_CAP_R, BOTTLE_H - BOTTLE_CAP_H
    # Shoulder from the body (z = 185) to the neck (z = 248): a cosine ogee, convex near the body and
    # flaring concavely into the neck like a real PET bottle's.
    u = np.linspace(0, 1, 13)[1:-1]
    dome = [(neck_r + (r - neck_r) * (1 + np.cos(np.pi * a)) / 2, 185 + 63 * a) for a in u]
    profile = [
        (0, 0),
        (r - 4, 0),
        (r - 1, 1.5),
        (r, 5),
        (r, 95),
        (r - 3, 103),  # grip waist
        (r - 3, 122),
        (r, 130),
        (r, 185),
        *dome,
        (neck_r, cap_z - 6),
        (neck_r + 3, cap_z - 6),  # neck support ring
        (neck_r + 3, cap_z - 4),
        (neck_r, cap_z - 4),
        (neck_r, cap_z),
        (cap_r, cap_z),  # cap, 30 mm diameter
        (cap_r, h - 1),
        (cap_r - 1, h),
        (0, h),
    ]
    return _finish([_revolve([(float(a), float(b)) for a, b in profile])], centre=True)


# Oval jar: a glass jar with an oval body and a round 70 mm screw lid, closed and empty.
JAR_BODY_RX, JAR_BODY_RY, JAR_H, JAR_LID_R, JAR_LID_H = 50.0, 37.5, 122.0, 35.0, 14.0


def _oval_jar() -> tuple[np.ndarray, np.ndarray]:
    r, neck_r, lid_z = JAR_BODY_RX, 33.0, JAR_H - JAR_LID_H
    shoulder_lo, shoulder_hi = 92.0, 104.0
    profile = [
        (0, 0),
        (r - 5, 0),
        (r - 1.5, 1.5),
        (r, 5),
        (r, shoulder_lo),
        (r - 3, shoulder_lo + 6),
        (r - 8, shoulder_hi - 2),
        (neck_r + 2, shoulder_hi),
        (neck_r, shoulder_hi + 1),
        (neck_r, lid_z),
        (JAR_LID_R, lid_z),  # lid skirt
        (JAR_LID_R, JAR_H - 1),
        (JAR_LID_R - 1, JAR_H),
        (0, JAR_H),
    ]
    jar = _revolve(profile)
    # Oval body: scale y by ry/rx below the shoulder, blending to round (scale 1) at the neck. The map
    # (x, y, z) -> (x, s(z) y, z) with s > 0 is a bijection that keeps orientation, so the mesh stays closed,
    # consistently wound and free of self-intersections.
    v = np.array(jar.vertices)
    rho = np.hypot(v[:, 0], v[:, 1])
    v[:, 1] *= np.minimum(1.0, JAR_BODY_RY / np.maximum(rho, 1e-12))
    return _finish([trimesh.Trimesh(v, jar.faces, process=False)], centre=True)


# Bottle crate: an empty 20 × 0.5 l beer crate (4 × 5 cells) with a central handle, outer 400 × 300 × 290 mm.
CRATE_L, CRATE_W, CRATE_H = 400.0, 300.0, 290.0
CRATE_WALL, CRATE_FLOOR, CRATE_DIVIDER, CRATE_DIVIDER_H = 4.0, 4.0, 3.0, 150.0
CRATE_BAR = ((-80.0, -12.5, 120.0), (80.0, 12.5, 145.0))  # handle bar corners (centred frame)
CRATE_POST_X, CRATE_POST_HW = (60.0, 80.0), 6.0  # handle posts: |x| range and half-width in y


def _crate_boxes() -> tuple[tuple[tuple[float, float, float], tuple[float, float, float]], ...]:
    """Corners (mm, centred frame) of every box of the crate: floor, 4 walls, dividers, handle."""
    lx, wy, hz = CRATE_L / 2, CRATE_W / 2, CRATE_H / 2
    t, f, d = CRATE_WALL, CRATE_FLOOR, CRATE_DIVIDER / 2
    z0, z1, zd = -hz, -hz + f, -hz + f + CRATE_DIVIDER_H
    ix, iy = lx - t, wy - t  # inner half-sizes
    boxes = [
        ((-lx, -wy, z0), (lx, wy, z1)),  # floor
        ((-lx, -wy, z1), (lx, -iy, hz)),  # long walls
        ((-lx, iy, z1), (lx, wy, hz)),
        ((-lx, -iy, z1), (-ix, iy, hz)),  # short walls
        ((ix, -iy, z1), (lx, iy, hz)),
    ]
    ys = [-iy + k * (2 * iy) / 4 for k in range(1, 4)]  # longitudinal dividers (run along x)
    xs = [-ix + k * (2 * ix) / 5 for k in range(1, 5)]  # transverse dividers, cut by the longitudinal ones
    boxes += [((-ix, y - d, z1), (ix, y + d, zd)) for y in ys]
    y_edges = [-iy, *(e for y in ys for e in (y - d, y + d)), iy]
    for x in xs:
        boxes += [((x - d, y_edges[i], z1), (x + d, y_edges[i + 1], zd)) for i in range(0, len(y_edges), 2)]
    px0, px1 = CRATE_POST_X
    bar_lo, bar_hi = CRATE_BAR
    for lo_x, hi_x in ((-px1, -px0), (px0, px1)):
        boxes.append(((lo_x, -CRATE_POST_HW, zd), (hi_x, CRATE_POST_HW, bar_lo[2])))
    boxes.append((bar_lo, bar_hi))
    return tuple(boxes)


def _crate() -> tuple[np.ndarray, np.ndarray]:
    # Floor and walls as ONE closed shell (separate boxes would share corner vertices and edges, which is
    # not a manifold surface); dividers and handle as separate boxes touching it and each other only in
    # faces, never in vertices, so the union is watertight and no volume is counted twice.
    lx, wy, hz = CRATE_L / 2, CRATE_W / 2, CRATE_H / 2
    ix, iy, zf = lx - CRATE_WALL, wy - CRATE_WALL, -hz + CRATE_FLOOR
    sq = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)], float)
    v = np.concatenate(
        [
            np.column_stack((sq * (lx, wy), np.full(4, -hz))),  # 0-3 outer bottom
            np.column_stack((sq * (lx, wy), np.full(4, hz))),  # 4-7 outer top
            np.column_stack((sq * (ix, iy), np.full(4, hz))),  # 8-11 inner top
            np.column_stack((sq * (ix, iy), np.full(4, zf))),  # 12-15 inner bottom
        ]
    )
    faces = [[0, 2, 1], [0, 3, 2], [12, 13, 14], [12, 14, 15]]  # outer bottom (down), inner floor (up)
    for i in range(4):
        j = (i + 1) % 4
        faces += [[i, j, 4 + j], [i, 4 + j, 4 + i]]  # outer wall
        faces += [[4 + i, 4 + j, 8 + j], [4 + i, 8 + j, 8 + i]]  # rim
        faces += [[8 + i, 8 + j, 12 + j], [8 + i, 12 + j, 12 + i]]  # inner wall (faces inwards)
    shell = trimesh.Trimesh(v, np.array(faces), process=False)
    parts = [shell, *(_box(lo, hi) for lo, hi in _crate_boxes()[5:])]
    return _finish(parts, centre=False)


# --------------------------------------------------------------------------------------------------------
# The catalogue

_TENNIS_BALL = (Primitive("sphere", (0.032,)),)
_PEN = (Primitive("cylinder", (0.010, 0.070), quat=_Q_Z_TO_X),)
_CUBE = (Primitive("box", (0.025, 0.025, 0.025)),)
_CARD = (Primitive("box", (0.0425, 0.0275, 0.0002)),)
_NOTEBOOK = (Primitive("box", (0.105, 0.065, 0.0075)),)
_CYLINDER_10 = (Primitive("cylinder", (0.005, 0.100), quat=_Q_Z_TO_X),)
_CYLINDER_25 = (Primitive("cylinder", (0.0125, 0.100), quat=_Q_Z_TO_X),)
_CARTON_LYING = (Primitive("box", (0.1875, 0.130, 0.038)),)
_CARTON_STANDING = (Primitive("box", (0.130, 0.038, 0.1875)),)
_CRATE = tuple(_box_primitive(lo, hi) for lo, hi in _crate_boxes())

_BOTTLE_NOTES = (
    "filled: the report says the bottle 'is filled with water but stays closed'; modelled as a 1.0 l PET "
    "bottle (80 mm is the usual diameter of 1 l PET bottles; a 1.5 l one is about 90 mm): 1000 g water + "
    "about 35 g bottle and cap",
    "the closed outer surface (body with grip waist, shoulder, neck ring, cap) is the collision and mass "
    "shape; uniform density over it is right for the water, which is 97 % of the mass (no sloshing)",
)

GRASPDB_OBJECTS: tuple[GraspDBObject, ...] = (
    GraspDBObject(
        name="tennis_ball",
        graspdb_id=1,
        description="Tennis ball (64 mm diameter)",
        mass_kg=0.0575,
        size_note="diameter 64 mm (report Table 4.1)",
        primitives=_TENNIS_BALL,
        notes=("mass 57.5 g: middle of the ITF range 56.0–59.4 g",),
    ),
    GraspDBObject(
        name="pen",
        graspdb_id=2,
        description="Pen (2 cm diameter)",
        mass_kg=0.020,
        size_note="diameter 20 mm (report Table 4.1); length 140 mm (typical, chosen: a capped pen/marker)",
        primitives=_PEN,
        notes=(
            "lies on the table with its axis along x",
            "a plain cylinder (the cap and tip are not modelled); 20 g: a 2 cm thick plastic pen or "
            "marker weighs 15–25 g",
        ),
    ),
    GraspDBObject(
        name="bottle",
        graspdb_id=3,
        description="Bottle (8 cm diameter)",
        mass_kg=1.035,
        size_note="diameter 80 mm (report Table 4.1), cap 30 mm (report Table 3.3); height 280 mm "
        "(typical, chosen: 1.0 l PET water bottle)",
        primitives=(),
        notes=_BOTTLE_NOTES,
    ),
    GraspDBObject(
        name="mug",
        graspdb_id=4,
        description="Mug",
        mass_kg=0.340,
        size_note="outer diameter 82 mm, height 95 mm, wall 5 mm, handle reaching 32 mm out (typical, "
        "chosen: a standard ceramic mug, about 350 ml to the brim; the report gives no size)",
        primitives=(),
        notes=(
            "empty (the report does not say it held liquid in transport)",
            "340 g: ceramic mugs of this size weigh 300–350 g; gives stoneware density ≈ 2.3 g/cm³",
            "the handle is a separate closed tube whose end caps touch the outer wall (no shared volume)",
        ),
    ),
    GraspDBObject(
        name="glass",
        graspdb_id=5,
        description="Glass (62 mm diameter)",
        mass_kg=0.170,
        size_note="outer diameter 62 mm (report Table 4.1); height 100 mm, wall 2.5 mm, base 8 mm (typical, "
        "chosen: a straight 0.2 l tumbler)",
        primitives=(),
        notes=("empty; 170 g is the mesh volume times soda-lime glass density 2.5 g/cm³",),
    ),
    GraspDBObject(
        name="bowl",
        graspdb_id=6,
        description="Bowl",
        mass_kg=0.450,
        size_note="rim diameter 150 mm, height 65 mm, foot 80 mm, wall 5 mm (typical, chosen: a ceramic "
        "cereal bowl; the report gives no size)",
        primitives=(),
        notes=(
            "empty; 450 g: the mesh volume times stoneware density ≈ 2.3 g/cm³ (ceramic bowls of this "
            "size weigh 350–500 g)",
        ),
    ),
    GraspDBObject(
        name="cube",
        graspdb_id=7,
        description="Cube",
        mass_kg=0.088,
        size_note="edge 50 mm (typical, chosen: a wooden toy cube; the report gives no size)",
        primitives=_CUBE,
        notes=("88 g: solid beech (about 700 kg/m³)",),
    ),
    GraspDBObject(
        name="business_card",
        graspdb_id=8,
        description="Business card",
        mass_kg=0.0016,
        size_note="85 × 55 × 0.4 mm (typical, chosen: the common European card size on 350 g/m² board)",
        primitives=_CARD,
        notes=("lies flat; 1.6 g = 350 g/m² × 85 mm × 55 mm",),
    ),
    GraspDBObject(
        name="oval_jar",
        graspdb_id=9,
        description="Oval jar",
        mass_kg=0.250,
        size_note="lid diameter 70 mm (report Table 3.3), lid height 14 mm; oval body 100 × 75 mm, "
        "height 122 mm with the lid (typical, chosen)",
        primitives=(),
        notes=(
            "the lid is part of this object, closed: it has no id of its own (report Table 4.1), and the "
            "controlled-transport grasp (power disk, grasp 10) holds the jar by its lid",
            "empty glass jar with a metal lid, 250 g; the mass is spread uniformly over the closed outer "
            "surface, so the inertia is that of a solid, not of a shell (about 1.5× too small)",
            "opening and screwing the lid (object-use scenario) would need a second, jointed body; not "
            "modelled",
        ),
    ),
    GraspDBObject(
        name="bottle_crate",
        graspdb_id=10,
        description="Bottle crate",
        mass_kg=1.800,
        size_note="outer 400 × 300 × 290 mm, walls and floor 4 mm, 4 × 5 cells with 3 mm dividers 150 mm "
        "high, central handle bar 160 × 25 × 25 mm (typical, chosen: a German 20 × 0.5 l beer crate)",
        primitives=_CRATE,
        notes=(
            "empty; 1.8 kg: empty HDPE crates of this kind weigh 1.5–2 kg (a full one, about 17 kg, is not "
            "lifted with one hand's wrap or hook grasp as in grasps 3 and 15)",
            "the grasps (medium wrap, fixed hook) hold the central handle bar",
            "solid walls and dividers stand for the real ribbed ones, so the mean density is low (≈ 0.6 "
            "g/cm³)",
        ),
    ),
    GraspDBObject(
        name="notebook",
        graspdb_id=11,
        description="Classic notebook (15 mm thick)",
        mass_kg=0.300,
        size_note="thickness 15 mm (report Table 4.1); 210 × 130 mm (typical, chosen: a large-format "
        "hardcover 'classic' notebook)",
        primitives=_NOTEBOOK,
        notes=("lies flat, closed; 300 g: paper and board at about 0.73 g/cm³",),
    ),
    GraspDBObject(
        name="cylinder_10mm",
        graspdb_id=12,
        description="Cylinder 10 mm diameter",
        mass_kg=0.011,
        size_note="diameter 10 mm (report Table 4.1); length 200 mm (typical, chosen: same length as the 25 "
        "mm cylinder)",
        primitives=_CYLINDER_10,
        notes=("lies on the table with its axis along x; 11 g: a beech dowel (about 700 kg/m³)",),
    ),
    GraspDBObject(
        name="cylinder_25mm",
        graspdb_id=13,
        description="Cylinder 25 mm diameter",
        mass_kg=0.069,
        size_note="diameter 25 mm (report Table 4.1); length 200 mm (typical, chosen: long enough for the "
        "whole-hand wraps of grasps 2, 4, 17 and 32)",
        primitives=_CYLINDER_25,
        notes=("lies on the table with its axis along x; 69 g: a beech rod (about 700 kg/m³)",),
    ),
    GraspDBObject(
        name="carton_lying",
        graspdb_id=14,
        description="Carton lying flat",
        mass_kg=0.300,
        size_note="76 × 260 × 375 mm (report Fig. 3.11 and Table 4.1); lying on its largest face: x 375, "
        "y 260, z 76 mm",
        primitives=_CARTON_LYING,
        notes=(
            "the same carton as carton_standing (id 15), placed differently",
            "empty corrugated cardboard box (the report does not say what it held), 300 g; so its mean "
            "density is only about 40 kg/m³",
        ),
    ),
    GraspDBObject(
        name="carton_standing",
        graspdb_id=15,
        description="Carton standing (7.6 × 26 × 37.5 cm³)",
        mass_kg=0.300,
        size_note="76 × 260 × 375 mm (report Fig. 3.11 and Table 4.1); standing on a 260 × 76 mm face: "
        "x 260, y 76, z 375 mm",
        primitives=_CARTON_STANDING,
        notes=(
            "the same carton as carton_lying (id 14), placed differently",
            "empty corrugated cardboard box (the report does not say what it held), 300 g; so its mean "
            "density is only about 40 kg/m³",
        ),
    ),
    GraspDBObject(
        name="bottle_by_cap",
        graspdb_id=16,
        description="Bottle (cap)",
        mass_kg=1.035,
        size_note="the bottle of id 3: diameter 80 mm, cap 30 mm (report Tables 4.1 and 3.3), height 280 mm "
        "(typical, chosen)",
        primitives=(),
        notes=(
            "id 16 is the bottle grasped by its 30 mm cap (tripod, grasp 14), not a loose cap: the report's "
            "objects (Fig. 3.11) include no separate cap, and 'Oval jar (lid)' likewise names the jar held "
            "by its lid; same geometry and mass as 'bottle'",
            *_BOTTLE_NOTES,
        ),
    ),
)

_BUILDERS: dict[str, Callable[[], tuple[np.ndarray, np.ndarray]]] = {
    "bottle": _bottle,
    "bottle_by_cap": _bottle,
    "mug": _mug,
    "glass": _glass,
    "bowl": _bowl,
    "oval_jar": _oval_jar,
    "bottle_crate": _crate,
}
_BY_NAME = {o.name: o for o in GRASPDB_OBJECTS}
_BY_ID = {o.graspdb_id: o for o in GRASPDB_OBJECTS}


@functools.cache
def _cached_mesh(name: str) -> Mesh:
    obj = _BY_NAME[name]
    builder = _BUILDERS.get(name)
    vertices, faces = builder() if builder is not None else _mesh_from_primitives(obj.primitives)
    mesh = validate_mesh(vertices, faces, f"graspdb14:{name}", require_watertight=True)
    mesh.vertices.flags.writeable = False
    mesh.faces.flags.writeable = False
    return mesh


def graspdb_object(name_or_id: str | int) -> GraspDBObject:
    """Look an object up by its name or by its GraspDB id (report Table 4.1).

    Every id names exactly one entry: the carton's two placements have their own ids (14 lying, 15
    standing), and id 16 (the bottle held by its cap) is an entry of its own with the bottle's geometry.

    Args:
        name_or_id: A catalogue name such as ``"mug"``, or an id 1–16.

    Returns:
        The object.

    Raises:
        UnknownObjectError: The name or id is not in the catalogue (the message lists the valid ones).
    """
    if isinstance(name_or_id, str):
        if name_or_id in _BY_NAME:
            return _BY_NAME[name_or_id]
        raise UnknownObjectError(
            f"unknown object {name_or_id!r}; catalogue objects are: {', '.join(sorted(_BY_NAME))}"
        )
    if isinstance(name_or_id, (int, np.integer)) and not isinstance(name_or_id, bool):
        if int(name_or_id) in _BY_ID:
            return _BY_ID[int(name_or_id)]
        listing = ", ".join(f"{i} ({o.name})" for i, o in sorted(_BY_ID.items()))
        raise UnknownObjectError(f"unknown GraspDB object id {int(name_or_id)}; catalogue ids are: {listing}")
    raise UnknownObjectError(
        f"expected an object name or GraspDB id, got {name_or_id!r}; catalogue objects are: "
        f"{', '.join(sorted(_BY_NAME))}"
    )
