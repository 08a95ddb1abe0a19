"""The catalogue's generated meshes on disk, so that a warm object build imports neither trimesh nor SciPy.

GraspDB14's objects are generated with trimesh (:mod:`handsim.builders.graspdb_meshes`) and validated
(:func:`handsim.datatypes.mesh.validate_mesh`, trimesh again): importing trimesh and SciPy is 0.7 s, most of
``handsim build object mug`` once its hulls are cached. :func:`generated_mesh` stores each validated mesh
in ``cache_dir/meshes/<key[:2]>/<key>.npz`` (``cache_dir``:
:func:`~handsim.cache.default_cache_dir`) and reads it back on later calls.

The key (:func:`mesh_key`) is the SHA-256 of the object's name, :data:`MESH_CACHE_FORMAT`, handsim's source
fingerprint (:func:`handsim.version.source_fingerprint`: any edit of handsim gives new keys), the NumPy,
trimesh, SciPy and networkx versions that generate and repair the mesh, and the CPU features NumPy
dispatches on, so a stale entry, or another machine's, is never read. Old entries are not deleted (about
50 kB per object and version). Entries are written
atomically and carry a checksum; an entry that fails it is regenerated (the generation is deterministic, so
nothing is lost), replaced, and logged.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import logging
import platform
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path

import numpy as np

from handsim.cache import CorruptEntryError, default_cache_dir, read_checked, write_checked, write_failed
from handsim.datatypes.mesh import Mesh
from handsim.version import source_fingerprint

MESH_CACHE_FORMAT = 1  # bump when the entry layout changes
_ARRAYS = ("vertices", "faces", "source", "watertight", "notes")
_log = logging.getLogger(__name__)


@lru_cache(maxsize=1)
def _generator_versions() -> str:
    """The libraries that generate a mesh, and the CPU features NumPy's vectorised sin/cos dispatch on.

    The features keep a cache folder shared by machines (a cluster's) from serving one machine's mesh to
    another, whose own could differ in the last bits.
    """
    versions = []
    for package in ("numpy", "trimesh", "scipy", "networkx"):
        try:
            versions.append(f"{package} {importlib.metadata.version(package)}")
        except importlib.metadata.PackageNotFoundError:
            versions.append(f"{package} not installed")
    features = getattr(getattr(np, "_core", None), "_multiarray_umath", None)
    enabled = getattr(features, "__cpu_features__", None)
    cpu = ",".join(sorted(k for k, v in enabled.items() if v)) if enabled else platform.machine()
    return "/".join([*versions, f"cpu {cpu}"])


def mesh_key(name: str) -> str:
    """The cache key of the generated mesh of catalogue object ``name`` (hex SHA-256)."""
    text = f"handsim-mesh/{MESH_CACHE_FORMAT}/{_generator_versions()}/code {source_fingerprint()}/{name}"
    return hashlib.sha256(text.encode()).hexdigest()


def entry_path(cache_dir: str | Path, key: str) -> Path:
    """Where the entry of ``key`` lives under ``cache_dir``."""
    return Path(cache_dir) / "meshes" / key[:2] / f"{key}.npz"


def write_entry(path: Path, mesh: Mesh) -> None:
    """Write a mesh entry atomically (:func:`~handsim.cache.write_checked`).

    Raises:
        OSError: It cannot be written.
    """
    arrays = {
        "vertices": np.ascontiguousarray(mesh.vertices, dtype=np.float64),
        "faces": np.ascontiguousarray(mesh.faces, dtype=np.int64),
        "source": np.array(mesh.source),
        "watertight": np.array(bool(mesh.watertight)),
        "notes": np.array(mesh.notes, dtype=str) if mesh.notes else np.zeros(0, dtype="<U1"),
    }
    write_checked(path, arrays, MESH_CACHE_FORMAT)


def read_entry(path: Path) -> Mesh:
    """Read and verify a mesh entry.

    Raises:
        CorruptEntryError: Unreadable, incomplete, of another format, checksum mismatch, or a mesh that is
            not triangles indexing its vertices.
    """
    arrays = read_checked(path, _ARRAYS, MESH_CACHE_FORMAT)
    vertices, faces = arrays["vertices"], arrays["faces"]
    if (
        vertices.dtype != np.float64
        or vertices.ndim != 2
        or vertices.shape[1] != 3
        or faces.dtype != np.int64
        or faces.ndim != 2
        or faces.shape[1] != 3
        or faces.size == 0
        or faces.min() < 0
        or faces.max() >= len(vertices)
    ):
        raise CorruptEntryError(f"not a triangle mesh: vertices {vertices.shape}, faces {faces.shape}")
    return Mesh(
        vertices=vertices,
        faces=faces,
        source=str(arrays["source"]),
        watertight=bool(arrays["watertight"]),
        notes=tuple(str(n) for n in arrays["notes"].reshape(-1)),
    )


def generated_mesh(name: str, generate: Callable[[], Mesh], cache_dir: str | Path | None = None) -> Mesh:
    """The generated mesh of catalogue object ``name``, from the cache or from ``generate`` (then cached).

    Args:
        name: The catalogue name (the key; ``generate`` must depend on nothing else but handsim's code).
        generate: Makes the validated mesh.
        cache_dir: Root of the cache; :func:`~handsim.cache.default_cache_dir` when None.

    Returns:
        The mesh, bitwise the one ``generate`` gives.
    """
    root = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    path = entry_path(root, mesh_key(name))
    if path.exists():
        try:
            return read_entry(path)
        except CorruptEntryError as e:
            _log.warning("mesh cache entry %s is corrupt (%s); regenerated and replaced", path, e)
    mesh = generate()
    try:
        write_entry(path, mesh)
    except OSError as e:
        write_failed(root, path, e, "mesh")
    return mesh
