"""A run's records: ``OUT/records.jsonl`` (one JSON line per finished trial) and ``OUT/run.json``.

The schema is documented in ``docs/records.md``. Writing is append-only and crash-safe: each line is one
``write`` of the whole line followed by ``flush`` and ``os.fsync``, so a killed run leaves complete lines
and at most one truncated last line. Reading ignores such a line (and says so); :func:`repair_records`
cuts it off before a resumed run appends.

JSON is written deterministically: keys in the order the record builder puts them, floats in Python's
shortest round-trip form, NaN and infinities as ``null``, UTF-8 without ASCII escapes.
"""

from __future__ import annotations

import contextlib
import errno
import json
import math
import os
import signal
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from handsim.errors import HandsimError
from handsim.files import write_atomic

RECORDS_FILE = "records.jsonl"
RUN_FILE = "run.json"
SCHEMA = 1
STATUSES = ("ok", "diverged", "error")
"""A record's ``status`` values."""
"""Version of the record schema (``docs/records.md``); changes when a key changes meaning or goes away."""


def record_valid(record: dict) -> bool:
    """False when the record's replay was flagged not valid (``summary["valid"]`` false), else True.

    Records without the key (failed trials, records written before the flags existed) count as valid; a
    not-valid trial is its own outcome in counts and reports and is left out of every rate and statistic.
    """
    return (record.get("summary") or {}).get("valid") is not False


class RecordsError(HandsimError):
    """A records file that is not a run's records (a malformed line other than a truncated last one)."""


def json_ready(value: Any) -> Any:
    """``value`` as plain JSON values.

    Numpy scalars and arrays become Python numbers and lists, tuples lists, NaN and infinities None,
    mapping keys strings.
    """
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):
        return json_ready(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def encode_record(record: dict) -> bytes:
    """One record as a JSON line (UTF-8, ending in a newline).

    Raises:
        TypeError: A value that is not JSON (a bug in the record builder).
    """
    text = json.dumps(json_ready(record), ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    return (text + "\n").encode("utf-8")


@dataclass(frozen=True)
class RecordsRead:
    """The records of a run as read back.

    Attributes:
        records: One dict per complete line, in file order, the first record of each id only.
        notes: What was ignored: a truncated last line, repeated ids.
        valid_bytes: Length of the file's complete part (where a truncated last line starts).
        size: Length of the file.
    """

    records: tuple[dict, ...]
    notes: tuple[str, ...]
    valid_bytes: int
    size: int


def load_records(out: str | Path) -> RecordsRead:
    """Read ``OUT/records.jsonl``, tolerating a truncated last line (a run killed while writing).

    Args:
        out: The run's output folder.

    Returns:
        The records (none when the file does not exist) and notes on what was ignored.

    Raises:
        RecordsError: A line other than the last is not a record (malformed JSON, no ``id``, another
            schema); the message names the file, the line and what was expected.
    """
    path = Path(out) / RECORDS_FILE
    if not path.is_file():
        return RecordsRead((), (), 0, 0)
    data = path.read_bytes()
    lines = data.split(b"\n")
    complete, tail = lines[:-1], lines[-1]  # text after the last newline: empty unless truncated
    records: list[dict] = []
    notes: list[str] = []
    seen: set[str] = set()
    valid = 0
    for number, line in enumerate(complete, start=1):
        record = _parse(path, number, line, last=number == len(complete) and not tail)
        if record is None:
            notes.append(
                f"{path}: line {number}, the last, is not complete JSON and is ignored (a killed run)"
            )
            break
        valid += len(line) + 1
        if record["id"] in seen:
            notes.append(f"{path}: line {number} repeats the record of {record['id']!r}; the first is kept")
            continue
        seen.add(record["id"])
        records.append(record)
    if tail:
        notes.append(
            f"{path}: the last line ({len(tail)} bytes, no newline) is truncated and ignored (a killed run)"
        )
    return RecordsRead(tuple(records), tuple(notes), valid, len(data))


def _parse(path: Path, number: int, line: bytes, *, last: bool) -> dict | None:
    """The record of one line; None for a malformed last line; RecordsError for another bad line."""
    try:
        record = json.loads(line.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        if last:
            return None
        raise RecordsError(
            f"{path}:{number}: not a JSON record ({exc}); expected one JSON object per line"
        ) from None
    if not isinstance(record, dict) or not isinstance(record.get("id"), str):
        raise RecordsError(f"{path}:{number}: expected a JSON object with a string 'id', got {line[:80]!r}")
    if record.get("schema") != SCHEMA:
        raise RecordsError(
            f"{path}:{number}: field 'schema' is {record.get('schema')!r}; this handsim reads schema {SCHEMA}"
        )
    return record


def read_records(out: str | Path) -> list[dict]:
    """The records of a run, in file order (a truncated last line is ignored; see :func:`load_records`).

    Args:
        out: The run's output folder.

    Returns:
        One dict per finished trial.

    Raises:
        RecordsError: A malformed line other than the last.
    """
    return list(load_records(out).records)


def repair_records(out: str | Path) -> tuple[str, ...]:
    """Cut a truncated last line off ``OUT/records.jsonl`` so that appending continues on a line start.

    Args:
        out: The run's output folder.

    Returns:
        Notes on what was ignored or removed (empty when the file was whole).

    Raises:
        RecordsError: A malformed line other than the last.
    """
    read = load_records(out)
    if read.valid_bytes < read.size:
        path = Path(out) / RECORDS_FILE
        with open(path, "r+b") as f:
            f.truncate(read.valid_bytes)
            f.flush()
            os.fsync(f.fileno())
        return (*read.notes, f"{path}: removed {read.size - read.valid_bytes} bytes of an incomplete line")
    return read.notes


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """Block SIGINT and SIGTERM in this thread inside the block; a signal that came meanwhile acts after.

    Where signal masks do not exist (Windows) the block runs unprotected; a record cut short there is a
    truncated last line, which reading ignores and resuming removes.
    """
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


class RecordWriter:
    """Appends records to ``OUT/records.jsonl``, each line written whole and fsynced before the next."""

    def __init__(self, out: str | Path) -> None:
        """Open (create) the records file of ``out`` for appending (unbuffered: a line is one write)."""
        Path(out).mkdir(parents=True, exist_ok=True)
        self.path = Path(out) / RECORDS_FILE
        self._file = open(self.path, "ab", buffering=0)

    def append(self, record: dict) -> None:
        """Write one record as a complete line and make it durable.

        Ctrl-C and SIGTERM are held back while the line is written (POSIX): they act after it, so an
        interrupted run leaves no partial record. A write that fails (a full disk, ``ulimit -f``) leaves
        no partial line either: the file is cut back to where the line began.

        Raises:
            OSError: The line could not be written; the error names the records file.
        """
        line = memoryview(encode_record(record))
        with _signals_deferred():
            start = os.fstat(self._file.fileno()).st_size
            try:
                while line:
                    written = self._file.write(line)
                    if not written:  # a regular file takes at least one byte or raises; never loop on 0
                        raise OSError(errno.EIO, "the file took no byte of the record")
                    line = line[written:]
                os.fsync(self._file.fileno())
            except OSError as exc:
                with contextlib.suppress(OSError):
                    os.ftruncate(self._file.fileno(), start)
                raise OSError(exc.errno, exc.strerror, str(self.path)) from exc

    def close(self) -> None:
        """Close the file."""
        self._file.close()

    def __enter__(self) -> RecordWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def write_run_info(out: str | Path, info: dict) -> Path:
    """Write ``OUT/run.json`` (atomically, indented)."""
    text = json.dumps(json_ready(info), ensure_ascii=False, allow_nan=False, indent=1)
    return write_atomic(Path(out) / RUN_FILE, (text + "\n").encode("utf-8"))


def read_run_info(out: str | Path) -> dict | None:
    """The content of ``OUT/run.json``, or None when there is none.

    Raises:
        RecordsError: The file is not JSON.
    """
    path = Path(out) / RUN_FILE
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise RecordsError(f"{path}: not JSON ({exc})") from None
