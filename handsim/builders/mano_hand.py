"""A MuJoCo MANO hand: MANO's kinematic tree as a hinge :class:`Skeleton`, built by :func:`build_hand`.

The skeleton (:func:`~handsim.builders.mano_tree.mano_skeleton`):

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

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.builders.hand import build_hand
from handsim.builders.mano_tree import (
    ANCHOR_AXIAL,
    ANCHOR_LATERAL,
    FINGER_KINDS,
    FINGERTIP_VERTEX_IDS,
    HINGE_LIMITS,
    TIP_EXTENSION,
    extrapolated_tips,
    mano_skeleton,
    vertex_tips,
)
from handsim.datatypes.skeleton import Skeleton, SkinnedMesh
from handsim.errors import ModelError
from handsim.io.arctic.mano import (
    MANO_FILES,
    MANO_JOINT_NAMES,
    MANOModel,
    find_mano_files,
    mano_mean_joints,
    mano_vertices,
    padded_betas,
    read_mano_model,
)

__all__ = [
    "ANCHOR_AXIAL",
    "ANCHOR_LATERAL",
    "FINGERTIP_VERTEX_IDS",
    "FINGER_KINDS",
    "HINGE_LIMITS",
    "ROOT_OPTIONS",
    "TIP_EXTENSION",
    "build_mano_hand",
    "build_mano_hands",
    "extrapolated_tips",
    "mano_hand_skeleton",
    "mano_model_skeleton",
    "mano_skeleton",
    "vertex_tips",
]

ROOT_OPTIONS = ("fixed", "mocap")
"""``build_mano_hand(root=…)``: the wrist welded to the world, or a mocap body."""


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
