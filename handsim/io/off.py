"""Reader for OFF meshes (Geomview's Object File Format: the Tzionas ``.OFF`` files and ``.off`` meshes).

Layout (``#`` starts a comment line; blank lines are skipped)::

    OFF                      keyword (COFF, NOFF, CNOFF, STOFF …: vertices carry extra numbers)
    nv nf ne                 counts (may follow the keyword on its line; ne, the edge count, is ignored)
    x y z                    nv vertex lines (more numbers for a COFF/NOFF/STOFF vertex: colour, normal …)
    n i_1 … i_n [colour]     nf face lines: n ≥ 3 vertex indices, 0-based, then 0 to 4 colour numbers

Polygons are triangulated as fans. The counts are checked against the lines that follow: a header that
promises more (or fewer) vertices or faces than the file holds is an error naming the header's line.
Binary OFF is not read.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from handsim.errors import FormatError
from handsim.io.text_files import numbered_lines, parse_floats, parse_int, read_text

_KEYWORD = re.compile(r"(ST)?C?N?OFF")
MAX_FACE_COLOUR = 4
"""Numbers a face line may carry after its indices (a colour: index, RGB or RGBA)."""


def read_off(path: str | Path, units_scale: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """Read an OFF mesh; polygons are triangulated as fans.

    Args:
        path: The ``.OFF`` file.
        units_scale: Factor applied to the coordinates (1e-3: mm to m).

    Returns:
        Vertices (V, 3) and triangles (F, 3).

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: Bad header or counts, wrong token counts, indices out of range, fewer or more
            vertex/face lines than the header promises (file, line and field are named).
    """
    p = Path(path)
    return parse_off(read_text(p), p, units_scale)


def parse_off(text: str, path: str | Path, units_scale: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """Parse the text of an OFF file (see :func:`read_off`); ``path`` names it in messages."""
    p = Path(path)
    lines = [(ln, s) for ln, s in numbered_lines(text) if not s.startswith("#")]
    keyword = lines[0][1].split()[0] if lines else ""
    if not _KEYWORD.fullmatch(keyword):
        got = f"got {keyword[:20]!r}" if lines else "the file is empty"
        raise FormatError(
            p, f"expected the keyword 'OFF' (or COFF, NOFF …), {got}", line=lines[0][0] if lines else 1,
            field="header",
        )  # fmt: skip
    counts = lines[0][1].split()[1:]
    k = 1
    if not counts:
        if len(lines) < 2:
            raise FormatError(p, "file ends; expected 'nv nf ne'", line=lines[0][0], field="counts")
        counts, k = lines[1][1].split(), 2
    if counts[:1] == ["BINARY"]:
        msg = "binary OFF is not read; save the mesh as text OFF"
        raise FormatError(p, msg, line=lines[0][0], field="header")
    header = lines[k - 1][0]
    if len(counts) not in (2, 3):
        raise FormatError(p, f"expected 'nv nf ne', got {counts}", line=header, field="counts")
    nv, nf, *_ = (parse_int(c, p, header, f) for c, f in zip(counts, ("nv", "nf", "ne"), strict=False))
    vertex_lines, face_lines = lines[k : k + nv], lines[k + nv : k + nv + nf]
    if len(vertex_lines) < nv or len(face_lines) < nf:
        msg = (
            f"the header promises {nv} vertices and {nf} faces, but the file ends after "
            f"{len(vertex_lines)} vertex and {len(face_lines)} face lines (line {lines[-1][0]})"
        )
        raise FormatError(p, msg, line=header, field="counts")
    plain = keyword == "OFF"
    verts = np.empty((nv, 3))
    for i, (ln, s) in enumerate(vertex_lines):
        tokens = s.split()
        if (len(tokens) != 3) if plain else (len(tokens) < 3):
            expected = "3 coordinates" if plain else f"3 coordinates and the numbers a {keyword} vertex adds"
            raise FormatError(p, f"expected {expected}, got {len(tokens)}", line=ln, field="vertex")
        verts[i] = parse_floats(tokens[:3], p, ln, ["x", "y", "z"])
        parse_floats(tokens[3:], p, ln, "vertex data")
    tris: list[tuple[int, int, int]] = []
    for ln, s in face_lines:
        tokens = s.split()
        n = parse_int(tokens[0], p, ln, "face size", minimum=3)
        if not n + 1 <= len(tokens) <= n + 1 + MAX_FACE_COLOUR:
            msg = (
                f"face of {n} vertices needs {n + 1} tokens, got {len(tokens)} (up to {MAX_FACE_COLOUR} "
                "colour numbers may follow the indices)"
            )
            raise FormatError(p, msg, line=ln, field="face")
        idx = [parse_int(t, p, ln, "face index") for t in tokens[1 : n + 1]]
        parse_floats(tokens[n + 1 :], p, ln, "face colour")
        if max(idx) >= nv:
            msg = f"vertex index {max(idx)} out of range; expected 0..{nv - 1}"
            raise FormatError(p, msg, line=ln, field="face index")
        tris.extend((idx[0], idx[j], idx[j + 1]) for j in range(1, n - 1))
    if len(lines) > k + nv + nf:
        ln = lines[k + nv + nf][0]
        msg = f"unexpected content after the {nf} faces the header (line {header}) promises"
        raise FormatError(p, msg, line=ln, field="end")
    return verts * units_scale, np.array(tris, dtype=np.int64).reshape(-1, 3)


__all__ = ["parse_off", "read_off"]
