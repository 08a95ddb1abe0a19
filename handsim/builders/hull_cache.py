"""The on-disk cache of convex decompositions, keyed by the content hash of the mesh and CoACD's settings.

Entries live in ``cache_dir/coacd/<key[:2]>/<key>.npz`` (``cache_dir``: :func:`default_cache_dir`), keyed
by :func:`cache_key`, with the catalogue's objects pre-decomposed in a read-only bundled cache
(:func:`bundled_entry`). Entries are written atomically and carry a checksum; :func:`read_entry` raises
:class:`CorruptEntryError` for any entry that cannot be trusted (:func:`handsim.builders.decompose.decompose`
deletes, rebuilds and reports it). Only successes are cached.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import io
import json
import os
import sys
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
from handsim.datatypes.mesh import Mesh
from handsim.files import write_atomic

CACHE_FORMAT_VERSION = 1  # bump when the entry layout or the hull post-processing changes

BUNDLED_CACHE_DIR = ASSETS_DIR / "coacd_cache"  # read-only entries for the catalogue, see bundled_entry


def bundled_entry(key: str) -> Path:
    """Where handsim's read-only cache of catalogue hulls would hold the entry ``key``.

    The catalogue's concave objects are decomposed once, by ``scripts/bundle_catalog_hulls.py``, and the
    entries ship in ``handsim/assets/coacd_cache`` so that building them is instant; the key includes the
    CoACD version, so another version decomposes anew.
    """
    return BUNDLED_CACHE_DIR / "coacd" / key[:2] / f"{key}.npz"


def default_cache_dir() -> Path:
    """The folder of handsim's on-disk caches.

    Returns:
        ``$HANDSIM_CACHE_DIR`` if set, else the platform's user cache folder: ``$XDG_CACHE_HOME/handsim``
        or ``~/.cache/handsim`` on Linux, ``~/Library/Caches/handsim`` on macOS,
        ``%LOCALAPPDATA%/handsim/Cache`` on Windows.
    """
    explicit = os.environ.get("HANDSIM_CACHE_DIR")
    if explicit:
        return Path(explicit).expanduser()
    if sys.platform == "win32":
        local = os.environ.get("LOCALAPPDATA")
        base = Path(local) if local else Path.home() / "AppData" / "Local"
        return base / "handsim" / "Cache"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "handsim"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".cache"
    return base / "handsim"


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


class CorruptEntryError(Exception):
    """A cache entry that cannot be trusted; the message says why."""


def array_checksum(arrays: dict[str, np.ndarray]) -> str:
    """SHA-256 of named arrays (names, dtypes, shapes and bytes, in name order): an entry's checksum."""
    h = hashlib.sha256()
    for k in sorted(arrays):
        a = np.ascontiguousarray(arrays[k])
        h.update(f"{k} {a.dtype.str} {a.shape}\n".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def write_checked(path: Path, arrays: dict[str, np.ndarray], format_version: int) -> None:
    """Write named arrays as an ``.npz`` entry with its format and checksum, atomically.

    The layout :func:`read_checked` verifies, shared by the on-disk caches (hulls, generated meshes).

    Raises:
        OSError: It cannot be written (:func:`handsim.files.write_atomic`).
    """
    arrays = {**arrays, "format": np.array(format_version, dtype=np.int64)}
    arrays["checksum"] = np.array(array_checksum(arrays))
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    write_atomic(path, buffer.getvalue())


def read_checked(path: Path, required: tuple[str, ...], format_version: int) -> dict[str, np.ndarray]:
    """The arrays of an entry :func:`write_checked` wrote, verified (without ``format`` and ``checksum``).

    Raises:
        CorruptEntryError: Unreadable, an array of ``required`` missing, another format, or a checksum
            mismatch.
    """
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: np.asarray(data[k]) for k in data.files}
    except Exception as e:  # any failure to parse means the entry cannot be used
        raise CorruptEntryError(f"unreadable: {type(e).__name__}: {e}") from e
    missing = [k for k in (*required, "format", "checksum") if k not in arrays]
    if missing:
        raise CorruptEntryError(f"missing arrays {', '.join(missing)}")
    try:
        if arrays["format"].shape != () or int(arrays["format"]) != format_version:
            raise ValueError(f"format {arrays['format']!r}, expected {format_version}")
    except (ValueError, TypeError) as e:
        raise CorruptEntryError(str(e)) from e
    stored = str(arrays.pop("checksum"))
    if array_checksum(arrays) != stored:
        raise CorruptEntryError("checksum mismatch")
    del arrays["format"]
    return arrays


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
