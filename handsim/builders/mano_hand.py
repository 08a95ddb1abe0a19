"""A MuJoCo MANO hand: MANO's kinematic tree as a hinge :class:`Skeleton`, built by :func:`build_hand`.

The skeleton (:func:`mano_skeleton`):

* the 16 MANO joints with identity frames (MANO's joint frames are aligned with the model frame at rest);
  each finger joint is three hinges about the model axes z, y, x, outermost first
  (``<joint>_z``, ``<joint>_y``, ``<joint>_x``), so ``Rz · Ry · Rx = exp(ω)`` of MANO's axis-angle ω
  (:func:`handsim.io.arctic.mano_pose.mano_pose_to_trajectory` does the exact conversion, continuous in
  time); limits are coordinate ranges wide enough for continuous angles (:data:`HINGE_LIMITS`), not
  anatomy; the wrist has no DoF (its pose is the root pose);
* palm anchors ``index0``, ``middle0``, ``ring0``, ``pinky0`` (no DoF) that only shape the palm, so that
  :func:`build_hand`'s rule "a finger chain starts with a metacarpal inside the palm" gives every MANO
  phalanx its own colliding capsule;
* fingertips ``<finger>_tip``: MANO's tip vertices when a model file is given, else extrapolated.

Two sources of joints for :func:`build_mano_hand`:

* a MANO model file (``MANO_RIGHT.pkl``/``MANO_LEFT.pkl``, supplied by the user under MPI's licence) and
  betas: shaped joints, fingertips at MANO's tip vertices, and the skinned mesh for per-bone hulls
  (``collision="mesh"``);
* no file: the bundled mean-shape joint table (betas = 0; the left hand mirrored in x), fingertips
  extrapolated, capsule collision only.

The wrist is the root body at J0, fixed to the world (``root="fixed"``) or a mocap body (``root="mocap"``:
set ``data.mocap_pos``/``mocap_quat`` to the trajectory's ``root_pose``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.builders.hand import build_hand
from handsim.datatypes.skeleton import Dof, Joint, Skeleton, SkinnedMesh
from handsim.errors import ModelError, SkeletonError
from handsim.io.arctic.mano import (
    FINGERS,
    HINGE_AXES,
    MANO_FILES,
    MANO_JOINT_NAMES,
    MANO_PARENTS,
    MANOModel,
    check_side,
    find_mano_files,
    joints_side,
    mano_mean_joints,
    mano_vertices,
    padded_betas,
    read_mano_model,
)

ROOT_OPTIONS = ("fixed", "mocap")
"""``build_mano_hand(root=…)``: the wrist welded to the world, or a mocap body."""

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
    index = {name: i for i, (name, _, _) in enumerate(order)}
    skeleton_joints = tuple(
        Joint(name, -1 if parent is None else index[parent], pos.copy(), np.eye(3))
        for name, parent, pos in order
    )
    dofs = tuple(
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
    return Skeleton(
        name=f"mano_{side}",
        joints=skeleton_joints,
        dofs=dofs,
        fingertips=tuple(f"{f}_tip" for f in FINGERS),
        source=source,
        notes=tuple(note_list),
        mesh=mesh,
    )


def mano_model_skeleton(model: MANOModel, betas: npt.ArrayLike | None = None) -> Skeleton:
    """The skeleton of a MANO model at shape β, with fingertips from its mesh and the skinned mesh attached.

    Args:
        model: The MANO model.
        betas: Shape coefficients; the mean shape when None.

    Returns:
        See :func:`mano_skeleton`; :attr:`Skeleton.mesh` holds the shaped rest mesh and MANO's skinning
        weights (bones = MANO joint names), so ``build_hand(collision="mesh")`` makes per-bone hulls.
    """
    b = padded_betas(model, betas)
    vertices = mano_vertices(model, b)
    joints = model.J_regressor @ vertices
    tips, note = vertex_tips(model, vertices, joints)
    mesh = SkinnedMesh(vertices=vertices, faces=model.faces, weights=model.weights, bones=MANO_JOINT_NAMES)
    shape = "mean shape" if not np.any(b) else "betas " + ", ".join(f"{x:.4g}" for x in b)
    return mano_skeleton(
        joints,
        model.parents,
        model.side,
        tips=tips,
        mesh=mesh,
        source=f"{model.source} ({shape})",
        notes=(note,),
    )


def mano_hand_skeleton(
    pkl_path: str | Path | None = None, betas: npt.ArrayLike | None = None, side: str = "right"
) -> Skeleton:
    """The MANO skeleton :func:`build_mano_hand` builds (use it for :func:`mano_pose_to_trajectory`).

    Args:
        pkl_path: A MANO model file; the bundled mean-shape table when None.
        betas: Shape coefficients (needs ``pkl_path`` unless all zero).
        side: ``"right"`` or ``"left"``; must match the file.

    Returns:
        The skeleton (with the skinned mesh when ``pkl_path`` is given).

    Raises:
        ModelError: Non-zero betas without a model file.
        SkeletonError: ``side`` does not match the model file's hand.
        FormatError: The model file is malformed (see :func:`handsim.io.arctic.mano.read_mano_model`).
    """
    if pkl_path is None:
        if betas is not None and np.any(np.asarray(betas, dtype=float) != 0.0):
            raise ModelError(
                "betas need the MANO model file (pkl_path): the bundled joint table is the mean shape only"
            )
        return mano_skeleton(
            mano_mean_joints(side),
            side=side,
            source="bundled MANO mean-shape joint table" + (" (mirrored in x)" if side == "left" else ""),
        )
    skeleton = mano_model_skeleton(read_mano_model(pkl_path), betas)
    if skeleton.name != f"mano_{side}":
        raise ModelError(
            f"{pkl_path}: the model is a {skeleton.name.removeprefix('mano_')} hand, but side={side!r}"
        )
    return skeleton


def build_mano_hand(
    pkl_path: str | Path | None = None,
    betas: npt.ArrayLike | None = None,
    side: str = "right",
    *,
    collision: str = "capsules",
    root: str = "fixed",
    mass: float | None = None,
    timestep: float = 0.002,
    name: str | None = None,
) -> mujoco.MjSpec:
    """Build a position-controlled MANO hand.

    Args:
        pkl_path: A MANO model file; the bundled mean-shape table when None.
        betas: Shape coefficients (needs ``pkl_path`` unless all zero).
        side: ``"right"`` or ``"left"``.
        collision: ``"capsules"`` (a capsule per bone and a convex palm) or ``"mesh"`` (a convex hull per
            MANO bone from the skinned mesh, each vertex assigned to its highest-weight joint; needs
            ``pkl_path``).
        root: ``"fixed"`` (the wrist body welded to the world at J0) or ``"mocap"`` (the wrist body is a
            mocap body, driven by the trajectory's root pose).
        mass: Whole-hand mass in kg; anthropometric by default (see :func:`build_hand`).
        timestep: Simulation timestep in seconds.
        name: Model name; ``mano_<side>`` by default.

    Returns:
        An uncompiled spec: 45 hinges ``<joint>_z/_y/_x`` with actuators ``<dof>_act``, a site per joint
        (MANO joints, palm anchors, ``<finger>_tip``).

    Raises:
        ModelError: Unknown ``collision``/``root`` option, ``"mesh"`` without a model file, or non-zero betas
            without one.
    """
    _check_root(root)
    if collision == "mesh" and pkl_path is None:
        raise ModelError(
            "collision='mesh' needs the MANO mesh: pass pkl_path (MANO_RIGHT.pkl / MANO_LEFT.pkl)"
        )
    skeleton = mano_hand_skeleton(pkl_path, betas, side)
    return _hand_spec(skeleton, collision, root, mass, timestep, name)


def _check_root(root: str) -> None:
    if root not in ROOT_OPTIONS:
        raise ModelError(f"unknown root option {root!r}; expected one of {list(ROOT_OPTIONS)}")


def _hand_spec(
    skeleton: Skeleton, collision: str, root: str, mass: float | None, timestep: float, name: str | None
) -> mujoco.MjSpec:
    spec = build_hand(skeleton, mass=mass, collision=collision, name=name, timestep=timestep)
    if root == "mocap":
        spec.body(skeleton.joints[0].name).mocap = True
    return spec


@dataclass(frozen=True)
class MANOHand:
    """A MANO hand built from a user's model file, with what converting its motion needs.

    Attributes:
        side: ``"right"`` or ``"left"``.
        spec: The uncompiled hand (:func:`build_mano_hand`'s layout; model name ``mano_<side>``).
        skeleton: Its hinge skeleton at ``betas`` (the wrist J0 is where the root pose puts the wrist body).
        model: The MANO model read from the file (``hands_mean`` for ``flat_hand_mean=False``).
        betas: The shape coefficients the hand was built with, shape (S,).
    """

    side: str
    spec: mujoco.MjSpec
    skeleton: Skeleton
    model: MANOModel
    betas: np.ndarray


def build_mano_hands(
    mano_dir: str | Path | None,
    betas: Mapping[str, npt.ArrayLike],
    *,
    collision: str = "capsules",
    root: str = "fixed",
    mass: float | None = None,
    timestep: float = 0.002,
) -> dict[str, MANOHand]:
    """Build MANO hands from the user's ``MANO_RIGHT.pkl`` / ``MANO_LEFT.pkl``, each with its own betas.

    Each model file is read once; its side must match its name (``MANO_LEFT.pkl`` must be a left hand).

    Args:
        mano_dir: The folder with the model files; None: ``$HANDSIM_MANO_DIR``
            (:func:`handsim.io.arctic.mano.find_mano_files`).
        betas: Side → shape coefficients (e.g. an ARCTIC subject's ``shape`` per hand); the sides given are
            the hands built.
        collision: ``"capsules"`` or ``"mesh"`` (see :func:`build_mano_hand`).
        root: ``"fixed"`` (the wrist body without joints: what ``build_scene(hand_root="weld")`` frees and
            welds to a mocap target) or ``"mocap"``.
        mass: Whole-hand mass in kg per hand; anthropometric by default.
        timestep: Simulation timestep in seconds.

    Returns:
        Side → the built hand, in the order of ``betas``.

    Raises:
        InputFileError: The folder or a model file is missing (the message says which files are needed and
            where to put them).
        FormatError: A model file is malformed.
        ModelError: A file holds the other hand, bad betas, or an unknown ``collision``/``root``.
    """
    _check_root(root)
    files = find_mano_files(mano_dir, tuple(betas))
    hands = {}
    for side, path in files.items():
        model = read_mano_model(path)
        if model.side != side:
            raise ModelError(
                f"{path}: the model is a {model.side} hand (fingers towards "
                f"{'−x' if model.side == 'right' else '+x'} from the wrist), but the file is the {side} "
                f"hand's {MANO_FILES[side]}"
            )
        b = padded_betas(model, betas[side])
        skeleton = mano_model_skeleton(model, b)
        spec = _hand_spec(skeleton, collision, root, mass, timestep, None)
        hands[side] = MANOHand(side=side, spec=spec, skeleton=skeleton, model=model, betas=b)
    return hands
