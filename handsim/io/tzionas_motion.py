"""Tzionas/Ballan ``.MOTION`` files as a hand `Trajectory` and object pose tracks.

Rows and times. ``.MOTION`` row 0 is the rigging (rest) pose. Aligned frame k (k = 0 … TotalAlligned − 1)
uses row k + MotionnOffset and shows video frame k + VideoooOffset, both offsets from the sequence's
``Configs/NN/INDEX_BOUNDS.txt`` (found from ``Models/NN/`` by default). The files give no frame rate:
times are k / fps with fps = 30 Hz by default, the frame rate of the Kinect-class 640 × 480 RGB-D sensor
the dataset was captured with (``Calibration/Cameras.txt``: f = 525 px, c = (319.5, 239.5)).

Hand (:func:`fit_tzionas_motion`). ``M_b,k = (R_b,k, T_b,k)`` is bone b's world transform at row k, ``F_b``
its rest frame (row 0, as in :func:`~handsim.io.tzionas.read_tzionas_skeleton`):

* Root pose = the world pose of the root body of :func:`handsim.builders.build_hand`, which sits at the
  root bone's rest origin with the root bone's rest frame; so the root pose of frame k is ``M_root,k``
  itself: position ``T_root,k`` (m) and the quaternion (w, x, y, z) of ``R_root,k``. A mocap (or free)
  root body set to it puts the hand where the recording has it; at row 0 it equals the spec's root body
  ``pos``/``quat``. Quaternion signs are kept continuous over time, the first with w ≥ 0.
* DoF angles: the rotation of bone b relative to its parent p, in b's rest frame,
  ``L_b,k = F_bᵀ F_p R_p,kᵀ R_b,k`` (= ``F_bᵀ A_p,k⁻¹ A_b,k F_b`` with ``A = M_k M_0⁻¹``), is exactly what
  :meth:`~handsim.datatypes.skeleton.Skeleton.forward_kinematics` composes (``R_b = R_p F_pᵀ F_b L_b``). It
  is split
  into the bone's DoF chain ``Rot(a_1, q_1) ⋯ Rot(a_n, q_n)`` (the ``.LIMITS`` axes, outermost first) by
  :func:`fit_dof_angles`, which minimises the angle between ``L`` and its reconstruction.
* Residuals (:class:`MotionFit`): per bone and frame, that angle; per skeleton joint and frame, the distance
  between the joint placed by forward kinematics of the fitted angles + root pose and the recording
  (bone origins ``T_b,k``; a joint not in the file, e.g. a fingertip, rigidly attached to its parent's
  recorded frame).

Objects (:func:`fit_tzionas_object_motion`). The object frame is the mesh frame (the rigging pose's world
frame, see :mod:`handsim.io.tzionas_objects`), so the pose of frame k is ``M_root,k · M_root,0⁻¹``; an
articulated object's angle is its second bone's single DoF, fitted as above (about the hinge axis of
:func:`~handsim.io.tzionas_objects.read_tzionas_object`, through the second bone's joint).

Sequence 20 (``tests/test_io_tzionas_motion.py``): the 3-DoF and 1-DoF bones are reproduced to the files'
precision (≤ 1.5e-6 rad); the two 2-DoF metacarpals turn a little about their missing axis (RFing.1_Hand
0.09°, RFing.4_Hand 1.8°), so forward kinematics (numpy or MuJoCo) puts every bone origin within 0.16 mm
and every fingertip within 0.23 mm of the recording.

Every rotation row is checked: ``max |RᵀR − I| > 1e-3`` or ``det R < 0`` is an error naming bone, row and
line; smaller deviations (the files print 6 digits) are removed by SVD (nearest rotation) and noted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import numpy.typing as npt

from handsim.datatypes.rotations import (
    matrix_to_quat,
    quat_about,
    quat_conjugate,
    quat_multiply,
    quat_to_axis_angle,
    rotation_about_axis,
)
from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.datatypes.trajectory_ops import join_hands, with_limit_note
from handsim.errors import FormatError, InputFileError, TrajectoryError
from handsim.io._text import numbered_lines, parse_int, read_bytes, read_text, sha256_of
from handsim.io.tzionas import SkelBone, read_motion, read_skel, read_tzionas_skeleton

DEFAULT_FPS = 30.0
"""Frame rate assumed when none is given, Hz: the dataset's Kinect-class RGB-D sensor streams at 30 Hz."""
ROTATION_ERROR_TOL = 1e-3
"""Largest ``max |RᵀR − I|`` of a ``.MOTION`` rotation that is repaired; beyond it the row is an error."""
INDEX_BOUNDS_KEYS = ("TotalAlligned", "MotionnOffset", "VideoooOffset")
"""The keys of ``INDEX_BOUNDS.txt``, in the dataset's spelling."""
_GRID = 180  # samples of the outermost angle of a 3-DoF bone (2° apart)
_GOLDEN_STEPS = 24  # brackets the outermost angle to ~1e-6 rad
_NEWTON_STEPS = 3  # Gauss-Newton polish: exact chains are then recovered to ~1e-15 rad
_TIE = 1e-9  # two 3-DoF solutions whose fit (cos of half the residual) differs less than this are equal


# --------------------------------------------------------------------------------------------------
# Sequence configuration files


@dataclass(frozen=True)
class IndexBounds:
    """The content of a sequence's ``INDEX_BOUNDS.txt``.

    Attributes:
        total_aligned: Number of aligned frames.
        motion_offset: ``.MOTION`` row of aligned frame 0 (row 0 is the rigging pose).
        video_offset: Video frame of aligned frame 0.
        source: The file, or "" when the values are defaults.
        lines: 1-based lines of the three values (0 for defaults).
    """

    total_aligned: int
    motion_offset: int
    video_offset: int
    source: str = ""
    lines: tuple[int, int, int] = (0, 0, 0)


def read_index_bounds(path: str | Path) -> IndexBounds:
    """Read a sequence's ``INDEX_BOUNDS.txt``: ``TotalAlligned N``, ``MotionnOffset m``, ``VideoooOffset v``.

    Args:
        path: The file.

    Returns:
        The three values (TotalAlligned ≥ 1, offsets ≥ 0).

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: A line is not one of the three keys and an integer, a key is repeated or missing.
    """
    p = Path(path)
    values: dict[str, tuple[int, int]] = {}
    lines = numbered_lines(read_text(p))
    for ln, text in lines:
        tokens = text.split()
        if len(tokens) != 2 or tokens[0] not in INDEX_BOUNDS_KEYS:
            msg = f"expected '<key> <integer>' with key one of {list(INDEX_BOUNDS_KEYS)}, got {text!r}"
            raise FormatError(p, msg, line=ln, field="key")
        key = tokens[0]
        if key in values:
            msg = f"second {key!r} (first at line {values[key][1]})"
            raise FormatError(p, msg, line=ln, field=key)
        values[key] = (parse_int(tokens[1], p, ln, key, 1 if key == "TotalAlligned" else 0), ln)
    missing = [k for k in INDEX_BOUNDS_KEYS if k not in values]
    if missing:
        msg = f"no {missing[0]!r} line; expected the keys {list(INDEX_BOUNDS_KEYS)}, one per line"
        raise FormatError(p, msg, line=lines[-1][0] if lines else 1, field=missing[0])
    (total, l1), (motion, l2), (video, l3) = (values[k] for k in INDEX_BOUNDS_KEYS)
    return IndexBounds(total, motion, video, str(p), (l1, l2, l3))


def read_models_info(path: str | Path) -> tuple[tuple[str, int], ...]:
    """Read a sequence's ``MODELS_INFO.txt``: the model count, then one model name per line.

    Args:
        path: The file.

    Returns:
        The model names (e.g. ``Model_Hand_R``) with their 1-based lines.

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: The count is not an integer ≥ 1 or does not match the names that follow.
    """
    p = Path(path)
    lines = numbered_lines(read_text(p))
    if not lines:
        raise FormatError(p, "empty file; expected the number of models", line=1, field="model count")
    count = parse_int(lines[0][1], p, lines[0][0], "model count", 1)
    names = lines[1:]
    if len(names) != count:
        msg = f"{len(names)} model names follow, expected {count} (the count on line {lines[0][0]})"
        raise FormatError(p, msg, line=(names[-1] if names else lines[0])[0], field="model names")
    return tuple((name, ln) for ln, name in names)


def config_dir_of(models_dir: str | Path) -> Path:
    """The ``Configs/NN`` folder that belongs to ``Models/NN`` (the dataset's layout)."""
    m = Path(models_dir)
    return m.parent.parent / "Configs" / m.name


# --------------------------------------------------------------------------------------------------
# Rotation decomposition


def _wrap(angles: np.ndarray) -> np.ndarray:
    return np.pi - np.mod(np.pi - angles, 2.0 * np.pi)  # (-π, π]


def _pair_matrix(q: np.ndarray, a1: np.ndarray, a2: np.ndarray) -> np.ndarray:
    """M with ⟨q, r(a1, x) r(a2, y)⟩ = [cos x/2, sin x/2] M [cos y/2, sin y/2]ᵀ, shape (…, 2, 2)."""
    w, v = q[..., 0], q[..., 1:]
    m11 = -w * float(a1 @ a2) + v @ np.cross(a1, a2)
    return np.stack([np.stack([w, v @ a2], -1), np.stack([v @ a1, m11], -1)], -2)


def _largest_singular(m: np.ndarray) -> np.ndarray:
    """Largest singular value of 2 × 2 matrices (closed form)."""
    s = np.sum(m * m, axis=(-2, -1))
    det = m[..., 0, 0] * m[..., 1, 1] - m[..., 0, 1] * m[..., 1, 0]
    return np.sqrt(0.5 * (s + np.sqrt(np.maximum(s * s - 4.0 * det * det, 0.0))))


def _fit_one(q: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The angle about ``a`` closest to ``q``: its twist about ``a``."""
    return _wrap(2.0 * np.arctan2(q[..., 1:] @ a, q[..., 0]))


def _fit_two(q: np.ndarray, a1: np.ndarray, a2: np.ndarray) -> np.ndarray:
    """Angles (…, 2) maximising |⟨q, r(a1, x) r(a2, y)⟩|: the largest singular pair of the pair matrix."""
    u, _, vt = np.linalg.svd(_pair_matrix(q, a1, a2))
    x = 2.0 * np.arctan2(u[..., 1, 0], u[..., 0, 0])
    y = 2.0 * np.arctan2(vt[..., 0, 1], vt[..., 0, 0])
    return _wrap(np.stack([x, y], axis=-1))


def _profile(q: np.ndarray, axes: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Best fit (|⟨q, fit⟩|) of a 3-DoF chain with its outermost angle fixed at ``x``."""
    rest = quat_multiply(quat_conjugate(quat_about(axes[0], x)), q)
    return _largest_singular(_pair_matrix(rest, axes[1], axes[2]))


def _golden_max(q: np.ndarray, axes: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Golden-section search for the maximum of :func:`_profile` in [lo, hi], all frames at once."""
    ratio = 0.5 * (math.sqrt(5.0) - 1.0)
    x1, x2 = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
    f1, f2 = _profile(q, axes, x1), _profile(q, axes, x2)
    for _ in range(_GOLDEN_STEPS):
        left = f1 >= f2  # the maximum lies in [lo, x2]
        lo, hi = np.where(left, lo, x1), np.where(left, x2, hi)
        new = np.where(left, hi - ratio * (hi - lo), lo + ratio * (hi - lo))
        f_new = _profile(q, axes, new)
        x1, x2 = np.where(left, new, x2), np.where(left, x1, new)
        f1, f2 = np.where(left, f_new, f2), np.where(left, f1, f_new)
    return 0.5 * (lo + hi)


def _fit_three(q: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Angles (T, 3): search the outermost angle, the other two in closed form; smallest exact solution."""
    step = 2.0 * np.pi / _GRID
    grid = -np.pi + step * np.arange(_GRID)
    values = _profile(q[:, None, :], axes, grid[None, :])  # (T, G)
    peaks = (values >= np.roll(values, 1, axis=1)) & (values >= np.roll(values, -1, axis=1))
    ranked = np.argsort(np.where(peaks, -values, np.inf), axis=1)[:, :2]
    candidates, fits = [], []
    for c in range(2):  # the two best peaks: a 3-DoF chain generally has two exact solutions
        x = _golden_max(q, axes, grid[ranked[:, c]] - step, grid[ranked[:, c]] + step)
        inner = _fit_two(quat_multiply(quat_conjugate(quat_about(axes[0], x)), q), axes[1], axes[2])
        candidates.append(np.concatenate([_wrap(x)[:, None], inner], axis=1))
        fits.append(_profile(q, axes, x))
    smaller = np.sum(candidates[1] ** 2, axis=1) < np.sum(candidates[0] ** 2, axis=1)
    second = (fits[1] >= np.maximum(fits[0], fits[1]) - _TIE) & (smaller | (fits[1] > fits[0] + _TIE))
    angles = np.where(second[:, None], candidates[1], candidates[0])
    for _ in range(_NEWTON_STEPS):
        angles = _newton_step(q, axes, angles)
    return angles


def _chain_quats(axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    out = np.tile([1.0, 0.0, 0.0, 0.0], (len(angles), 1))
    for i, axis in enumerate(axes):
        out = quat_multiply(out, quat_about(axis, angles[:, i]))
    return out


def _residual(q: np.ndarray, axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Rotation vector (T, 3) taking the chain to ``q``, in the chain's end frame."""
    return quat_to_axis_angle(quat_multiply(quat_conjugate(_chain_quats(axes, angles)), q))


def _newton_step(q: np.ndarray, axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """One Gauss-Newton step on the residual rotation, kept only where it lowers the residual."""
    error = _residual(q, axes, angles)
    jacobian = np.empty((len(angles), 3, len(axes)))
    for i, axis in enumerate(axes):  # d(chain)/d(q_i) in the end frame: a_i turned back by the inner DoFs
        inner = np.tile(np.eye(3), (len(angles), 1, 1))
        for j in range(i + 1, len(axes)):
            inner = inner @ rotation_about_axis(axes[j], angles[:, j])
        jacobian[:, :, i] = np.einsum("kji,j->ki", inner, axis)
    step = np.einsum("kij,kj->ki", np.linalg.pinv(jacobian), error)
    moved = _wrap(angles + step)
    better = np.linalg.norm(_residual(q, axes, moved), axis=1) < np.linalg.norm(error, axis=1)
    return np.where(better[:, None], moved, angles)


def fit_dof_angles(rotations: npt.ArrayLike, axes: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Split rotations into a chain of rotations about fixed axes, ``R ≈ Rot(a_1, q_1) ⋯ Rot(a_n, q_n)``.

    The angles minimise the angle between ``R`` and the chain. One axis: the twist of ``R`` about it
    (closed form). Two axes: the largest singular pair of a 2 × 2 matrix (closed form). Three axes: a
    search over ``q_1`` (2° grid, then golden section) with the other two in closed form, polished by
    Gauss-Newton steps; where two exact solutions exist, the one with the smaller ``Σ q²`` is returned.

    Args:
        rotations: Rotation matrices, shape (T, 3, 3).
        axes: Unit axes, outermost first, shape (n, 3) with n ≤ 3.

    Returns:
        Angles in radians in (−π, π], shape (T, n), and the residual angle between each rotation and its
        reconstruction, radians, shape (T,).

    Raises:
        ValueError: More than 3 axes, an axis that is not a unit vector, or wrongly shaped input.
    """
    r = np.asarray(rotations, dtype=float)
    a = np.asarray(axes, dtype=float).reshape(-1, 3)
    if r.ndim != 3 or r.shape[1:] != (3, 3):
        raise ValueError(f"rotations must have shape (T, 3, 3), got {r.shape}")
    if len(a) > 3:
        raise ValueError(f"at most 3 axes can be fitted, got {len(a)}")
    if len(a) and np.abs(np.linalg.norm(a, axis=1) - 1.0).max() > 1e-6:
        raise ValueError(f"axes must be unit vectors, got norms {np.linalg.norm(a, axis=1)}")
    q = matrix_to_quat(r)
    if len(a) == 0:
        angles = np.zeros((len(r), 0))
    elif len(a) == 1:
        angles = _fit_one(q, a[0])[:, None]
    elif len(a) == 2:
        angles = _fit_two(q, a[0], a[1])
    else:
        angles = _fit_three(q, a)
    return angles, np.linalg.norm(_residual(q, a, angles), axis=1)


# --------------------------------------------------------------------------------------------------
# Reading and checking a .MOTION file


@dataclass(frozen=True)
class _Recording:
    """A checked ``.MOTION``: orthonormal rotations (z, 3, 3) and origins (z, 3) in metres per bone."""

    path: Path
    sha256: str
    rotations: dict[str, np.ndarray]
    origins: dict[str, np.ndarray]
    notes: tuple[str, ...]


def _sibling(path: Path, ext: str) -> Path:
    upper, lower = path.with_suffix("." + ext.upper()), path.with_suffix("." + ext.lower())
    first, second = (lower, upper) if path.suffix.islower() else (upper, lower)
    return second if not first.is_file() and second.is_file() else first


def _row_line(path: Path, bone: str, row: int) -> int:
    """1-based line of row ``row`` of ``bone``'s block (the file is known to be well formed)."""
    lines = numbered_lines(read_text(path))
    start = next(i for i, (_, s) in enumerate(lines) if s == bone.strip())
    return lines[start + 1 + row][0]


def _read_recording(skel: Path, frames: int, bones: list[SkelBone]) -> _Recording:
    motion = _sibling(skel, "MOTION")
    if not motion.exists():
        raise InputFileError(f"{motion}: file not found; a motion needs the .MOTION beside the .SKEL {skel}")
    data = read_bytes(motion)
    blocks = read_motion(motion, [b.name for b in bones], frames)
    for b in bones:
        if b.name not in blocks:
            msg = f"no block for bone {b.name!r} ({skel}:{b.line}); expected one block per .SKEL bone"
            raise FormatError(motion, msg, field="bone name")
    rotations, origins, worst = {}, {}, 0.0
    for name, (r, t) in blocks.items():
        deviation = np.abs(np.einsum("kji,kjl->kil", r, r) - np.eye(3)).max(axis=(1, 2))
        det = np.linalg.det(r)
        bad = np.flatnonzero((deviation > ROTATION_ERROR_TOL) | ~np.isfinite(deviation) | (det <= 0))
        if len(bad):
            k = int(bad[0])
            what = (
                f"det R = {det[k]:.6g}, a reflection"
                if deviation[k] <= ROTATION_ERROR_TOL
                else f"max |RᵀR − I| = {deviation[k]:.3g} > {ROTATION_ERROR_TOL:g}"
            )
            msg = f"bone {name!r} row {k}: {what}; expected a rotation matrix (R row-major, then T)"
            raise FormatError(motion, msg, line=_row_line(motion, name, k), field="R")
        u, _, vt = np.linalg.svd(r)
        rotations[name], origins[name] = u @ vt, t
        worst = max(worst, float(deviation.max()))
    note = (
        f"{motion.name}: every R re-orthonormalised by SVD (max |RᵀR − I| {worst:.2g} ≤ "
        f"{ROTATION_ERROR_TOL:g}, the file's printing precision)"
    )
    return _Recording(motion, sha256_of(data), rotations, origins, (note,) if worst > 1e-12 else ())


def _bounds(
    skel: Path, frames: int, index_bounds: str | Path | None, motion: str
) -> tuple[IndexBounds, list[str]]:
    """INDEX_BOUNDS given or found from ``Models/NN``; defaults (all rows after the rigging pose) else."""
    path = Path(index_bounds) if index_bounds is not None else config_dir_of(skel.parent) / "INDEX_BOUNDS.txt"
    if index_bounds is None and not path.is_file():
        note = f"no {path}: aligned frame k = MOTION row k + 1 for every row after the rigging pose"
        return IndexBounds(frames - 1, 1, 0), [note]
    bounds = read_index_bounds(path)
    needed = bounds.total_aligned + bounds.motion_offset
    if needed > frames:
        msg = (
            f"TotalAlligned {bounds.total_aligned} + MotionnOffset {bounds.motion_offset} = {needed} rows "
            f"needed, but {motion} has {frames} rows per bone (the .SKEL frame "
            f"count); expected TotalAlligned + MotionnOffset ≤ {frames}"
        )
        raise FormatError(path, msg, line=bounds.lines[0], field="TotalAlligned")
    notes = []
    if bounds.motion_offset == 0:
        notes.append(f"{path}: MotionnOffset 0 makes aligned frame 0 the rigging pose (the dataset uses 1)")
    return bounds, notes


# --------------------------------------------------------------------------------------------------
# Fitting


@dataclass(frozen=True)
class MotionFit:
    """How well the skeleton's DoFs and root pose reproduce a ``.MOTION`` recording.

    Attributes:
        bones: The non-root bones whose rotation relative to their parent was fitted, skeleton order.
        rotation_residual: Angle between each recorded and reconstructed relative rotation, radians,
            shape (T, len(bones)).
        joints: The skeleton's joints (bones and fingertip joints), skeleton order.
        position_error: Distance between each joint placed by forward kinematics (fitted angles + root
            pose) and the recording, metres, shape (T, len(joints)).
        notes: Decisions and repairs made while reading, for the user to see.
    """

    bones: tuple[str, ...]
    rotation_residual: np.ndarray
    joints: tuple[str, ...]
    position_error: np.ndarray
    notes: tuple[str, ...] = field(default=())

    @property
    def max_rotation_residual(self) -> dict[str, float]:
        """Largest rotation residual of each bone over the frames, radians."""
        return {b: float(self.rotation_residual[:, i].max()) for i, b in enumerate(self.bones)}

    @property
    def max_position_error(self) -> dict[str, float]:
        """Largest position error of each joint over the frames, metres."""
        return {j: float(self.position_error[:, i].max()) for i, j in enumerate(self.joints)}


def _check_skeleton(skeleton: Skeleton, skel: Path, bones: list[SkelBone]) -> None:
    names = skeleton.joint_names
    parents = {j.name: (names[j.parent] if j.parent >= 0 else None) for j in skeleton.joints}
    wrong = [b.name for b in bones[1:] if parents.get(b.name, "") != b.parent]
    if wrong or names[0] != bones[0].name:
        raise TrajectoryError(
            f"skeleton {skeleton.name!r} does not match {skel}: root {names[0]!r} (expected "
            f"{bones[0].name!r}); bones missing or with another parent: {wrong}"
        )
    if skeleton.dofs_of(names[0]):
        raise TrajectoryError(
            f"skeleton {skeleton.name!r}: root {names[0]!r} has DoFs; a .MOTION root is a 6-D pose "
            "(root_pose)"
        )
    recorded = {b.name for b in bones}
    unrecorded = sorted({d.joint for d in skeleton.dofs if d.joint not in recorded})
    if unrecorded:
        raise TrajectoryError(
            f"skeleton {skeleton.name!r}: joints {unrecorded} have DoFs but are not bones of {skel}"
        )


def _world_pose(skeleton: Skeleton, rec: _Recording, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Recorded frames (T, nj, 3, 3) and positions (T, nj, 3) of every skeleton joint."""
    n = len(rows)
    frames = np.empty((n, skeleton.njoints, 3, 3))
    positions = np.empty((n, skeleton.njoints, 3))
    for i, joint in enumerate(skeleton.joints):
        if joint.name in rec.rotations:
            frames[:, i], positions[:, i] = rec.rotations[joint.name][rows], rec.origins[joint.name][rows]
            continue
        parent = skeleton.joints[joint.parent]  # not recorded: rigidly attached to the parent's frame
        carry = frames[:, joint.parent] @ parent.frame.T
        frames[:, i] = carry @ joint.frame
        positions[:, i] = positions[:, joint.parent] + carry @ (joint.position - parent.position)
    return frames, positions


def _continuous(quats: np.ndarray) -> np.ndarray:
    """Quaternions with signs chosen continuous over time, the first with w ≥ 0."""
    out = quats.copy()
    out[0] *= 1.0 if out[0, 0] >= 0 else -1.0
    for k in range(1, len(out)):
        if out[k] @ out[k - 1] < 0:
            out[k] *= -1.0
    return out


def _fit(skeleton: Skeleton, rec: _Recording, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, MotionFit]:
    """DoF angles (T, ndof), root pose (T, 7) and the fit of a checked recording at the given rows."""
    frames, positions = _world_pose(skeleton, rec, rows)
    targets = np.zeros((len(rows), skeleton.ndof))
    column = {d: i for i, d in enumerate(skeleton.dof_names)}
    fitted, residuals = [], []
    for i, joint in enumerate(skeleton.joints[1:], start=1):
        if joint.name not in rec.rotations:
            continue
        parent = skeleton.joints[joint.parent]
        local = joint.frame.T @ parent.frame @ np.swapaxes(frames[:, joint.parent], 1, 2) @ frames[:, i]
        dofs = skeleton.dofs_of(joint.name)
        angles, residual = fit_dof_angles(local, [d.axis for d in dofs])
        for d, values in zip(dofs, angles.T, strict=True):
            targets[:, column[d.name]] = values
        fitted.append(joint.name)
        residuals.append(residual)
    root = skeleton.joints[0]
    quat = _continuous(matrix_to_quat(frames[:, 0]))
    root_pose = np.concatenate([positions[:, 0], quat], axis=1)
    fk = skeleton.forward_kinematics(targets)
    turn = frames[:, 0] @ root.frame.T
    placed = positions[:, :1] + np.einsum("kij,knj->kni", turn, fk.positions - root.position)
    fit = MotionFit(
        bones=tuple(fitted),
        rotation_residual=np.stack(residuals, axis=1) if residuals else np.zeros((len(rows), 0)),
        joints=skeleton.joint_names,
        position_error=np.linalg.norm(placed - positions, axis=2),
    )
    return targets, root_pose, fit


def _fit_notes(fit: MotionFit) -> list[str]:
    errors = fit.position_error.max(axis=0)
    worst = int(np.argmax(errors))
    per_bone = ", ".join(f"{b} {math.degrees(r):.2g}" for b, r in fit.max_rotation_residual.items())
    return [
        f"fit over {len(fit.position_error)} frames: every joint placed by forward kinematics of the fitted "
        f"angles + root pose is within {1e3 * errors[worst]:.3g} mm of the recording (worst "
        f"{fit.joints[worst]!r})",
        "max rotation residual per bone (recorded vs reconstructed rotation relative to the parent), "
        f"degrees: {per_bone}",
    ]


@dataclass(frozen=True)
class _Setup:
    path: Path
    skeleton: Skeleton
    recording: _Recording
    bounds: IndexBounds
    rows: np.ndarray
    notes: tuple[str, ...]


def _setup(skel_path: str | Path, index_bounds: str | Path | None, skeleton: Skeleton | None) -> _Setup:
    path = Path(skel_path)
    frames, bones = read_skel(path)
    recording = _read_recording(path, frames, bones)
    bounds, notes = _bounds(path, frames, index_bounds, recording.path.name)
    if skeleton is None:
        skeleton = read_tzionas_skeleton(path)
    _check_skeleton(skeleton, path, bones)
    rows = bounds.motion_offset + np.arange(bounds.total_aligned)
    where = f" ({bounds.source})" if bounds.source else ""
    notes.insert(
        0,
        f"aligned frame k = 0 … {bounds.total_aligned - 1} is {recording.path.name} row k + "
        f"{bounds.motion_offset} (row 0 is the rigging pose) and video frame k + "
        f"{bounds.video_offset}{where}",
    )
    return _Setup(path, skeleton, recording, bounds, rows, (*notes, *recording.notes))


def _frame_rate(fps: float | None) -> tuple[float, str]:
    """The frame rate in Hz and a note on where it comes from."""
    if fps is None:
        note = (
            f"times are k / {DEFAULT_FPS:g} s: the files give no frame rate; {DEFAULT_FPS:g} Hz (the "
            "dataset's Kinect-class RGB-D sensor) is assumed"
        )
        return DEFAULT_FPS, note
    if isinstance(fps, bool) or not isinstance(fps, int | float) or not math.isfinite(fps) or fps <= 0:
        raise ValueError(f"fps must be a finite number > 0 (Hz), got {fps!r}")
    return float(fps), f"times are k / {fps:g} s (frame rate {fps:g} Hz as given)"


def fit_tzionas_motion(
    skel_path: str | Path,
    *,
    fps: float | None = None,
    index_bounds: str | Path | None = None,
    skeleton: Skeleton | None = None,
) -> tuple[Trajectory, MotionFit]:
    """Read a Tzionas/Ballan hand's ``.MOTION`` as DoF targets + root pose, with the fit's residuals.

    Conventions are in the module docstring: aligned frames from ``INDEX_BOUNDS.txt``, root pose = the
    world pose of :func:`~handsim.builders.build_hand`'s root body, DoF angles fitted to each bone's
    rotation relative to its parent.

    Args:
        skel_path: The hand's ``.SKEL``; its ``.MOTION`` (and ``.LIMITS``) lie beside it.
        fps: Frame rate in Hz; None assumes :data:`DEFAULT_FPS` (the files give none) and says so in notes.
        index_bounds: The sequence's ``INDEX_BOUNDS.txt``; None looks in ``Configs/NN`` beside
            ``Models/NN`` and, when there is none, uses every row after the rigging pose (noted).
        skeleton: The hand the targets are for; by default read from ``skel_path``. It must have the
            ``.SKEL``'s bones with the same parents and a root without DoFs.

    Returns:
        The trajectory (times s, targets rad, ``root_pose`` (T, 7) m + wxyz; ``source``/``sha256`` of
        the ``.MOTION``; the fit's per-bone worst residuals in ``notes``) and the fit itself.

    Raises:
        InputFileError: A file is missing or unreadable.
        FormatError: A file does not follow its format (bone block missing, row count other than the
            ``.SKEL`` frame count, a rotation that is not one, INDEX_BOUNDS malformed or beyond the rows);
            the message names file, line and field.
        TrajectoryError: ``skeleton`` does not match the ``.SKEL``.
        ValueError: ``fps`` is not a finite number > 0.
    """
    rate, time_note = _frame_rate(fps)
    setup = _setup(skel_path, index_bounds, skeleton)
    targets, root_pose, fit = _fit(setup.skeleton, setup.recording, setup.rows)
    notes = (
        *setup.notes,
        time_note,
        "root_pose = world pose of the root body of build_hand (root bone origin and frame): MOTION "
        "row M_root,k itself; DoF angles fitted to each bone's rotation relative to its parent",
        *_fit_notes(fit),
    )
    trajectory = Trajectory(
        times=np.arange(len(setup.rows)) / rate,
        dof_names=setup.skeleton.dof_names,
        targets=targets,
        valid=np.ones(targets.shape, dtype=bool),
        root_pose=root_pose,
        source=str(setup.recording.path),
        sha256=setup.recording.sha256,
        notes=notes,
    )
    trajectory = with_limit_note(trajectory, setup.skeleton, "fitted angles")
    fit = MotionFit(fit.bones, fit.rotation_residual, fit.joints, fit.position_error, trajectory.notes)
    return trajectory, fit


def read_tzionas_motion(
    skel_path: str | Path,
    *,
    fps: float | None = None,
    index_bounds: str | Path | None = None,
    skeleton: Skeleton | None = None,
) -> Trajectory:
    """Read a Tzionas/Ballan hand's ``.MOTION`` as a trajectory: :func:`fit_tzionas_motion` without the fit.

    Args:
        skel_path: The hand's ``.SKEL``; its ``.MOTION`` (and ``.LIMITS``) lie beside it.
        fps: Frame rate in Hz; None assumes :data:`DEFAULT_FPS`.
        index_bounds: The sequence's ``INDEX_BOUNDS.txt``; None finds it from ``Models/NN``.
        skeleton: The hand the targets are for; by default read from ``skel_path``.

    Returns:
        The trajectory with ``root_pose``; the fit's residuals are summarised in ``notes``.

    Raises:
        InputFileError: A file is missing or unreadable.
        FormatError: A file does not follow its format (file, line and field are named).
        TrajectoryError: ``skeleton`` does not match the ``.SKEL``.
        ValueError: ``fps`` is not a finite number > 0.
    """
    return fit_tzionas_motion(skel_path, fps=fps, index_bounds=index_bounds, skeleton=skeleton)[0]


def _object_pose(recording: _Recording, root: str, rows: np.ndarray) -> np.ndarray:
    """``M_k · M_0⁻¹`` of the root bone as position (m) + quaternion (w, x, y, z), shape (T, 7)."""
    r, t = recording.rotations[root], recording.origins[root]
    turn = r[rows] @ r[0].T
    shift = t[rows] - turn @ t[0]
    return np.concatenate([shift, _continuous(matrix_to_quat(turn))], axis=1)


def fit_tzionas_object_motion(
    skel_path: str | Path, *, index_bounds: str | Path | None = None
) -> tuple[ObjectTrack, MotionFit]:
    """Read a Tzionas/Ballan object's ``.MOTION`` as a pose track, with the fit of its articulation.

    Args:
        skel_path: The object's ``.SKEL`` (one bone, or two with the second bone's single ``.LIMITS`` DoF
            as the hinge); its ``.MOTION`` and ``.LIMITS`` lie beside it.
        index_bounds: The sequence's ``INDEX_BOUNDS.txt``; None finds it from ``Models/NN``.

    Returns:
        The track (pose of the object frame = ``M_root,k · M_root,0⁻¹``, position m + quaternion wxyz;
        articulation = the second bone's angle about its hinge in radians, None for one bone; all valid)
        and the fit (the hinge's rotation residual, joint position errors; notes).

    Raises:
        InputFileError: A file is missing or unreadable.
        FormatError: A file does not follow its format (file, line and field are named).
        TrajectoryError: More than two bones, or a second bone without exactly one DoF.
    """
    setup = _setup(skel_path, index_bounds, None)
    skeleton = setup.skeleton
    bones = [name for name in skeleton.joint_names if name in setup.recording.rotations]
    if len(bones) > 2 or (len(bones) == 2 and len(skeleton.dofs) != 1):
        raise TrajectoryError(
            f"{setup.path}: {len(bones)} bones with {len(skeleton.dofs)} DoFs; an object track holds a rigid "
            "pose and at most one hinge angle (two bones, the second with exactly one DoF)"
        )
    targets, _, fit = _fit(skeleton, setup.recording, setup.rows)
    pose = _object_pose(setup.recording, bones[0], setup.rows)
    articulation = targets[:, 0].copy() if len(bones) == 2 else None
    notes = [*setup.notes, "pose = M_root,k · M_root,0⁻¹ (object frame = mesh frame = rigging world frame)"]
    if articulation is not None:
        lo, hi = math.degrees(articulation.min()), math.degrees(articulation.max())
        notes.append(
            f"articulation = {skeleton.dofs[0].name} ({bones[1]!r} about its hinge axis) from {lo:.1f}° to "
            f"{hi:.1f}°; 1-DoF fit residual up to {math.degrees(fit.rotation_residual.max()):.2g}°"
        )
        notes.append(_fit_notes(fit)[0])
    track = ObjectTrack(pose=pose, articulation=articulation, valid=np.ones(len(pose), dtype=bool))
    return track, MotionFit(fit.bones, fit.rotation_residual, fit.joints, fit.position_error, tuple(notes))


def read_tzionas_object_motion(
    skel_path: str | Path, *, index_bounds: str | Path | None = None
) -> ObjectTrack:
    """Read a Tzionas/Ballan object's ``.MOTION`` as a pose track: :func:`fit_tzionas_object_motion`'s track.

    Args:
        skel_path: The object's ``.SKEL``.
        index_bounds: The sequence's ``INDEX_BOUNDS.txt``; None finds it from ``Models/NN``.

    Returns:
        The object's pose track (and hinge angle for a two-bone object).

    Raises:
        InputFileError: A file is missing or unreadable.
        FormatError: A file does not follow its format (file, line and field are named).
        TrajectoryError: More than two bones, or a second bone without exactly one DoF.
    """
    return fit_tzionas_object_motion(skel_path, index_bounds=index_bounds)[0]


def object_track_name(model: str) -> str:
    """Key of an object model in :attr:`Trajectory.objects` (``Model_Object_Cube`` → ``cube``).

    It equals the name :func:`~handsim.io.tzionas_objects.read_tzionas_object` gives the object model.
    """
    return model.removeprefix("Model_Object_").lower()


HAND_SIDES = {"Model_Hand_R": "right", "Model_Hand_L": "left"}
"""A two-hand sequence's hand models and the names of their hands in the scene (right first)."""


@dataclass(frozen=True)
class _Sequence:
    directory: Path
    info_path: Path
    models: tuple[tuple[str, int], ...]
    hands: list[tuple[str, int]]
    index_bounds: Path | None


def _sequence(models_dir: str | Path) -> _Sequence:
    directory = Path(models_dir)
    config = config_dir_of(directory)
    info_path = config / "MODELS_INFO.txt"
    models = read_models_info(info_path)
    hands = [(name, ln) for name, ln in models if name.startswith("Model_Hand")]
    bounds = config / "INDEX_BOUNDS.txt"
    return _Sequence(directory, info_path, models, hands, bounds if bounds.is_file() else None)


def _object_tracks(seq: _Sequence) -> tuple[dict[str, ObjectTrack], list[str]]:
    """Every listed object's track by :func:`object_track_name`, and notes (objects', unknown models')."""
    notes: list[str] = []
    objects: dict[str, ObjectTrack] = {}
    for model, ln in seq.models:
        if not model.startswith("Model_Object"):
            if not model.startswith("Model_Hand"):
                notes.append(
                    f"{seq.info_path.name}:{ln}: model {model!r} is neither a hand nor an object: ignored"
                )
            continue
        skel = _listed(seq.directory, model, seq.info_path, ln)
        track, fit = fit_tzionas_object_motion(skel, index_bounds=seq.index_bounds)
        key = object_track_name(model)
        objects[key] = track
        notes.extend(f"object {key!r}: {n}" for n in fit.notes)
    return objects, notes


def read_tzionas_sequence(
    models_dir: str | Path, *, hand: str | None = None, fps: float | None = None
) -> Trajectory:
    """Read a whole Tzionas/Ballan sequence: one hand's trajectory with every object's pose track.

    The models are those of ``Configs/NN/MODELS_INFO.txt`` (beside ``Models/NN``), the aligned frames those
    of ``Configs/NN/INDEX_BOUNDS.txt``. Other hands are ignored (noted); :func:`read_tzionas_hands` reads
    both hands of a two-hand sequence.

    Args:
        models_dir: The sequence's ``Models/NN`` folder.
        hand: The hand model to read (e.g. ``Model_Hand_L``); by default the first ``Model_Hand_*`` listed.
        fps: Frame rate in Hz; None assumes :data:`DEFAULT_FPS`.

    Returns:
        The hand's trajectory (as :func:`read_tzionas_motion`) with ``objects`` keyed by
        :func:`object_track_name`; object notes are prefixed with the object's name.

    Raises:
        InputFileError: ``MODELS_INFO.txt`` or a listed model's file is missing or unreadable.
        FormatError: A file does not follow its format (file, line and field are named).
        TrajectoryError: No hand listed, or ``hand`` is not one of the listed hands.
        ValueError: ``fps`` is not a finite number > 0.
    """
    seq = _sequence(models_dir)
    hands, info_path = seq.hands, seq.info_path
    if not hands or (hand is not None and hand not in [h for h, _ in hands]):
        raise TrajectoryError(
            f"{info_path}: {'no hand model' if not hands else f'no hand {hand!r}'} (Model_Hand_*) listed; "
            f"it lists {[name for name, _ in seq.models]}"
        )
    name, line = next((h, ln) for h, ln in hands if hand in (None, h))
    trajectory = read_tzionas_motion(
        _listed(seq.directory, name, seq.info_path, line), fps=fps, index_bounds=seq.index_bounds
    )
    notes = list(trajectory.notes)
    others = [h for h, _ in hands if h != name]
    if others:
        notes.append(f"{seq.info_path.name} also lists {others}: ignored (a trajectory drives one hand)")
    objects, object_notes = _object_tracks(seq)
    return replace(trajectory, objects=objects, notes=(*notes, *object_notes))


def two_hand_models(info_path: Path, models: tuple[tuple[str, int], ...]) -> dict[str, str]:
    """The hands of a sequence listing two: scene name (``right``, ``left``) → model, right first.

    Args:
        info_path: The sequence's ``MODELS_INFO.txt`` (for messages).
        models: Its models (:func:`read_models_info`).

    Returns:
        ``{"right": "Model_Hand_R", "left": "Model_Hand_L"}``.

    Raises:
        TrajectoryError: The hands listed are not exactly :data:`HAND_SIDES` (the message names the lines).
    """
    hands = [(name, ln) for name, ln in models if name.startswith("Model_Hand")]
    if sorted(name for name, _ in hands) != sorted(HAND_SIDES):
        listed = ", ".join(f"{name!r} (line {ln})" for name, ln in hands)
        raise TrajectoryError(
            f"{info_path}: lists the hands {listed}; a two-hand sequence lists exactly "
            f"{' and '.join(HAND_SIDES)}, one each"
        )
    return {side: model for model, side in HAND_SIDES.items()}


def read_tzionas_hands(models_dir: str | Path, *, fps: float | None = None) -> Trajectory:
    """Read a Tzionas/Ballan sequence with two hands: both hands' trajectories and every object's track.

    Each hand is read as :func:`read_tzionas_motion` reads it (aligned frames from the sequence's
    ``INDEX_BOUNDS.txt``) and the two are joined (:func:`handsim.datatypes.trajectory_ops.join_hands`): DoF
    columns
    ``right/<dof>`` and ``left/<dof>``, root poses under ``hand_roots["right"]`` and ``["left"]``.

    Args:
        models_dir: The sequence's ``Models/NN`` folder; its ``Configs/NN/MODELS_INFO.txt`` lists
            ``Model_Hand_R`` and ``Model_Hand_L`` (:func:`two_hand_models`).
        fps: Frame rate in Hz; None assumes :data:`DEFAULT_FPS`.

    Returns:
        The two-hand trajectory (``source`` the ``Models/NN`` folder, no ``sha256``: the run records hash
        each input file) with ``objects`` keyed by :func:`object_track_name`; each hand's notes are prefixed
        with its name, object notes with the object's.

    Raises:
        InputFileError: ``MODELS_INFO.txt`` or a listed model's file is missing or unreadable.
        FormatError: A file does not follow its format (file, line and field are named).
        TrajectoryError: The hands listed are not ``Model_Hand_R`` and ``Model_Hand_L``, or their motions
            have different frame counts (both files and counts are named).
        ValueError: ``fps`` is not a finite number > 0.
    """
    seq = _sequence(models_dir)
    models = two_hand_models(seq.info_path, seq.models)
    lines = dict(seq.hands)
    skels = {
        side: _listed(seq.directory, model, seq.info_path, lines[model]) for side, model in models.items()
    }
    frames = {side: read_skel(skel)[0] for side, skel in skels.items()}
    if len(set(frames.values())) > 1:
        counts = " and ".join(
            f"{skels[side].with_suffix('.MOTION')} has {n} frames ({skels[side].name}'s count)"
            for side, n in frames.items()
        )
        raise TrajectoryError(
            f"the two hands of sequence {seq.directory.name} must share their frames: {counts}"
        )
    parts = {
        side: read_tzionas_motion(skel, fps=fps, index_bounds=seq.index_bounds)
        for side, skel in skels.items()
    }
    objects, object_notes = _object_tracks(seq)
    joined = join_hands(parts, objects=objects, source=str(seq.directory), sha256="")
    return replace(joined, notes=(*joined.notes, *object_notes))


def _listed(directory: Path, model: str, info_path: Path, line: int) -> Path:
    skel = directory / f"{model}.SKEL"
    if not skel.is_file():
        raise InputFileError(f"{skel}: file not found; {info_path}:{line} lists model {model!r}")
    return skel
