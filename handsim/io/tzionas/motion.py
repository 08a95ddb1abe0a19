"""One Tzionas/Ballan ``.MOTION`` file as a hand `Trajectory` (DoF angles + root pose) or an object track.

Whole sequences (a hand with every object, or two hands) are assembled by :mod:`handsim.io.tzionas.sequence`.

Rows and times. ``.MOTION`` row 0 is the rigging (rest) pose. Aligned frame k (k = 0 … TotalAlligned − 1)
uses row k + MotionnOffset and shows video frame k + VideoooOffset, both offsets from the sequence's
``Configs/NN/INDEX_BOUNDS.txt`` (found from ``Models/NN/`` by default). The files give no frame rate:
times are k / fps with fps = 30 Hz by default, the frame rate of the Kinect-class 640 × 480 RGB-D sensor
the dataset was captured with (``Calibration/Cameras.txt``: f = 525 px, c = (319.5, 239.5)).

Hand (:func:`fit_tzionas_motion`). ``M_b,k = (R_b,k, T_b,k)`` is bone b's world transform at row k, ``F_b``
its rest frame (row 0, as in :func:`~handsim.io.tzionas.skeleton.read_tzionas_skeleton`):

* Root pose = the world pose of the root body of :func:`handsim.builders.build_hand`, which sits at the
  root bone's rest origin with the root bone's rest frame; so the root pose of frame k is ``M_root,k``
  itself: position ``T_root,k`` (m) and the quaternion (w, x, y, z) of ``R_root,k``. A mocap (or free)
  root body set to it puts the hand where the recording has it; at row 0 it equals the spec's root body
  ``pos``/``quat``. Quaternion signs are kept continuous over time, the first with w ≥ 0.
* DoF angles: the rotation of bone b relative to its parent p, in b's rest frame,
  ``L_b,k = F_bᵀ F_p R_p,kᵀ R_b,k`` (= ``F_bᵀ A_p,k⁻¹ A_b,k F_b`` with ``A = M_k M_0⁻¹``), is exactly what
  :meth:`~handsim.datatypes.skeleton.Skeleton.forward_kinematics` composes (``R_b = R_p F_pᵀ F_b L_b``). It
  is split into the bone's DoF chain ``Rot(a_1, q_1) ⋯ Rot(a_n, q_n)`` (the ``.LIMITS`` axes, outermost
  first) by :func:`~handsim.datatypes.kinematics.fit_dof_angles`, which minimises the angle between ``L``
  and its reconstruction.
* Residuals (:class:`MotionFit`): per bone and frame, that angle; per skeleton joint and frame, the distance
  between the joint placed by forward kinematics of the fitted angles + root pose and the recording
  (bone origins ``T_b,k``; a joint not in the file, e.g. a fingertip, rigidly attached to its parent's
  recorded frame).

Objects (:func:`fit_tzionas_object_motion`). The object frame is the mesh frame (the rigging pose's world
frame, see :mod:`handsim.io.tzionas.objects`), so the pose of frame k is ``M_root,k · M_root,0⁻¹``; an
articulated object's angle is its second bone's single DoF, fitted as above (about the hinge axis of
:func:`~handsim.io.tzionas.objects.read_tzionas_object`, through the second bone's joint).

Sequence 20 (``tests/test_io_tzionas_motion.py``): the 3-DoF and 1-DoF bones are reproduced to the files'
precision (≤ 1.5e-6 rad); the two 2-DoF metacarpals turn a little about their missing axis (RFing.1_Hand
0.09°, RFing.4_Hand 1.8°), so forward kinematics (numpy or MuJoCo) puts every bone origin within 0.16 mm
and every fingertip within 0.23 mm of the recording.

Every rotation row is checked: ``max |RᵀR − I| > 1e-3`` or ``det R < 0`` is an error naming bone, row and
line; smaller deviations (the files print 6 digits) are removed by SVD (nearest rotation) and noted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from handsim.datatypes.kinematics import fit_dof_angles
from handsim.datatypes.rotations import matrix_to_quat
from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.datatypes.trajectory_ops import with_limit_note
from handsim.errors import TrajectoryError
from handsim.io.tzionas.configs import IndexBounds
from handsim.io.tzionas.motion_recording import Recording, aligned_bounds, read_recording
from handsim.io.tzionas.skel import SkelBone, read_skel
from handsim.io.tzionas.skeleton import read_tzionas_skeleton

DEFAULT_FPS = 30.0
"""Frame rate assumed when none is given, Hz: the dataset's Kinect-class RGB-D sensor streams at 30 Hz."""


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


def _world_pose(skeleton: Skeleton, rec: Recording, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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


def _fit(skeleton: Skeleton, rec: Recording, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, MotionFit]:
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
    recording: Recording
    bounds: IndexBounds
    rows: np.ndarray
    notes: tuple[str, ...]


def _setup(skel_path: str | Path, index_bounds: str | Path | None, skeleton: Skeleton | None) -> _Setup:
    path = Path(skel_path)
    frames, bones = read_skel(path)
    recording = read_recording(path, frames, bones)
    bounds, notes = aligned_bounds(path, frames, index_bounds, recording.path.name)
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


def _object_pose(recording: Recording, root: str, rows: np.ndarray) -> np.ndarray:
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
