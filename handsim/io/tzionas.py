"""Reader for Tzionas/Ballan hand models: ``.SKEL`` + ``.LIMITS`` [+ ``.MOTION``/``.OFF``/``.SKIN``/``.VOI``].

Files use mm and degrees; everything returned is in metres and radians. Conventions (see the dataset's
format spec; checked on the IJCV16 sample data):

* ``.MOTION`` rows are ``R`` (3x3, row-major) then ``T``: the columns of ``R`` are the bone's local axes in
  the world, ``T`` its origin; each bone runs along its local +x. Row 0 is the rigging (rest) pose.
* ``.LIMITS`` axes are unit vectors in the bone's local rest frame. A flag of 1 makes the axis a DoF named
  ``<bone>_pron`` (rx, twist), ``<bone>_flex`` (ry) or ``<bone>_abd`` (rz), chained abd, flex, pron from
  the outside in. The root's entry is its global pose (its "axes" hold a translation), tracked separately
  as a 6-D pose, so it gives no skeleton DoFs. Limits of ±3.4e38 mean unlimited and become ±π.
* ``.SKIN`` names may contain spaces; the name line is split by matching the ``.SKEL`` names.
* ``.VOI``: blank-line separated groups of vertex ids; the spec gives one id per finger, ordered little,
  ring, middle, index, thumb. The IJCV16 hand (``Models/20/Model_Hand_R.VOI``) has 3 such groups: in each,
  the 5 ids are dominated (skin weight 0.95 to 0.9996) by RFing.0_2, RFing.1_2, RFing.2_2, RFing.3_2 and
  RFing.4_1 in that order, so each group is "one vertex per finger"; the groups step down the finger
  (2-3 mm, 5-9 mm and 10-13 mm from the tip joints). :attr:`Skeleton.fingertip_vertices` holds, per finger in
  :attr:`Skeleton.fingertips` order (thumb first), that finger's id from every group.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.datatypes.skeleton import Dof, Joint, Skeleton, SkinnedMesh, mj_name
from handsim.errors import FormatError, InputFileError
from handsim.io._text import numbered_lines, parse_float, parse_floats, parse_int, read_text
from handsim.io.off import read_off

ROOT_PARENT = "Root_NULL_Bone_0"
MM = 1e-3
UNLIMITED = 1e38
AXIS_NORM_TOL = 1e-3
ROTATION_TOL = 1e-2
AXES = ("rx", "ry", "rz")
AXIS_KINDS = ("pron", "flex", "abd")
DOF_CHAIN_ORDER = (2, 1, 0)  # outermost first: abd (z), flex (y), pron (x)
VOI_FINGERS = ("little", "ring", "middle", "index", "thumb")
MOTION_FIELDS = [f"R[{i}][{j}]" for i in range(3) for j in range(3)] + ["T.x", "T.y", "T.z"]
_HAND_LEAF = re.compile(r"[LR]Fing\.(\d+)_\w+")


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


def _blocks(text: str) -> list[list[tuple[int, str]]]:
    """Non-blank stripped lines with their line numbers, grouped by blank lines."""
    blocks: list[list[tuple[int, str]]] = [[]]
    for i, raw in enumerate(text.splitlines()):
        if raw.strip():
            blocks[-1].append((i + 1, raw.strip()))
        elif blocks[-1]:
            blocks.append([])
    return [b for b in blocks if b]


def read_limits(path: str | Path, bone_names: list[str], root: str | None = None) -> dict[str, BoneLimits]:
    """Read a ``.LIMITS`` file.

    Args:
        path: The ``.LIMITS`` file.
        bone_names: The bones of the ``.SKEL``; an entry for any other name is an error.
        root: The root bone, whose axis lines hold a translation and are not checked to be unit.

    Returns:
        Entries by bone name, axes normalised (except the root's), limits in radians.

    Raises:
        FormatError: Unknown or duplicate bone, wrong entry size, bad flag, axis or limit.
    """
    p = Path(path)
    out: dict[str, BoneLimits] = {}
    for block in _blocks(read_text(p)):
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


def _motion_blocks(
    path: Path, bone_names: list[str] | None, expected_frames: int | None
) -> dict[str, tuple[np.ndarray, int]]:
    """Raw MOTION rows (mm) per bone, with the line of each bone's first row."""
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
    blocks = _motion_blocks(Path(path), bone_names, expected_frames)
    return {k: (rows[:, :9].reshape(-1, 3, 3), rows[:, 9:] * MM) for k, (rows, _) in blocks.items()}


def _split_names(path: Path, line: int, text: str, bone_names: list[str]) -> list[str]:
    """Split a line of space-separated names that may contain spaces (greedy longest match)."""
    tokens, out, i = text.split(), [], 0
    known = {" ".join(n.split()): n for n in bone_names}
    while i < len(tokens):
        j = next((j for j in range(len(tokens), i, -1) if " ".join(tokens[i:j]) in known), None)
        if j is None:
            msg = f"unknown bone name starting at {tokens[i]!r}; expected .SKEL bones {list(bone_names)}"
            raise FormatError(path, msg, line=line, field="bone names")
        out.append(known[" ".join(tokens[i:j])])
        i = j
    return out


def read_skin(
    path: str | Path, bone_names: list[str], nvertices: int, mesh_path: str | Path | None = None
) -> tuple[np.ndarray, tuple[str, ...]]:
    """Read a ``.SKIN`` file.

    Args:
        path: The ``.SKIN`` file.
        bone_names: The ``.SKEL`` bone names (used to split the header line).
        nvertices: Vertex count of the mesh; the file must have one row per vertex.
        mesh_path: The mesh file, named in the row-count error.

    Returns:
        Weights (nvertices, B) and the bone name of each column.

    Raises:
        FormatError: Bad count, unknown or duplicate names, malformed rows, row count ≠ ``nvertices``.
    """
    p = Path(path)
    lines = numbered_lines(read_text(p))
    if len(lines) < 2:
        raise FormatError(p, "expected the bone count and the bone names", line=1, field="header")
    count = parse_int(lines[0][1], p, lines[0][0], "bone count", minimum=1)
    names = _split_names(p, lines[1][0], lines[1][1], bone_names)
    if len(names) != count or len(set(names)) != len(names):
        msg = f"expected {count} distinct bone names (line {lines[0][0]}), got {names}"
        raise FormatError(p, msg, line=lines[1][0], field="bone names")
    rows = lines[2:]
    if len(rows) != nvertices:
        mesh = mesh_path or "the mesh"
        msg = f"{len(rows)} weight rows, but {mesh} has {nvertices} vertices; expected one row per vertex"
        raise FormatError(p, msg, line=(rows[-1][0] if rows else lines[1][0]), field="rows")
    weights = np.empty((nvertices, count))
    for i, (ln, s) in enumerate(rows):
        tokens = s.split()
        if len(tokens) != count:
            raise FormatError(p, f"expected {count} weights, got {len(tokens)}", line=ln, field="weights")
        weights[i] = parse_floats(tokens, p, ln, "weight")
    return weights, tuple(names)


def _voi_groups(path: Path) -> list[list[tuple[int, int]]]:
    groups = [[(parse_int(s, path, ln, "vertex id"), ln) for ln, s in b] for b in _blocks(read_text(path))]
    if not groups:
        raise FormatError(path, "no vertex ids", line=1, field="vertex id")
    return groups


def read_voi(path: str | Path) -> tuple[tuple[int, ...], ...]:
    """Read a ``.VOI`` file: blank-line separated groups of vertex ids, as in the file.

    Raises:
        FormatError: A line that is not one vertex id ≥ 0, or an empty file.
    """
    return tuple(tuple(v for v, _ in g) for g in _voi_groups(Path(path)))


def _sibling(path: Path, ext: str) -> Path | None:
    upper = path.with_suffix("." + ext.upper())
    lower = path.with_suffix("." + ext.lower())
    candidates = (lower, upper) if path.suffix.islower() else (upper, lower)
    return next((c for c in candidates if c.is_file()), None)


def _rest_pose(
    path: Path, bones: list[SkelBone], frames: int, notes: list[str]
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Rest position (m) and frame of every bone: MOTION row 0, else a chain laid out along +x."""
    motion = _sibling(path, "MOTION")
    if motion is None:
        notes.append(
            "no .MOTION beside the .SKEL: rest pose unknown, bones laid out along +x, identity frames"
        )
        pose: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for b in bones:
            parent = next((q for q in bones if q.name == b.parent), None)
            base = np.zeros(3) if parent is None else pose[parent.name][0] + [parent.length, 0.0, 0.0]
            pose[b.name] = (base, np.eye(3))
        return pose
    blocks = _motion_blocks(motion, [b.name for b in bones], frames)
    missing = [b.name for b in bones if b.name not in blocks]
    if missing:
        msg = f"no block for bones {missing}; expected one per .SKEL bone"
        raise FormatError(motion, msg, line=max(line for _, line in blocks.values()), field="bone name")
    pose, worst = {}, 0.0
    for b in bones:
        rows, line = blocks[b.name]
        r = rows[0, :9].reshape(3, 3)
        u, s, vt = np.linalg.svd(r)
        if np.abs(s - 1.0).max() > ROTATION_TOL or np.linalg.det(r) <= 0:
            msg = f"rest R of bone {b.name!r} has singular values {s}, det {np.linalg.det(r):.3g}"
            msg += "; expected a rotation matrix"
            raise FormatError(motion, msg, line=line, field="R")
        worst = max(worst, float(np.abs(u @ vt - r).max()))
        pose[b.name] = (rows[0, 9:] * MM, u @ vt)
    note = f"rest pose from {motion.name} row 0"
    notes.append(note + (f"; frames re-orthonormalised by SVD (max change {worst:.2g})" if worst else ""))
    return pose


def _dofs(bones: list[SkelBone], limits: dict[str, BoneLimits], notes: list[str]) -> list[Dof]:
    root = bones[0].name
    if root in limits:
        notes.append(
            f"root bone {root!r}: its LIMITS entry is the global 6-D pose, tracked separately; no DoFs"
        )
    missing = [b.name for b in bones[1:] if b.name not in limits]
    if missing:
        notes.append(f"no LIMITS entry for bones {missing}: they get no DoFs")
    dofs: list[Dof] = []
    for b in bones[1:]:
        lim = limits.get(b.name)
        if lim is None:
            continue
        if lim.translate:
            notes.append(f"bone {b.name!r}: translation flag ignored (only the root may translate)")
        for i in DOF_CHAIN_ORDER:
            if not lim.rotate[i]:
                continue
            name = f"{mj_name(b.name)}_{AXIS_KINDS[i]}"
            dofs.append(
                Dof(name, b.name, lim.axes[i], float(lim.lower[i]), float(lim.upper[i]), AXIS_KINDS[i])
            )
            if lim.unlimited[i]:
                notes.append(f"DoF {name!r}: unlimited (±3.4e38) range replaced by ±π")
    return dofs


def _fingertip_bones(bones: list[SkelBone]) -> tuple[list[str], bool]:
    """Leaf bones, thumb to little finger when named RFing.k_* (k = 4 thumb … 0 little), else file order."""
    leaves = [b.name for b in bones if not any(c.parent == b.name for c in bones)]
    fingers = {n: int(m.group(1)) for n in leaves if (m := _HAND_LEAF.fullmatch(n))}
    if len(fingers) == len(leaves) and sorted(fingers.values()) == [0, 1, 2, 3, 4]:
        return sorted(leaves, key=lambda n: -fingers[n]), True
    return leaves, False


def _fingertip_vertices(
    voi: Path, tips: list[str], bones: list[SkelBone], mesh: SkinnedMesh | None, notes: list[str]
) -> tuple[tuple[int, ...], ...]:
    """VOI ids per finger (thumb first); each VOI group lists one id per finger, little → thumb."""
    groups = _voi_groups(voi)
    for g in groups:
        if len(g) != len(VOI_FINGERS):
            msg = f"group has {len(g)} vertex ids; expected one per finger ({', '.join(VOI_FINGERS)})"
            raise FormatError(voi, msg, line=g[0][1], field="group")
    per_finger = [[g[len(VOI_FINGERS) - 1 - f] for g in groups] for f in range(len(tips))]
    note = f"{voi.name}: {len(groups)} groups read as one vertex per finger (little → thumb)"
    if mesh is not None:
        parent = {b.name: b.parent for b in bones}
        strays = []
        for tip, ids in zip(tips, per_finger, strict=True):
            chain, bone = set(), tip
            while bone in parent and parent[bone] in parent:
                chain.add(bone)
                bone = parent[bone]
            for v, ln in ids:
                if v >= len(mesh.vertices):
                    msg = f"vertex id {v} out of range; the mesh has {len(mesh.vertices)} vertices"
                    raise FormatError(voi, msg, line=ln, field="vertex id")
                if mesh.bones[int(np.argmax(mesh.weights[v]))] not in chain:
                    strays.append(v)
        note += f"; SKIN weights disagree for ids {strays}" if strays else "; confirmed by SKIN weights"
    notes.append(note)
    return tuple(tuple(v for v, _ in ids) for ids in per_finger)


def read_tzionas_skeleton(skel_path: str | Path) -> Skeleton:
    """Read a Tzionas/Ballan model: ``.SKEL``, ``.LIMITS`` and any ``.MOTION``/``.OFF``/``.SKIN``/``.VOI``.

    One joint per bone at the bone's origin, plus a ``<bone>_tip`` joint at the end of every leaf bone.

    Args:
        skel_path: The ``.SKEL`` file; its siblings share its stem.

    Returns:
        The skeleton in metres and radians, with notes on every decision and repair.

    Raises:
        InputFileError: The ``.SKEL`` or its ``.LIMITS`` is missing or unreadable.
        FormatError: A file does not follow its format (file, line and field are named).
    """
    path = Path(skel_path)
    frames, bones = read_skel(path)
    names = [b.name for b in bones]
    limits_path = _sibling(path, "LIMITS")
    if limits_path is None:
        expected = path.with_suffix(".limits" if path.suffix.islower() else ".LIMITS")
        raise InputFileError(f"{expected}: file not found; a .SKEL needs its .LIMITS beside it (same stem)")
    notes: list[str] = []
    limits = read_limits(limits_path, names, root=names[0])
    pose = _rest_pose(path, bones, frames, notes)
    dofs = _dofs(bones, limits, notes)
    index = {n: i for i, n in enumerate(names)}
    joints = [Joint(b.name, index.get(b.parent, -1), *pose[b.name]) for b in bones]
    tips, is_hand = _fingertip_bones(bones)
    length = {b.name: b.length for b in bones}
    for tip in tips:
        position, frame = pose[tip]
        joints.append(Joint(f"{tip}_tip", index[tip], position + length[tip] * frame[:, 0], frame))
    mesh = None
    off, skin = _sibling(path, "OFF"), _sibling(path, "SKIN")
    if off is not None and skin is not None:
        vertices, faces = read_off(off)
        weights, skin_bones = read_skin(skin, names, len(vertices), mesh_path=off)
        mesh = SkinnedMesh(vertices, faces, weights, skin_bones)
    elif off is not None:
        notes.append(f"mesh ignored: {off.name} has no .SKIN beside it")
    elif skin is not None:
        notes.append(f"skin ignored: {skin.name} has no .OFF beside it")
    voi, fingertip_vertices = _sibling(path, "VOI"), None
    if voi is not None and is_hand:
        fingertip_vertices = _fingertip_vertices(voi, tips, bones, mesh, notes)
    elif voi is not None:
        notes.append(f"{voi.name} ignored: the leaf bones are not the five RFing.k fingers")
    return Skeleton(
        name=path.stem,
        joints=tuple(joints),
        dofs=tuple(dofs),
        fingertips=tuple(f"{t}_tip" for t in tips),
        source=str(path),
        notes=tuple(notes),
        mesh=mesh,
        fingertip_vertices=fingertip_vertices,
    )
