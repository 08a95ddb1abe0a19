"""Test helpers for child processes: run this checkout's handsim; list and reap what a test started."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def child_env(*first: Path) -> dict[str, str]:
    """The environment of a ``python -m handsim.cli`` child that imports this checkout's handsim (after
    the folders ``first``)."""
    path = [*map(str, first), str(ROOT), os.environ.get("PYTHONPATH", "")]
    return {**os.environ, "PYTHONPATH": os.pathsep.join(path)}


def descendants(pid: int) -> set[int]:
    """Every live process below ``pid`` (Linux: from /proc)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        children.setdefault(ppid, []).append(int(entry.name))
    found, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.add(child)
            todo.append(child)
    return found


def _stat(pid: int) -> list[str] | None:
    """The fields of ``/proc/PID/stat`` after the command name (state first), or None when gone."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None


def alive(pid: int) -> bool:
    """The process exists and is not a zombie."""
    fields = _stat(pid)
    return fields is not None and fields[0] != "Z"


class Children(dict):
    """Processes a test started (pid → start time), so that only they are ever killed by it."""

    def add(self, pids: set[int]) -> Children:
        """Remember these processes; returns self (true when some are known)."""
        for pid in pids:
            fields = _stat(pid)
            if fields is not None:
                self.setdefault(pid, fields[19])
        return self

    def alive(self) -> list[int]:
        """Those still alive (the same process: same start time, not a zombie)."""
        return [pid for pid, start in self.items() if alive(pid) and _stat(pid)[19] == start]


def wait_for(condition, timeout: float, what: str) -> None:
    """Poll ``condition`` until it holds; fail naming ``what`` after ``timeout`` seconds (a bound, not a
    speed assertion)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            pytest.fail(f"{what} within {timeout:g} s")
        time.sleep(0.05)


linux_only = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads processes from /proc")


@contextlib.contextmanager
def reaped(process: subprocess.Popen) -> Iterator[Children]:
    """For the test to fill with ``process``'s children; whatever is left of them and of the process is
    killed afterwards (a failing test leaves no process behind)."""
    children = Children()
    try:
        yield children
    finally:
        for pid in children.alive():
            os.kill(pid, signal.SIGKILL)
        if process.poll() is None:
            process.kill()
            process.wait()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def ray_head(cpus: int, log: Path, timeout: float = 180.0) -> Iterator[tuple[str, subprocess.Popen]]:
    """A local Ray cluster of ``cpus`` CPUs (``ray start --head --block``): its address and process.

    The cluster uses Ray's token authentication (``RAY_AUTH_MODE=token``, as ``ray start`` does by
    default): a driver connecting by address needs ``RAY_AUTH_MODE=token`` in its environment when it
    starts (Ray reads it once, on import), and the cluster and its drivers need the token in this
    process's environment (``~/.ray/auth_token`` or ``RAY_AUTH_TOKEN_PATH``: the ``ray_home`` fixture of
    tests/conftest.py makes one; ``ray start`` makes none). Only this cluster is stopped
    afterwards (SIGINT to its ``ray start``, which stops what it started; SIGKILL to its process group if that
    hangs), never other Ray clusters of the machine, as ``ray stop`` would.

    Args:
        cpus: CPUs the cluster offers.
        log: File for ``ray start``'s output.
        timeout: Longest wait for the cluster to start, s (a bound, not a speed assertion).

    Raises:
        RuntimeError: ``ray`` is not installed, or the cluster did not start (its output says why).
    """
    ray = shutil.which("ray", path=os.pathsep.join([str(Path(sys.executable).parent), os.environ["PATH"]]))
    if ray is None:
        raise RuntimeError("the `ray` command is not installed: pip install 'handsim[ray]'")
    port = _free_port()
    command = [ray, "start", "--head", "--block", f"--num-cpus={cpus}", f"--port={port}",
               "--include-dashboard=false", "--disable-usage-stats"]  # fmt: skip
    env = {**os.environ, "RAY_AUTH_MODE": "token"}
    with open(log, "w") as out:
        process = subprocess.Popen(
            command, stdout=out, stderr=subprocess.STDOUT, env=env, start_new_session=True
        )
    try:
        deadline = time.monotonic() + timeout
        while "Ray runtime started" not in log.read_text(errors="replace"):
            if process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the local Ray cluster did not start:\n{log.read_text(errors='replace')}")
            time.sleep(0.2)
        yield f"127.0.0.1:{port}", process
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
            try:
                process.wait(timeout=60)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
        _forget_cluster(port)


def _forget_cluster(port: int) -> None:
    """Remove Ray's note of the latest cluster when it names ours (a stopped ``--block`` head leaves it,
    and a later ``ray.init()`` without an address would try to connect to it)."""
    note = Path(tempfile.gettempdir()) / "ray" / "ray_current_cluster"
    with contextlib.suppress(OSError):
        if note.read_text().strip().endswith(f":{port}"):
            note.unlink()
