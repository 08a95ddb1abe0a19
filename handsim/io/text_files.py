"""Helpers shared by the readers: opening input files with bounds, decoding text, parsing numbers.

Every input file is read through :func:`open_input` (or :func:`read_bytes`, which uses it), so every read is
bounded: only a regular file (or a link to one) is opened — a named pipe, a device such as ``/dev/zero`` or
a socket could block forever or never end —, and only up to a size limit checked from the file's size
before any byte is read (:data:`MAX_FILE_BYTES`; glove recordings :data:`MAX_RECORDING_BYTES`). The limits
are documented in ``docs/cli.md`` ("Input files").
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from handsim.errors import FormatError, InputFileError

UTF8_BOM = b"\xef\xbb\xbf"
"""The UTF-8 byte-order mark some editors (Windows Notepad, Excel) write at the start of a text file."""

UTF16_BOMS = (b"\xff\xfe", b"\xfe\xff")
"""The UTF-16 byte-order marks (little- and big-endian; a UTF-32 one starts like the little-endian one)."""

MIB = 1 << 20
"""Bytes in a mebibyte."""

MAX_FILE_BYTES = 256 * MIB
"""Largest input file handsim reads, bytes (256 MiB): over 3 times a 2-million-face OBJ mesh, far beyond
any skeleton, motion, annotation or calibration (an ARCTIC ``.mano.npy`` holds about 0.4 kB per frame: 52
float32 values per hand). A larger file is refused before it is read."""

MAX_RECORDING_BYTES = 64 * MIB
"""Largest glove recording handsim reads, bytes (64 MiB: about 290,000 rows, 80 minutes at 60 Hz; a
GraspDB14 trial is about 60 kB). Reading keeps about 13 bytes of memory per byte of the file
(``handsim inspect`` of a 27 MB recording peaked at 0.41 GB), replaying it more: a larger recording is
refused before it is read, with the advice to cut it."""

_NOT_REGULAR = (
    (stat.S_ISFIFO, "a named pipe (FIFO)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def _special_kind(mode: int) -> str | None:
    """What a file of this ``st_mode`` is when it is neither a regular file nor a folder, else None."""
    return next((what for test, what in _NOT_REGULAR if test(mode)), None)


def special_file(path: str | Path) -> str | None:
    """What ``path`` is when it is a named pipe, a device or a socket (links followed), else None.

    Found with ``stat``, which never opens the file: a named pipe without a writer blocks whoever opens it
    for reading, and a device such as ``/dev/zero`` never ends, so neither may be read as an input.

    Args:
        path: Any path (a missing one, or one that cannot be examined, is None).

    Returns:
        ``"a named pipe (FIFO)"``, ``"a character device"``, ``"a block device"``, ``"a socket"``, or None.
    """
    try:
        return _special_kind(os.stat(path).st_mode)
    except (OSError, ValueError):
        return None


def _not_regular_error(p: Path, what: str) -> InputFileError:
    real = os.path.realpath(p)
    target = f" ({real})" if Path(real) != p.absolute() else ""
    return InputFileError(
        f"{p}: {what}{target}, not a regular file; handsim reads regular files only (a pipe or a device may "
        "block or never end)"
    )


def require_file(path: str | Path) -> Path:
    """``path`` as a :class:`~pathlib.Path` when it is an existing regular file (or a link to one).

    Raises:
        InputFileError: Nothing exists at ``path`` ("file not found"), or it is a directory, a named pipe,
            a device or a socket (the message says which, and where a link leads).
    """
    p = Path(path)
    if p.is_dir():
        raise InputFileError(f"{p}: is a directory, expected a file")
    if not p.exists():
        raise InputFileError(f"{p}: file not found")
    what = special_file(p)
    if what is not None:
        raise _not_regular_error(p, what)
    return p


def _too_large(p: Path, size: int, limit: int, what: str, advice: str) -> InputFileError:
    return InputFileError(
        f"{p}: {size} bytes, more than the {limit / MIB:g} MiB ({limit} bytes) handsim reads from "
        f"{what}{advice}"
    )


@contextlib.contextmanager
def open_input(
    path: str | Path, limit: int = MAX_FILE_BYTES, what: str = "an input file", advice: str = ""
) -> Iterator[tuple[BinaryIO, int]]:
    """Open an input file for reading, bounded: a regular file of at most ``limit`` bytes.

    The file is opened without blocking and examined through its open descriptor, so a file swapped for a
    pipe after :func:`require_file` looked at it is refused too.

    Args:
        path: The file.
        limit: The most bytes it may hold.
        what: The kind of file, for the message (``"a glove recording"``).
        advice: Text after the refusal of a file over ``limit``, e.g. ``": cut it into shorter recordings"``.

    Yields:
        The open binary file and its size in bytes (read no more than that: :func:`read_bytes` does).

    Raises:
        InputFileError: Missing, a directory, not a regular file, larger than ``limit``, or unreadable.
    """
    p = require_file(path)
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except OSError as exc:
        raise InputFileError(f"{p}: cannot read ({exc.strerror or exc})") from exc
    with os.fdopen(fd, "rb") as f:
        info = os.fstat(fd)
        special = _special_kind(info.st_mode)
        if special is not None:
            raise _not_regular_error(p, special)
        if info.st_size > limit:
            raise _too_large(p, info.st_size, limit, what, advice)
        yield f, info.st_size


def read_bytes(
    path: str | Path, limit: int = MAX_FILE_BYTES, what: str = "an input file", advice: str = ""
) -> bytes:
    """Read a file's bytes, bounded as :func:`open_input` bounds them.

    Args:
        path: The file.
        limit: The most bytes it may hold (default :data:`MAX_FILE_BYTES`).
        what: The kind of file, for the message of a file over the limit.
        advice: Text after that message.

    Raises:
        InputFileError: Missing, a directory, not a regular file, over ``limit`` (also when it grows past it
            while read), or unreadable; the message names the file.
    """
    p = Path(path)
    with open_input(p, limit, what, advice) as (f, _):
        try:
            data = f.read(limit + 1)
        except OSError as exc:
            raise InputFileError(f"{p}: cannot read ({exc.strerror or exc})") from exc
    if len(data) > limit:
        raise _too_large(p, len(data), limit, what, advice)
    return data


def decode_text_file(data: bytes, path: str | Path) -> str:
    """A text file's content as :func:`decode_text` decodes it, refusing bytes no text file holds.

    Text is UTF-8 (Latin-1 accepted); a UTF-16 byte-order mark or a NUL byte means UTF-16/32 text or binary
    data, whose Latin-1 reading would only give a confusing error about the file's entries.

    Raises:
        FormatError: "not a UTF-8 text file": a UTF-16/32 byte-order mark at the start, or a NUL byte (the
            message gives its line and byte offset).
    """
    if data.startswith(UTF16_BOMS):
        raise FormatError(
            path, "not a UTF-8 text file: it starts with a UTF-16 byte-order mark; save it as UTF-8 text"
        )
    nul = data.find(b"\0")
    if nul >= 0:
        raise FormatError(
            path,
            f"not a UTF-8 text file: a NUL byte at byte {nul} (binary data, or UTF-16/32 text); save it as "
            "UTF-8 text",
            line=data.count(b"\n", 0, nul) + 1,
        )
    return decode_text(data)


def decode_text(data: bytes) -> str:
    """A text file's content: UTF-8 after any byte-order mark, Latin-1 when it is not UTF-8.

    Line ends are left as they are: ``str.splitlines`` (used by every reader) splits LF, CRLF and CR
    alike, and ``str.split``/``str.strip`` drop trailing blanks.
    """
    data = data.removeprefix(UTF8_BOM)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def decode_utf8(data: bytes, path: str | Path) -> str:
    """A UTF-8 text file's content (JSON), after any byte-order mark.

    Raises:
        FormatError: The bytes are not UTF-8 (the message gives the byte offset in the file).
    """
    skip = len(UTF8_BOM) if data.startswith(UTF8_BOM) else 0
    try:
        return data[skip:].decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FormatError(path, f"not UTF-8 text ({exc.reason} at byte {skip + exc.start})") from None


def read_text(path: str | Path) -> str:
    """Read a text file (see :func:`decode_text_file`: a byte-order mark dropped, Latin-1 as fallback).

    Raises:
        InputFileError: As :func:`read_bytes`.
        FormatError: UTF-16 text or NUL bytes (:func:`decode_text_file`).
    """
    return decode_text_file(read_bytes(path), path)


def sha256_of(data: bytes) -> str:
    """Hex SHA-256 of ``data``."""
    return hashlib.sha256(data).hexdigest()


def parse_float(token: str, path: str | Path, line: int, field: str, *, finite: bool = True) -> float:
    """Parse one number, raising :class:`FormatError` with file, line and field on failure.

    Args:
        token: The text to parse.
        path: File name for the error message.
        line: 1-based line number for the error message.
        field: Field name for the error message.
        finite: Reject NaN and infinities.
    """
    try:
        value = float(token)
    except ValueError:
        raise FormatError(path, f"expected a number, got {token!r}", line=line, field=field) from None
    if finite and not math.isfinite(value):
        raise FormatError(path, f"expected a finite number, got {token!r}", line=line, field=field)
    return value


def parse_int(token: str, path: str | Path, line: int, field: str, minimum: int = 0) -> int:
    """Parse one integer ≥ ``minimum``, raising :class:`FormatError` with file, line and field on failure."""
    try:
        value = int(token)
    except ValueError:
        value = None
    if value is None or value < minimum:
        raise FormatError(path, f"expected an integer ≥ {minimum}, got {token!r}", line=line, field=field)
    return value


def parse_floats(
    tokens: list[str], path: str | Path, line: int, fields: list[str] | str, *, finite: bool = True
) -> list[float]:
    """Parse several numbers; ``fields`` names each token (or is one name used with an index)."""
    names = fields if isinstance(fields, list) else [f"{fields}[{i}]" for i in range(len(tokens))]
    return [parse_float(t, path, line, n, finite=finite) for t, n in zip(tokens, names, strict=True)]


def numbered_lines(text: str) -> list[tuple[int, str]]:
    """Non-blank lines of ``text`` with their 1-based line numbers, stripped."""
    return [(i + 1, s.strip()) for i, s in enumerate(text.splitlines()) if s.strip()]


def blank_line_blocks(text: str) -> list[list[tuple[int, str]]]:
    """Non-blank stripped lines with their line numbers, grouped by blank lines."""
    blocks: list[list[tuple[int, str]]] = [[]]
    for i, raw in enumerate(text.splitlines()):
        if raw.strip():
            blocks[-1].append((i + 1, raw.strip()))
        elif blocks[-1]:
            blocks.append([])
    return [b for b in blocks if b]
