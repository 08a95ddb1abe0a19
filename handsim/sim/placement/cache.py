"""The glove placement search's results on disk, keyed by the content of everything the search reads.

A placement depends only on the search scene (hand, object and their poses: the compiled model, saved as
MuJoCo's binary model), the trajectory's times and targets, the grasp frames, the search's parameters
(:class:`~handsim.sim.specs.PlacementSpec`, release delay, control rate, the robustness moves)
and the code that searches and simulates. The key (:func:`placement_key`) is the SHA-256 of all of them,
with the MuJoCo and NumPy versions and a fingerprint of handsim's own source files (any edit of handsim
gives new keys: a stale entry is never read). A hit gives the stored
:class:`~handsim.sim.placement.candidates.Placement` bit for bit (pickled, read back with
:mod:`handsim.io.safe_pickle`'s restricted unpickler, which resolves only the placement's own classes and
NumPy arrays).

Entries live in ``cache_dir/placement/<key[:2]>/<key>.pkl`` (``cache_dir`` as for the convex hulls:
:func:`handsim.cache.default_cache_dir`), written atomically (temporary file, then rename).
An entry whose checksum, format or key does not match is ignored and replaced, with a note; it is never
trusted. A value changed at run time rather than in a source file (a module constant patched by a
script) is not in the key: such a caller passes ``use_cache=False`` to
:func:`~handsim.sim.placement.place.place_object`.
"""

from __future__ import annotations

import hashlib
import json
import pickle
from pathlib import Path

import mujoco
import numpy as np

from handsim.cache import CorruptEntryError, read_framed, update_array, write_framed
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import FormatError
from handsim.io.safe_pickle import loads_restricted_pickle
from handsim.sim.placement.grasp_frame import GraspFrame
from handsim.sim.scene.compiled import SimScene
from handsim.version import source_fingerprint

CACHE_FORMAT_VERSION = 1  # bump when the entry layout changes
_MAGIC = b"handsim-placement\n"


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
    update_array(h, "model", model)
    h.update(repr(scene.layout).encode())
    h.update(json.dumps(list(trajectory.dof_names)).encode())
    update_array(h, "times", np.asarray(trajectory.times, dtype=float))
    update_array(h, "targets", np.asarray(trajectory.targets, dtype=float))
    update_array(h, "valid", np.asarray(trajectory.valid))
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
    payload = read_framed(path, _MAGIC, key, "handsim placement cache entry")
    try:
        format_version, placement = loads_restricted_pickle(payload, path, allowed)
    except (FormatError, TypeError, ValueError) as e:
        raise CorruptEntryError(str(e)) from e
    if format_version != CACHE_FORMAT_VERSION:
        raise CorruptEntryError(f"format {format_version!r}, expected {CACHE_FORMAT_VERSION}")
    return placement


def write_entry(path: Path, key: str, placement: object) -> None:
    """Write an entry atomically (:func:`handsim.cache.write_framed`).

    Raises:
        OSError: It cannot be written.
    """
    payload = pickle.dumps((CACHE_FORMAT_VERSION, placement), protocol=5)
    write_framed(path, _MAGIC, key, payload)
