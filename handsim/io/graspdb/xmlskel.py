"""Reader for GraspDB14 ``.xmlskel`` hand skeletons.

Format (GraspDB14 technical report, §4.2.3): nested ``<joint>`` elements, each with ``<name>``, ``<id>``,
``<position>`` and ``<limits>`` (``<rotx>``, ``<roty>``, ``<rotz>``: "min max"), and a ``<units>`` block
declaring ``<angle>`` (deg|rad) and ``<length>`` (mm|m).

Conventions, as the GraspDB14 MATLAB tools define them (``readXMLSKEL``/``fix_llc``, ``fwdKinematics``,
``constructSensor2JointMap``) and as the FK oracle confirms:

* ``<position>`` is the ABSOLUTE rest position of the joint, not an offset from its parent. The skeleton
  is translated so that the root sits at the origin (``rootToZero``).
* Local frames: the root's is the identity; ``th-tmc`` takes its parent's frame; every other joint's frame
  is a rotation about z by ``sign(q_z)·asin(|q|)``, ``q = v × (0, 1, 0)``, ``v`` the unit bone vector from
  the parent (for bones in the x/y plane this is ``asin(v_x)``), so local y runs along the bone.
* An axis whose limits differ (min ≠ max) is a degree of freedom. DoF names are the joint name with ``-``
  replaced by ``_`` plus ``_flex`` (local x), ``_pron`` (local y) or ``_abd`` (local z).
* Within a joint the DoFs are chained abduction (z) outermost, then y, then flexion (x) innermost: the
  tools rotate a joint's subtree about its own unrotated axes, flexion first, so abduction ends up outer.
* The GraspDB14 tools drive ``th-tmc`` about its local y with the T-TMCJ sensor although the file gives
  that axis the range 0..0 (Table 5.1 of the report says z; the code and the oracle use y). The reader
  adds that DoF with the range in :data:`TOOL_DRIVEN_AXES` and records a note.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np

from handsim.datatypes.rotations import rotation_about_axis
from handsim.datatypes.skeleton import Dof, Joint, Skeleton, mj_name
from handsim.errors import FormatError
from handsim.io.text_files import parse_floats, read_bytes

AXIS_TAGS = ("rotx", "roty", "rotz")
AXIS_KINDS = {"rotx": "flex", "roty": "pron", "rotz": "abd"}
# Outermost first: abduction (z), then y, then flexion (x).
DOF_CHAIN_ORDER = ("rotz", "roty", "rotx")
ANGLE_UNITS = {"deg": math.pi / 180.0, "rad": 1.0}
LENGTH_UNITS = {"mm": 1e-3, "m": 1.0}

TOOL_DRIVEN_AXES: dict[tuple[str, str], tuple[float, float]] = {
    # (joint, axis tag) -> range in degrees. Covers the T-TMCJ angles seen in the GraspDB14 samples
    # (-25 deg to 116 deg after the tools' sign flip).
    ("th-tmc", "roty"): (-30.0, 120.0),
}


@dataclass
class _Node:
    tag: str
    line: int
    text: str = ""
    children: list[_Node] = field(default_factory=list)

    def child(self, tag: str) -> _Node | None:
        return next((c for c in self.children if c.tag == tag), None)


def _parse_xml(path: Path, data: bytes) -> _Node:
    """Parse XML into a small tree that remembers each element's line (ElementTree does not)."""
    parser = expat.ParserCreate()
    root = _Node("#document", 0)
    stack = [root]

    def start(tag: str, _attrs: dict[str, str]) -> None:
        node = _Node(tag.lower(), parser.CurrentLineNumber)
        stack[-1].children.append(node)
        stack.append(node)

    def end(_tag: str) -> None:
        stack.pop()

    def chars(text: str) -> None:
        stack[-1].text += text

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise FormatError(path, f"malformed XML: {expat.ErrorString(exc.code)}", line=exc.lineno) from None
    return root


def _units(path: Path, skel: _Node) -> tuple[float, float]:
    units = skel.child("units")
    if units is None:
        raise FormatError(
            path,
            "missing <units>; expected <angle>deg|rad</angle> and <length>mm|m</length>",
            element="skeleton",
            line=skel.line,
        )
    scales = []
    for tag, table in (("angle", ANGLE_UNITS), ("length", LENGTH_UNITS)):
        node = units.child(tag)
        value = node.text.strip().lower() if node is not None else ""
        if value not in table:
            raise FormatError(
                path,
                f"unit {value!r} is not supported; expected one of {sorted(table)}",
                line=(node or units).line,
                element=f"units/{tag}",
                field=tag,
            )
        scales.append(table[value])
    return scales[0], scales[1]


@dataclass
class _RawJoint:
    name: str
    id: int
    parent: int
    position: np.ndarray
    limits: dict[str, tuple[float, float]]
    line: int


def _required_text(path: Path, node: _Node, tag: str) -> _Node:
    child = node.child(tag)
    if child is None or not child.text.strip():
        raise FormatError(path, f"<joint> has no <{tag}>", line=node.line, element="joint", field=tag)
    return child


def _read_joint(path: Path, node: _Node, parent: int, out: list[_RawJoint]) -> None:
    name = _required_text(path, node, "name").text.strip()
    id_node = _required_text(path, node, "id")
    try:
        joint_id = int(id_node.text.strip())
    except ValueError:
        raise FormatError(
            path,
            f"joint {name!r}: id {id_node.text.strip()!r} is not an integer",
            line=id_node.line,
            element="id",
            field="id",
        ) from None
    pos_node = _required_text(path, node, "position")
    tokens = pos_node.text.split()
    if len(tokens) != 3:
        raise FormatError(
            path,
            f"joint {name!r}: expected 3 numbers (x y z), got {len(tokens)}",
            line=pos_node.line,
            element="position",
            field="position",
        )
    position = np.array(parse_floats(tokens, path, pos_node.line, ["position x", "position y", "position z"]))
    limits: dict[str, tuple[float, float]] = {}
    limits_node = node.child("limits")
    for tag in AXIS_TAGS:
        axis_node = limits_node.child(tag) if limits_node is not None else None
        if axis_node is None:
            limits[tag] = (0.0, 0.0)
            continue
        vals = axis_node.text.split()
        if len(vals) != 2:
            raise FormatError(
                path,
                f"joint {name!r}: expected 'min max', got {axis_node.text.strip()!r}",
                line=axis_node.line,
                element=f"limits/{tag}",
                field=tag,
            )
        lo, hi = parse_floats(vals, path, axis_node.line, [f"{tag} min", f"{tag} max"])
        if lo > hi:
            raise FormatError(
                path,
                f"joint {name!r}: min {lo:g} > max {hi:g}",
                line=axis_node.line,
                element=f"limits/{tag}",
                field=tag,
            )
        limits[tag] = (lo, hi)
    if node.child("basis") is not None:
        raise FormatError(
            path,
            f"joint {name!r}: explicit <basis> frames are not supported; remove it to use the "
            "GraspDB14 default frames",
            line=node.child("basis").line,
            element="basis",
        )
    index = len(out)
    for existing in out:
        if existing.name == name:
            raise FormatError(
                path,
                f"duplicate joint name {name!r} (first defined on line {existing.line})",
                line=node.line,
                element="joint",
                field="name",
            )
        if existing.id == joint_id:
            raise FormatError(
                path,
                f"duplicate joint id {joint_id} ({name!r} and {existing.name!r}, line {existing.line})",
                line=node.line,
                element="joint",
                field="id",
            )
    out.append(_RawJoint(name, joint_id, parent, position, limits, node.line))
    for child in node.children:
        if child.tag == "joint":
            _read_joint(path, child, index, out)


def local_frame(bone: np.ndarray) -> np.ndarray:
    """GraspDB14 ``fix_llc`` frame: rotate about z so that local y aligns with the bone in x/y."""
    v = bone / np.linalg.norm(bone)
    q = np.cross(v, [0.0, 1.0, 0.0])
    angle = float(np.sign(q[2]) * math.asin(min(1.0, float(np.linalg.norm(q)))))
    return rotation_about_axis((0.0, 0.0, 1.0), angle)


def read_xmlskel(path: str | Path) -> Skeleton:
    """Read a GraspDB14 ``.xmlskel`` skeleton.

    Args:
        path: The ``.xmlskel`` file.

    Returns:
        The skeleton in metres and radians, root at the origin, with the GraspDB14 tools' local frames
        and DoFs (see the module docstring).

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: Malformed XML, a missing or unsupported unit, a joint without name/id/position,
            duplicate joint names or ids, non-numeric limits or min > max, a zero-length bone. The
            message names the file, the line, the element and the field.
    """
    p = Path(path)
    doc = _parse_xml(p, read_bytes(p))
    skel = doc.child("skeleton")
    if skel is None:
        raise FormatError(p, "no <skeleton> root element", line=1)
    angle_scale, length_scale = _units(p, skel)
    joint_nodes = [c for c in skel.children if c.tag == "joint"]
    if len(joint_nodes) != 1:
        raise FormatError(
            p,
            f"expected exactly one root <joint> in <skeleton>, found {len(joint_nodes)}",
            line=skel.line,
            element="skeleton",
        )
    raw: list[_RawJoint] = []
    _read_joint(p, joint_nodes[0], -1, raw)

    notes: list[str] = []
    origin = raw[0].position.copy()
    if np.any(origin != 0):
        notes.append(f"root moved from {origin.tolist()} to the origin (as the GraspDB14 tools do)")
    positions = [(r.position - origin) * length_scale for r in raw]

    frames: list[np.ndarray] = []
    for i, r in enumerate(raw):
        if r.parent < 0:
            frames.append(np.eye(3))
            continue
        bone = positions[i] - positions[r.parent]
        if np.linalg.norm(bone) < 1e-9:
            raise FormatError(
                p,
                f"joint {r.name!r} sits on its parent {raw[r.parent].name!r} (zero-length bone)",
                line=r.line,
                element="position",
                field="position",
            )
        frames.append(frames[r.parent].copy() if r.name == "th-tmc" else local_frame(bone))

    dofs: list[Dof] = []
    for r in raw:
        for tag in DOF_CHAIN_ORDER:
            lo, hi = r.limits[tag]
            if lo == hi and (r.name, tag) in TOOL_DRIVEN_AXES:
                lo, hi = TOOL_DRIVEN_AXES[(r.name, tag)]
                notes.append(
                    f"{r.name} {tag}: the file gives 0..0 but the GraspDB14 tools drive this axis "
                    f"(T-TMCJ); using {lo:g}..{hi:g} deg"
                )
                lo, hi = lo * math.pi / 180.0, hi * math.pi / 180.0
            elif lo == hi:
                continue
            else:
                lo, hi = lo * angle_scale, hi * angle_scale
            axis = np.eye(3)[AXIS_TAGS.index(tag)]
            kind = AXIS_KINDS[tag]
            dofs.append(Dof(f"{mj_name(r.name)}_{kind}", r.name, axis, lo, hi, kind))

    joints = tuple(Joint(r.name, r.parent, positions[i], frames[i]) for i, r in enumerate(raw))
    tips = tuple(r.name for i, r in enumerate(raw) if all(o.parent != i for o in raw) and r.parent >= 0)
    return Skeleton(
        name=p.stem, joints=joints, dofs=tuple(dofs), fingertips=tips, source=str(p), notes=tuple(notes)
    )
