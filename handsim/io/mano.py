"""MANO hand model: reading ``MANO_*.pkl``, shaped joints, and poses as hinge angles plus a root pose.

The hinge skeleton these angles drive is built by :mod:`handsim.builders.mano_hand`.

Conventions (pinned by ``tests/test_mano.py``; details and measured numbers in ``docs/mano.md``):

* **Frame and units.** Everything is in the MANO model frame, metres. MANO's 16 joints are ordered wrist,
  index1-3, middle1-3, pinky1-3, ring1-3, thumb1-3; the rest pose is the flat hand (all rotations zero)
  and every MANO joint frame is aligned with the model frame at rest.
* **Joints.** ``J = J_regressor · (v_template + shapedirs · β)`` (the pose blend shapes move vertices,
  never joints).
* **Hinges.** Each of the 15 finger joints is a ball joint of MANO, here three hinges about the model
  axes z, y, x, outermost first: ``R = Rz(a) · Ry(b) · Rx(c)`` (DoFs ``<joint>_z``, ``<joint>_y``,
  ``<joint>_x``). Any 3-axis order represents every rotation; Z·Y·X puts the singular middle axis on y, the
  palm normal, where finger rotations (ab/adduction) stay far from the ±90° gimbal lock, while the
  large rotations (finger flexion about z, the thumb's about x) sit on the outer axes. The conversion
  from axis-angle is exact up to rounding (residual reported in :attr:`Trajectory.notes`).
* **Angles** come out in the Euler ranges: z and x in [−π, π], y in [−π/2, π/2] (the hinge limits).
* **Root.** MANO rotates the whole hand by the global rotation ``rot`` about the wrist joint J0 (not the
  origin) and then translates by ``trans``, so the wrist body's world pose is position ``J0 + trans``,
  orientation ``exp(rot)`` (quaternion w, x, y, z) — what :attr:`Trajectory.root_pose` holds.
* **Mean pose.** With ``flat_hand_mean=False`` (MANO's and smplx's default, and what ARCTIC's code uses)
  the stored pose is relative to ``hands_mean``: full pose = pose + hands_mean.
* **Left hands.** MANO's left model is the mirror image (x → −x) of the right one; a left-hand pose does
  not drive a right hand (error), and the side is read from the joints (fingers towards −x from the wrist
  on a right hand, towards +x on a left one).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from handsim.assets import ASSETS_DIR
from handsim.datatypes.rotations import (
    axis_angle_to_matrix,
    axis_angle_to_quat,
    matrix_to_zyx,
    rotation_error,
    zyx_to_matrix,
)
from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.errors import FormatError, InputFileError, ModelError, SkeletonError, TrajectoryError
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


@dataclass(frozen=True)
class MANOSequence:
    """MANO parameters of one hand over time.

    Attributes:
        rot: Global rotation, axis-angle in radians, about the wrist joint J0, shape (N, 3).
        pose: Finger pose, shape (N, 45) axis-angle in radians (15 joints in MANO order, x y z each), or
            (N, K) PCA coefficients.
        trans: Global translation in metres, applied after ``rot``, shape (N, 3).
        shape: Shape coefficients β, shape (10,).
        fitting_err: Per-frame fitting error as stored (ARCTIC gives no unit), shape (N,), or None.
        side: ``"right"`` or ``"left"``.
        source: The file it was read from.
        sha256: SHA-256 of that file ("" when not read from a file).
        notes: Decisions made while reading.
    """

    rot: np.ndarray
    pose: np.ndarray
    trans: np.ndarray
    shape: np.ndarray
    fitting_err: np.ndarray | None = None
    side: str = "right"
    source: str = ""
    sha256: str = ""
    notes: tuple[str, ...] = ()

    @property
    def nframes(self) -> int:
        """Number of frames N."""
        return int(self.rot.shape[0])


# --------------------------------------------------------------------------------------------------
# Reading a MANO pkl


class ChumpyArray:
    """Inert stand-in for ``chumpy.ch.Ch`` while unpickling: keeps only the value array ``x``."""

    x: Any = None

    def __setstate__(self, state: Any) -> None:
        if isinstance(state, tuple) and len(state) == 2:  # (dict state, slot state)
            state = state[0]
        self.x = state.get("x") if isinstance(state, dict) else None


class SparseMatrixStub:
    """Inert stand-in for a pickled ``scipy.sparse`` csc/csr matrix: keeps its arrays, rebuilt densely."""

    layout = "csc"
    state: Any = None

    def __setstate__(self, state: Any) -> None:
        self.state = state

    def to_dense(self) -> np.ndarray:
        """The matrix as a dense float array, rebuilt by :mod:`scipy.sparse` from the pickled arrays.

        The arrays are fully checked (``check_format(full_check=True)``: index pointers, index range)
        before scipy's native code densifies them.

        Raises:
            ValueError: The state lacks ``data``/``indices``/``indptr``/shape or they are inconsistent.
        """
        s = self.state if isinstance(self.state, dict) else {}
        shape = s.get("_shape", s.get("shape"))
        data, indices, indptr = (np.asarray(s.get(k)) for k in ("data", "indices", "indptr"))
        if shape is None or data.ndim != 1 or indices.shape != data.shape or indptr.ndim != 1:
            raise ValueError(f"sparse matrix state has keys {sorted(s)}; need data, indices, indptr, _shape")
        if indices.dtype.kind not in "iu" or indptr.dtype.kind not in "iu":
            raise ValueError(
                f"sparse indices and indptr must be integers, got {indices.dtype} and {indptr.dtype}"
            )
        nrows, ncols = (int(n) for n in shape)
        # lazy: only a MANO .pkl needs scipy.sparse; the ARCTIC readers beside this module are light
        import scipy.sparse

        build = scipy.sparse.csc_array if self.layout == "csc" else scipy.sparse.csr_array
        try:
            matrix = build((data.astype(float), indices, indptr), shape=(nrows, ncols))
            matrix.check_format(full_check=True)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"inconsistent {self.layout} arrays for shape {(nrows, ncols)}: {exc}") from None
        return matrix.toarray()


class CscStub(SparseMatrixStub):
    """Stand-in for ``scipy.sparse.csc_matrix``."""

    layout = "csc"


class CsrStub(SparseMatrixStub):
    """Stand-in for ``scipy.sparse.csr_matrix``."""

    layout = "csr"


MANO_PICKLE_GLOBALS: dict[tuple[str, str], type] = {
    ("chumpy.ch", "Ch"): ChumpyArray,
    ("chumpy", "Ch"): ChumpyArray,
    **{(m, "csc_matrix"): CscStub for m in ("scipy.sparse.csc", "scipy.sparse._csc")},
    **{(m, "csr_matrix"): CsrStub for m in ("scipy.sparse.csr", "scipy.sparse._csr")},
}
"""Globals a MANO pkl may name beyond numpy, each mapped to an inert stand-in (chumpy is never imported)."""


def _mano_array(path: Path, key: str, value: Any) -> np.ndarray:
    if isinstance(value, ChumpyArray):
        value = value.x
    elif isinstance(value, SparseMatrixStub):
        try:
            value = value.to_dense()
        except ValueError as exc:
            raise FormatError(path, str(exc), field=key) from None
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "biuf":
        raise FormatError(path, f"expected a numeric array, got {type(value).__name__}", field=key)
    return value


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
        arrays[key] = _mano_array(path, key, raw[key])
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


# --------------------------------------------------------------------------------------------------
# Poses → trajectory


def _skeleton_side(skeleton: Skeleton) -> str:
    side = skeleton.name.removeprefix("mano_")
    expected = tuple(f"{j}_{ax}" for j in MANO_JOINT_NAMES[1:] for ax, _ in HINGE_AXES)
    if side not in ("right", "left") or not set(expected) <= set(skeleton.dof_names):
        raise TrajectoryError(
            f"skeleton {skeleton.name!r} is not a MANO hand; build it with mano_skeleton or build_mano_hand"
        )
    return side


def full_mano_pose(
    seq: MANOSequence,
    *,
    flat_hand_mean: bool = False,
    hands_mean: npt.ArrayLike | None = None,
    hands_components: npt.ArrayLike | None = None,
) -> np.ndarray:
    """The absolute axis-angle finger pose, shape (N, 45): PCA expanded, ``hands_mean`` added if needed.

    Args:
        seq: The sequence (pose (N, 45) axis-angle, or (N, K) PCA coefficients).
        flat_hand_mean: True if ``seq.pose`` is absolute (zero = flat hand); False if it is relative to
            MANO's mean pose (full = pose + hands_mean), as in ARCTIC.
        hands_mean: MANO's mean pose (``MANOModel.hands_mean``), needed when ``flat_hand_mean`` is False.
        hands_components: MANO's PCA basis (``MANOModel.hands_components``), needed for PCA poses.

    Raises:
        TrajectoryError: PCA coefficients without components, more coefficients than components, or a
            relative pose without ``hands_mean``.
    """
    pose = np.asarray(seq.pose, dtype=float)
    k = pose.shape[1] if pose.ndim == 2 else -1
    if pose.ndim != 2 or pose.shape[0] != seq.nframes:
        raise TrajectoryError(f"pose must have shape ({seq.nframes}, 45), got {pose.shape}")
    if k != 45:
        if hands_components is None:
            raise TrajectoryError(
                f"pose has {k} values per frame: PCA coefficients need hands_components (MANO's PCA basis, "
                "read_mano_model(pkl).hands_components); axis-angle poses have 45"
            )
        comps = np.asarray(hands_components, dtype=float)
        if comps.ndim != 2 or comps.shape[1] != 45 or comps.shape[0] < k:
            raise TrajectoryError(
                f"{k} PCA coefficients need at least {k} components of 45, got {comps.shape}"
            )
        pose = pose @ comps[:k]
    if not flat_hand_mean:
        if hands_mean is None:
            raise TrajectoryError(
                "flat_hand_mean=False: the pose is relative to MANO's mean hand pose (as in ARCTIC), so "
                "hands_mean is needed (read_mano_model(pkl).hands_mean); pass flat_hand_mean=True if the "
                "pose is absolute"
            )
        mean = np.asarray(hands_mean, dtype=float).reshape(-1)
        if mean.shape != (45,):
            raise TrajectoryError(f"hands_mean must have 45 values, got {mean.shape}")
        pose = pose + mean
    return pose


def mano_pose_to_trajectory(
    seq: MANOSequence,
    skeleton: Skeleton,
    fps: float = 30.0,
    flat_hand_mean: bool = False,
    hands_mean: npt.ArrayLike | None = None,
    *,
    hands_components: npt.ArrayLike | None = None,
    objects: dict[str, ObjectTrack] | None = None,
) -> Trajectory:
    """Convert MANO parameters to hinge-angle targets and a wrist root pose for a MANO skeleton.

    Each joint's axis-angle ``ω`` becomes the Z·Y·X angles with ``Rz(a) Ry(b) Rx(c) = exp(ω)``; the largest
    rotation error of that decomposition is reported in ``notes``. The root pose is the wrist body's world
    pose: position ``J0 + trans`` (MANO rotates about the wrist J0 of the skeleton's shape, then
    translates), orientation ``exp(rot)`` as a quaternion (w, x, y, z).

    Args:
        seq: MANO parameters (build ``skeleton`` with the same betas: J0 depends on them).
        skeleton: A MANO skeleton of the same side (:func:`mano_skeleton`).
        fps: Frame rate in Hz; sample ``i`` is at ``i / fps`` seconds.
        flat_hand_mean: See :func:`full_mano_pose`. ARCTIC's poses are relative (False).
        hands_mean: MANO's mean pose, needed when ``flat_hand_mean`` is False.
        hands_components: MANO's PCA basis, needed when ``seq.pose`` holds PCA coefficients.
        objects: Object tracks of the same frames to carry in the trajectory.

    Returns:
        The trajectory: columns = ``skeleton.dof_names``, radians, all samples valid.

    Raises:
        TrajectoryError: A side mismatch (e.g. a left-hand sequence for a right hand), a skeleton that is
            not MANO's, a non-positive ``fps``, or the pose errors of :func:`full_mano_pose`.
    """
    side = _skeleton_side(skeleton)
    if seq.side != side:
        raise TrajectoryError(
            f"a {seq.side}-hand MANO sequence cannot drive a {side} MANO hand: MANO's left model is the "
            f"mirror image of the right one; build the hand with side={seq.side!r} "
            f"(and MANO_{seq.side.upper()}.pkl)"
        )
    if not fps > 0:
        raise TrajectoryError(f"fps must be positive, got {fps}")
    n = seq.nframes
    for name, arr in (("rot", seq.rot), ("trans", seq.trans)):
        if np.shape(arr) != (n, 3):
            raise TrajectoryError(f"{name} must have shape ({n}, 3), got {np.shape(arr)}")
    pose = full_mano_pose(
        seq, flat_hand_mean=flat_hand_mean, hands_mean=hands_mean, hands_components=hands_components
    ).reshape(n, 15, 3)
    rotations = axis_angle_to_matrix(pose)
    angles = matrix_to_zyx(rotations)  # (n, 15, 3): z, y, x
    residual = float(rotation_error(zyx_to_matrix(angles), rotations).max()) if n else 0.0
    columns = {
        f"{j}_{ax}": angles[:, k, a]
        for k, j in enumerate(MANO_JOINT_NAMES[1:])
        for a, (ax, _) in enumerate(HINGE_AXES)
    }
    targets = np.zeros((n, skeleton.ndof))
    for c, name in enumerate(skeleton.dof_names):
        targets[:, c] = columns.get(name, 0.0)
    wrist = skeleton.joints[0].position
    root_pose = np.concatenate(
        [wrist + np.asarray(seq.trans, dtype=float), axis_angle_to_quat(seq.rot)], axis=1
    )
    convention = (
        "absolute (flat_hand_mean=True)"
        if flat_hand_mean
        else "relative to hands_mean (flat_hand_mean=False)"
    )
    notes = (
        *seq.notes,
        f"MANO pose {convention}",
        f"Z·Y·X hinge decomposition: max rotation residual {residual:.1e} rad over {n * 15} joint rotations",
        "root pose = wrist body: position J0 + trans (MANO rotates about J0), quaternion of rot",
    )
    return Trajectory(
        times=np.arange(n) / float(fps),
        dof_names=skeleton.dof_names,
        targets=targets,
        valid=np.ones((n, skeleton.ndof), dtype=bool),
        root_pose=root_pose,
        objects=dict(objects or {}),
        source=seq.source,
        sha256=seq.sha256,
        notes=notes,
    )
