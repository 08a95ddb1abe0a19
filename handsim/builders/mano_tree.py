"""MANO's kinematic tree as a hinge :class:`~handsim.datatypes.skeleton.Skeleton`: joints, anchors, tips.

* the 16 MANO joints with identity frames (MANO's joint frames are aligned with the model frame at rest);
  each finger joint is three hinges about the model axes z, y, x, outermost first
  (``<joint>_z``, ``<joint>_y``, ``<joint>_x``), so ``Rz · Ry · Rx = exp(ω)`` of MANO's axis-angle ω;
  limits are coordinate ranges (:data:`HINGE_LIMITS`), not anatomy; the wrist has no DoF;
* palm anchors ``index0``, ``middle0``, ``ring0``, ``pinky0`` (no DoF) that only shape the palm;
* fingertips ``<finger>_tip``: MANO's tip vertices when a model file is given (:func:`vertex_tips`), else
  extrapolated (:func:`extrapolated_tips`).

:mod:`handsim.builders.mano_hand` builds the MuJoCo hand from it.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from handsim.datatypes.skeleton import Dof, Joint, Skeleton, SkinnedMesh
from handsim.errors import SkeletonError
from handsim.io.arctic.mano import (
    FINGERS,
    HINGE_AXES,
    MANO_JOINT_NAMES,
    MANO_PARENTS,
    MANOModel,
    check_side,
    joints_side,
)

FINGERTIP_VERTEX_IDS: dict[str, int] = {"thumb": 744, "index": 320, "middle": 443, "ring": 554, "pinky": 671}
"""MANO vertex at each fingertip (the ``'mano'`` ids of smplx's ``vertex_ids.py``); the same ids serve the
left model, whose topology is the right one's."""

TIP_EXTENSION: dict[str, float] = {"thumb": 1.41, "index": 1.06, "middle": 1.36, "ring": 1.23, "pinky": 1.20}
"""Without a MANO mesh, the fingertip is ``J3 + k · (J3 − J2)``: k = distance from the last joint to the
fingertip over the last bone's length, from the mean-shape fingertip offsets in ``rsc/mano/mano_mean.urdf``
of github.com/christsa/dgrasp (e.g. index 23.6 mm / 22.2 mm)."""

HINGE_LIMITS: dict[str, tuple[float, float]] = {
    "z": (-2.0 * math.pi, 2.0 * math.pi),
    "y": (-2.0 * math.pi, 2.0 * math.pi),
    "x": (-2.0 * math.pi, 2.0 * math.pi),
}
"""Joint ranges in radians: coordinate ranges, not anatomy (MANO fits are anatomically regularised). The
targets are continuous in time (:func:`handsim.datatypes.rotations.continuous_zyx`), so a joint whose
rotation passes ±180° or near y = ±90° leaves the principal Euler box (z, x in [−π, π], y in [−π/2, π/2]).
Each column is centred on zero (its middle within ±π, y's within ±π/2), so ±2π holds every sequence in
which a hinge's angle spans at most a whole turn (one and a half for y): more only where the joint turns
round. The ranges stay finite because the position actuators' ``ctrlrange`` equals them and the
environments scale actions to them."""

FINGER_KINDS: dict[str, str] = {"z": "flex", "y": "abd", "x": "pron"}
"""DoF kinds of the four fingers (z flexion, y ab/adduction about the palm normal, x axial rotation); the
thumb's axes do not align with its anatomy, so its DoFs are of kind ``rot``."""

ANCHOR_AXIAL = 0.25
ANCHOR_LATERAL = 0.8
"""Palm anchors ``<finger>0`` (index, middle, ring, pinky): DoF-less points rigid with the wrist at the
metacarpal bases, ``wrist + 0.25 · axial + 0.8 · lateral`` part of the way to the finger's first joint
(axial along wrist → middle1). They only shape the palm; MANO has no such joints."""


def extrapolated_tips(joints: npt.ArrayLike) -> np.ndarray:
    """Fingertips ``J3 + k (J3 − J2)`` with :data:`TIP_EXTENSION`, thumb first, shape (5, 3)."""
    j = np.asarray(joints, dtype=float)
    index = {n: i for i, n in enumerate(MANO_JOINT_NAMES)}
    return np.array(
        [j[index[f"{f}3"]] + TIP_EXTENSION[f] * (j[index[f"{f}3"]] - j[index[f"{f}2"]]) for f in FINGERS]
    )


def vertex_tips(model: MANOModel, vertices: np.ndarray, joints: np.ndarray) -> tuple[np.ndarray | None, str]:
    """Fingertips at :data:`FINGERTIP_VERTEX_IDS` if those vertices are plausible tips, with a note.

    A tip vertex must exist, be skinned mostly to its finger's last joint, lie beyond that joint along the
    last bone (0.3 to 3 bone lengths away) and within 45° of the bone's direction; otherwise the tips are
    extrapolated and the note says why.
    """
    index = {n: i for i, n in enumerate(MANO_JOINT_NAMES)}
    tips = []
    for finger in FINGERS:
        vid = FINGERTIP_VERTEX_IDS[finger]
        if vid >= len(vertices):
            return None, f"model has {len(vertices)} vertices, fewer than MANO's 778: fingertips extrapolated"
        j2, j3 = joints[index[f"{finger}2"]], joints[index[f"{finger}3"]]
        bone, offset = j3 - j2, vertices[vid] - j3
        ratio = np.linalg.norm(offset) / np.linalg.norm(bone)
        cos = float(offset @ bone) / (np.linalg.norm(offset) * np.linalg.norm(bone) + 1e-300)
        owner = MANO_JOINT_NAMES[int(np.argmax(model.weights[vid]))]
        if owner != f"{finger}3" or not 0.3 <= ratio <= 3.0 or cos < math.cos(math.radians(45.0)):
            return None, (
                f"vertex {vid} is not a plausible {finger} tip (skinned to {owner}, {ratio:.2f} bone lengths "
                f"from {finger}3, {math.degrees(math.acos(max(-1.0, min(1.0, cos)))):.0f}° off the bone): "
                "fingertips extrapolated"
            )
        tips.append(vertices[vid])
    ids = "/".join(str(FINGERTIP_VERTEX_IDS[f]) for f in FINGERS)
    return np.array(tips), f"fingertips at MANO vertices {ids} (thumb, index, middle, ring, pinky)"


def mano_skeleton(
    joints: npt.ArrayLike,
    parents: npt.ArrayLike = MANO_PARENTS,
    side: str = "right",
    *,
    tips: npt.ArrayLike | None = None,
    mesh: SkinnedMesh | None = None,
    source: str = "",
    notes: tuple[str, ...] = (),
) -> Skeleton:
    """A hinge skeleton of MANO's kinematic tree: 15 joints × 3 hinges (z, y, x), plus tips and palm anchors.

    Joints (parents first): ``wrist``; for index, middle, pinky, ring: the palm anchor ``<finger>0`` (no
    DoF, see :data:`ANCHOR_AXIAL`) and ``<finger>1..3``; ``thumb1..3``; then the five ``<finger>_tip``
    leaves (thumb first, :attr:`Skeleton.fingertips`). Every frame is the identity (MANO frames are
    aligned with the model frame at rest). DoFs, in MANO pose order: ``<joint>_z``, ``<joint>_y``,
    ``<joint>_x`` per MANO joint, limits :data:`HINGE_LIMITS`. The wrist has no DoF: its pose is the
    trajectory's root pose.

    Args:
        joints: Rest joint positions in MANO order, metres, shape (16, 3).
        parents: Parent indices; must be MANO's.
        side: ``"right"`` or ``"left"``; must match the joints (fingers towards −x on a right hand).
        tips: Fingertip positions thumb first, shape (5, 3); extrapolated along the last bones when None.
        mesh: Optional skinned mesh (bones = MANO joint names) for per-bone collision hulls.
        source: Where the joints came from.
        notes: Decisions to carry in :attr:`Skeleton.notes`.

    Returns:
        The skeleton, named ``mano_<side>``.

    Raises:
        SkeletonError: Wrong shapes, non-MANO parents, or a side that contradicts the joints.
    """
    j = _checked_joints(joints, parents, side)
    tip_pos, note_list = _tip_positions(j, tips, notes)
    order = _joint_order(j, tip_pos)
    index = {name: i for i, (name, _, _) in enumerate(order)}
    skeleton_joints = tuple(
        Joint(name, -1 if parent is None else index[parent], pos.copy(), np.eye(3))
        for name, parent, pos in order
    )
    return Skeleton(
        name=f"mano_{side}",
        joints=skeleton_joints,
        dofs=_mano_dofs(),
        fingertips=tuple(f"{f}_tip" for f in FINGERS),
        source=source,
        notes=tuple(note_list),
        mesh=mesh,
    )


def _checked_joints(joints: npt.ArrayLike, parents: npt.ArrayLike, side: str) -> np.ndarray:
    """MANO's 16 rest joint positions as floats, checked against MANO's tree and the hand's side.

    Raises:
        SkeletonError: Not 16 × 3 finite positions, parents other than MANO's, or joints of the other side.
    """
    check_side(side)
    j = np.asarray(joints, dtype=float)
    if j.shape != (16, 3) or not np.all(np.isfinite(j)):
        raise SkeletonError(f"MANO joints must be 16 × 3 finite positions, got shape {j.shape}")
    if tuple(int(p) for p in np.asarray(parents).reshape(-1)) != MANO_PARENTS:
        raise SkeletonError(f"MANO parents must be {list(MANO_PARENTS)}, got {np.asarray(parents).tolist()}")
    found = joints_side(j)
    if found != side:
        raise SkeletonError(
            f"the joints are a {found} MANO hand (fingers towards {'−x' if found == 'right' else '+x'} "
            f"from the wrist), but side={side!r}"
        )
    return j


def _tip_positions(
    j: np.ndarray, tips: npt.ArrayLike | None, notes: tuple[str, ...]
) -> tuple[np.ndarray, list[str]]:
    """The fingertips, thumb first (5, 3), given or extrapolated, and the notes with how they were found.

    Raises:
        SkeletonError: Given fingertips that are not 5 × 3 positions.
    """
    note_list = list(notes)
    if tips is None:
        tip_pos = extrapolated_tips(j)
        if not any("fingertip" in n for n in note_list):
            note_list.append("fingertips extrapolated along the last bones (TIP_EXTENSION)")
    else:
        tip_pos = np.asarray(tips, dtype=float)
        if tip_pos.shape != (5, 3):
            raise SkeletonError(
                f"fingertips must be 5 × 3 positions (thumb first), got shape {tip_pos.shape}"
            )
    return tip_pos, note_list


def _joint_order(j: np.ndarray, tip_pos: np.ndarray) -> list[tuple[str, str | None, np.ndarray]]:
    """The skeleton's joints parents first, as (name, parent name, rest position).

    The wrist; per finger its palm anchor (:data:`ANCHOR_AXIAL` of the way along the hand's axis and
    :data:`ANCHOR_LATERAL` across towards the finger's first joint) and three joints; the thumb's three
    joints; then the five fingertips.
    """
    position = dict(zip(MANO_JOINT_NAMES, j, strict=True))
    axis = position["middle1"] - position["wrist"]
    axis /= np.linalg.norm(axis)
    order: list[tuple[str, str | None, np.ndarray]] = [("wrist", None, position["wrist"])]
    for finger in ("index", "middle", "pinky", "ring"):
        rel = position[f"{finger}1"] - position["wrist"]
        along = (rel @ axis) * axis
        anchor = position["wrist"] + ANCHOR_AXIAL * along + ANCHOR_LATERAL * (rel - along)
        order.append((f"{finger}0", "wrist", anchor))
        order += [(f"{finger}{k}", f"{finger}{k - 1}", position[f"{finger}{k}"]) for k in (1, 2, 3)]
    order += [(f"thumb{k}", "wrist" if k == 1 else f"thumb{k - 1}", position[f"thumb{k}"]) for k in (1, 2, 3)]
    order += [(f"{f}_tip", f"{f}3", tip) for f, tip in zip(FINGERS, tip_pos, strict=True)]
    return order


def _mano_dofs() -> tuple[Dof, ...]:
    """Three hinges (z, y, x) per MANO joint but the wrist, in pose order, limits :data:`HINGE_LIMITS`."""
    return tuple(
        Dof(
            name=f"{name}_{ax}",
            joint=name,
            axis=np.array(vec),
            lower=HINGE_LIMITS[ax][0],
            upper=HINGE_LIMITS[ax][1],
            kind="rot" if name.startswith("thumb") else FINGER_KINDS[ax],
        )
        for name in MANO_JOINT_NAMES[1:]
        for ax, vec in HINGE_AXES
    )
