"""What an object rested on in a capture: a stand no larger than its footprint, out of the hands' way.

A capture's object stands on something small (ARCTIC's objects on a stand in the middle of the capture
volume, hands passing below their resting height around them), never on a table larger than the object. So
the support under an object is a **stand**: a column from the support plane (z = 0, the object's lowest
point at its first frame) down to the floor, whose top is the object's **footprint**: the convex hull of the
object's collision points within :data:`FOOTPRINT_BAND` of its lowest point (:func:`footprint`).

The recorded hands must not pass through it (:mod:`handsim.sim.scene.clearance`): :func:`shrink_outline`
cuts the footprint back, one half-plane at a time, until no recorded hand point lies deeper than the limit
inside the column, keeping the object's centre of mass (its projection at the first frame) at least
:data:`STAND_MIN_RADIUS` inside, or says which points no such stand avoids.

A recording that moves the object up or down from its first frame (:func:`vertical_motion`: lifted, or
falling) gets no stand: nothing held it up but the hands.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.errors import ModelError

FOOTPRINT_BAND = 0.005
"""The part of an object within this height of its lowest point at the first frame rests on its support, m:
ARCTIC's object poses are fitted to markers with millimetres of error, so a flat bottom can appear tilted by
that much."""
STAND_MIN_RADIUS = 0.02
"""A stand keeps at least the disc of this radius around the object's centre of mass (its projection at the
first frame), m: a narrower stand (under 4 cm across) could not have held a tabletop object upright in the
capture. A recorded hand point that only a narrower stand avoids makes the world not fit the recording."""
START_MOTION = 0.005
"""A recording holds its object off any support from the first frame when the object's origin rises or sinks
more than this, m …"""
START_WINDOW = 0.1
"""… within this time of the first frame, s (0.05 m/s on average: an object at rest does not move so)."""
_MIN_AREA = 1e-4
"""A footprint smaller than 1 cm² is an edge or a corner: the band is widened until it is not, m²."""


def collision_points(model: mujoco.MjModel, data: mujoco.MjData, geoms: npt.ArrayLike) -> np.ndarray:
    """World points on the surfaces of geoms as collided: mesh hull vertices, box corners, primitives sampled.

    Args:
        model: The model.
        data: Its data with the geoms' poses computed (``mj_kinematics``).
        geoms: Geom ids.

    Returns:
        Points, m (M, 3).

    Raises:
        ModelError: A geom type without a surface here (plane, height field, SDF).
    """
    ring = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
    circle = np.column_stack([np.cos(ring), np.sin(ring), np.zeros(16)])
    out = []
    for g in np.asarray(geoms, dtype=np.int64):
        kind, size = int(model.geom_type[g]), model.geom_size[g]
        if kind == mujoco.mjtGeom.mjGEOM_MESH:
            mesh = int(model.geom_dataid[g])
            start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
            local = np.asarray(model.mesh_vert[start : start + count], dtype=float)
        elif kind == mujoco.mjtGeom.mjGEOM_BOX:
            local = np.array(np.meshgrid(*([-1.0, 1.0],) * 3)).T.reshape(-1, 3) * size
        elif kind in (mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_ELLIPSOID):
            radii = size if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID else np.full(3, size[0])
            local = np.vstack([circle, circle[:, [2, 0, 1]], circle[:, [1, 2, 0]]]) * radii
        elif kind in (mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_CAPSULE):
            rim, half = circle * size[0], np.array([0.0, 0.0, size[1]])
            local = np.vstack([rim + half, rim - half])
            if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
                local = np.vstack([local, [[0, 0, size[1] + size[0]], [0, 0, -size[1] - size[0]]]])
        else:
            raise ModelError(
                f"geom {model.geom(int(g)).name!r}: a {mujoco.mjtGeom(kind).name} has no surface points here"
            )
        out.append(local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g])
    return np.vstack(out) if out else np.zeros((0, 3))


def footprint(points: npt.ArrayLike) -> np.ndarray:
    """The object's footprint on its support: the 2-D convex hull of its points near its lowest one.

    Args:
        points: The object's collision points at its first frame, m (M, 3), z up.

    Returns:
        The hull's corners (x, y), counter-clockwise, m (k, 2). Points within :data:`FOOTPRINT_BAND` of the
        lowest count; where they span less than 1 cm² (the object rests on an edge or a corner), the band
        is doubled until they do (at most the whole object).

    Raises:
        ModelError: No three of the points span an area (a degenerate object).
    """
    from scipy.spatial import ConvexHull, QhullError  # lazy: SciPy's Qhull, only where a stand is built

    p = np.asarray(points, dtype=float)
    lowest, height = float(p[:, 2].min()), float(np.ptp(p[:, 2]))
    band = FOOTPRINT_BAND
    while True:
        near = p[p[:, 2] <= lowest + band, :2]
        try:
            hull = ConvexHull(near)
            if hull.volume >= _MIN_AREA or band > height:
                return near[hull.vertices]
        except (QhullError, ValueError):
            if band > height:
                raise ModelError("the object's collision points span no area: it has no footprint") from None
        band *= 2.0


def vertical_motion(times: npt.ArrayLike, positions: npt.ArrayLike) -> float:
    """How far a recorded object's origin rises or sinks within :data:`START_WINDOW` of the first frame, m.

    More than :data:`START_MOTION`: the recording holds the object off any support from the start (lifted
    by the hands, or falling).

    Args:
        times: Recording times, s (N,).
        positions: The object's origin per frame, z up, m (N, 3).
    """
    t = np.asarray(times, dtype=float)
    z = np.asarray(positions, dtype=float)[:, 2]
    window = t - t[0] <= START_WINDOW + 1e-9
    return float(np.max(np.abs(z[window] - z[0])))


def inward_distance(outline: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Distance of points inside a convex polygon to its boundary, m (negative outside).

    Args:
        outline: The polygon's corners, counter-clockwise (k, 2).
        xy: Points (M, 2).
    """
    edges = np.roll(outline, -1, axis=0) - outline
    normals = np.column_stack([edges[:, 1], -edges[:, 0]]) / np.linalg.norm(edges, axis=1)[:, None]
    signed = np.einsum("mkj,kj->mk", xy[:, None, :] - outline[None], normals)
    return -signed.max(axis=1)


def _cut(outline: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """The convex polygon clipped to the half-plane ``normal · x ≤ offset`` (Sutherland–Hodgman)."""
    side = outline @ normal - offset
    kept = []
    for i in range(len(outline)):
        a, b = outline[i], outline[(i + 1) % len(outline)]
        sa, sb = side[i], side[(i + 1) % len(outline)]
        if sa <= 0:
            kept.append(a)
        if (sa < 0 < sb) or (sb < 0 < sa):
            kept.append(a + (b - a) * (sa / (sa - sb)))
    return np.asarray(kept)


@dataclass(frozen=True)
class Shrunk:
    """A stand's outline cut back out of the recorded hands' way.

    Attributes:
        outline: The new top (x, y), counter-clockwise, m.
        cuts: How many half-planes were cut off.
        blocked: Indices (into the points given) of those only a stand narrower than
            :data:`STAND_MIN_RADIUS` around the centre would avoid, deepest first.
    """

    outline: np.ndarray
    cuts: int
    blocked: tuple[int, ...]


def shrink_outline(
    outline: npt.ArrayLike, centre: npt.ArrayLike, points: npt.ArrayLike, floor: float, limit: float
) -> Shrunk:
    """Cut a stand's top back until no point lies deeper than ``limit`` inside the stand's column.

    A point's depth in the column (top z = 0, foot ``floor``) is the least of its depth below the top, its
    height above the foot and its distance inside the outline. Deepest first, each point still deeper than
    ``limit`` is cut off by the half-plane across the line from the centre to it, ``limit`` beyond it (so it
    ends ``limit`` inside); a cut that would come nearer the centre than :data:`STAND_MIN_RADIUS` is not made
    and the point is reported as blocked.

    Args:
        outline: The stand's top, counter-clockwise (k, 2), m.
        centre: The object's centre of mass projected on the support (x, y), m.
        points: The recorded hand points, m (M, 3).
        floor: The stand's foot, m (< 0).
        limit: Depth a point may lie inside, m.

    Returns:
        The new outline, the number of cuts and the blocked points.
    """
    poly = np.asarray(outline, dtype=float)
    c = np.asarray(centre, dtype=float)
    p = np.asarray(points, dtype=float)
    index = np.flatnonzero((p[:, 2] < -limit) & (p[:, 2] > floor + limit))
    xy = p[index, :2]
    blocked: list[int] = []
    cuts = 0
    while index.size:
        inward = inward_distance(poly, xy)
        deep = inward > limit
        if not deep.any():
            break
        k = int(np.argmax(np.where(deep, inward, -np.inf)))
        away = xy[k] - c
        reach = float(np.linalg.norm(away))
        if reach + limit < STAND_MIN_RADIUS:
            blocked.append(int(index[k]))
        else:
            normal = away / reach
            poly = _cut(poly, normal, float(normal @ xy[k]) + limit)
            cuts += 1
        index, xy = np.delete(index, k), np.delete(xy, k, axis=0)
    return Shrunk(poly, cuts, tuple(blocked))


def polygon_area(outline: np.ndarray) -> float:
    """Area of a simple polygon (shoelace), m²."""
    x, y = outline[:, 0], outline[:, 1]
    return 0.5 * float(abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
