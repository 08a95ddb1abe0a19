"""Reader for Tzionas/Ballan hand models: ``.SKEL`` + ``.LIMITS`` [+ ``.MOTION``/``.OFF``/``.SKIN``/``.VOI``].

:func:`read_tzionas_skeleton` assembles a model's files into a :class:`~handsim.datatypes.skeleton.Skeleton`;
each file is parsed by its own module (:mod:`handsim.io.tzionas.skel`: ``.SKEL``, ``.LIMITS``;
:mod:`handsim.io.tzionas.motion_file`: ``.MOTION``; :mod:`handsim.io.off`: ``.OFF``;
:mod:`handsim.io.tzionas.surface`: ``.SKIN``, ``.VOI``). Files use mm and degrees; everything returned is
in metres and radians. Conventions (see the dataset's format spec; checked on the IJCV16 sample data):

* The rest pose is ``.MOTION`` row 0 (the rigging pose): one joint per bone at the bone's origin with the
  bone's frame (the columns of ``R``), each bone running along its local +x.
* A ``.LIMITS`` flag of 1 makes the axis a DoF named ``<bone>_pron`` (rx, twist), ``<bone>_flex`` (ry) or
  ``<bone>_abd`` (rz), chained abd, flex, pron from the outside in. The root's entry is its global pose,
  tracked separately as a 6-D pose, so it gives no skeleton DoFs. Unlimited ranges become ±π.
* Fingertips: a ``<bone>_tip`` joint at the end of every leaf bone; the five ``RFing.k`` leaves of a hand
  are ordered thumb (k = 4) to little finger (k = 0), with their ``.VOI`` vertices.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from handsim.datatypes.skeleton import Dof, Joint, Skeleton, SkinnedMesh, mj_name
from handsim.errors import FormatError, InputFileError
from handsim.io.off import read_off
from handsim.io.tzionas.motion_file import read_motion_rows
from handsim.io.tzionas.skel import MM, BoneLimits, SkelBone, read_limits, read_skel
from handsim.io.tzionas.surface import read_skin, voi_fingertip_vertices

ROTATION_TOL = 1e-2
AXIS_KINDS = ("pron", "flex", "abd")
DOF_CHAIN_ORDER = (2, 1, 0)  # outermost first: abd (z), flex (y), pron (x)
_HAND_LEAF = re.compile(r"[LR]Fing\.(\d+)_\w+")


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
    blocks = read_motion_rows(motion, [b.name for b in bones], frames)
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
        fingertip_vertices = voi_fingertip_vertices(voi, tips, bones, mesh, notes)
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
