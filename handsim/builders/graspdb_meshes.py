"""Meshes of the GraspDB14 objects, generated with trimesh (no files, no randomness).

:func:`generate_mesh` makes an object's vertices and faces in metres: the hollow or waisted objects from
their own generators (mug, glass, bowl, bottle, oval jar, bottle crate), every other one from its collision
primitives. Dimensions and their sources are in :mod:`handsim.builders.graspdb_objects` (``size_note``) and
``docs/objects.md``. Kept apart from the table so that listing the catalogue does not import trimesh.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import trimesh

from handsim.builders.graspdb_shapes import (
    CRATE_FLOOR,
    CRATE_H,
    CRATE_L,
    CRATE_W,
    CRATE_WALL,
    MM,
    Q_Z_TO_X,
    crate_boxes,
)
from handsim.datatypes.object_model import Primitive
from handsim.errors import MeshError

SECTIONS = 64  # segments around a revolved body; a multiple of 4 puts vertices on the ±x and ±y extremes
SPHERE_RINGS = 32  # meridian segments of a sphere (pole to pole)

# All lengths in mm, converted to metres and centred at the end.


def _box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> trimesh.Trimesh:
    lo_a, hi_a = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(
        extents=hi_a - lo_a, transform=trimesh.transformations.translation_matrix((lo_a + hi_a) / 2)
    )


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
        elif p.kind == "cylinder" and p.quat == Q_Z_TO_X:
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
    parts = [shell, *(_box(lo, hi) for lo, hi in crate_boxes()[5:])]
    return _finish(parts, centre=False)


_BUILDERS: dict[str, Callable[[], tuple[np.ndarray, np.ndarray]]] = {
    "bottle": _bottle,
    "bottle_by_cap": _bottle,
    "mug": _mug,
    "glass": _glass,
    "bowl": _bowl,
    "oval_jar": _oval_jar,
    "bottle_crate": _crate,
}


def generate_mesh(name: str, primitives: tuple[Primitive, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) in metres and faces (F, 3) of the catalogue object ``name``.

    Args:
        name: A GraspDB14 catalogue name.
        primitives: The object's collision primitives (metres): the mesh of an object without a generator
            of its own is made of them.
    """
    builder = _BUILDERS.get(name)
    return builder() if builder is not None else _mesh_from_primitives(primitives)
