"""Files written whole or not at all: what the records, caches, reports and CLI outputs share.

A bottom-layer module (no handsim imports), so every layer that writes a result can use it.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import threading
from pathlib import Path

HASH_CHUNK = 1 << 20
"""Bytes read at a time while hashing a file (1 MiB: a large recording is never held whole)."""


def sha256_file(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex), read in chunks of :data:`HASH_CHUNK`.

    Raises:
        OSError: The file cannot be read.
    """
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(HASH_CHUNK):
            digest.update(chunk)
    return digest.hexdigest()


def write_atomic(path: str | Path, data: bytes) -> Path:
    """Write a file so that readers see the old or the new content, never a part (temp file + rename).

    Raises:
        OSError: The file cannot be written; its ``filename`` is ``path`` (not the temporary file's).
    """
    target = Path(path)
    # one temporary file per process and thread: writers of the same target never share one
    tmp = target.with_name(f".{target.name}.tmp{os.getpid()}.{threading.get_ident()}")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, target)
    except BaseException as exc:  # a full disk, Ctrl-C: no partial file left behind
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError) and exc.errno is not None:
            raise OSError(exc.errno, exc.strerror, str(target)) from exc
        raise
    return target
