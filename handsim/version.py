"""The package version, in one place: ``pyproject.toml`` reads it, records and ``--version`` print it.

A module of its own (not ``handsim/__init__.py``) so that any layer can name the version without importing
the package's ``__init__`` — which registers the gymnasium environments, the top layer. The source
fingerprint identifies the code more finely than the version, for cache keys.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

__version__ = "0.1.0"

_PACKAGE = Path(__file__).resolve().parent


@lru_cache(maxsize=1)
def source_fingerprint() -> str:
    """SHA-256 of every handsim source file (path and bytes), read once per process (~6 ms).

    The code part of the keys of caches whose entries the code computes (placements, generated meshes): any
    edit of handsim gives new keys, so a stale entry is never read.
    """
    h = hashlib.sha256()
    for path in sorted(_PACKAGE.rglob("*.py")):
        h.update(f"{path.relative_to(_PACKAGE).as_posix()}\n".encode())
        h.update(path.read_bytes())
    return h.hexdigest()
