"""Child process that runs CoACD on one mesh; started by :mod:`handsim.builders.coacd_process`, not by users.

Usage: ``python _coacd_worker.py IN.npz OUT.npz``. ``IN.npz`` holds ``vertices`` (V, 3) float64 metres,
``faces`` (F, 3) int64 and ``params``, a JSON object of keyword arguments for :func:`coacd.run_coacd`.
``OUT.npz`` receives the hulls packed as ``vertices`` (sum V_i, 3), ``faces`` (sum F_i, 3) with per-hull
indices, ``vertex_counts`` and ``face_counts`` (H,), and ``seconds``, the time CoACD itself took.

The parent starts this file by path, not with ``-m handsim.builders._coacd_worker``: ``-m`` would import
``handsim/__init__`` and ``handsim/builders/__init__`` (MuJoCo, SciPy), about 0.5 s of dead weight per
decomposition. So this module imports nothing from handsim; only the standard library, NumPy and CoACD.

A crash here (CoACD aborts on some inputs) takes down only this process; the parent reports the exit
status and the last lines of the output. This process ends with its parent, also under ``kill -9`` of it
(:mod:`handsim.lifeline`, loaded by path: the kernel's parent-death signal on Linux, and everywhere a
thread reading stdin, a pipe whose writing end only the parent holds, until its end).
"""

from __future__ import annotations

import os
import sys

# Started by path, Python put this folder first on sys.path; drop it so that sibling modules (hand.py,
# scene.py, ...) can never shadow a standard or third-party module imported below.
if sys.path and os.path.abspath(sys.path[0] or os.curdir) == os.path.dirname(os.path.abspath(__file__)):
    del sys.path[0]

import importlib.util
import json
import time

import numpy as np


def _exit_with_parent() -> None:
    """End this process when the parent dies (see :mod:`handsim.lifeline`, loaded without handsim)."""
    path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "lifeline.py")
    spec = importlib.util.spec_from_file_location("_handsim_lifeline", path)
    lifeline = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(lifeline)
    lifeline.die_with_parent()
    lifeline.watch(_read_to_end)


def _read_to_end(fd: int = 0) -> None:
    """Read the file descriptor (stdin) until its end: the parent, the only writer, is gone.

    Raw reads, not ``sys.stdin``: a daemon thread holding the buffered reader's lock would abort the
    interpreter at its shutdown.
    """
    while os.read(fd, 4096):
        pass


def _no_core_dumps() -> None:
    """Keep a deliberate or real abort from writing a core file."""
    try:
        import resource  # lazy: POSIX only (ImportError on Windows)

        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    except (ImportError, ValueError, OSError):  # Windows, or a hard limit we may not lower
        pass


def _pack(hulls: list[tuple[np.ndarray, np.ndarray]], seconds: float) -> dict[str, np.ndarray]:
    """Hulls as the flat arrays stored in ``OUT.npz``."""
    vertices = [np.asarray(v, dtype=np.float64).reshape(-1, 3) for v, _ in hulls]
    faces = [np.asarray(f, dtype=np.int64).reshape(-1, 3) for _, f in hulls]
    return {
        "vertices": np.concatenate(vertices) if vertices else np.zeros((0, 3)),
        "faces": np.concatenate(faces) if faces else np.zeros((0, 3), dtype=np.int64),
        "vertex_counts": np.array([len(v) for v in vertices], dtype=np.int64),
        "face_counts": np.array([len(f) for f in faces], dtype=np.int64),
        "seconds": np.float64(seconds),
    }


def _save(path: str, arrays: dict[str, np.ndarray]) -> None:
    """Write ``arrays`` to ``path`` exactly (``np.savez`` on a name would append ``.npz``)."""
    with open(path, "wb") as f:
        np.savez(f, **arrays)


def main(argv: list[str]) -> int:
    """Run CoACD on ``argv[0]`` and write the hulls to ``argv[1]``.

    Args:
        argv: The input and output ``.npz`` paths.

    Returns:
        The process exit status (0 on success).
    """
    if len(argv) != 2:
        print("usage: _coacd_worker.py IN.npz OUT.npz", file=sys.stderr)
        return 2
    in_path, out_path = argv
    _exit_with_parent()
    _no_core_dumps()
    import coacd  # lazy: after the lifeline is set, so a parent killed during this slow import still ends us

    coacd.set_log_level("error")
    with np.load(in_path, allow_pickle=False) as data:
        vertices = np.ascontiguousarray(data["vertices"], dtype=np.float64)
        faces = np.ascontiguousarray(data["faces"], dtype=np.int32)
        params = json.loads(str(data["params"]))
    start = time.perf_counter()
    parts = coacd.run_coacd(coacd.Mesh(vertices, faces), **params)
    seconds = time.perf_counter() - start
    _save(out_path, _pack([(v, f) for v, f in parts], seconds))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
