"""MANO hand model: reading ``MANO_*.pkl``, finding the user's model files, and the shaped joints.

Poses become hinge angles in :mod:`handsim.io.arctic.mano_pose`; the hinge skeleton they drive is built by
:mod:`handsim.builders.mano_hand`.

Conventions (pinned by ``tests/test_mano.py``; details and measured numbers in ``docs/mano.md``):

* **Frame and units.** Everything is in the MANO model frame, metres. MANO's 16 joints are ordered wrist,
  index1-3, middle1-3, pinky1-3, ring1-3, thumb1-3; the rest pose is the flat hand (all rotations zero)
  and every MANO joint frame is aligned with the model frame at rest.
* **Joints.** ``J = J_regressor · (v_template + shapedirs · β)`` (the pose blend shapes move vertices,
  never joints).
* **Hinges.** Each finger joint is three hinges about the model axes z, y, x, outermost first
  (:data:`HINGE_AXES`; the conversion is :func:`handsim.io.arctic.mano_pose.mano_pose_to_trajectory`).
* **Left hands.** MANO's left model is the mirror image (x → −x) of the right one; the side is read from
  the joints (fingers towards −x from the wrist on a right hand, towards +x on a left one).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from handsim.assets import ASSETS_DIR
from handsim.errors import FormatError, InputFileError, ModelError, SkeletonError
from handsim.io.arctic.mano_pickle import MANO_PICKLE_GLOBALS, mano_array
from handsim.io.safe_pickle import load_restricted_pickle

MANO_JOINT_NAMES: tuple[str, ...] = (
    "wrist",
    *(f"{finger}{k}" for finger in ("index", "middle", "pinky", "ring", "thumb") for k in (1, 2, 3)),
)
"""MANO's 16 joints in MANO order (the order of ``J_regressor`` rows and of the 45 pose values)."""

MANO_PARENTS: tuple[int, ...] = (-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 0, 10, 11, 0, 13, 14)
"""Parent index of each MANO joint (``kintree_table[0]``, root = −1)."""

FINGERS: tuple[str, ...] = ("thumb", "index", "middle", "ring", "pinky")
"""Fingers in fingertip order (thumb first, as :attr:`Skeleton.fingertips`)."""

HINGE_AXES: tuple[tuple[str, tuple[float, float, float]], ...] = (
    ("z", (0.0, 0.0, 1.0)),
    ("y", (0.0, 1.0, 0.0)),
    ("x", (1.0, 0.0, 0.0)),
)
"""The three hinges of every MANO joint, outermost first: R = Rz · Ry · Rx."""

MEAN_JOINTS_FILE = ASSETS_DIR / "mano" / "mano_right_mean_joints.json"
"""The bundled right-hand mean-shape joint table (see ``handsim/assets/mano/NOTICE``)."""

MANO_ARRAYS = (
    "v_template",
    "shapedirs",
    "J_regressor",
    "kintree_table",
    "weights",
    "f",
    "posedirs",
    "hands_components",
    "hands_mean",
)
"""The entries :func:`read_mano_model` reads from a MANO pkl; every other entry is ignored."""

_OPTIONAL = ("posedirs", "hands_components", "hands_mean")


# --------------------------------------------------------------------------------------------------
# Data types


@dataclass(frozen=True)
class MANOModel:
    """The arrays of a MANO model file (no chumpy, no scipy objects), in metres.

    Attributes:
        v_template: Mean-shape rest vertices, shape (V, 3).
        shapedirs: Shape blend shapes, shape (V, 3, S) (S = 10 in MANO).
        J_regressor: Joint regressor, dense, shape (16, V).
        parents: Parent of each joint, root −1, shape (16,).
        weights: Skinning weights, shape (V, 16).
        faces: Triangles, shape (F, 3).
        posedirs: Pose blend shapes, shape (V, 3, 135), or None (not needed for kinematics).
        hands_components: PCA basis of hand poses, shape (K, 45), or None.
        hands_mean: Mean hand pose (axis-angle), shape (45,), or None.
        side: ``"right"`` or ``"left"`` (from the joints; see the module notes).
        source: The file.
    """

    v_template: np.ndarray
    shapedirs: np.ndarray
    J_regressor: np.ndarray
    parents: np.ndarray
    weights: np.ndarray
    faces: np.ndarray
    posedirs: np.ndarray | None = None
    hands_components: np.ndarray | None = None
    hands_mean: np.ndarray | None = None
    side: str = "right"
    source: str = ""

    @property
    def nvertices(self) -> int:
        """Number of vertices V."""
        return int(self.v_template.shape[0])


# --------------------------------------------------------------------------------------------------
# Reading a MANO pkl


def _check_shape(path: Path, key: str, array: np.ndarray, expected: tuple[int | None, ...]) -> None:
    ok = array.ndim == len(expected) and all(
        e is None or e == n for e, n in zip(expected, array.shape, strict=True)
    )
    if not ok:
        want = "(" + ", ".join("N" if e is None else str(e) for e in expected) + ")"
        raise FormatError(path, f"expected shape {want}, got {array.shape}", field=key)


def _parents_from_kintree(path: Path, kintree: np.ndarray) -> np.ndarray:
    _check_shape(path, "kintree_table", kintree, (2, 16))
    parents = np.full(16, -2, dtype=np.int64)
    for parent, child in kintree.astype(np.int64).T:
        if not 0 <= child < 16:
            raise FormatError(path, f"joint id {child} outside 0..15", field="kintree_table")
        parents[child] = -1 if parent < 0 or parent >= 2**31 else parent
    if tuple(parents) != MANO_PARENTS:
        raise FormatError(
            path, f"parents {parents.tolist()} differ from MANO's {list(MANO_PARENTS)}", field="kintree_table"
        )
    return parents


def joints_side(joints: npt.ArrayLike) -> str:
    """``"right"`` if the fingers point towards −x from the wrist (MANO right), else ``"left"``."""
    j = np.asarray(joints, dtype=float)
    return "right" if j[0, 0] > j[4, 0] else "left"


def read_mano_model(pkl_path: str | Path) -> MANOModel:
    """Read the arrays of a MANO model file (``MANO_RIGHT.pkl`` / ``MANO_LEFT.pkl``) without chumpy.

    The file is unpickled with :func:`~handsim.io.safe_pickle.load_restricted_pickle`: numpy arrays,
    ``chumpy.ch.Ch`` (only its array is kept) and ``scipy.sparse`` csc/csr matrices (rebuilt from their
    arrays) are the only objects it may create. Only :data:`MANO_ARRAYS` are read.

    Args:
        pkl_path: The MANO model file (Python 2 pickle, metres).

    Returns:
        The model's arrays; ``side`` from its mean-shape joints.

    Raises:
        InputFileError: The file does not exist.
        FormatError: A refused global, a missing entry, or an entry of the wrong shape (the message names
            the file and the entry).
    """
    path = Path(pkl_path)
    raw = load_restricted_pickle(path, allowed=MANO_PICKLE_GLOBALS)
    if not isinstance(raw, dict):
        raise FormatError(path, f"expected a pickled dict of MANO arrays, got {type(raw).__name__}")
    arrays: dict[str, np.ndarray] = {}
    for key in MANO_ARRAYS:
        if key not in raw or raw[key] is None:
            if key in _OPTIONAL:
                continue
            raise FormatError(path, f"missing entry; a MANO model needs {list(MANO_ARRAYS[:6])}", field=key)
        arrays[key] = mano_array(path, key, raw[key])
    v_template = arrays["v_template"].astype(float)
    _check_shape(path, "v_template", v_template, (None, 3))
    nv = v_template.shape[0]
    shapedirs = arrays["shapedirs"].astype(float)
    _check_shape(path, "shapedirs", shapedirs, (nv, 3, None))
    regressor = arrays["J_regressor"].astype(float)
    _check_shape(path, "J_regressor", regressor, (16, nv))
    weights = arrays["weights"].astype(float)
    _check_shape(path, "weights", weights, (nv, 16))
    faces = arrays["f"]
    _check_shape(path, "f", faces, (None, 3))
    if faces.dtype.kind == "f" or (faces.size and (faces.min() < 0 or faces.max() >= nv)):
        raise FormatError(path, f"face indices must be integers in 0..{nv - 1}", field="f")
    parents = _parents_from_kintree(path, arrays["kintree_table"])
    posedirs = arrays.get("posedirs")
    if posedirs is not None:
        posedirs = posedirs.astype(float)
        _check_shape(path, "posedirs", posedirs, (nv, 3, 135))
    components = arrays.get("hands_components")
    if components is not None:
        components = components.astype(float)
        _check_shape(path, "hands_components", components, (None, 45))
    mean = arrays.get("hands_mean")
    if mean is not None:
        mean = mean.astype(float).reshape(-1)
        _check_shape(path, "hands_mean", mean, (45,))
    for key, value in (("v_template", v_template), ("shapedirs", shapedirs), ("J_regressor", regressor)):
        if not np.all(np.isfinite(value)):
            raise FormatError(path, "contains non-finite values", field=key)
    return MANOModel(
        v_template=v_template,
        shapedirs=shapedirs,
        J_regressor=regressor,
        parents=parents,
        weights=weights,
        faces=faces.astype(np.int64),
        posedirs=posedirs,
        hands_components=components,
        hands_mean=mean,
        side=joints_side(regressor @ v_template),
        source=str(path),
    )


MANO_FILES: dict[str, str] = {"right": "MANO_RIGHT.pkl", "left": "MANO_LEFT.pkl"}
"""The model file of each hand, as MPI distributes them."""

MANO_DIR_ENV = "HANDSIM_MANO_DIR"
"""Environment variable naming the folder with the user's MANO model files."""

MANO_DOWNLOAD = "https://mano.is.tue.mpg.de/"


def find_mano_files(
    mano_dir: str | Path | None = None, sides: tuple[str, ...] = ("right", "left")
) -> dict[str, Path]:
    """The user's MANO model files: ``MANO_RIGHT.pkl`` and ``MANO_LEFT.pkl`` in one folder.

    Args:
        mano_dir: The folder; when None, the folder named by ``$HANDSIM_MANO_DIR``.
        sides: The hands needed.

    Returns:
        Side → path of its model file.

    Raises:
        InputFileError: No folder given and ``$HANDSIM_MANO_DIR`` unset, the folder missing, or a file
            missing. The message names the files needed, where they come from and where to put them.
    """
    for side in sides:
        check_side(side)
    needed = " and ".join(MANO_FILES[s] for s in sides)
    advice = (
        f"handsim needs the MANO hand model{'s' if len(sides) > 1 else ''} {needed} (MPI's MANO licence: "
        f"register and download them from {MANO_DOWNLOAD}); put them in one folder and pass it with "
        f"--mano-dir DIR (Python: mano_dir=DIR) or set {MANO_DIR_ENV}=DIR"
    )
    if mano_dir is None:
        env = os.environ.get(MANO_DIR_ENV, "")
        if not env:
            raise InputFileError(f"no MANO folder given and {MANO_DIR_ENV} is not set: {advice}")
        mano_dir = env
    folder = Path(mano_dir)
    if not folder.is_dir():
        raise InputFileError(f"{folder}: MANO folder not found: {advice}")
    missing = [MANO_FILES[s] for s in sides if not (folder / MANO_FILES[s]).is_file()]
    if missing:
        raise InputFileError(f"{folder}: {' and '.join(missing)} not found there: {advice}")
    return {side: folder / MANO_FILES[side] for side in sides}


# --------------------------------------------------------------------------------------------------
# Shape → joints


def padded_betas(model: MANOModel, betas: npt.ArrayLike | None) -> np.ndarray:
    """``betas`` padded with zeros to the model's S shape directions (zeros when None).

    Raises:
        ModelError: More than S values, or non-finite values.
    """
    nshape = model.shapedirs.shape[2]
    b = np.zeros(nshape) if betas is None else np.asarray(betas, dtype=float).reshape(-1)
    if len(b) > nshape or not np.all(np.isfinite(b)):
        raise ModelError(
            f"betas must be at most {nshape} finite values (the model's shape space), got {len(b)}"
        )
    return np.pad(b, (0, nshape - len(b)))


def mano_vertices(model: MANOModel, betas: npt.ArrayLike | None = None) -> np.ndarray:
    """Shaped rest vertices ``v_template + shapedirs · β``, metres, shape (V, 3); β padded with zeros."""
    return model.v_template + model.shapedirs @ padded_betas(model, betas)


def mano_joints(model: MANOModel, betas: npt.ArrayLike | None = None) -> np.ndarray:
    """Rest joints ``J_regressor · (v_template + shapedirs · β)``, metres, shape (16, 3).

    Args:
        model: The MANO model.
        betas: Shape coefficients (up to S values, padded with zeros); the mean shape when None.

    Returns:
        Joint positions in MANO order.

    Raises:
        ModelError: More betas than the model has shape directions, or non-finite betas.
    """
    return model.J_regressor @ mano_vertices(model, betas)


def mano_mean_joints(side: str = "right", path: str | Path | None = None) -> np.ndarray:
    """The bundled mean-shape joints (betas = 0), metres, MANO order, shape (16, 3).

    The left hand is the right table mirrored in x (MANO's left model is the mirror image of the right).

    Args:
        side: ``"right"`` or ``"left"``.
        path: Another table in the same JSON layout; the bundled one by default.

    Returns:
        Joint positions.

    Raises:
        FormatError: The table's joint names, parents or positions are not MANO's 16.
        SkeletonError: ``side`` is neither ``"right"`` nor ``"left"``.
    """
    check_side(side)
    p = Path(path) if path is not None else MEAN_JOINTS_FILE
    table = json.loads(p.read_text(encoding="utf-8"))
    if tuple(table.get("joint_names", ())) != MANO_JOINT_NAMES:
        raise FormatError(p, f"joint names must be {list(MANO_JOINT_NAMES)}", field="joint_names")
    if tuple(table.get("parents", ())) != MANO_PARENTS:
        raise FormatError(p, f"parents must be {list(MANO_PARENTS)}", field="parents")
    joints = np.asarray(table.get("rest_joint_positions"), dtype=float)
    if joints.shape != (16, 3) or not np.all(np.isfinite(joints)):
        raise FormatError(
            p, f"expected 16 × 3 finite positions, got shape {joints.shape}", field="rest_joint_positions"
        )
    return joints * np.array([-1.0, 1.0, 1.0]) if side == "left" else joints


def check_side(side: str) -> None:
    """Raise :class:`SkeletonError` unless ``side`` is ``"right"`` or ``"left"``."""
    if side not in ("right", "left"):
        raise SkeletonError(f"side must be 'right' or 'left', got {side!r}")
