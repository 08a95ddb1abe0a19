"""Triangle meshes in SI units, validated and repaired before any native code (CoACD, MuJoCo) sees them.

CoACD aborts the whole process on some malformed meshes and silently returns garbage on others, and
MuJoCo's qhull can fail on flat input, so :func:`validate_mesh` checks everything those libraries assume
and repairs only what is safe to repair (duplicate vertices, degenerate or duplicate faces, inconsistent
or inverted winding, small holes), reporting each repair in :attr:`Mesh.notes`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from handsim.datatypes.mesh_mass import mesh_volume
from handsim.errors import MeshError

if TYPE_CHECKING:
    import trimesh

FLATNESS_TOL = 1e-6  # smallest / largest principal extent below which a mesh is flat
MAX_HOLE_EDGES = 64  # holes with at most this many boundary edges are "small" and filled
PART_GAP_M = 1e-3
"""Gap between the bounding boxes of two edge-disconnected pieces of a mesh above which they are separate
parts, m: pieces that overlap or touch (a mug's handle modelled as its own closed surface through the
wall) form one object."""
MAX_PIECES_GROUPED = 2000
"""Most edge-disconnected pieces :func:`separate_parts` groups by their bounding boxes (pairwise); above
it, every piece counts as a part."""


@dataclass(frozen=True)
class Mesh:
    """A validated triangle mesh.

    Attributes:
        vertices: Vertex positions in metres, shape (V, 3).
        faces: Triangles as vertex indices, shape (F, 3), outward winding.
        source: Where it came from (file path or description).
        watertight: True if every edge is shared by exactly two faces (a closed surface).
        notes: Repairs made, for the user to see.
    """

    vertices: np.ndarray
    faces: np.ndarray
    source: str = ""
    watertight: bool = True
    notes: tuple[str, ...] = ()

    @property
    def extent(self) -> np.ndarray:
        """Axis-aligned size in metres, shape (3,)."""
        return self.vertices.max(axis=0) - self.vertices.min(axis=0)

    @property
    def volume(self) -> float:
        """Enclosed volume in m³ (meaningful only for a watertight mesh)."""
        return mesh_volume(self.vertices, self.faces)

    def to_trimesh(self) -> trimesh.Trimesh:
        """The mesh as a :class:`trimesh.Trimesh` (no processing)."""
        import trimesh  # lazy: trimesh + SciPy; the Mesh type is used where no mesh operation is

        return trimesh.Trimesh(self.vertices, self.faces, process=False)


def separate_parts(vertices: np.ndarray, faces: np.ndarray) -> int:
    """How many separate parts a mesh falls into: its edge-connected pieces, grouped where they meet.

    Pieces joined by no edge but whose bounding boxes overlap or lie within :data:`PART_GAP_M` of each
    other count as one part (closed shells modelled through each other, such as a handle through a wall);
    pieces farther apart are separate parts, which one rigid body cannot mean.

    Args:
        vertices: Vertex positions in metres, shape (V, 3).
        faces: Triangles, shape (F, 3).

    Returns:
        The number of parts (1 for a connected mesh).
    """
    from scipy.sparse import coo_matrix  # lazy: SciPy, as trimesh below
    from scipy.sparse.csgraph import connected_components

    edges = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    n = len(vertices)
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    pieces, piece = np.unique(labels[faces[:, 0]], return_inverse=True)
    if len(pieces) == 1 or len(pieces) > MAX_PIECES_GROUPED:
        return len(pieces)
    corners = vertices[faces]  # (F, 3, 3): every vertex a face uses
    low = np.full((len(pieces), 3), np.inf)
    high = np.full((len(pieces), 3), -np.inf)
    np.minimum.at(low, piece, corners.min(axis=1))
    np.maximum.at(high, piece, corners.max(axis=1))
    meet = np.all(
        (low[:, None, :] <= high[None, :, :] + PART_GAP_M)
        & (low[None, :, :] <= high[:, None, :] + PART_GAP_M),
        axis=2,
    )
    groups, _ = connected_components(coo_matrix(meet), directed=False)
    return int(groups)


def validate_mesh(
    vertices: npt.ArrayLike, faces: npt.ArrayLike, source: str, *, require_watertight: bool = True
) -> Mesh:
    """Check a mesh, repair what is safe to repair, and return it.

    Args:
        vertices: Vertex positions in metres, shape (V, 3).
        faces: Triangles, shape (F, 3), integer vertex indices.
        source: Name used in messages (usually the file path).
        require_watertight: Raise if the repaired mesh is still not closed (its volume, and so its mass
            from a density, would be meaningless). Pass False when the mass is given explicitly.

    Returns:
        The repaired mesh, with each repair listed in ``notes``, and a note when it falls into several
        disconnected parts (they move as one rigid body, which is rarely what two objects in one file mean).

    Raises:
        MeshError: Fewer than 4 vertices, no faces, non-finite vertices, face indices out of range,
            a flat or degenerate mesh, or (with ``require_watertight``) a mesh that stays open.
    """
    v, f = _checked_arrays(vertices, faces, source)
    mesh, notes = _repaired(v, f, source)
    parts = separate_parts(np.asarray(mesh.vertices), np.asarray(mesh.faces))
    if parts > 1:
        notes.append(
            f"the mesh has {parts} disconnected parts, apart from one another (no edge joins them and their "
            "bounding boxes do not meet); they are simulated as one rigid object: split the file to get "
            "separate objects"
        )
    if require_watertight and not mesh.is_watertight:
        raise MeshError(
            f"{source}: the mesh is not watertight after repair (open boundary or non-manifold edges), so "
            "its volume and mass are undefined; close it, or give the object's mass explicitly"
        )
    return Mesh(
        vertices=np.asarray(mesh.vertices, dtype=float),
        faces=np.asarray(mesh.faces, dtype=np.int64),
        source=source,
        watertight=bool(mesh.is_watertight),
        notes=tuple(notes),
    )


def _checked_arrays(
    vertices: npt.ArrayLike, faces: npt.ArrayLike, source: str
) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) as floats and faces (F, 3) as integers, checked before any repair.

    Raises:
        MeshError: Fewer than 4 vertices, no faces, non-finite vertices, non-integer or out-of-range face
            indices, or a flat or degenerate mesh.
    """
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(faces)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) < 4:
        raise MeshError(f"{source}: a mesh needs at least 4 vertices of 3 coordinates, got shape {v.shape}")
    bad = ~np.all(np.isfinite(v), axis=1)
    if bad.any():
        raise MeshError(
            f"{source}: vertex {int(np.argmax(bad))} is not finite ({v[bad][0].tolist()}); "
            f"{int(bad.sum())} non-finite vertices in all"
        )
    if f.ndim != 2 or f.shape[1] != 3 or len(f) == 0:
        raise MeshError(f"{source}: expected triangles of shape (F, 3) with F > 0, got shape {f.shape}")
    if not np.issubdtype(f.dtype, np.integer):
        if not np.all(np.isfinite(f)) or np.any(f != np.round(f)):
            raise MeshError(f"{source}: face indices must be integers")
        f = f.astype(np.int64)
    out = (f < 0) | (f >= len(v))
    if out.any():
        face = int(np.argmax(out.any(axis=1)))
        raise MeshError(f"{source}: face {face} has vertex index {int(f[out][0])} outside 0..{len(v) - 1}")
    centred = v - v.mean(axis=0)
    singular = np.linalg.svd(centred, compute_uv=False)
    if singular[0] <= 0 or singular[-1] / singular[0] < FLATNESS_TOL:
        raise MeshError(f"{source}: the mesh is flat or degenerate (all vertices on a plane or a line)")
    return v, f


def _repaired(v: np.ndarray, f: np.ndarray, source: str) -> tuple[trimesh.Trimesh, list[str]]:
    """The mesh with duplicates merged, bad faces removed, winding fixed, small holes capped, outward faces.

    Returns the repaired trimesh and a note per repair made.

    Raises:
        MeshError: Fewer than 4 faces remain once the degenerate and duplicate ones are removed.
    """
    import trimesh  # lazy: trimesh + SciPy; the Mesh type is used where no mesh operation is

    mesh = trimesh.Trimesh(v, f, process=False)
    notes: list[str] = []
    nv = len(mesh.vertices)
    mesh.merge_vertices()
    if len(mesh.vertices) != nv:
        notes.append(f"merged {nv - len(mesh.vertices)} duplicate vertices")
    keep = mesh.nondegenerate_faces() & mesh.unique_faces()
    if not keep.all():
        mesh.update_faces(keep)
        mesh.remove_unreferenced_vertices()
        notes.append(f"removed {int((~keep).sum())} degenerate or duplicate faces")
    if len(mesh.faces) < 4:
        raise MeshError(
            f"{source}: only {len(mesh.faces)} usable faces remain after removing degenerate ones"
        )
    if not mesh.is_winding_consistent:
        trimesh.repair.fix_winding(mesh)
        notes.append("made face winding consistent")
    if not mesh.is_watertight and mesh.is_winding_consistent:
        mesh = _capped(mesh, notes)
    if mesh.is_watertight and mesh.volume < 0:
        trimesh.repair.fix_inversion(mesh)
        notes.append("inverted faces pointing inwards")
    return mesh, notes


def _capped(mesh: trimesh.Trimesh, notes: list[str]) -> trimesh.Trimesh:
    """The mesh with its holes capped when each has at most :data:`MAX_HOLE_EDGES` edges and that closes it.

    Otherwise the mesh as it is; a capping is added to ``notes``.
    """
    import trimesh  # lazy: trimesh + SciPy

    loops = boundary_loops(mesh.faces)
    if loops and all(len(loop) <= MAX_HOLE_EDGES for loop in loops):
        capped_v, capped_f = cap_loops(mesh.vertices, mesh.faces, loops)
        capped = trimesh.Trimesh(capped_v, capped_f, process=False)
        if capped.is_watertight:
            notes.append(
                f"filled {len(loops)} small holes (at most {MAX_HOLE_EDGES} edges each) with "
                f"{len(capped_f) - len(mesh.faces)} faces"
            )
            return capped
    return mesh


def principal_extents(vertices: npt.ArrayLike) -> np.ndarray:
    """Extents of a point set along its principal axes, largest first, in its own units, shape (3,).

    The smallest is the thickness of a plate whatever its orientation (an axis-aligned box would overstate
    a tilted plate's).

    Args:
        vertices: Points, shape (V, 3), V ≥ 1, finite.
    """
    v = np.asarray(vertices, dtype=float)
    centred = v - v.mean(axis=0)
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    projected = centred @ axes.T
    extents = projected.max(axis=0) - projected.min(axis=0)
    return np.concatenate([extents, np.zeros(3 - len(extents))])


def boundary_loops(faces: npt.ArrayLike) -> list[list[int]]:
    """The open boundary of a consistently wound triangle mesh as closed vertex loops.

    Args:
        faces: Triangles, shape (F, 3).

    Returns:
        One list of vertex indices per hole, in the order of the faces' directed boundary edges; empty for a
        closed mesh. Boundaries through non-manifold vertices (where loops cannot be told apart) give none.
    """
    f = np.asarray(faces, dtype=np.int64)
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    present = {(int(a), int(b)) for a, b in directed}
    boundary = [(a, b) for a, b in present if (b, a) not in present]
    nxt: dict[int, int] = {}
    for a, b in boundary:
        if a in nxt:
            return []
        nxt[a] = b
    loops = []
    while nxt:
        start, loop = next(iter(nxt)), []
        v = start
        while v in nxt:
            loop.append(v)
            v = nxt.pop(v)
        if v != start:
            return []
        loops.append(loop)
    return loops


def cap_loops(
    vertices: npt.ArrayLike, faces: npt.ArrayLike, loops: list[list[int]]
) -> tuple[np.ndarray, np.ndarray]:
    """Close each boundary loop with a fan of triangles around the loop's centroid.

    The fan keeps the mesh's winding (each cap triangle runs against its boundary edge). It is exact for
    planar star-shaped loops — a cut through a tube, a missing patch of a smooth surface — which is what
    callers pass.

    Args:
        vertices: Vertex positions, shape (V, 3).
        faces: Triangles, shape (F, 3).
        loops: Loops from :func:`boundary_loops`.

    Returns:
        Vertices with one centroid appended per loop, and the faces with the caps appended.
    """
    v = [np.asarray(vertices, dtype=float)]
    f = [np.asarray(faces, dtype=np.int64)]
    n = len(v[0])
    for loop in loops:
        ring = np.asarray(loop, dtype=np.int64)
        if len(ring) == 3:
            f.append(ring[::-1][None, :])
            continue
        v.append(v[0][ring].mean(axis=0, keepdims=True))
        f.append(np.column_stack([np.roll(ring, -1), ring, np.full(len(ring), n)]))
        n += 1
    return np.vstack(v), np.vstack(f)
