"""The on-disk cache of convex decompositions, keyed by the content hash of the mesh and CoACD's settings.

Entries live in ``cache_dir/coacd/<key[:2]>/<key>.npz`` (``cache_dir``:
:func:`handsim.cache.default_cache_dir`), keyed by :func:`cache_key`, with the catalogue's objects
pre-decomposed in a read-only bundled cache (:func:`bundled_entry`). Entries are written atomically and
carry a checksum (:func:`handsim.cache.write_checked`); :func:`read_entry` raises
:class:`~handsim.cache.CorruptEntryError` for any entry that cannot be trusted
(:func:`handsim.builders.decompose.decompose` deletes, rebuilds and reports it). Only successes are cached.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import json
from functools import lru_cache
from pathlib import Path

import numpy as np

from handsim.assets import ASSETS_DIR
from handsim.builders.decomposition_types import (
    HULL_ARRAYS,
    ConvexHull,
    DecompositionParams,
    coacd_kwargs,
    pack_hulls,
    unpack_hulls,
)
from handsim.cache import CorruptEntryError, read_checked, write_checked
from handsim.datatypes.mesh import Mesh

CACHE_FORMAT_VERSION = 1  # bump when the entry layout or the hull post-processing changes

BUNDLED_CACHE_DIR = ASSETS_DIR / "coacd_cache"  # read-only entries for the catalogue, see bundled_entry


def bundled_entry(key: str) -> Path:
    """Where handsim's read-only cache of catalogue hulls would hold the entry ``key``.

    The catalogue's concave objects are decomposed once, by ``scripts/bundle_catalog_hulls.py``, and the
    entries ship in ``handsim/assets/coacd_cache`` so that building them is instant; the key includes the
    CoACD version, so another version decomposes anew.
    """
    return BUNDLED_CACHE_DIR / "coacd" / key[:2] / f"{key}.npz"


@lru_cache(maxsize=1)
def _coacd_version() -> str:
    try:
        return importlib.metadata.version("coacd")
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def cache_key(mesh: Mesh, params: DecompositionParams) -> str:
    """The cache key of decomposing ``mesh`` with ``params``.

    Args:
        mesh: The mesh.
        params: CoACD settings; ``timeout_s`` does not enter the key.

    Returns:
        Hex SHA-256 of the vertex bytes (float64, C order), the face bytes (int64), the CoACD arguments
        as canonical JSON, the CoACD version and :data:`CACHE_FORMAT_VERSION`.
    """
    h = hashlib.sha256()
    h.update(f"handsim-coacd/{CACHE_FORMAT_VERSION}/coacd {_coacd_version()}\n".encode())
    h.update(json.dumps(coacd_kwargs(params), sort_keys=True, separators=(",", ":")).encode() + b"\n")
    for name, array, dtype in (("vertices", mesh.vertices, "<f8"), ("faces", mesh.faces, "<i8")):
        a = np.ascontiguousarray(array, dtype=dtype)
        h.update(f"{name} {a.shape}\n".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def write_entry(path: Path, hulls: tuple[ConvexHull, ...], seconds: float, notes: tuple[str, ...]) -> None:
    """Write a cache entry atomically (:func:`handsim.files.write_atomic`)."""
    arrays = pack_hulls(hulls)
    arrays["coacd_seconds"] = np.array(seconds, dtype=np.float64)
    arrays["notes"] = np.array(notes, dtype=str) if notes else np.zeros(0, dtype="<U1")
    write_checked(path, arrays, CACHE_FORMAT_VERSION)


def read_entry(path: Path) -> tuple[tuple[ConvexHull, ...], float, tuple[str, ...]]:
    """Read and verify a cache entry.

    Returns:
        The hulls, the original CoACD seconds and the original notes.

    Raises:
        CorruptEntryError: Unreadable, incomplete, checksum mismatch, bad shapes or indices.
    """
    arrays = read_checked(path, (*HULL_ARRAYS, "coacd_seconds", "notes"), CACHE_FORMAT_VERSION)
    try:
        raw = unpack_hulls(arrays)
        seconds = float(arrays["coacd_seconds"])
        notes = tuple(str(n) for n in arrays["notes"].reshape(-1))
    except (ValueError, TypeError) as e:
        raise CorruptEntryError(str(e)) from e
    if not raw:
        raise CorruptEntryError("no hulls")
    return tuple(ConvexHull(vertices=v, faces=f) for v, f in raw), seconds, notes
