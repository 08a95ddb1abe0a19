"""What a CoACD decomposition takes and gives: its settings, the convex hulls, and their array form.

:class:`DecompositionParams` (CoACD's settings and the timeout, checked on construction), :class:`ConvexHull`
and :class:`Decomposition` (the result of :func:`handsim.builders.decompose.decompose`), and the packed
array layout of a list of hulls that both the CoACD worker's output and the hull cache's entries use
(:func:`pack_hulls`, :func:`unpack_hulls`).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from handsim.datatypes.mesh_mass import mesh_volume
from handsim.errors import MeshError

_PREPROCESS_MODES = ("auto", "on", "off")
HULL_ARRAYS = ("vertices", "faces", "vertex_counts", "face_counts")  # the packed layout, see pack_hulls


class DecompositionError(MeshError):
    """CoACD crashed, timed out, or returned no usable convex hull."""


def _as_int(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    return int(value)


def _as_float(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class DecompositionParams:
    """CoACD settings (see the CoACD README for their exact meaning).

    Attributes:
        threshold: Concavity threshold, in [0.01, 1]; lower gives more, tighter hulls.
        max_convex_hull: Upper bound on the hull count, or -1 for no limit.
        preprocess_mode: Manifold pre-processing: ``"auto"``, ``"on"`` or ``"off"``.
        preprocess_resolution: Voxel resolution of the pre-processing.
        resolution: Sampling resolution of the Hausdorff distance.
        mcts_nodes: Maximum child nodes in the Monte Carlo tree search.
        mcts_iterations: Search iterations of the Monte Carlo tree search.
        mcts_max_depth: Maximum search depth of the Monte Carlo tree search.
        max_ch_vertex: Maximum vertices per hull (CoACD's hull decimation is always on).
        seed: Random seed, in [0, 2**32 - 1]; fixed seed, identical result.
        timeout_s: Seconds after which the CoACD child process is killed; not part of the cache key.
    """

    threshold: float = 0.05
    max_convex_hull: int = 16
    preprocess_mode: str = "auto"
    preprocess_resolution: int = 50
    resolution: int = 2000
    mcts_nodes: int = 20
    mcts_iterations: int = 150
    mcts_max_depth: int = 3
    max_ch_vertex: int = 256
    seed: int = 0
    timeout_s: float = 600.0

    def __post_init__(self) -> None:
        def put(name: str, value: Any) -> None:
            object.__setattr__(self, name, value)

        threshold = _as_float("threshold", self.threshold)
        if not 0.01 <= threshold <= 1.0:
            raise ValueError(f"threshold must be in [0.01, 1], got {threshold!r}")
        put("threshold", threshold)
        max_hulls = _as_int("max_convex_hull", self.max_convex_hull)
        if max_hulls != -1 and max_hulls < 1:
            raise ValueError(f"max_convex_hull must be -1 (no limit) or at least 1, got {max_hulls}")
        put("max_convex_hull", max_hulls)
        if self.preprocess_mode not in _PREPROCESS_MODES:
            raise ValueError(
                f"preprocess_mode must be one of 'auto', 'on', 'off', got {self.preprocess_mode!r}"
            )
        for name in (
            "preprocess_resolution",
            "resolution",
            "mcts_nodes",
            "mcts_iterations",
            "mcts_max_depth",
        ):
            value = _as_int(name, getattr(self, name))
            if value < 1:
                raise ValueError(f"{name} must be at least 1, got {value}")
            put(name, value)
        max_ch_vertex = _as_int("max_ch_vertex", self.max_ch_vertex)
        if max_ch_vertex < 4:
            raise ValueError(
                f"max_ch_vertex must be at least 4 (a hull needs 4 vertices), got {max_ch_vertex}"
            )
        put("max_ch_vertex", max_ch_vertex)
        seed = _as_int("seed", self.seed)
        if not 0 <= seed <= 2**32 - 1:
            raise ValueError(f"seed must be in [0, 2**32 - 1], got {seed}")
        put("seed", seed)
        timeout = _as_float("timeout_s", self.timeout_s)
        if timeout <= 0:
            raise ValueError(f"timeout_s must be positive, got {timeout!r}")
        put("timeout_s", timeout)


@dataclass(frozen=True)
class ConvexHull:
    """One convex piece, valid as a MuJoCo mesh.

    Attributes:
        vertices: Hull vertices in metres, shape (K, 3), K >= 4, not coplanar.
        faces: Triangles with outward winding, shape (J, 3), int64 indices into ``vertices``.
    """

    vertices: np.ndarray
    faces: np.ndarray

    @property
    def volume(self) -> float:
        """Volume in m³."""
        return mesh_volume(self.vertices, self.faces)


@dataclass(frozen=True)
class Decomposition:
    """The convex pieces of a mesh, and how they were obtained.

    Attributes:
        hulls: The convex pieces (at least one).
        key: The cache key (hex SHA-256), see :func:`cache_key`.
        from_cache: True if the hulls were read from the cache.
        seconds: Wall time in seconds of the CoACD child process run by this call (process start
            included); 0 for a cache hit or a convex mesh.
        coacd_seconds: Wall time in seconds of the CoACD run that produced the hulls, also for a cache
            hit (the original run's); 0 for a convex mesh.
        skipped: ``""``, or why CoACD was not run (``"mesh is convex"``).
        notes: What the user should know: dropped flat hulls (a cache hit repeats the original run's
            notes), a corrupt cache entry rebuilt, a cache entry that could not be written.
    """

    hulls: tuple[ConvexHull, ...]
    key: str
    from_cache: bool = False
    seconds: float = 0.0
    coacd_seconds: float = 0.0
    skipped: str = ""
    notes: tuple[str, ...] = field(default=())


def coacd_kwargs(params: DecompositionParams) -> dict[str, Any]:
    """Keyword arguments of :func:`coacd.run_coacd` (decimation on, so ``max_ch_vertex`` applies)."""
    kwargs = asdict(params)
    del kwargs["timeout_s"]
    kwargs["decimate"] = True
    return kwargs


def pack_hulls(hulls: tuple[ConvexHull, ...]) -> dict[str, np.ndarray]:
    """Hulls as the flat arrays :data:`HULL_ARRAYS` (all vertices, all faces, per-hull counts)."""
    return {
        "vertices": np.concatenate([h.vertices for h in hulls]),
        "faces": np.concatenate([h.faces for h in hulls]),
        "vertex_counts": np.array([len(h.vertices) for h in hulls], dtype=np.int64),
        "face_counts": np.array([len(h.faces) for h in hulls], dtype=np.int64),
    }


def unpack_hulls(data: Any) -> list[tuple[np.ndarray, np.ndarray]]:
    """Split packed hull arrays (an open ``.npz``) into per-hull arrays.

    Raises:
        ValueError: An array is missing or has the wrong dtype or shape, or a face index is out of range.
    """
    missing = [k for k in HULL_ARRAYS if k not in data]
    if missing:
        raise ValueError(f"missing arrays {', '.join(missing)}")
    v, f, nv, nf = (np.asarray(data[k]) for k in HULL_ARRAYS)
    if v.ndim != 2 or v.shape[1] != 3 or not np.issubdtype(v.dtype, np.floating):
        raise ValueError(f"vertices must be floats of shape (N, 3), got {v.dtype} {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError("vertices are not all finite")
    if f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.integer):
        raise ValueError(f"faces must be integers of shape (M, 3), got {f.dtype} {f.shape}")
    for k, counts in (("vertex_counts", nv), ("face_counts", nf)):
        if counts.ndim != 1 or not np.issubdtype(counts.dtype, np.integer) or np.any(counts < 0):
            raise ValueError(
                f"{k} must be non-negative integers of shape (H,), got {counts.dtype} {counts.shape}"
            )
    if len(nv) != len(nf) or nv.sum() != len(v) or nf.sum() != len(f):
        raise ValueError(
            f"hull counts do not match the arrays ({len(nv)} vertex counts summing to {int(nv.sum())} for "
            f"{len(v)} vertices, {len(nf)} face counts summing to {int(nf.sum())} for {len(f)} faces)"
        )
    hulls = []
    v_parts = np.split(v.astype(np.float64), np.cumsum(nv)[:-1]) if len(nv) else []
    f_parts = np.split(f.astype(np.int64), np.cumsum(nf)[:-1]) if len(nf) else []
    for i, (hv, hf) in enumerate(zip(v_parts, f_parts, strict=True)):
        if hf.size and (hf.min() < 0 or hf.max() >= len(hv)):
            raise ValueError(f"hull {i} has a face index outside 0..{len(hv) - 1}")
        hulls.append((np.ascontiguousarray(hv), np.ascontiguousarray(hf)))
    return hulls
