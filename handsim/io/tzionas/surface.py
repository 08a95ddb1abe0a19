"""The surface files of a Tzionas/Ballan model: ``.SKIN`` (skin weights) and ``.VOI`` (fingertip vertices).

The mesh itself is the ``.OFF`` (:mod:`handsim.io.off`). Conventions (checked on the IJCV16 sample data):

* ``.SKIN`` names may contain spaces; the name line is split by matching the ``.SKEL`` names.
* ``.VOI``: blank-line separated groups of vertex ids; the spec gives one id per finger, ordered little,
  ring, middle, index, thumb. The IJCV16 hand (``Models/20/Model_Hand_R.VOI``) has 3 such groups: in each,
  the 5 ids are dominated (skin weight 0.95 to 0.9996) by RFing.0_2, RFing.1_2, RFing.2_2, RFing.3_2 and
  RFing.4_1 in that order, so each group is "one vertex per finger"; the groups step down the finger
  (2-3 mm, 5-9 mm and 10-13 mm from the tip joints). :attr:`Skeleton.fingertip_vertices` holds, per finger in
  :attr:`Skeleton.fingertips` order (thumb first), that finger's id from every group
  (:func:`voi_fingertip_vertices`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from handsim.datatypes.skeleton import SkinnedMesh
from handsim.errors import FormatError
from handsim.io.text_files import blank_line_blocks, numbered_lines, parse_floats, parse_int, read_text
from handsim.io.tzionas.skel import SkelBone

VOI_FINGERS = ("little", "ring", "middle", "index", "thumb")


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
    blocks = blank_line_blocks(read_text(path))
    groups = [[(parse_int(s, path, ln, "vertex id"), ln) for ln, s in b] for b in blocks]
    if not groups:
        raise FormatError(path, "no vertex ids", line=1, field="vertex id")
    return groups


def read_voi(path: str | Path) -> tuple[tuple[int, ...], ...]:
    """Read a ``.VOI`` file: blank-line separated groups of vertex ids, as in the file.

    Raises:
        FormatError: A line that is not one vertex id ≥ 0, or an empty file.
    """
    return tuple(tuple(v for v, _ in g) for g in _voi_groups(Path(path)))


def voi_fingertip_vertices(
    voi: Path, tips: list[str], bones: list[SkelBone], mesh: SkinnedMesh | None, notes: list[str]
) -> tuple[tuple[int, ...], ...]:
    """VOI ids per finger (thumb first); each VOI group lists one id per finger, little → thumb.

    Args:
        voi: The ``.VOI`` file.
        tips: The fingertip (leaf) bones, thumb first.
        bones: The ``.SKEL`` bones (to find each fingertip's chain).
        mesh: The skinned mesh, when there is one: ids are checked against its vertex count and each id's
            dominant skin weight is compared with its finger's bones (the outcome is noted).
        notes: Decisions, appended to.

    Returns:
        Per finger in ``tips`` order, its vertex id from every group.

    Raises:
        FormatError: A group without one id per finger, or an id beyond the mesh's vertices.
    """
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
