"""CoACD run in a child process: started by file path, timed out, interrupted, its crashes reported.

The child is started with :mod:`subprocess` (not :mod:`multiprocessing`, which daemonic pool workers and
Ray tasks cannot use) on ``_coacd_worker.py`` by path. It is killed after
:attr:`~handsim.builders.decomposition_types.DecompositionParams.timeout_s` or when the caller is
interrupted (Ctrl-C), and ends by itself when the caller dies (:mod:`handsim.lifeline`); a CoACD crash (it
aborts the process on some inputs) becomes a :class:`~handsim.builders.decomposition_types.DecompositionError`
naming the mesh instead of the death of the caller.
"""

from __future__ import annotations

import importlib.util
import json
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from handsim.builders.decomposition_types import (
    DecompositionError,
    DecompositionParams,
    coacd_kwargs,
    unpack_hulls,
)
from handsim.datatypes.mesh import Mesh
from handsim.progress import progress_bar, progress_line

_WORKER = Path(__file__).with_name("_coacd_worker.py")
_POLL_S = 0.1  # how often the parent checks the child (and refreshes the progress bar on a terminal)
_TAIL_LINES = 20  # lines of the child's output quoted in an error


def run_worker(
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
                params=np.array(json.dumps(coacd_kwargs(params))),
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
                raw = unpack_hulls(data)
        except Exception as e:  # any unreadable output is the worker's fault, reported the same way
            raise DecompositionError(f"{name}: the CoACD worker wrote invalid output ({e})") from e
    if not raw:
        raise DecompositionError(f"{name}: CoACD returned no hulls")
    return raw, seconds


def _wait(proc: subprocess.Popen, timeout_s: float, start: float, name: str, progress: bool) -> int | None:
    """Wait for the child, showing elapsed time if asked; its exit status, or None on timeout.

    On a terminal the elapsed time counts up in place; elsewhere (a log) one line says that CoACD started
    and one how it ended (:mod:`handsim.progress`). The child's own output goes to its log file, never here.
    """
    what = f"CoACD {name}"
    progress_line(f"{what}: running, timeout {timeout_s:g} s", enabled=progress)
    with progress_bar(
        enabled=progress, desc=what, bar_format="{desc}: {elapsed}{postfix}", mininterval=0.5
    ) as bar:
        while True:
            elapsed = time.perf_counter() - start
            remaining = timeout_s - elapsed
            if remaining <= 0:
                bar.set_postfix_str(f"timed out after {timeout_s:g} s")
                progress_line(f"{what}: timed out after {timeout_s:g} s", enabled=progress)
                return None
            try:
                status = proc.wait(timeout=min(_POLL_S, remaining))
            except subprocess.TimeoutExpired:
                bar.set_postfix_str(f"running, timeout {timeout_s:g} s")
            else:
                ended = "done" if status == 0 else "failed"
                bar.set_postfix_str(ended)
                progress_line(f"{what}: {ended} after {time.perf_counter() - start:.1f} s", enabled=progress)
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
