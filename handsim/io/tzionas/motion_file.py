"""The ``.MOTION`` file of a Tzionas/Ballan model: per bone, its name, then one row per frame.

A row is ``R`` (3x3, row-major) then ``T`` (mm): the columns of ``R`` are the bone's local axes in the
world, ``T`` its origin; each bone runs along its local +x. Row 0 is the rigging (rest) pose. Fitting the
rows to DoF angles is :mod:`handsim.io.tzionas.motion`'s job.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.errors import FormatError
from handsim.io.text_files import numbered_lines, parse_floats, read_text
from handsim.io.tzionas.skel import MM

MOTION_FIELDS = [f"R[{i}][{j}]" for i in range(3) for j in range(3)] + ["T.x", "T.y", "T.z"]


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _is_row(tokens: list[str]) -> bool:
    """Whether a ``.MOTION`` line is a row of numbers rather than a bone name.

    It is when it starts with a number, or has 12 tokens of which the last 11 are numbers (a row with a
    bad first entry, e.g. ``O.98`` for ``0.98``, whose error must name that entry, not an unknown bone).
    """
    return _is_number(tokens[0]) or (len(tokens) == len(MOTION_FIELDS) and all(map(_is_number, tokens[1:])))


@dataclass
class _MotionBlock:
    name_line: int
    rows: list[list[float]]
    first_row_line: int = 0


def read_motion_rows(
    path: Path, bone_names: list[str] | None, expected_frames: int | None
) -> dict[str, tuple[np.ndarray, int]]:
    """Raw MOTION rows (mm) per bone, with the line of each bone's first row.

    Args:
        path: The ``.MOTION`` file.
        bone_names: Allowed bone names (all names allowed when None).
        expected_frames: Rows every bone must have (the ``.SKEL`` frame count), unchecked when None.

    Returns:
        Per bone, its rows as in the file (R row-major, then T in mm), shape (z, 12), and the 1-based line
        of its first row.

    Raises:
        FormatError: Unknown or repeated bone, malformed row, or a row count other than expected.
    """
    blocks: dict[str, _MotionBlock] = {}
    known = set(bone_names or ())
    lines = numbered_lines(read_text(path))
    for ln, s in lines:
        tokens = s.split()
        if s not in known and _is_row(tokens):
            if not blocks:
                raise FormatError(
                    path, "expected a bone name before the first row", line=ln, field="bone name"
                )
            if len(tokens) != 12:
                msg = f"expected 12 numbers (R row-major, then T in mm), got {len(tokens)}"
                raise FormatError(path, msg, line=ln, field="row")
            block = blocks[next(reversed(blocks))]
            block.first_row_line = block.first_row_line or ln
            block.rows.append(parse_floats(tokens, path, ln, MOTION_FIELDS))
            continue
        if bone_names is not None and s not in known:
            msg = f"unknown bone {s!r}; expected one of the .SKEL bones {list(bone_names)}"
            raise FormatError(path, msg, line=ln, field="bone name")
        if s in blocks:
            msg = f"second block for bone {s!r} (first at line {blocks[s].name_line})"
            raise FormatError(path, msg, line=ln, field="bone name")
        blocks[s] = _MotionBlock(ln, [])
    if not blocks:
        raise FormatError(path, "no bones; expected a bone name and its rows", line=1, field="bone name")
    for name, b in blocks.items():
        if expected_frames is not None and len(b.rows) != expected_frames:
            msg = f"bone {name!r} has {len(b.rows)} rows, expected {expected_frames} (the .SKEL frame count)"
            raise FormatError(path, msg, line=b.name_line, field="rows")
    return {k: (np.array(b.rows, dtype=float).reshape(-1, 12), b.first_row_line) for k, b in blocks.items()}


def read_motion(
    path: str | Path, bone_names: list[str] | None = None, expected_frames: int | None = None
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Read a ``.MOTION`` file.

    Args:
        path: The ``.MOTION`` file.
        bone_names: Allowed bone names (all names allowed when None).
        expected_frames: Rows every bone must have (the ``.SKEL`` frame count), unchecked when None.

    Returns:
        Per bone ``(R, T)``: rotations (z, 3, 3), columns = local axes in the world, and origins (z, 3)
        in metres.

    Raises:
        FormatError: Unknown or repeated bone, malformed row, or a row count other than expected.
    """
    blocks = read_motion_rows(Path(path), bone_names, expected_frames)
    return {k: (rows[:, :9].reshape(-1, 3, 3), rows[:, 9:] * MM) for k, (rows, _) in blocks.items()}
