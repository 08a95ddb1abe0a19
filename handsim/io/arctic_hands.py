"""ARCTIC hands → joint targets and root poses, and a check that each entry holds the hand it claims.

* :func:`arctic_hand_trajectory` — one hand of an :class:`~handsim.io.arctic_motion.ArcticSequence` as a
  :class:`~handsim.trajectory.Trajectory` for the MuJoCo MANO hand built from the user's model file with the
  subject's betas: hinge targets (Z·Y·X angles of the full pose ``pose + hands_mean``, ARCTIC's
  ``flat_hand_mean=False``), the wrist's root pose ``(J0 + trans, exp(rot))`` and the object track.
* :func:`hand_side_check` — a heuristic for left-hand data stored under ``right`` (or the reverse).

What distinguishes the two hands' data: MANO's left model is the right one mirrored in x, and nothing in a
hand's parameters says which model they were fitted with — both readings are valid MANO hands. The pose
alone hardly tells (a relative pose read by the other model flexes each finger joint by ``2·mean − flexion``,
which bends a joint backwards only when the fingers close past twice MANO's mean curl: with a full power
grasp the DIP joints reach ~17° of hyperextension, inside a normal hand's range, so a pose-only test judges
almost nothing). Geometry does: read by the other model, the wrist lands ``J0_other − J0_own`` (≈ 19 cm along
the world x axis, MANO adds J0 unrotated) away and the fingers point back along the forearm. ARCTIC hands
hold the object, so the reading that touches the object is the hand's own. :func:`hand_side_check` measures,
frame by frame, the distance from the hand's joints to the object's surface in both readings and compares
how often each touches it. It flags, never refuses; a hand that never touches the object, or touches it in
both readings, is **not judged** (``docs/mano.md`` gives the measured margins).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
import trimesh
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from handsim.errors import TrajectoryError
from handsim.io.arctic_motion import ARCTIC_FPS, HANDS, ArcticSequence
from handsim.io.mano import (
    MANO_JOINT_NAMES,
    MANOModel,
    MANOSequence,
    axis_angle_to_matrix,
    mano_joints,
    mano_pose_to_trajectory,
)
from handsim.object_model import ObjectModel
from handsim.skeleton import Skeleton
from handsim.trajectory import ObjectTrack, Trajectory

BETAS_TOLERANCE_M = 1e-9
"""The wrist of the hand a sequence drives must sit at the sequence's J0 (its betas) within this, metres."""

CONTACT_M = 0.02
"""A hand touches the object in a frame when one of its joints or fingertips is within this distance of the
object's surface, metres. MANO's finger joints lie 6–10 mm under the skin, so a touching finger has a joint
within ~1 cm; 2 cm allows for fitting error."""

SIDE_CONTACT_FRACTION = 0.05
"""A reading is judged the hand's own when it touches the object in at least this fraction of the frames
and the other reading in at most a fifth as many."""

SURFACE_SPACING_M = 0.005
"""The object's surface is sampled by subdividing its triangles to edges of at most this length, metres (the
distance to the surface is then overestimated by at most about half of it)."""


def arctic_hand_trajectory(
    sequence: ArcticSequence, side: str, skeleton: Skeleton, model: MANOModel
) -> Trajectory:
    """One hand of an ARCTIC sequence as hinge targets and a wrist root pose (``flat_hand_mean=False``).

    Args:
        sequence: The sequence (:func:`~handsim.io.arctic_motion.read_arctic_sequence`).
        side: ``"right"`` or ``"left"``.
        skeleton: The hand's MANO skeleton, built from ``model`` with the sequence's betas for this hand
            (``build_mano_hands(mano_dir, {side: sequence.hand(side).shape})[side].skeleton``).
        model: The MANO model of that side (its ``hands_mean`` completes ARCTIC's relative pose).

    Returns:
        The trajectory: columns = ``skeleton.dof_names`` (radians), times ``i / sequence.fps``, root pose
        (N, 7) = wrist body position ``J0 + trans`` and quaternion (w, x, y, z) of ``rot``, the object track
        under ``sequence.object_name``, the hand file's SHA-256.

    Raises:
        TrajectoryError: The model or skeleton is of the other side, the model has no ``hands_mean``, or
            the skeleton was built with other betas than the sequence's (its wrist is not at the
            sequence's J0).
        HandsimError: ``side`` is neither ``"right"`` nor ``"left"``.
    """
    seq = sequence.hand(side)
    if model.side != side:
        raise TrajectoryError(
            f"{model.source}: a {model.side} MANO model cannot convert the {side} hand of {sequence.name}; "
            f"use MANO_{side.upper()}.pkl"
        )
    if model.hands_mean is None:
        raise TrajectoryError(
            f"{model.source}: the MANO model has no hands_mean; ARCTIC's poses are relative to MANO's mean "
            "hand pose (flat_hand_mean=False), so the model file must carry it"
        )
    j0 = mano_joints(model, seq.shape)[0]
    off = float(np.linalg.norm(j0 - skeleton.joints[0].position))
    if off > BETAS_TOLERANCE_M:
        raise TrajectoryError(
            f"the {side} hand was built with other betas than {sequence.name}'s {side}.shape: its wrist is "
            f"{off * 1000:.3g} mm from the sequence's J0; build it with betas=sequence.{side}.shape"
        )
    return mano_pose_to_trajectory(
        seq,
        skeleton,
        fps=sequence.fps,
        flat_hand_mean=False,
        hands_mean=model.hands_mean,
        objects={sequence.object_name: sequence.object},
    )


@dataclass(frozen=True)
class SideCheck:
    """Whether one entry of an ARCTIC ``.mano.npy`` holds the hand its key names (a heuristic).

    Attributes:
        side: The entry checked (``"right"`` or ``"left"``).
        verdict: ``"as stored"`` (the data drive their own model onto the object), ``"mirrored"`` (they
            touch the object only when driving the other hand's model: flagged) or ``"not judged"``.
        stored_fraction: Fraction of frames in which the hand, read as stored, touches the object
            (:data:`CONTACT_M`).
        mirrored_fraction: The same, the data driving the other hand's model.
        stored_closest: Closest approach of the hand to the object's surface read as stored, metres.
        mirrored_closest: The same, read mirrored.
        message: One line for the user.
    """

    side: str
    verdict: str
    stored_fraction: float
    mirrored_fraction: float
    stored_closest: float
    mirrored_closest: float
    message: str


def hand_points(
    seq: MANOSequence, skeleton: Skeleton, model: MANOModel, fps: float = ARCTIC_FPS
) -> np.ndarray:
    """World positions of a MANO hand's 16 joints and 5 fingertips per frame, metres, shape (N, 21, 3).

    The sequence's parameters drive ``skeleton`` (relative pose, ``flat_hand_mean=False``) whatever side the
    sequence claims: this is how data of one hand are read by the other hand's model.

    Args:
        seq: MANO parameters.
        skeleton: A MANO skeleton (:func:`handsim.builders.mano_hand.mano_model_skeleton`).
        model: Its model (for ``hands_mean``).
        fps: Frame rate, Hz (time stamps only).
    """
    as_side = replace(seq, side=skeleton.name.removeprefix("mano_"), notes=())
    trajectory = mano_pose_to_trajectory(
        as_side, skeleton, fps=fps, flat_hand_mean=False, hands_mean=model.hands_mean
    )
    names = (*MANO_JOINT_NAMES, *skeleton.fingertips)
    index = [skeleton.joint_index(n) for n in names]
    local = skeleton.forward_kinematics(trajectory.targets).positions[:, index] - skeleton.joints[0].position
    rotation = Rotation.from_quat(trajectory.root_pose[:, 3:], scalar_first=True).as_matrix()
    return trajectory.root_pose[:, None, :3] + local @ np.swapaxes(rotation, 1, 2)


def surface_distances(obj: ObjectModel, track: ObjectTrack, points: np.ndarray) -> np.ndarray:
    """Per frame, the smallest distance from ``points`` (N, P, 3) to the object's surface, metres (N,).

    The root part follows the track's pose; the second part also turns by the articulation about the
    object's hinge (ARCTIC: ``R_z(−θ)`` for the hinge axis (0, 0, −1)).
    """
    n = len(points)
    pos, quat = track.pose[:, :3], track.pose[:, 3:]
    rotation = Rotation.from_quat(quat, scalar_first=True).as_matrix()
    in_object = np.einsum("nji,npj->npi", rotation, points - pos[:, None])  # Rᵀ (p − t)
    best = np.full(n, np.inf)
    for index, part in enumerate(obj.parts):
        vertices, _ = trimesh.remesh.subdivide_to_size(part.mesh.vertices, part.mesh.faces, SURFACE_SPACING_M)
        tree = cKDTree(vertices)
        local = in_object
        if index > 0 and obj.hinge is not None and track.articulation is not None:
            axis = np.asarray(obj.hinge.axis, dtype=float)
            turn = axis_angle_to_matrix(axis[None, :] * np.asarray(track.articulation)[:, None])
            local = np.einsum("nji,npj->npi", turn, in_object - np.asarray(obj.hinge.pos)) + np.asarray(
                obj.hinge.pos
            )
        distance, _ = tree.query(local.reshape(-1, 3))
        best = np.minimum(best, distance.reshape(n, -1).min(axis=1))
    return best


def hand_side_check(
    sequence: ArcticSequence,
    side: str,
    hands: Mapping[str, tuple[Skeleton, MANOModel]],
    obj: ObjectModel,
) -> SideCheck:
    """Check, heuristically, that the ``side`` entry of a sequence holds that hand (see the module notes).

    Args:
        sequence: The sequence.
        side: The entry to check.
        hands: Both hands' skeletons and models (``{s: (h.skeleton, h.model)}`` of
            :func:`handsim.builders.mano_hand.build_mano_hands`); the other hand's skeleton is the mirrored
            reading (its betas are the other entry's, a difference of millimetres).
        obj: The sequence's object (:func:`handsim.io.arctic.read_arctic_template`).

    Returns:
        The verdict, with how often each reading touches the object and how close it comes.

    Raises:
        TrajectoryError: A hand missing from ``hands``, or a skeleton/model of the wrong side.
        HandsimError: ``side`` is neither ``"right"`` nor ``"left"``.
    """
    seq = sequence.hand(side)
    other = HANDS[1 - HANDS.index(side)]
    for s in HANDS:
        if s not in hands:
            raise TrajectoryError(f"the side check of the {side} hand needs both hands; {s!r} is missing")
        skeleton, model = hands[s]
        if skeleton.name != f"mano_{s}" or model.side != s:
            raise TrajectoryError(
                f"hands[{s!r}] holds a {skeleton.name} skeleton and a {model.side} model; "
                f"expected the {s} hand's"
            )
    closest = {}
    fraction = {}
    for reading in (side, other):
        skeleton, model = hands[reading]
        d = surface_distances(obj, sequence.object, hand_points(seq, skeleton, model, sequence.fps))
        closest[reading] = float(d.min())
        fraction[reading] = float(np.mean(d <= CONTACT_M))
    fs, fm = fraction[side], fraction[other]
    where = f"{sequence.mano_path} [{side}]"
    counts = (
        f"driving the {side} model it touches the {sequence.object_name} in {fs:.0%} of the frames (closest "
        f"{closest[side] * 1000:.0f} mm), driving the {other} model in {fm:.0%} (closest "
        f"{closest[other] * 1000:.0f} mm)"
    )
    if fm >= SIDE_CONTACT_FRACTION and fs <= fm / 5:
        verdict = "mirrored"
        message = (
            f"{where}: the data look like the {other} hand's (heuristic): {counts}; check the file's "
            "'right'/'left' entries"
        )
    elif fs >= SIDE_CONTACT_FRACTION and fm <= fs / 5:
        verdict = "as stored"
        message = f"{where}: the data are the {side} hand's (heuristic): {counts}"
    else:
        verdict = "not judged"
        message = f"{where}: side not judged: {counts}; the hand must touch the object in one reading only"
    return SideCheck(side, verdict, fs, fm, closest[side], closest[other], message)
