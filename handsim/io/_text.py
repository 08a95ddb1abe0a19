"""Helpers shared by the text-format readers: reading files and parsing numbers with locations."""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

from handsim.errors import FormatError, InputFileError


def read_bytes(path: str | Path) -> bytes:
    """Read a file's bytes, turning OS errors into :class:`InputFileError` naming the file."""
    p = Path(path)
    if not p.exists():
        raise InputFileError(f"{p}: file not found")
    if p.is_dir():
        raise InputFileError(f"{p}: is a directory, expected a file")
    try:
        return p.read_bytes()
    except OSError as exc:
        raise InputFileError(f"{p}: cannot read ({exc.strerror or exc})") from exc


def read_text(path: str | Path) -> str:
    """Read a text file (UTF-8, with Latin-1 as fallback for old datasets)."""
    data = read_bytes(path)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


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
