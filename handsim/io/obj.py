"""Checks of a Wavefront OBJ mesh's vertex and face lines, before trimesh reads the file.

trimesh reads OBJ files quickly but says little when one is malformed: a vertex line with a stray word
fails with "string or file could not be read to its end due to unmatched data", a face index past the last
vertex with numpy's 0-based "index 99 is out of bounds for axis 0 with size 8", and some mistakes pass
silently (a face index 0 becomes the last vertex, a vertex line of two numbers shifts the ones after it, a
face of two indices is dropped). :func:`check_obj` reads the lines handsim uses and names the file, the
1-based line, the field and what was expected for the first bad one:

* ``v x y z [w | r g b]``: at least 3 finite numbers;
* ``vt u [v [w]]`` and ``vn x y z``: numbers;
* ``f v1 v2 v3 …`` (each ``v``, ``v/vt``, ``v/vt/vn`` or ``v//vn``): at least 3 vertex references, each a
  whole number in ``1..V`` (``V``: the file's vertex count) or a negative one counting back from the last
  vertex read so far (``-1`` is the latest), never 0.

Other statements (``o``, ``g``, ``s``, ``usemtl``, ``mtllib``, ``l``, comments …) are left to trimesh. The
check reads every line in Python, about as long as trimesh's own reading (2 s for a 330,000-face sphere
on the 2-core development machine).
"""

from __future__ import annotations

import math
from pathlib import Path

from handsim.errors import FormatError

_NUMBER_COUNTS = {"v": (3, 7), "vt": (1, 3), "vn": (3, 3)}
"""Numbers per vertex statement: (fewest, most); ``v`` may carry a weight or an RGB colour."""
_FIELDS = {"v": "vertex", "vt": "texture coordinate", "vn": "normal"}


def check_obj(path: str | Path, text: str) -> None:
    """Refuse an OBJ whose vertex or face lines are malformed (see the module docstring).

    Args:
        path: The file, for messages.
        text: Its text (decoded, a byte-order mark removed).

    Raises:
        FormatError: The first bad ``v``/``vt``/``vn`` or ``f`` line: a token that is not a number, too few
            or too many numbers, a non-finite coordinate, a face of fewer than 3 vertices, or a vertex
            index out of range (the message gives the range of valid indices for that line).
    """
    lines = text.splitlines()
    total = sum(1 for line in lines if line.split(None, 1)[:1] == ["v"])
    seen = 0
    for number, line in enumerate(lines, start=1):
        tokens = line.split()
        if not tokens:
            continue
        keyword = tokens[0]
        if keyword in _NUMBER_COUNTS:
            _check_numbers(path, number, keyword, tokens[1:])
            seen += keyword == "v"
        elif keyword == "f":
            _check_face(path, number, tokens[1:], seen, total)


def _check_numbers(path: str | Path, line: int, keyword: str, tokens: list[str]) -> None:
    fewest, most = _NUMBER_COUNTS[keyword]
    field = _FIELDS[keyword]
    if not fewest <= len(tokens) <= most:
        expected = f"{fewest} to {most}" if fewest != most else str(fewest)
        raise FormatError(
            path, f"expected {expected} numbers after '{keyword}', got {len(tokens)}", line=line, field=field
        )
    for token in tokens:
        try:
            value = float(token)
        except ValueError:
            raise FormatError(path, f"expected a number, got {token!r}", line=line, field=field) from None
        if not math.isfinite(value):
            raise FormatError(path, f"expected a finite number, got {token!r}", line=line, field=field)


def _check_face(path: str | Path, line: int, tokens: list[str], seen: int, total: int) -> None:
    if len(tokens) < 3:
        raise FormatError(
            path, f"a face needs at least 3 vertex indices, got {len(tokens)}", line=line, field="face"
        )
    for token in tokens:
        reference = token.split("/", 1)[0]
        try:
            index = int(reference)
        except ValueError:
            raise FormatError(
                path,
                f"expected a vertex index (a whole number, optionally followed by /texture/normal indices), "
                f"got {token!r}",
                line=line,
                field="face index",
            ) from None
        if not (1 <= index <= total or -seen <= index <= -1):
            if total == 0:
                expected = "none: the file has no vertex ('v' line)"
            else:
                back = f" or -{seen}..-1 (counting back from the last vertex read)" if seen else ""
                expected = f"1..{total}{back}: the file has {total} vertices and OBJ indices are 1-based"
            raise FormatError(
                path, f"vertex index {index} out of range; expected {expected}", line=line, field="face index"
            )


__all__ = ["check_obj"]
