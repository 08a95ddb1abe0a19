"""Convex decomposition of concave meshes with CoACD, run in a child process and cached on disk.

MuJoCo collides every mesh as its convex hull, so a concave object (a mug, a bowl, a ring) must be
split into convex pieces. :func:`decompose` does that:

- A convex mesh (volume equal to its hull's) skips CoACD; its convex hull is the single piece.
- Otherwise CoACD runs in a child process (:mod:`handsim.builders.coacd_process`) started with
  :mod:`subprocess` (not :mod:`multiprocessing`, which daemonic pool workers and Ray tasks cannot use).
  The child is killed after :attr:`DecompositionParams.timeout_s` or when the caller is interrupted
  (Ctrl-C), and ends by itself when the caller dies (:mod:`handsim.lifeline`); a CoACD crash (it aborts
  the process on some inputs) becomes a :class:`DecompositionError` naming the mesh instead of the death
  of the caller.
- Results are cached (:mod:`handsim.builders.hull_cache`) in ``cache_dir/coacd/<key[:2]>/<key>.npz``,
  keyed by :func:`cache_key`, with the catalogue's objects pre-decomposed in a read-only bundled cache
  (:func:`bundled_entry`). Entries are written atomically and carry a checksum; a corrupt entry is
  deleted, rebuilt and reported in :attr:`Decomposition.notes`. Only successes are cached, so an entry
  exists only for a mesh found concave: the cache is read before the convexity test, and a hit computes
  no hull (nor imports trimesh and SciPy).
- A mesh of more than :data:`COACD_FACE_WARNING` faces is decomposed all the same, after a warning on
  stderr (and a note) naming the mesh and its face count: CoACD may then run until its timeout.
- Every hull returned is recomputed by qhull (consistent outward faces) and has at least 4
  non-coplanar vertices, as MuJoCo requires; flat pieces from CoACD are dropped with a note.

The child is started by file path and imports only NumPy and CoACD, so starting it and exchanging the
``.npz`` files adds about 0.2 s per decomposition (``python -m handsim.builders._coacd_worker`` would
import the package and MuJoCo first: about 0.9 s; measured costs in ``docs/measurements.md``).

The settings and result types are in :mod:`handsim.builders.decomposition_types`.
"""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

import numpy as np

from handsim.builders.coacd_process import run_worker
from handsim.builders.decomposition_types import (
    ConvexHull,
    Decomposition,
    DecompositionError,
    DecompositionParams,
)
from handsim.builders.hull_cache import bundled_entry, cache_key, read_entry, write_entry
from handsim.cache import CorruptEntryError, default_cache_dir, write_failed
from handsim.datatypes.mesh import FLATNESS_TOL, Mesh

CONVEX_RTOL = 1e-3  # within 0.1 % of its hull's volume a mesh counts as convex (tessellation dents)
"""Part of the convexity rule that decides which meshes are decomposed. The hull cache is read before the
rule is applied (an entry exists only for a mesh the rule found concave), and its key does not hold the
rule: a change of the rule (this tolerance, :func:`_hull_if_convex`) must bump
:data:`~handsim.builders.hull_cache.CACHE_FORMAT_VERSION` and rebuild the bundled cache
(``scripts/bundle_catalog_hulls.py``), or cached decompositions would outlive it."""

COACD_FACE_WARNING = 200_000
"""Face count beyond which :func:`decompose` warns before starting CoACD. CoACD's time grows with the face
count (its preprocessing and every cut visit all faces): a 2.1M-face scan ran out the default 600 s
timeout. Grasped household objects need a few thousand to some tens of thousands of faces for contact; a
larger mesh is usually an unsimplified scan, better decimated first (e.g. trimesh's
``simplify_quadric_decimation``) than decomposed for minutes."""


def decompose(
    mesh: Mesh,
    params: DecompositionParams = DecompositionParams(),  # noqa: B008  (a frozen dataclass: immutable)
    *,
    cache_dir: str | Path | None = None,
    use_cache: bool = True,
    progress: bool = False,
) -> Decomposition:
    """Split a mesh into convex hulls with CoACD (or return its hull if it is convex).

    Args:
        mesh: A validated mesh (see :func:`handsim.datatypes.mesh.validate_mesh`); its ``source`` names it in
            messages.
        params: CoACD settings and the timeout.
        cache_dir: Root of the cache; :func:`default_cache_dir` when None.
        use_cache: Read and write the cache. When False, neither.
        progress: Show elapsed time on stderr while CoACD runs.

    Returns:
        The hulls, with the cache key, timing and notes.

    Raises:
        DecompositionError: CoACD is not installed, did not finish within ``params.timeout_s``,
            crashed, wrote invalid output, or returned no hull that is not flat.
    """
    name = mesh.source or "<unnamed mesh>"
    key = cache_key(mesh, params)
    notes: list[str] = []
    path: Path | None = None
    if use_cache:
        # looked up before the convexity test: only a mesh found concave is ever decomposed and cached, so
        # a hit needs no hull (qhull, and importing trimesh and SciPy: 0.7 s of a warm object build)
        root = Path(cache_dir) if cache_dir is not None else default_cache_dir()
        path = root / "coacd" / key[:2] / f"{key}.npz"
        cached = _cached(path, bundled_entry(key), key, notes)
        if cached is not None:
            return cached
    hull = _hull_if_convex(mesh)
    if hull is not None:
        return Decomposition(hulls=(hull,), key=key, skipped="mesh is convex")

    faces = len(mesh.faces)
    if faces > COACD_FACE_WARNING:
        note = (
            f"{name}: {faces} faces, more than the {COACD_FACE_WARNING} beyond which CoACD may run until its "
            f"{params.timeout_s:g} s timeout; decimate the mesh first to decompose it in seconds"
        )
        print(f"handsim: warning: {note}", file=sys.stderr, flush=True)
        notes.append(note)
    raw, seconds = run_worker(mesh, params, name, progress)
    hulls, dropped = _usable_hulls(raw, name)
    if path is not None:
        try:
            write_entry(path, hulls, seconds, tuple(dropped))
        except OSError as e:
            notes.append(write_failed(root, path, e, "hull"))
    return Decomposition(
        hulls=hulls,
        key=key,
        seconds=seconds,
        coacd_seconds=seconds,
        notes=(*dropped, *notes),
    )


def _cached(path: Path, bundled: Path, key: str, notes: list[str]) -> Decomposition | None:
    """The decomposition cached at ``path`` (else in the bundled cache), or None.

    A corrupt entry at ``path`` is deleted (the rebuilt one replaces it) and a corrupt bundled entry
    ignored, each with a note appended to ``notes``.
    """
    for where, own in ((path, True), (bundled, False)):
        if not where.exists():
            continue
        try:
            hulls, coacd_seconds, old_notes = read_entry(where)
        except CorruptEntryError as e:
            if own:
                notes.append(f"cache entry {where} was corrupt ({e}) and was rebuilt")
                with contextlib.suppress(OSError):  # the rebuilt entry replaces it anyway
                    where.unlink(missing_ok=True)
            else:
                notes.append(f"bundled cache entry {where} is corrupt ({e}); decomposing anew")
            continue
        return Decomposition(
            hulls=hulls, key=key, from_cache=True, coacd_seconds=coacd_seconds, notes=old_notes
        )
    return None


# ----------------------------------------------------------------------------------------------- hulls


def _hull_of(points: np.ndarray) -> ConvexHull | None:
    """The convex hull of ``points``, or None if they are too few, not finite, or (nearly) coplanar."""
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 4 or not np.all(np.isfinite(p)):
        return None
    singular = np.linalg.svd(p - p.mean(axis=0), compute_uv=False)
    if singular[0] <= 0 or singular[-1] / singular[0] < FLATNESS_TOL:
        return None
    import trimesh  # lazy: trimesh and SciPy (0.7 s), only when a hull is computed
    from scipy.spatial import QhullError

    try:
        hull = trimesh.convex.convex_hull(p)
    except (QhullError, ValueError):
        return None
    if len(hull.vertices) < 4 or not hull.is_watertight or not hull.volume > 0:
        return None
    return ConvexHull(
        vertices=np.ascontiguousarray(hull.vertices, dtype=np.float64),
        faces=np.ascontiguousarray(hull.faces, dtype=np.int64),
    )


def _hull_if_convex(mesh: Mesh) -> ConvexHull | None:
    """The mesh's convex hull if the (watertight) mesh is convex, else None."""
    if not mesh.watertight:
        return None
    hull = _hull_of(mesh.vertices)
    if hull is None:
        return None
    hull_volume = hull.volume
    if abs(hull_volume - mesh.volume) <= CONVEX_RTOL * hull_volume:
        return hull
    return None


def _usable_hulls(
    raw: list[tuple[np.ndarray, np.ndarray]], name: str
) -> tuple[tuple[ConvexHull, ...], list[str]]:
    """Recompute each CoACD piece's hull; drop flat ones with a note."""
    hulls: list[ConvexHull] = []
    notes: list[str] = []
    for i, (vertices, _) in enumerate(raw):
        hull = _hull_of(vertices)
        if hull is None:
            notes.append(
                f"dropped CoACD hull {i} of {len(raw)}: flat or degenerate ({len(vertices)} vertices)"
            )
        else:
            hulls.append(hull)
    if not hulls:
        raise DecompositionError(f"{name}: all {len(raw)} hulls returned by CoACD are flat or degenerate")
    return tuple(hulls), notes
