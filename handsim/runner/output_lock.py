"""One run per output at a time: a lock file naming its holder, taken over when the holder is gone.

:class:`OutputLock` creates the lock file (``O_CREAT | O_EXCL`` when it is new) and locks it with the
kernel (``fcntl.flock`` on POSIX, ``msvcrt.locking`` on Windows) for as long as the run lasts. The file
holds the holder's pid, host, start time and command line as JSON, so that a second run is refused with an
error naming the first (:class:`OutputBusyError`). The kernel releases its lock when the holder's process
ends, however it ends (``kill -9`` included): a lock file that can be locked again belongs to a run that is
gone, and is taken over with a note naming that run. Releasing removes the file.

Where the file system has no kernel locks (some network file systems), the holder's pid decides: a lock
whose holder ran on this host and whose pid no longer runs is taken over; any other is refused (remove the
file by hand once its run is known to be over).
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import socket
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from handsim.runner.errors import RunnerError

try:
    import fcntl  # POSIX
except ImportError:  # Windows
    fcntl = None

LOCK_FILE = ".handsim.lock"
"""Name of the lock file a dataset run keeps in its output folder."""
_WINDOWS_LOCK_OFFSET = 1 << 20
"""Windows locks a byte range, which others then cannot read: the byte locked lies past the holder's JSON."""
_NO_KERNEL_LOCK = {errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS, errno.EINVAL}
"""``flock`` errors of a file system without locks (not: "held by another process")."""
_ATTEMPTS = 5
"""Tries before giving up when other runs create and remove the lock file between our steps."""


class OutputBusyError(RunnerError):
    """Another run holds the lock of the output: the message names it (pid, host, start, command)."""


@dataclass(frozen=True)
class LockHolder:
    """Who holds (or held) a lock: what its lock file says.

    Attributes:
        pid: Process id of the holder.
        host: Host name of the machine it runs on.
        started: Local time the lock was taken, ISO 8601 with the UTC offset.
        command: Its command line.
    """

    pid: int
    host: str
    started: str
    command: tuple[str, ...]

    @classmethod
    def this_process(cls, command: Sequence[str] | None = None) -> LockHolder:
        """This process as a holder, with ``command`` (default ``sys.argv``)."""
        return cls(
            pid=os.getpid(),
            host=socket.gethostname(),
            started=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            command=tuple(str(a) for a in (sys.argv if command is None else command)),
        )

    @classmethod
    def from_json(cls, data: bytes) -> LockHolder | None:
        """The holder a lock file names, or None when it names none (empty, cut short, not ours)."""
        try:
            info = json.loads(data.decode("utf-8"))
            return cls(
                pid=int(info["pid"]),
                host=str(info["host"]),
                started=str(info["started"]),
                command=tuple(str(a) for a in info["command"]),
            )
        except (ValueError, KeyError, TypeError):
            return None

    def to_json(self) -> bytes:
        """The lock file's content."""
        info = {"pid": self.pid, "host": self.host, "started": self.started, "command": list(self.command)}
        return (json.dumps(info, ensure_ascii=False) + "\n").encode("utf-8")

    def describe(self) -> str:
        """``pid 123 on host, started 2024-…+0100: handsim report …`` (the command shortened to 200 chars)."""
        command = " ".join(self.command)
        if len(command) > 200:
            command = command[:199] + "…"
        return f"pid {self.pid} on {self.host}, started {self.started}: {command}"

    def running_here(self) -> bool | None:
        """Whether the holder still runs: None when that cannot be told (another host, or Windows)."""
        if self.host != socket.gethostname() or fcntl is None:
            return None
        try:
            os.kill(self.pid, 0)  # signal 0: only checks that the process exists
        except ProcessLookupError:
            return False
        except PermissionError:  # exists, another user's
            return True
        return True


class OutputLock:
    """The lock of one output (a run's folder, an exported dataset): one holder at a time.

    Use as a context manager, or :meth:`acquire` then :meth:`release`::

        with OutputLock(out / LOCK_FILE, what=f"output folder {out}") as lock:
            for note in lock.notes: ...

    Args:
        path: The lock file (created with its folder; removed on release).
        what: What the lock guards, for messages (``"output folder OUT"``).
        command: The command line written into the lock file (default ``sys.argv``).

    Attributes:
        notes: What acquiring found: the lock of a run that ended without releasing it, taken over.
    """

    def __init__(self, path: str | Path, *, what: str, command: Sequence[str] | None = None) -> None:
        self.path = Path(path)
        self.what = what
        self._command = command
        self._fd: int | None = None
        self.notes: list[str] = []

    def acquire(self) -> list[str]:
        """Take the lock, or refuse naming its holder.

        Returns:
            Notes on a stale lock taken over (empty when there was none).

        Raises:
            OutputBusyError: Another live run holds the lock.
            OSError: The lock file cannot be created or written (its ``filename`` is the lock file).
        """
        if self._fd is not None:
            raise RuntimeError(f"{self.path} is locked by this process already")
        for _ in range(_ATTEMPTS):
            self.path.parent.mkdir(parents=True, exist_ok=True)
            try:
                fd, created = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644), True
            except FileNotFoundError:  # its folder was removed meanwhile (an empty work folder): again
                continue
            except FileExistsError:
                try:
                    fd, created = os.open(self.path, os.O_RDWR), False
                except FileNotFoundError:  # its holder removed it meanwhile: try again
                    continue
            try:
                note = self._lock(fd, created)
            except _LockFileChangedError:
                os.close(fd)
                continue
            except BaseException:
                os.close(fd)
                raise
            self._fd = fd
            self.notes = [note] if note else []
            return self.notes
        raise OutputBusyError(
            f"{self.what} is in use: its lock file {self.path} was created and removed {_ATTEMPTS} times "
            "while this run tried to take it; other runs keep starting there: wait for them, or write "
            "elsewhere"
        )

    def _lock(self, fd: int, created: bool) -> str | None:
        """Lock the open lock file ``fd`` and write this process into it; a note on a stale lock taken over.

        Raises:
            OutputBusyError: A live run holds it.
            _LockFileChangedError: The file at the path is another one now (its holder removed it).
        """
        kernel = _try_lock(fd)
        previous = LockHolder.from_json(_read(fd))
        if kernel is False:
            raise OutputBusyError(self._busy_message(previous))
        if not _same_file(fd, self.path):  # removed (and maybe created anew) since we opened it
            raise _LockFileChangedError
        note = None
        if not created:
            if kernel is None and (previous is None or previous.running_here() is not False):
                raise OutputBusyError(
                    self._busy_message(previous)
                    + f" (this file system has no locks: if that run is over, remove {self.path})"
                )
            note = self._stale_note(previous)
        _write(fd, LockHolder.this_process(self._command).to_json(), self.path)
        return note

    def _busy_message(self, holder: LockHolder | None) -> str:
        who = holder.describe() if holder is not None else "a run that is starting (its lock file is empty)"
        return (
            f"{self.what} is in use by another run ({who}; lock file {self.path}): wait for it to end, or "
            "write to another place"
        )

    def _stale_note(self, holder: LockHolder | None) -> str:
        if holder is None:
            return f"took over the lock {self.path}: it named no run (a run killed while taking it)"
        gone = "no longer runs" if holder.running_here() is False else "holds no lock any more"
        return (
            f"took over the lock {self.path} of a run that ended without releasing it ({holder.describe()}; "
            f"pid {holder.pid} {gone})"
        )

    def release(self) -> None:
        """Remove the lock file and unlock (nothing when not held)."""
        fd, self._fd = self._fd, None
        if fd is None:
            return
        if fcntl is not None:  # POSIX: remove it while locked, so no one locks a removed file
            with contextlib.suppress(OSError):
                self.path.unlink()
            os.close(fd)  # unlocks
            return
        os.close(fd)  # Windows: an open file cannot be removed; closing unlocks
        with contextlib.suppress(OSError):
            self.path.unlink()

    def __enter__(self) -> OutputLock:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


class _LockFileChangedError(Exception):
    """The lock file was removed (or replaced) between opening and locking it: open it again."""


def _try_lock(fd: int) -> bool | None:
    """Lock ``fd`` without waiting: True locked, False held by another process, None no kernel locks."""
    if fcntl is not None:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        except OSError as exc:
            if exc.errno in _NO_KERNEL_LOCK:
                return None
            raise
        return True
    import msvcrt  # lazy: Windows only

    os.lseek(fd, _WINDOWS_LOCK_OFFSET, os.SEEK_SET)
    try:
        msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
    except OSError:
        return False
    return True


def _same_file(fd: int, path: Path) -> bool:
    """The open file ``fd`` still is the file at ``path``."""
    try:
        now = os.stat(path)
    except FileNotFoundError:
        return False
    mine = os.fstat(fd)
    return (now.st_dev, now.st_ino) == (mine.st_dev, mine.st_ino)


def _read(fd: int, limit: int = 1 << 16) -> bytes:
    """The lock file's content (its first ``limit`` bytes)."""
    os.lseek(fd, 0, os.SEEK_SET)
    return os.read(fd, limit)


def _write(fd: int, data: bytes, path: Path) -> None:
    """Replace the lock file's content with ``data``, durably."""
    try:
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, data)
        os.fsync(fd)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, str(path)) from exc
