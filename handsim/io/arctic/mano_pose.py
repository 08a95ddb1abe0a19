"""MANO poses as hinge angles plus a root pose: :func:`mano_pose_to_trajectory`.

Conventions (pinned by ``tests/test_mano.py``; details and measured numbers in ``docs/mano.md``; the model
frame, joint order and sides are :mod:`handsim.io.arctic.mano`'s):

* **Hinges.** Each of the 15 finger joints is a ball joint of MANO, here three hinges about the model
  axes z, y, x, outermost first: ``R = Rz(a) · Ry(b) · Rx(c)`` (DoFs ``<joint>_z``, ``<joint>_y``,
  ``<joint>_x``). Any 3-axis order represents every rotation; Z·Y·X puts the singular middle axis on y, the
  palm normal, where finger rotations (ab/adduction) stay far from the ±90° gimbal lock, while the
  large rotations (finger flexion about z, the thumb's about x) sit on the outer axes. The conversion
  from axis-angle is exact up to rounding (residual reported in :attr:`Trajectory.notes`).
* **Continuous in time.** Each frame's angles are the exact solution nearest the previous frame's
  (:func:`handsim.datatypes.rotations.continuous_zyx`): no turn where an angle crosses ±π, no flip to the
  other solution near y = ±90°, so the linear interpolation to the control rate never sweeps round. Each
  hinge changes between frames by at most ``φ / cos β`` (φ the recorded rotation between the frames, β
  the mean of their principal |y| plus φ/2; ``docs/mano.md``), never by more than π. The angles are then
  moved by whole turns into the skeleton's hinge ranges where needed, at the fewest frames (a note names
  them: only a hinge whose angle spans more than its range, a joint that turns round, needs it).
* **Root.** MANO rotates the whole hand by the global rotation ``rot`` about the wrist joint J0 (not the
  origin) and then translates by ``trans``, so the wrist body's world pose is position ``J0 + trans``,
  orientation ``exp(rot)`` (quaternion w, x, y, z) — what :attr:`Trajectory.root_pose` holds.
* **Mean pose.** With ``flat_hand_mean=False`` (MANO's and smplx's default, and what ARCTIC's code uses)
  the stored pose is relative to ``hands_mean``: full pose = pose + hands_mean.
* **Left hands.** A left-hand pose does not drive a right hand (error).

The Z·Y·X angles come from :func:`handsim.datatypes.rotations.continuous_zyx` (exact also at gimbal lock).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from handsim.datatypes.rotations import (
    axis_angle_to_matrix,
    axis_angle_to_quat,
    continuous_zyx,
    rotation_error,
    zyx_to_matrix,
)
from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.errors import TrajectoryError
from handsim.io.arctic.mano import HINGE_AXES, MANO_JOINT_NAMES


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

    Each joint's axis-angle ``ω`` becomes the Z·Y·X angles with ``Rz(a) Ry(b) Rx(c) = exp(ω)``, continuous in
    time (each frame the exact solution nearest the previous frame's,
    :func:`handsim.datatypes.rotations.continuous_zyx`) and within the skeleton's hinge ranges (moved by
    whole turns where needed, with a note); the largest rotation error of the decomposition and the
    largest hinge change between frames are reported in ``notes``. The root pose is the wrist body's world
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
    _check_sequence(seq, skeleton, fps)
    n = seq.nframes
    pose = full_mano_pose(
        seq, flat_hand_mean=flat_hand_mean, hands_mean=hands_mean, hands_components=hands_components
    ).reshape(n, 15, 3)
    rotations = axis_angle_to_matrix(pose)
    targets, angles, moved = _hinge_targets(rotations, skeleton)
    residual = float(rotation_error(zyx_to_matrix(angles), rotations).max()) if n else 0.0
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
        _step_note(angles, rotations),
        *moved,
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


def _check_sequence(seq: MANOSequence, skeleton: Skeleton, fps: float) -> None:
    """Refuse a sequence of the other side, a non-positive frame rate, or rot and trans not (N, 3).

    Raises:
        TrajectoryError: Any of these, or a skeleton that is not MANO's.
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


def _hinge_targets(
    rotations: np.ndarray, skeleton: Skeleton
) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Hinge targets (N, ndof) of the joints' rotations (N, 15, 3, 3), continuous and within the ranges.

    Returns:
        The targets in ``skeleton.dof_names`` order (DoFs MANO does not drive at 0), the Z·Y·X angles
        (N, 15, 3) and the notes on joints moved by whole turns into their ranges.
    """
    names = [[f"{j}_{ax}" for ax, _ in HINGE_AXES] for j in MANO_JOINT_NAMES[1:]]
    limits = {dof.name: (dof.lower, dof.upper) for dof in skeleton.dofs}
    angles, moved = _within_ranges(continuous_zyx(rotations), np.array(names), limits)  # (n, 15, 3): z y x
    columns = {names[k][a]: angles[:, k, a] for k in range(15) for a in range(3)}
    targets = np.zeros((len(rotations), skeleton.ndof))
    for c, name in enumerate(skeleton.dof_names):
        targets[:, c] = columns.get(name, 0.0)
    return targets, angles, moved


def _within_ranges(
    angles: np.ndarray, names: np.ndarray, limits: dict[str, tuple[float, float]]
) -> tuple[np.ndarray, tuple[str, ...]]:
    """Hinge angles (N, 15, 3) moved by whole turns into their DoFs' ranges where they leave them; a note.

    A whole turn leaves the joint's rotation as it is, but the servo sweeps a turn where a column's offset
    changes, so each column that leaves its range gets the fewest changes (:func:`_fewest_turns`) and the
    note names the DoFs and the frames of the sweeps.
    """
    lower, upper = np.moveaxis(np.array([[limits[str(name)] for name in row] for row in names]), -1, 0)
    outside = (angles < lower) | (angles > upper)
    if not outside.any():
        return angles, ()
    out = angles.copy()
    sweeps: set[int] = set()
    for k, a in zip(*np.nonzero(outside.any(axis=0)), strict=True):
        out[:, k, a], changes = _fewest_turns(angles[:, k, a], float(lower[k, a]), float(upper[k, a]))
        sweeps.update(changes)
    moved = out != angles
    dofs = [str(name) for name in names[moved.any(axis=0)]]
    frames = sorted(sweeps)
    listed = ", ".join(str(f) for f in frames[:10]) + (" …" if len(frames) > 10 else "")
    return out, (
        f"{int(moved.sum())} hinge targets of {len(dofs)} DoF{'' if len(dofs) == 1 else 's'} "
        f"({', '.join(dofs)}) moved by whole turns into the hinge ranges (the angle spans more than its "
        "range: the joint turns round in the sequence): the rotations are the recorded ones, but the servo "
        f"sweeps a turn at {len(frames)} "
        + ("frame" if len(frames) == 1 else "frames")
        + (f" ({listed})" if frames else ""),
    )


def _fewest_turns(x: np.ndarray, lower: float, upper: float) -> tuple[np.ndarray, list[int]]:
    """A column (N,) moved by whole turns into [lower, upper] with the fewest offset changes; their frames.

    At the first frame, and again where the column leaves the range, it takes the offset that keeps it in
    range the longest (the furthest-reaching choice needs the fewest changes); where no offset fits (a
    range narrower than a turn), the one nearest the range's middle, for that frame.
    """
    turn = 2.0 * math.pi
    out, changes, t, n = x.copy(), [], 0, x.shape[0]
    while t < n:
        rest = x[t:]
        offsets = list(range(math.ceil((lower - x[t]) / turn), math.floor((upper - x[t]) / turn) + 1))
        offsets = offsets or [round(((lower + upper) / 2 - x[t]) / turn)]
        reach = {}
        for k in offsets:
            bad = np.flatnonzero((rest + turn * k < lower) | (rest + turn * k > upper))
            reach[k] = t + (int(bad[0]) if bad.size else n - t)
        k = max(offsets, key=lambda k: (reach[k], -abs(k)))
        stop = max(reach[k], t + 1)
        out[t:stop] = x[t:stop] + turn * k
        changes += [t] if t else []
        t = stop
    return out, changes


def _step_note(angles: np.ndarray, rotations: np.ndarray) -> str:
    """The largest hinge change between frames beside the recorded rotation between those frames."""
    if angles.shape[0] < 2:
        return "hinge targets continuous in time (one frame)"
    step = np.abs(np.diff(angles, axis=0)).max(axis=2)  # (N − 1, 15)
    t, k = np.unravel_index(int(np.argmax(step)), step.shape)
    turned = float(rotation_error(rotations[t + 1, k], rotations[t, k]))
    return (
        "hinge targets continuous in time (each frame the exact Z·Y·X solution nearest the last): largest "
        f"hinge change between frames {math.degrees(float(step[t, k])):.3g}° ({MANO_JOINT_NAMES[k + 1]}, "
        f"frames {t}–{t + 1}, where the recorded joint rotation turned {math.degrees(turned):.3g}°)"
    )
