"""The on-disk caches' common ground: where they live, how entries are checked, and what a bad entry is.

handsim caches work that is expensive and deterministic — convex decompositions
(:mod:`handsim.builders.hull_cache`), the catalogue's generated meshes (:mod:`handsim.builders.mesh_cache`)
and glove placements (:mod:`handsim.sim.placement.cache`) — under one folder (:func:`default_cache_dir`).
Every entry is written atomically (:func:`handsim.files.write_atomic`) and carries a SHA-256 checksum of its
content; an entry that is unreadable, of another format, written for another key or whose checksum does
not match raises :class:`CorruptEntryError` when read, and its cache computes the value again instead of
trusting it. Two entry layouts exist: named NumPy arrays in an ``.npz`` (:func:`write_checked`,
:func:`read_checked`) and a payload of bytes behind a header naming its key (:func:`write_framed`,
:func:`read_framed`). An entry that cannot be written is reported by :func:`write_failed`: a warning once
per cache folder, and a note on the result.
"""

from __future__ import annotations

import hashlib
import io
import logging
import os
import sys
from pathlib import Path
from typing import Protocol

import numpy as np

from handsim.errors import HandsimError
from handsim.files import write_atomic

CACHE_DIR_ENV = "HANDSIM_CACHE_DIR"
"""The environment variable that names the cache folder, overriding the platform's default."""


_log = logging.getLogger(__name__)
_unwritable: set[str] = set()
"""The cache folders this process has already reported it cannot write to."""


class CorruptEntryError(HandsimError):
    """A cache entry that cannot be trusted; the message says why."""


class Hasher(Protocol):
    """What :func:`update_array` needs of a :mod:`hashlib` object (whose class hashlib does not export)."""

    def update(self, data: bytes, /) -> None:
        """Feed ``data`` to the hash."""


def default_cache_dir() -> Path:
    """The folder of handsim's on-disk caches.

    Returns:
        ``$HANDSIM_CACHE_DIR`` if set, else the platform's user cache folder: ``$XDG_CACHE_HOME/handsim``
        or ``~/.cache/handsim`` on Linux, ``~/Library/Caches/handsim`` on macOS,
        ``%LOCALAPPDATA%/handsim/Cache`` on Windows.
    """
    explicit = os.environ.get(CACHE_DIR_ENV)
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


def write_failed(root: Path, path: Path, error: OSError, what: str) -> str:
    """Report that a cache entry could not be written: a warning once per cache folder, a note every time.

    A cache that cannot be written (a read-only folder, ``$HANDSIM_CACHE_DIR`` naming a file, a full disk)
    costs time, not correctness: the value is computed again on every run. The first failure under
    ``root`` in this process is logged as a warning (on stderr from the command line), saying so and how to
    fix it; later ones stay quiet, so a dataset run does not repeat it for every trial.

    Args:
        root: The cache folder.
        path: The entry that could not be written.
        error: Why.
        what: The cache, e.g. ``"hull"``, ``"mesh"``, ``"placement"``.

    Returns:
        The note for the result that was not cached: ``could not write <what> cache entry PATH: REASON``.
    """
    note = f"could not write {what} cache entry {path}: {error.strerror or error}"
    if str(root) not in _unwritable:
        _unwritable.add(str(root))
        _log.warning(
            "%s; the cache folder %s cannot be written, so cached results are computed again on every run "
            "(make it writable, or set %s to a writable folder)",
            note,
            root,
            CACHE_DIR_ENV,
        )
    return note


def update_array(h: Hasher, name: str, array: np.ndarray | None) -> None:
    """Feed an array to a hash: its name, dtype, shape and bytes (C order); None is a name and ``none``."""
    if array is None:
        h.update(f"{name} none\n".encode())
        return
    a = np.ascontiguousarray(array)
    h.update(f"{name} {a.dtype.str} {a.shape}\n".encode())
    h.update(a.tobytes())


def array_checksum(arrays: dict[str, np.ndarray]) -> str:
    """SHA-256 of named arrays (names, dtypes, shapes and bytes, in name order): an entry's checksum."""
    h = hashlib.sha256()
    for k in sorted(arrays):
        update_array(h, k, arrays[k])
    return h.hexdigest()


def write_checked(path: Path, arrays: dict[str, np.ndarray], format_version: int) -> None:
    """Write named arrays as an ``.npz`` entry with its format and checksum, atomically.

    The layout :func:`read_checked` verifies, shared by the on-disk caches of arrays (hulls, generated
    meshes).

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


def write_framed(path: Path, magic: bytes, key: str, payload: bytes) -> None:
    """Write ``payload`` behind a header (``magic``, the hex ``key``, the payload's SHA-256), atomically.

    The layout :func:`read_framed` verifies, for caches whose value is not a set of arrays (placements).

    Raises:
        OSError: It cannot be written (:func:`handsim.files.write_atomic`).
    """
    write_atomic(path, magic + f"{key}\n{hashlib.sha256(payload).hexdigest()}\n".encode("ascii") + payload)


def read_framed(path: Path, magic: bytes, key: str, what: str) -> bytes:
    """The payload of an entry :func:`write_framed` wrote for ``key``, verified.

    Args:
        path: The entry.
        magic: The header it must start with.
        key: The hex SHA-256 key (64 characters) it must have been written for.
        what: What the entry is, for the message (e.g. ``"handsim placement cache entry"``).

    Raises:
        CorruptEntryError: Unreadable, another header, written for another key, or a checksum mismatch.
    """
    try:
        data = path.read_bytes()
    except OSError as e:
        raise CorruptEntryError(f"unreadable: {e}") from e
    header_end = len(magic) + 64 + 1 + 64 + 1
    if not data.startswith(magic) or len(data) < header_end:
        raise CorruptEntryError(f"not a {what}")
    stored_key = data[len(magic) : len(magic) + 64].decode("ascii", errors="replace")
    checksum = data[len(magic) + 65 : header_end - 1].decode("ascii", errors="replace")
    payload = data[header_end:]
    if stored_key != key:
        raise CorruptEntryError("written for another key")
    if hashlib.sha256(payload).hexdigest() != checksum:
        raise CorruptEntryError("checksum mismatch")
    return payload
