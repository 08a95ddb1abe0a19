"""The kinematic files of a Tzionas/Ballan model: ``.SKEL`` (bones) and ``.LIMITS`` (DoF axes and limits).

Files use mm and degrees; everything returned is in metres and radians (see the dataset's format spec;
checked on the IJCV16 sample data):

* ``.SKEL``: the frame count, then ``parent``, ``bone``, ``length`` (mm) triples; the one root bone's
  parent is ``Root_NULL_Bone_0``.
* ``.LIMITS`` axes are unit vectors in the bone's local rest frame. A flag of 1 makes the axis a DoF (rx
  twist, ry, rz; :func:`~handsim.io.tzionas.skeleton.read_tzionas_skeleton` names and chains them). The
  root's entry
  is its global pose (its "axes" hold a translation), so its axes are not checked to be unit. Limits of
  ±3.4e38 mean unlimited and become ±π.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.errors import FormatError
from handsim.io.text_files import (
    blank_line_blocks,
    numbered_lines,
    parse_float,
    parse_floats,
    parse_int,
    read_text,
)

ROOT_PARENT = "Root_NULL_Bone_0"
MM = 1e-3
UNLIMITED = 1e38
AXIS_NORM_TOL = 1e-3
AXES = ("rx", "ry", "rz")


@dataclass(frozen=True)
class SkelBone:
    """One ``.SKEL`` bone: name, parent name, length in metres and the 1-based line of its name."""

    name: str
    parent: str
    length: float
    line: int


@dataclass(frozen=True)
class BoneLimits:
    """One ``.LIMITS`` entry.

    Attributes:
        bone: Bone name.
        line: 1-based line of the name.
        translate: The ``t`` flag.
        rotate: The ``rx ry rz`` flags.
        axes: Rows = rx, ry, rz axes in the bone's local frame, shape (3, 3); unit except for the root.
        lower: Lower limits in radians, shape (3,); -π where unlimited.
        upper: Upper limits in radians, shape (3,); π where unlimited.
        unlimited: Whether each axis had a ±3.4e38 (unlimited) bound.
    """

    bone: str
    line: int
    translate: bool
    rotate: tuple[bool, bool, bool]
    axes: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    unlimited: tuple[bool, bool, bool]


def read_skel(path: str | Path) -> tuple[int, list[SkelBone]]:
    """Read a ``.SKEL`` file.

    Args:
        path: The ``.SKEL`` file.

    Returns:
        The frame count z and the bones ordered parents first (file order otherwise).

    Raises:
        FormatError: Incomplete triples, duplicate or undefined names, bad numbers, not one root.
    """
    p = Path(path)
    lines = numbered_lines(read_text(p))
    if not lines:
        raise FormatError(p, "empty file; expected the frame count", line=1, field="frame count")
    frames = parse_int(lines[0][1], p, lines[0][0], "frame count", minimum=1)
    rest = lines[1:]
    if not rest or len(rest) % 3:
        start = rest[-(len(rest) % 3)][0] if rest else lines[0][0] + 1
        raise FormatError(
            p,
            f"expected 1 + 3k non-blank lines (frame count, then parent/bone/length triples), got "
            f"{len(lines)}; the triple starting at line {start} is incomplete",
            line=start,
            field="triple",
        )
    bones: dict[str, SkelBone] = {}
    parent_lines: dict[str, int] = {}
    for (lp, parent), (ln, name), (ll, length) in zip(rest[0::3], rest[1::3], rest[2::3], strict=True):
        if name in bones:
            msg = f"bone {name!r} is already defined at line {bones[name].line}; expected unique names"
            raise FormatError(p, msg, line=ln, field="bone name")
        value = parse_float(length, p, ll, "length")
        if value < 0:
            raise FormatError(p, f"expected a length ≥ 0 mm, got {length!r}", line=ll, field="length")
        bones[name] = SkelBone(name, parent, value * MM, ln)
        parent_lines[name] = lp
    return frames, _parents_first(p, bones, parent_lines)


def _parents_first(path: Path, bones: dict[str, SkelBone], parent_lines: dict[str, int]) -> list[SkelBone]:
    roots = [b for b in bones.values() if b.parent == ROOT_PARENT]
    for b in bones.values():
        if b.parent != ROOT_PARENT and b.parent not in bones:
            msg = f"parent {b.parent!r} of bone {b.name!r} is not defined; expected {ROOT_PARENT!r} or a bone"
            raise FormatError(path, msg + " of this file", line=parent_lines[b.name], field="parent")
    if len(roots) != 1:
        line = parent_lines[roots[1].name] if roots else parent_lines[next(iter(bones))]
        msg = f"expected exactly one bone with parent {ROOT_PARENT!r}, found {[b.name for b in roots]}"
        raise FormatError(path, msg, line=line, field="parent")
    ordered, done = [roots[0]], {roots[0].name}
    while len(ordered) < len(bones):
        before = len(ordered)
        for b in bones.values():
            if b.name not in done and b.parent in done:
                ordered.append(b)
                done.add(b.name)
        if len(ordered) == before:
            bad = next(b for b in bones.values() if b.name not in done)
            msg = f"bone {bad.name!r} is not connected to the root (its parents form a cycle)"
            raise FormatError(path, msg, line=parent_lines[bad.name], field="parent")
    return ordered


def read_limits(path: str | Path, bone_names: list[str], root: str | None = None) -> dict[str, BoneLimits]:
    """Read a ``.LIMITS`` file.

    Args:
        path: The ``.LIMITS`` file.
        bone_names: The bones of the ``.SKEL``; an entry for any other name is an error.
        root: The root bone, whose axis lines hold a translation and are not checked to be unit.

    Returns:
        Entries by bone name, axes normalised (except the root's), limits in radians.

    Raises:
        FormatError: No entry at all (an empty or blank file: the model would get no DoF), unknown or
            duplicate bone, wrong entry size, bad flag, axis or limit.
    """
    p = Path(path)
    out: dict[str, BoneLimits] = {}
    blocks = blank_line_blocks(read_text(p))
    if not blocks:
        raise FormatError(
            p,
            "no bone entries (the file is empty or blank): expected 8 lines per bone (name, flags "
            f"'t rx ry rz', 3 axis lines, 3 'min max' lines), at least one for the root bone"
            f"{f' {root!r}' if root else ''}; without them the model would have no degree of freedom",
        )
    for block in blocks:
        if len(block) % 8:
            msg = (
                f"entry has {len(block)} non-blank lines; expected 8 per bone (name, flags 't rx ry rz', "
                "3 axis lines, 3 'min max' lines)"
            )
            raise FormatError(p, msg, line=block[0][0], field="entry")
        for k in range(0, len(block), 8):
            entry = _limits_entry(p, block[k : k + 8], bone_names, root)
            if entry.bone in out:
                msg = f"second entry for bone {entry.bone!r} (first at line {out[entry.bone].line})"
                raise FormatError(p, msg, line=entry.line, field="bone name")
            out[entry.bone] = entry
    return out


def _limits_entry(
    p: Path, lines: list[tuple[int, str]], bone_names: list[str], root: str | None
) -> BoneLimits:
    (ln, name), (lf, flags) = lines[0], lines[1]
    if name not in bone_names:
        msg = f"entry for unknown bone {name!r}; expected one of the .SKEL bones {list(bone_names)}"
        raise FormatError(p, msg, line=ln, field="bone name")
    bits = flags.split()
    if len(bits) != 4 or any(b not in ("0", "1") for b in bits):
        raise FormatError(
            p, f"expected 4 flags 't rx ry rz' of 0 or 1, got {flags!r}", line=lf, field="flags"
        )
    axes = np.zeros((3, 3))
    lower, upper, unlimited = np.zeros(3), np.zeros(3), [False] * 3
    for i, axis in enumerate(AXES):
        la, text = lines[2 + i]
        tokens = text.split()
        if len(tokens) != 3:
            msg = f"expected 3 numbers (the {axis} axis), got {text!r}"
            raise FormatError(p, msg, line=la, field=f"{axis} axis")
        axes[i] = parse_floats(tokens, p, la, f"{axis} axis")
        norm = float(np.linalg.norm(axes[i]))
        if name != root:
            if not math.isfinite(norm) or abs(norm - 1.0) > AXIS_NORM_TOL:
                msg = f"axis has norm {norm:.6g}; expected a unit vector (within {AXIS_NORM_TOL})"
                raise FormatError(p, msg, line=la, field=f"{axis} axis")
            axes[i] /= norm
        ll, text = lines[5 + i]
        tokens = text.split()
        if len(tokens) != 2:
            msg = f"expected 2 numbers 'min max' in degrees, got {text!r}"
            raise FormatError(p, msg, line=ll, field=f"{axis} limits")
        lo, hi = parse_floats(tokens, p, ll, [f"{axis} min", f"{axis} max"])
        if lo > hi:
            msg = f"min {lo:g} > max {hi:g}; expected min ≤ max (degrees)"
            raise FormatError(p, msg, line=ll, field=f"{axis} limits")
        unlimited[i] = abs(lo) >= UNLIMITED or abs(hi) >= UNLIMITED
        lower[i] = -math.pi if abs(lo) >= UNLIMITED else math.radians(lo)
        upper[i] = math.pi if abs(hi) >= UNLIMITED else math.radians(hi)
    rotate = (bits[1] == "1", bits[2] == "1", bits[3] == "1")
    return BoneLimits(name, ln, bits[0] == "1", rotate, axes, lower, upper, tuple(unlimited))  # type: ignore[arg-type]
