"""Bounds of the distance from any point to an object's colliding geoms, on a grid in the object's frame.

The placement search (:mod:`handsim.sim.placement_search`) asks of tens of thousands of object poses only
whether the hand touches the object and whether it goes deeper than a tolerance. Bounding spheres and balls
inscribed in the object's convex parts settle few of them for a thin-walled object (a mug's wall is a few
millimetres thick), so MuJoCo had to run collision detection on most. This field settles them from the
object's own convex parts:

* ``upper``: at each grid node, an upper bound of the signed distance to the nearest part (negative inside a
  part: minus the depth in the part it lies deepest in, exact from the part's face planes; outside: the
  distance to the nearest of points sampled on the parts' surfaces, or +inf beyond ``reach``);
* ``lower``: at each node, a lower bound of the distance to the object (0 inside): the least over the parts
  of the largest distance above a face plane.

Both are 1-Lipschitz functions of the point bounded at the nodes, so at any point ``q`` with nearest node
``g``: signed distance ≤ ``upper[g] + |q − g|`` and distance ≥ ``lower[g] − |q − g|``
(:meth:`ObjectField.at`).
A ball of radius ``r`` centred at ``q`` then goes at least ``r − upper[g] − |q − g|`` deep into the object
(penetration depth of a ball into a convex part is ``r`` minus the signed distance of its centre), and a
capsule whose core stays farther than ``r`` plus the touch distance touches nothing.

:func:`object_field` makes a field once per object (about 0.4 s for the 16 convex parts of GraspDB14's mug)
and keeps it in memory and on disk (``<cache dir>/field/``, entries like the placements').

Only objects made of convex meshes, boxes and spheres get a field (MuJoCo collides a mesh as its vertices'
convex hull, which is what the planes and surface samples here describe); other geoms give None and the
collider's sphere bounds apply alone. So does an object of spheres only: a sphere's inscribed ball is its
bounding sphere, so those bounds are already tight (on the tennis ball the field settled no more poses and
cost more time than it saved).
"""

from __future__ import annotations

import hashlib
import math
import threading
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import scipy
from scipy.spatial import ConvexHull, QhullError, cKDTree

from handsim.builders.hull_cache import default_cache_dir
from handsim.sim.placement_cache import (
    CorruptEntryError,
    code_fingerprint,
    entry_path,
    read_entry,
    write_entry,
)

MAX_NODES = 160_000
"""Grid nodes at most: the spacing grows from :data:`MIN_SPACING` until the padded box holds no more."""
MIN_SPACING = 0.001
"""Finest grid spacing, m."""
OUTER_PLANES = 64
"""Face planes kept per convex part for the distance's lower bound (any of its faces' planes bounds it)."""
INNER_VERTICES = 48
"""Vertices kept per convex part for the depth's bound: depth inside their hull is at most the part's."""
FIELD_REACH = 0.012
"""Outside the object, signed-distance bounds are kept this far out, m: a hand ball goes deeper than the
placement's tolerance only within its radius of the object, and finger capsules are 7–10 mm in radius
(the default hand and GraspDB14's ``default.xmlskel``); a bigger ball gains nothing farther out."""
PAD = 0.02
"""The grid covers the object's box grown by this on every side, m (beyond it bounds still hold, looser)."""
_CACHE: OrderedDict[str, ObjectField | None] = OrderedDict()
_CACHE_SIZE = 8
_LOCK = threading.Lock()
_SHAPES = frozenset(
    int(t) for t in (mujoco.mjtGeom.mjGEOM_MESH, mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_SPHERE)
)


@dataclass(frozen=True)
class ObjectField:
    """Distance bounds on a regular grid in an object's frame (see the module docstring).

    Attributes:
        origin: Position of node (0, 0, 0) in the object's frame, m.
        spacing: Distance between neighbouring nodes, m.
        upper: (nx, ny, nz) upper bounds of the signed distance to the nearest part, m.
        lower: (nx, ny, nz) lower bounds of the distance to the object, m (0 inside).
        low: Lower corner of the object's box in its frame, m (beyond the grid, the distance to the box
            bounds the distance to the object).
        high: Upper corner of that box, m.
    """

    origin: np.ndarray
    spacing: float
    upper: np.ndarray
    lower: np.ndarray
    low: np.ndarray
    high: np.ndarray

    def at(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bounds at points in the object's frame: signed distance at most, distance at least.

        Args:
            points: (..., 3) points in the object's frame, m (anywhere: outside the grid the nearest node
                on its border bounds them, more loosely).

        Returns:
            Two arrays of the points' leading shape, m.
        """
        shape = np.asarray(self.upper.shape)
        scaled = (points - self.origin) * (1.0 / self.spacing)
        index = np.rint(scaled)
        np.minimum(np.maximum(index, 0.0, out=index), shape - 1.0, out=index)
        offset = scaled - index
        gap = np.sqrt(np.einsum("...i,...i->...", offset, offset)) * self.spacing
        flat = (index @ np.array([shape[1] * shape[2], shape[2], 1.0])).astype(np.intp)  # exact: < 2**53
        upper = self.upper.ravel().take(flat) + gap
        lower = self.lower.ravel().take(flat) - gap
        far = np.flatnonzero(gap.ravel() > 0.87 * self.spacing)  # clamped to the grid's border: off the grid
        if far.size:  # there the distance to the object's box is the tighter bound
            off = points.reshape(-1, 3)[far]
            box = np.maximum(np.maximum(self.low - off, off - self.high), 0.0)
            lower.ravel()[far] = np.maximum(lower.ravel()[far], np.sqrt(np.einsum("ki,ki->k", box, box)))
        return upper, lower


@dataclass(frozen=True)
class _Part:
    """One convex part in the object's frame, a polytope or a sphere.

    A polytope has ``planes`` (n, d rows, n·x + d ≤ 0 inside, |n| = 1: at most :data:`OUTER_PLANES` of its
    faces' planes, so each bounds the distance from below), ``inner`` (the planes of the hull of at most
    :data:`INNER_VERTICES` of its vertices, inside the part: their depth bounds the part's from below; None
    when flat) and its hull ``triangles`` (T, 3, 3). A sphere has ``centre`` and ``radius``.
    """

    planes: np.ndarray | None = None
    inner: np.ndarray | None = None
    triangles: np.ndarray | None = None
    centre: np.ndarray | None = None
    radius: float = 0.0


def object_field(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    geoms: np.ndarray,
    reach: float,
    *,
    use_cache: bool = True,
    cache_dir: str | Path | None = None,
) -> ObjectField | None:
    """The field of an object's colliding geoms, computed once per distinct object.

    A field is kept in memory for the process and on disk like the placements
    (:mod:`handsim.sim.placement_cache`, ``<cache dir>/field/``), keyed by the SHA-256 of the object's
    geoms (types, sizes, frames, mesh vertices), the field's parameters, the MuJoCo, NumPy and SciPy
    versions and handsim's source files; an entry that cannot be trusted is recomputed and replaced.

    Args:
        model: The model holding the object.
        data: Its data with the object at the identity pose (``geom_xpos``/``geom_xmat`` current): the
            geoms' frames there are their frames in the object's frame.
        geoms: The object's colliding geom ids.
        reach: Outside the parts, signed-distance upper bounds are kept only within this distance of the
            object (+inf beyond), m: farther points cannot decide a query.
        use_cache: Read and write the disk cache (the in-memory one is always used).
        cache_dir: Root of the disk cache; :func:`handsim.builders.hull_cache.default_cache_dir` when None.

    Returns:
        The field, or None when a geom is neither a mesh, a box nor a sphere, a part is degenerate, or every
        part is a sphere.
    """
    frames = [(data.geom_xpos[g].copy(), data.geom_xmat[g].reshape(3, 3).copy()) for g in geoms]
    key = _key(model, geoms, frames, reach)
    with _LOCK:  # searches on several threads share the fields
        if key in _CACHE:
            _CACHE.move_to_end(key)
            return _CACHE[key]
    field = _stored_or_made(model, geoms, frames, reach, key, use_cache, cache_dir)
    with _LOCK:
        _CACHE[key] = field
        if len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    return field


def _stored_or_made(
    model: mujoco.MjModel,
    geoms: np.ndarray,
    frames: list,
    reach: float,
    key: str,
    use_cache: bool,
    cache_dir: str | Path | None,
) -> ObjectField | None:
    kinds = {int(model.geom_type[g]) for g in geoms}
    if not kinds or not kinds <= _SHAPES or kinds == {int(mujoco.mjtGeom.mjGEOM_SPHERE)}:
        return None
    path = entry_path(cache_dir if cache_dir is not None else default_cache_dir(), key, "field")
    if use_cache and path.is_file():
        try:
            return read_entry(path, key, {(ObjectField.__module__, ObjectField.__qualname__): ObjectField})  # type: ignore[return-value]
        except CorruptEntryError:
            pass  # recomputed and replaced below
    parts = [_part(model, int(g), pos, mat) for g, (pos, mat) in zip(geoms, frames, strict=True)]
    if any(p is None for p in parts):
        return None
    field = _field(parts, reach)  # type: ignore[arg-type]
    if use_cache:
        try:
            write_entry(path, key, field)
        except OSError:  # a read-only or full disk: the field is still used
            pass
    return field


def _key(model: mujoco.MjModel, geoms: np.ndarray, frames: list, reach: float) -> str:
    digest = hashlib.sha256(
        f"handsim-object-field/mujoco {mujoco.__version__}/numpy {np.__version__}/scipy {scipy.__version__}/"
        f"code {code_fingerprint()}\n".encode()
    )
    digest.update(repr((float(reach), MAX_NODES, MIN_SPACING, PAD, OUTER_PLANES, INNER_VERTICES)).encode())
    for g, (pos, mat) in zip(geoms, frames, strict=True):
        digest.update(np.array([model.geom_type[g]], dtype=np.int64).tobytes())
        digest.update(np.ascontiguousarray(model.geom_size[g], dtype=float).tobytes())
        digest.update(pos.tobytes() + mat.tobytes())
        if int(model.geom_type[g]) == mujoco.mjtGeom.mjGEOM_MESH:
            digest.update(np.ascontiguousarray(_mesh_points(model, int(g))).tobytes())
    return digest.hexdigest()


def _mesh_points(model: mujoco.MjModel, geom: int) -> np.ndarray:
    mesh = int(model.geom_dataid[geom])
    start = model.mesh_vertadr[mesh]
    return np.asarray(model.mesh_vert[start : start + model.mesh_vertnum[mesh]], dtype=float)


def _part(model: mujoco.MjModel, geom: int, pos: np.ndarray, mat: np.ndarray) -> _Part | None:
    """A geom as a convex part in the object's frame, or None for a geom type without one here."""
    kind, size = int(model.geom_type[geom]), model.geom_size[geom]
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return _Part(centre=pos, radius=float(size[0]))
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        local = np.array(np.meshgrid(*([-1.0, 1.0],) * 3, indexing="ij")).reshape(3, -1).T * size[:3]
    elif kind == mujoco.mjtGeom.mjGEOM_MESH and model.geom_dataid[geom] >= 0:
        local = _mesh_points(model, geom)
    else:
        return None
    points = pos + local @ mat.T
    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError):
        return None
    planes = hull.equations[_farthest(hull.equations[:, :3], OUTER_PLANES)]  # n·x + d ≤ 0 inside, |n| = 1
    vertices = points[hull.vertices]
    inner = None
    try:
        inner = ConvexHull(vertices[_farthest(vertices, INNER_VERTICES)]).equations
    except (QhullError, ValueError):  # flat: no inner depth bound
        pass
    return _Part(planes=planes, inner=inner, triangles=points[hull.simplices])


def _farthest(points: np.ndarray, count: int) -> np.ndarray:
    """Indices of ``count`` of the points spread by farthest-point sampling from the first (all if fewer)."""
    if len(points) <= count:
        return np.arange(len(points))
    chosen = [0]
    distance = np.linalg.norm(points - points[0], axis=1)
    for _ in range(count - 1):
        chosen.append(int(np.argmax(distance)))
        np.minimum(distance, np.linalg.norm(points - points[chosen[-1]], axis=1), out=distance)
    return np.sort(np.array(chosen))


def _surface_samples(triangles: np.ndarray, spacing: float) -> np.ndarray:
    """Points on triangles (T, 3, 3), no farther apart than ``spacing`` along each triangle's edges."""
    samples = [triangles.reshape(-1, 3)]
    edges = np.linalg.norm(triangles - np.roll(triangles, 1, axis=1), axis=2).max(axis=1)
    counts = np.maximum(1, np.ceil(edges / spacing)).astype(int)
    for n in np.unique(counts):
        if n == 1:
            continue
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        keep = i + j <= n
        weights = np.stack([i[keep], j[keep], n - i[keep] - j[keep]], axis=1) / n  # (W, 3) barycentric
        chosen = triangles[counts == n]
        samples.append(np.einsum("wk,tkc->twc", weights, chosen).reshape(-1, 3))
    return np.concatenate(samples)


def _box(parts: list[_Part]) -> tuple[np.ndarray, np.ndarray]:
    """The box holding every part, in the object's frame."""
    boxes = [
        (p.centre - p.radius, p.centre + p.radius)
        if p.centre is not None
        else (p.triangles.min(axis=(0, 1)), p.triangles.max(axis=(0, 1)))  # type: ignore[union-attr]
        for p in parts
    ]
    return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)


def _grid(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, float, tuple[int, int, int]]:
    """Origin, spacing and shape of the grid over the box grown by :data:`PAD`."""
    low, high = low - PAD, high + PAD
    spacing = max(MIN_SPACING, (float(np.prod(high - low)) / MAX_NODES) ** (1 / 3))
    while math.prod(int(np.floor(e / spacing)) + 2 for e in high - low) > MAX_NODES:
        spacing *= 1.01
    shape = tuple(int(np.floor(e / spacing)) + 2 for e in high - low)
    return low, spacing, shape  # type: ignore[return-value]


def _field(parts: list[_Part], reach: float) -> ObjectField:
    box_low, box_high = _box(parts)
    origin, spacing, shape = _grid(box_low, box_high)
    axes = [origin[a] + spacing * np.arange(shape[a]) for a in range(3)]
    depth = np.full(shape, -np.inf)  # deepest inside any part (negative: outside all)
    lower = np.full(shape, np.inf)  # least over the parts of a lower bound of the distance to each
    band = reach + 2.0 * spacing  # plane bounds within this of a part's box; its box's distance farther
    for part in parts:
        if part.centre is not None:
            signed = _distance_to_box(axes, part.centre, part.centre) - part.radius
            np.maximum(depth, -signed, out=depth)
            np.minimum(lower, np.maximum(signed, 0.0), out=lower)
            continue
        low, high = part.triangles.min(axis=(0, 1)), part.triangles.max(axis=(0, 1))  # type: ignore[union-attr]
        bound = _distance_to_box(axes, low, high)  # the part lies in its box
        first = np.clip(np.floor((low - band - origin) / spacing).astype(int), 0, np.asarray(shape))
        last = np.clip(np.ceil((high + band - origin) / spacing).astype(int) + 1, 0, np.asarray(shape))
        block = tuple(slice(a, b) for a, b in zip(first, last, strict=True))
        nodes = np.stack(np.meshgrid(*(ax[s] for ax, s in zip(axes, block, strict=True)), indexing="ij"), -1)
        flat = nodes.reshape(-1, 3)
        signed = _plane_distance(flat, part.planes).reshape(nodes.shape[:3])  # type: ignore[arg-type]
        np.maximum(bound[block], signed, out=bound[block])
        if part.inner is not None:
            inner = _plane_distance(flat, part.inner).reshape(nodes.shape[:3])
            np.maximum(depth[block], -inner, out=depth[block])
        np.minimum(lower, bound, out=lower)
    upper = np.where(depth >= 0.0, -depth, np.inf)
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    outside = (depth < 0.0) & (lower <= reach)
    for p in parts:  # exact distances to the spheres
        if p.centre is not None:
            upper[outside] = np.minimum(
                upper[outside], np.linalg.norm(nodes[outside] - p.centre, axis=1) - p.radius
            )
    meshes = [_surface_samples(p.triangles, spacing) for p in parts if p.triangles is not None]
    if meshes and outside.any():
        tree = cKDTree(np.concatenate(meshes), balanced_tree=False, compact_nodes=False)
        distance, _ = tree.query(nodes[outside], distance_upper_bound=reach + spacing)
        upper[outside] = np.minimum(upper[outside], distance)
    return ObjectField(origin=origin, spacing=spacing, upper=upper, lower=lower, low=box_low, high=box_high)


def _plane_distance(points: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """Largest signed distance of each point above the planes (n, d) rows: n·x + d, |n| = 1."""
    return (points @ planes[:, :3].T + planes[:, 3]).max(axis=1)


def _distance_to_box(axes: list[np.ndarray], low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Distance from every grid node to the box [low, high] (0 inside), shape of the grid."""
    gaps = [np.maximum(np.maximum(low[a] - axes[a], axes[a] - high[a]), 0.0) ** 2 for a in range(3)]
    return np.sqrt(gaps[0][:, None, None] + gaps[1][None, :, None] + gaps[2][None, None, :])
