"""Helpers shared by the text-format readers: reading files and parsing numbers with locations."""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

from handsim.errors import FormatError, InputFileError

UTF8_BOM = b"\xef\xbb\xbf"
"""The UTF-8 byte-order mark some editors (Windows Notepad, Excel) write at the start of a text file."""


def require_file(path: str | Path) -> Path:
    """``path`` as a :class:`~pathlib.Path` when it is an existing file (or a link to one).

    Raises:
        InputFileError: Nothing exists at ``path`` ("file not found"), or it is a directory.
    """
    p = Path(path)
    if p.is_dir():
        raise InputFileError(f"{p}: is a directory, expected a file")
    if not p.exists():
        raise InputFileError(f"{p}: file not found")
    return p


def read_bytes(path: str | Path) -> bytes:
    """Read a file's bytes, turning OS errors into :class:`InputFileError` naming the file."""
    p = require_file(path)
    try:
        return p.read_bytes()
    except OSError as exc:
        raise InputFileError(f"{p}: cannot read ({exc.strerror or exc})") from exc


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
    """Read a text file (see :func:`decode_text`: a byte-order mark dropped, Latin-1 as fallback)."""
    return decode_text(read_bytes(path))


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
