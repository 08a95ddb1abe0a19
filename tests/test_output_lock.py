"""The output lock: one holder at a time, a second refused naming the first, a dead holder's lock taken
over."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from handsim.runner.output_lock import LockHolder, OutputBusyError, OutputLock
from tests.processes import ROOT, child_env, wait_for


def _ended_pid() -> int:
    """The pid of a process that has ended and been reaped."""
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def test_the_lock_file_names_its_holder_and_is_removed_on_release(tmp_path: Path) -> None:
    path = tmp_path / "out" / ".handsim.lock"
    with OutputLock(path, what="output folder out", command=["handsim", "report", "d", "-o", "out"]) as lock:
        assert lock.notes == []
        holder = LockHolder.from_json(path.read_bytes())
        assert holder.pid == os.getpid() and holder.host == socket.gethostname()
        assert holder.command == ("handsim", "report", "d", "-o", "out")
    assert not path.exists()


def test_a_second_holder_is_refused_with_an_error_naming_the_first(tmp_path: Path) -> None:
    path = tmp_path / ".handsim.lock"
    with OutputLock(path, what=f"output folder {tmp_path}", command=["handsim", "report", "a"]):
        holder = LockHolder.from_json(path.read_bytes())
        with pytest.raises(OutputBusyError) as caught:
            OutputLock(path, what=f"output folder {tmp_path}").acquire()
        assert str(caught.value) == (
            f"output folder {tmp_path} is in use by another run (pid {os.getpid()} on "
            f"{socket.gethostname()}, started {holder.started}: handsim report a; lock file {path}): wait "
            "for it to end, or write to another place"
        )
        assert LockHolder.from_json(path.read_bytes()) == holder  # the holder's file is untouched
    OutputLock(path, what="again").acquire()  # free once released


def test_the_lock_of_a_holder_that_no_longer_runs_is_taken_over_with_a_note(tmp_path: Path) -> None:
    path = tmp_path / ".handsim.lock"
    dead = LockHolder(_ended_pid(), socket.gethostname(), "2000-01-01T00:00:00+0000", ("handsim", "report"))
    path.write_bytes(dead.to_json())
    lock = OutputLock(path, what="output folder x")
    notes = lock.acquire()
    assert notes == [
        f"took over the lock {path} of a run that ended without releasing it (pid {dead.pid} on "
        f"{dead.host}, started 2000-01-01T00:00:00+0000: handsim report; pid {dead.pid} no longer runs)"
    ]
    assert LockHolder.from_json(path.read_bytes()).pid == os.getpid()
    lock.release()


def test_an_empty_lock_file_left_by_a_run_killed_while_taking_it_is_taken_over(tmp_path: Path) -> None:
    path = tmp_path / ".handsim.lock"
    path.write_bytes(b"")
    with OutputLock(path, what="output folder x") as lock:
        assert lock.notes == [f"took over the lock {path}: it named no run (a run killed while taking it)"]


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_the_lock_of_a_process_killed_with_sigkill_is_taken_over(tmp_path: Path) -> None:
    path = tmp_path / ".handsim.lock"
    code = (
        "import sys, time\n"
        "from handsim.runner.output_lock import OutputLock\n"
        f"OutputLock({str(path)!r}, what='x', command=['holder']).acquire()\n"
        "print('locked', flush=True)\n"
        "time.sleep(600)\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, env=child_env(), cwd=ROOT
    )
    try:
        assert process.stdout.readline().strip() == "locked"
        with pytest.raises(OutputBusyError, match=rf"pid {process.pid} on .*: holder; lock file"):
            OutputLock(path, what="x").acquire()
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    wait_for(lambda: process.poll() is not None, 10, "the holder did not end")
    with OutputLock(path, what="x") as lock:
        assert lock.notes[0].endswith(f"holder; pid {process.pid} no longer runs)")


def test_a_holder_on_another_host_is_named_and_its_stale_lock_taken_over(tmp_path: Path) -> None:
    path = tmp_path / ".handsim.lock"
    path.write_text(json.dumps({"pid": 1, "host": "elsewhere", "started": "t", "command": ["c"]}))
    with OutputLock(path, what="x") as lock:  # no process holds the kernel lock: its run is gone
        assert lock.notes == [
            f"took over the lock {path} of a run that ended without releasing it (pid 1 on elsewhere, "
            "started t: c; pid 1 holds no lock any more)"
        ]


def test_without_kernel_locks_a_live_holder_is_refused_and_a_dead_one_taken_over(tmp_path, monkeypatch):
    from handsim.runner import output_lock

    monkeypatch.setattr(output_lock, "_try_lock", lambda fd: None)  # a file system without locks
    path = tmp_path / ".handsim.lock"
    alive = LockHolder(os.getpid(), socket.gethostname(), "t", ("handsim", "report"))
    path.write_bytes(alive.to_json())
    with pytest.raises(OutputBusyError) as caught:
        OutputLock(path, what="x").acquire()
    assert str(caught.value).endswith(
        f"wait for it to end, or write to another place (this file system has no locks: if that run is "
        f"over, remove {path})"
    )
    path.write_bytes(LockHolder(_ended_pid(), socket.gethostname(), "t", ("handsim",)).to_json())
    with OutputLock(path, what="x") as lock:
        assert lock.notes[0].endswith("no longer runs)")
