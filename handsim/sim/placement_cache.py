"""The glove placement search's results on disk, keyed by the content of everything the search reads.

A placement depends only on the search scene (hand, object and their poses: the compiled model, saved as
MuJoCo's binary model), the trajectory's times and targets, the grasp frames, the search's parameters
(:class:`~handsim.sim.placement_types.PlacementSpec`, release delay, control rate, the robustness moves)
and the code that searches and simulates. The key (:func:`placement_key`) is the SHA-256 of all of them,
with the MuJoCo and NumPy versions and a fingerprint of handsim's own source files (any edit of handsim
gives new keys: a stale entry is never read). A hit gives the stored
:class:`~handsim.sim.placement_types.Placement` bit for bit (pickled, read back with
:mod:`handsim.io.safe_pickle`'s restricted unpickler, which resolves only the placement's own classes and
NumPy arrays).

Entries live in ``cache_dir/placement/<key[:2]>/<key>.pkl`` (``cache_dir`` as for the convex hulls:
:func:`handsim.builders.hull_cache.default_cache_dir`), written atomically (temporary file, then rename).
An entry whose checksum, format or key does not match is ignored and replaced, with a note; it is never
trusted. A value changed at run time rather than in a source file (a module constant patched by a
script) is not in the key: such a caller passes ``use_cache=False`` to
:func:`~handsim.sim.placement.place_object`.
"""

from __future__ import annotations

import hashlib
import json
import pickle
from pathlib import Path
from typing import Protocol

import mujoco
import numpy as np

from handsim.datatypes.trajectory import Trajectory
from handsim.errors import FormatError
from handsim.files import write_atomic
from handsim.io.safe_pickle import loads_restricted_pickle
from handsim.sim.compiled import SimScene
from handsim.sim.grasp_frame import GraspFrame
from handsim.version import source_fingerprint

CACHE_FORMAT_VERSION = 1  # bump when the entry layout changes
_MAGIC = b"handsim-placement\n"


class _Hasher(Protocol):
    """What :func:`_update_array` needs of a :mod:`hashlib` object (whose class hashlib does not export)."""

    def update(self, data: bytes, /) -> None:
        """Feed ``data`` to the hash."""


class CorruptEntryError(Exception):
    """A placement cache entry that cannot be trusted; the message says why."""


def _update_array(h: _Hasher, name: str, array: np.ndarray | None) -> None:
    if array is None:
        h.update(f"{name} none\n".encode())
        return
    a = np.ascontiguousarray(array)
    h.update(f"{name} {a.dtype.str} {a.shape}\n".encode())
    h.update(a.tobytes())


def placement_key(scene: SimScene, trajectory: Trajectory, grasp: GraspFrame, arguments: dict) -> str:
    """The cache key of a placement search (hex SHA-256).

    Args:
        scene: The search scene.
        trajectory: The glove trajectory.
        grasp: Its grasp frames.
        arguments: The search's other inputs, JSON-ready (floats are written exactly).
    """
    h = hashlib.sha256()
    h.update(
        f"handsim-placement/{CACHE_FORMAT_VERSION}/mujoco {mujoco.__version__}/numpy {np.__version__}/"
        f"code {source_fingerprint()}\n".encode()
    )
    model = np.zeros(mujoco.mj_sizeModel(scene.model), dtype=np.uint8)
    mujoco.mj_saveModel(scene.model, None, model)
    _update_array(h, "model", model)
    h.update(repr(scene.layout).encode())
    h.update(json.dumps(list(trajectory.dof_names)).encode())
    _update_array(h, "times", np.asarray(trajectory.times, dtype=float))
    _update_array(h, "targets", np.asarray(trajectory.targets, dtype=float))
    _update_array(h, "valid", np.asarray(trajectory.valid))
    h.update(json.dumps({"grasp": grasp.to_dict(), **arguments}, sort_keys=True).encode())
    return h.hexdigest()


def entry_path(cache_dir: str | Path, key: str) -> Path:
    """Where the entry of ``key`` lives under ``cache_dir``."""
    return Path(cache_dir) / "placement" / key[:2] / f"{key}.pkl"


def read_entry(path: Path, key: str, allowed: dict) -> object:
    """The placement stored at ``path`` for ``key``.

    Args:
        path: The entry.
        key: The key it must have been written for.
        allowed: The classes the restricted unpickler may create (``(module, name) → class``).

    Raises:
        CorruptEntryError: Unreadable, wrong header, key or format, checksum mismatch, or a pickle naming
            anything but the placement's classes and arrays.
    """
    try:
        data = path.read_bytes()
    except OSError as e:
        raise CorruptEntryError(f"unreadable: {e}") from e
    header_end = len(_MAGIC) + 64 + 1 + 64 + 1
    if not data.startswith(_MAGIC) or len(data) < header_end:
        raise CorruptEntryError("not a handsim placement cache entry")
    stored_key = data[len(_MAGIC) : len(_MAGIC) + 64].decode("ascii", errors="replace")
    checksum = data[len(_MAGIC) + 65 : header_end - 1].decode("ascii", errors="replace")
    payload = data[header_end:]
    if stored_key != key:
        raise CorruptEntryError("written for another key")
    if hashlib.sha256(payload).hexdigest() != checksum:
        raise CorruptEntryError("checksum mismatch")
    try:
        format_version, placement = loads_restricted_pickle(payload, path, allowed)
    except (FormatError, TypeError, ValueError) as e:
        raise CorruptEntryError(str(e)) from e
    if format_version != CACHE_FORMAT_VERSION:
        raise CorruptEntryError(f"format {format_version!r}, expected {CACHE_FORMAT_VERSION}")
    return placement


def write_entry(path: Path, key: str, placement: object) -> None:
    """Write an entry atomically (:func:`handsim.files.write_atomic`).

    Raises:
        OSError: It cannot be written.
    """
    payload = pickle.dumps((CACHE_FORMAT_VERSION, placement), protocol=5)
    write_atomic(path, _MAGIC + f"{key}\n{hashlib.sha256(payload).hexdigest()}\n".encode("ascii") + payload)
