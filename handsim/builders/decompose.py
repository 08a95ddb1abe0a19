"""Convex decomposition of concave meshes with CoACD, run in a child process and cached on disk.

MuJoCo collides every mesh as its convex hull, so a concave object (a mug, a bowl, a ring) must be
split into convex pieces. :func:`decompose` does that:

- A convex mesh (volume equal to its hull's) skips CoACD; its convex hull is the single piece.
- Otherwise CoACD runs in a child process started with :mod:`subprocess` (not :mod:`multiprocessing`,
  which daemonic pool workers and Ray tasks cannot use). The child is killed after
  :attr:`DecompositionParams.timeout_s` or when the caller is interrupted (Ctrl-C), and ends by itself
  when the caller dies (:mod:`handsim.lifeline`); a CoACD crash (it aborts the process on some inputs)
  becomes a :class:`DecompositionError` naming the mesh instead of the death of the caller.
- Results are cached in ``cache_dir/coacd/<key[:2]>/<key>.npz``, keyed by :func:`cache_key`, with the
  catalogue's objects pre-decomposed in a read-only bundled cache (:func:`bundled_entry`). Entries
  are written atomically and carry a checksum; a corrupt entry is deleted, rebuilt and reported in
  :attr:`Decomposition.notes`. Only successes are cached.
- Every hull returned is recomputed by qhull (consistent outward faces) and has at least 4
  non-coplanar vertices, as MuJoCo requires; flat pieces from CoACD are dropped with a note.

Costs measured on the 2-core development machine (Python 3.11, coacd 1.0.14, other jobs running):
starting the child and exchanging the ``.npz`` files adds about 0.2 s per decomposition, because the
child is started by file path and imports only NumPy and CoACD (``python -m
handsim.builders._coacd_worker`` would import the package and MuJoCo first: about 0.9 s). The test
annulus (128 vertices; resolution 500, preprocess resolution 30, 60 MCTS iterations) gives 8 hulls in
about 1 s of wall time (0.6 to 0.8 s of it CoACD itself); a cache hit for it takes about 5 ms.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.metadata
import importlib.util
import io
import json
import math
import numbers
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from scipy.spatial import QhullError
from tqdm import tqdm

from handsim.assets import ASSETS_DIR
from handsim.datatypes.mesh import FLATNESS_TOL, Mesh
from handsim.errors import MeshError
from handsim.files import write_atomic

CACHE_FORMAT_VERSION = 1  # bump when the entry layout or the hull post-processing changes
CONVEX_RTOL = 1e-3  # within 0.1 % of its hull's volume a mesh counts as convex (tessellation dents)

BUNDLED_CACHE_DIR = ASSETS_DIR / "coacd_cache"  # read-only entries for the catalogue, see bundled_entry

_WORKER = Path(__file__).with_name("_coacd_worker.py")
_PREPROCESS_MODES = ("auto", "on", "off")
_POLL_S = 0.1  # how often the parent checks the child (and refreshes the progress bar)
_TAIL_LINES = 20  # lines of the child's output quoted in an error
_HULL_ARRAYS = ("vertices", "faces", "vertex_counts", "face_counts")


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
        return float(trimesh.Trimesh(self.vertices, self.faces, process=False).volume)


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


def _coacd_kwargs(params: DecompositionParams) -> dict[str, Any]:
    """Keyword arguments of :func:`coacd.run_coacd` (decimation on, so ``max_ch_vertex`` applies)."""
    kwargs = asdict(params)
    del kwargs["timeout_s"]
    kwargs["decimate"] = True
    return kwargs


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
    h.update(json.dumps(_coacd_kwargs(params), sort_keys=True, separators=(",", ":")).encode() + b"\n")
    for name, array, dtype in (("vertices", mesh.vertices, "<f8"), ("faces", mesh.faces, "<i8")):
        a = np.ascontiguousarray(array, dtype=dtype)
        h.update(f"{name} {a.shape}\n".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def decompose(
    mesh: Mesh,
    params: DecompositionParams = DecompositionParams(),
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
    hull = _hull_if_convex(mesh)
    if hull is not None:
        return Decomposition(hulls=(hull,), key=key, skipped="mesh is convex")

    notes: list[str] = []
    path: Path | None = None
    if use_cache:
        root = Path(cache_dir) if cache_dir is not None else default_cache_dir()
        path = root / "coacd" / key[:2] / f"{key}.npz"
        if path.exists():
            try:
                hulls, coacd_seconds, old_notes = _read_entry(path)
            except _CorruptEntryError as e:
                notes.append(f"cache entry {path} was corrupt ({e}) and was rebuilt")
                with contextlib.suppress(OSError):  # the rebuilt entry replaces it anyway
                    path.unlink(missing_ok=True)
            else:
                return Decomposition(
                    hulls=hulls, key=key, from_cache=True, coacd_seconds=coacd_seconds, notes=old_notes
                )
        bundled = bundled_entry(key)
        if bundled.exists():
            try:
                hulls, coacd_seconds, old_notes = _read_entry(bundled)
            except _CorruptEntryError as e:
                notes.append(f"bundled cache entry {bundled} is corrupt ({e}); decomposing anew")
            else:
                return Decomposition(
                    hulls=hulls, key=key, from_cache=True, coacd_seconds=coacd_seconds, notes=old_notes
                )

    raw, seconds = _run_worker(mesh, params, name, progress)
    hulls, dropped = _usable_hulls(raw, name)
    if path is not None:
        try:
            _write_entry(path, hulls, seconds, tuple(dropped))
        except OSError as e:
            notes.append(f"could not write cache entry {path}: {e}")
    return Decomposition(
        hulls=hulls,
        key=key,
        seconds=seconds,
        coacd_seconds=seconds,
        notes=(*dropped, *notes),
    )


# ----------------------------------------------------------------------------------------------- hulls


def _hull_of(points: np.ndarray) -> ConvexHull | None:
    """The convex hull of ``points``, or None if they are too few, not finite, or (nearly) coplanar."""
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 4 or not np.all(np.isfinite(p)):
        return None
    singular = np.linalg.svd(p - p.mean(axis=0), compute_uv=False)
    if singular[0] <= 0 or singular[-1] / singular[0] < FLATNESS_TOL:
        return None
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


def _pack(hulls: tuple[ConvexHull, ...]) -> dict[str, np.ndarray]:
    return {
        "vertices": np.concatenate([h.vertices for h in hulls]),
        "faces": np.concatenate([h.faces for h in hulls]),
        "vertex_counts": np.array([len(h.vertices) for h in hulls], dtype=np.int64),
        "face_counts": np.array([len(h.faces) for h in hulls], dtype=np.int64),
    }


def _unpack(data: Any) -> list[tuple[np.ndarray, np.ndarray]]:
    """Split packed hull arrays (an open ``.npz``) into per-hull arrays.

    Raises:
        ValueError: An array is missing or has the wrong dtype or shape, or a face index is out of range.
    """
    missing = [k for k in _HULL_ARRAYS if k not in data]
    if missing:
        raise ValueError(f"missing arrays {', '.join(missing)}")
    v, f, nv, nf = (np.asarray(data[k]) for k in _HULL_ARRAYS)
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


# ---------------------------------------------------------------------------------------------- worker


def _run_worker(
    mesh: Mesh, params: DecompositionParams, name: str, progress: bool
) -> tuple[list[tuple[np.ndarray, np.ndarray]], float]:
    """Run CoACD in a child process.

    Returns:
        The raw pieces (vertices, faces) and the child's wall time in seconds.
    """
    if importlib.util.find_spec("coacd") is None:
        raise DecompositionError(f"{name}: CoACD is not installed (pip install coacd)")
    with tempfile.TemporaryDirectory(prefix="handsim-coacd-") as tmp:
        in_path, out_path, log_path = (Path(tmp) / n for n in ("in.npz", "out.npz", "worker.log"))
        with open(in_path, "wb") as f:
            np.savez(
                f,
                vertices=np.ascontiguousarray(mesh.vertices, dtype=np.float64),
                faces=np.ascontiguousarray(mesh.faces, dtype=np.int64),
                params=np.array(json.dumps(_coacd_kwargs(params))),
            )
        with open(log_path, "wb") as log:
            start = time.perf_counter()
            # cwd=tmp: a core file, should the system still write one, goes away with the folder.
            proc = subprocess.Popen(
                [sys.executable, str(_WORKER), str(in_path), str(out_path)],
                stdin=subprocess.PIPE,  # never written; the child ends when it closes (our death)
                stdout=log,
                stderr=subprocess.STDOUT,
                cwd=tmp,
            )
            try:
                status = _wait(proc, params.timeout_s, start, name, progress)
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait()
                proc.stdin.close()  # only now: the child reads its closing as our death
            seconds = time.perf_counter() - start
        if status is None:
            limit = "no hull limit" if params.max_convex_hull == -1 else f"max {params.max_convex_hull} hulls"
            raise DecompositionError(
                f"{name}: CoACD did not finish within {params.timeout_s:g} s (threshold "
                f"{params.threshold:g}, {limit}); raise the timeout or the threshold"
            )
        if status != 0:
            raise DecompositionError(
                f"{name}: the CoACD worker {_describe_status(status)}; {_tail(log_path)}"
            )
        try:
            with np.load(out_path, allow_pickle=False) as data:
                raw = _unpack(data)
        except Exception as e:  # any unreadable output is the worker's fault, reported the same way
            raise DecompositionError(f"{name}: the CoACD worker wrote invalid output ({e})") from e
    if not raw:
        raise DecompositionError(f"{name}: CoACD returned no hulls")
    return raw, seconds


def _wait(proc: subprocess.Popen, timeout_s: float, start: float, name: str, progress: bool) -> int | None:
    """Wait for the child, showing elapsed time if asked; its exit status, or None on timeout."""
    with tqdm(
        desc=f"CoACD {name}",
        bar_format="{desc}: {elapsed}{postfix}",
        file=sys.stderr,
        mininterval=0.5
        if sys.stderr.isatty()
        else 30.0,  # a log file gets a line every 30 s, not 10 a second
        disable=not progress,
    ) as bar:
        while True:
            elapsed = time.perf_counter() - start
            remaining = timeout_s - elapsed
            if remaining <= 0:
                bar.set_postfix_str(f"timed out after {timeout_s:g} s")
                return None
            try:
                status = proc.wait(timeout=min(_POLL_S, remaining))
            except subprocess.TimeoutExpired:
                bar.set_postfix_str(f"running, timeout {timeout_s:g} s")
            else:
                bar.set_postfix_str("done" if status == 0 else "failed")
                return status


def _describe_status(status: int) -> str:
    if status < 0:
        try:
            signame = signal.Signals(-status).name
        except ValueError:
            signame = "unknown signal"
        return f"was killed by signal {-status} ({signame})"
    return f"exited with status {status}"


def _tail(log_path: Path) -> str:
    text = log_path.read_bytes().decode("utf-8", errors="replace").strip()
    if not text:
        return "it printed nothing"
    lines = text.splitlines()[-_TAIL_LINES:]
    return "last lines of its output:\n" + "\n".join(lines)


# ----------------------------------------------------------------------------------------------- cache


class _CorruptEntryError(Exception):
    """A cache entry that cannot be trusted; the message says why."""


def _checksum(arrays: dict[str, np.ndarray]) -> str:
    h = hashlib.sha256()
    for k in sorted(arrays):
        a = np.ascontiguousarray(arrays[k])
        h.update(f"{k} {a.dtype.str} {a.shape}\n".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _write_entry(path: Path, hulls: tuple[ConvexHull, ...], seconds: float, notes: tuple[str, ...]) -> None:
    """Write a cache entry atomically (:func:`handsim.files.write_atomic`)."""
    arrays = _pack(hulls)
    arrays["coacd_seconds"] = np.array(seconds, dtype=np.float64)
    arrays["notes"] = np.array(notes, dtype=str) if notes else np.zeros(0, dtype="<U1")
    arrays["format"] = np.array(CACHE_FORMAT_VERSION, dtype=np.int64)
    arrays["checksum"] = np.array(_checksum(arrays))
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    write_atomic(path, buffer.getvalue())


def _read_entry(path: Path) -> tuple[tuple[ConvexHull, ...], float, tuple[str, ...]]:
    """Read and verify a cache entry.

    Returns:
        The hulls, the original CoACD seconds and the original notes.

    Raises:
        _CorruptEntryError: Unreadable, incomplete, checksum mismatch, bad shapes or indices.
    """
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: np.asarray(data[k]) for k in data.files}
    except Exception as e:  # any failure to parse means the entry cannot be used
        raise _CorruptEntryError(f"unreadable: {type(e).__name__}: {e}") from e
    missing = [k for k in (*_HULL_ARRAYS, "coacd_seconds", "notes", "format", "checksum") if k not in arrays]
    if missing:
        raise _CorruptEntryError(f"missing arrays {', '.join(missing)}")
    try:
        if arrays["format"].shape != () or int(arrays["format"]) != CACHE_FORMAT_VERSION:
            raise ValueError(f"format {arrays['format']!r}, expected {CACHE_FORMAT_VERSION}")
        stored = str(arrays.pop("checksum"))
        if _checksum(arrays) != stored:
            raise ValueError("checksum mismatch")
        raw = _unpack(arrays)
        seconds = float(arrays["coacd_seconds"])
        notes = tuple(str(n) for n in arrays["notes"].reshape(-1))
    except (ValueError, TypeError) as e:
        raise _CorruptEntryError(str(e)) from e
    if not raw:
        raise _CorruptEntryError("no hulls")
    return tuple(ConvexHull(vertices=v, faces=f) for v, f in raw), seconds, notes
