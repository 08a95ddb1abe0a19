"""ARCTIC hands → joint targets and root poses, and a check that each entry holds the hand it claims.

* :func:`arctic_hand_trajectory` — one hand of an :class:`~handsim.io.arctic.sequence.ArcticSequence` as a
  :class:`~handsim.datatypes.trajectory.Trajectory` for the MuJoCo MANO hand built from the user's model
  file with the
  subject's betas: hinge targets (Z·Y·X angles of the full pose ``pose + hands_mean``, ARCTIC's
  ``flat_hand_mean=False``), the wrist's root pose ``(J0 + trans, exp(rot))`` and the object track.
* :func:`hand_side_check` — a heuristic for left-hand data stored under ``right`` (entries swapped).

What distinguishes the two hands' data: MANO's left model is the right one mirrored in x, and nothing in a
hand's parameters says which model they were fitted with — both readings are valid MANO hands. The pose
alone hardly tells (a relative pose read by the other model flexes each finger joint by ``2·mean − flexion``,
which bends a joint backwards only when the fingers close past twice MANO's mean curl: with a full power
grasp the DIP joints reach ~17° of hyperextension, inside a normal hand's range, so a pose-only test judges
almost nothing). Geometry does: read by the other model, the wrist lands ``J0_other − J0_own`` (≈ 19 cm along
the world x axis, MANO adds J0 unrotated) away and the fingers point back along the forearm. ARCTIC hands
hold the object, so the reading that touches the object (without entering it) is the hand's own.
:func:`hand_contact` measures, frame by frame, how close each reading of an entry comes to the object's
surface and whether it enters it; :func:`hand_side_check` flags a sequence as swapped only when both entries
touch the object only mirrored (a hand idle in its own reading may land on the object mirrored, so one entry
alone never flags). It flags, never refuses: a swapped verdict is the replay flag ``hands_swapped``
(:attr:`SideCheck.flags`, not valid), carried by the trajectory into every replay's flags;
``docs/mano.md`` gives the measured margins.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from handsim.datatypes.flags import Flag
from handsim.datatypes.object_model import ObjectModel
from handsim.datatypes.rotations import axis_angle_to_matrix, quat_to_matrix
from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.datatypes.trajectory_ops import join_hands
from handsim.errors import TrajectoryError
from handsim.io.arctic.mano import MANO_JOINT_NAMES, MANOModel, mano_joints
from handsim.io.arctic.mano_pose import MANOSequence, mano_pose_to_trajectory
from handsim.io.arctic.sequence import ARCTIC_FPS, HANDS, ArcticSequence

BETAS_TOLERANCE_M = 1e-9
"""The wrist of the hand a sequence drives must sit at the sequence's J0 (its betas) within this, metres."""

CONTACT_M = 0.02
"""A hand touches the object in a frame when one of its joints or fingertips is within this distance of the
object's surface, metres. MANO's finger joints lie 6–10 mm under the skin, so a touching finger has a joint
within ~1 cm; 2 cm allows for fitting error."""

PENETRATION_M = 0.01
"""A hand cannot be inside the object: a frame in which a joint or fingertip lies deeper than this inside
a (watertight) part does not count as touching, metres (ARCTIC's fits penetrate by millimetres at most)."""

SIDE_CONTACT_FRACTION = 0.05
"""A reading is judged the hand's own when it touches the object in at least this fraction of the frames
and the other reading in none: a hand that is idle in its own reading may land on the object in the other
(displaced by ≈ 19 cm), so any contact in both readings leaves the side not judged."""

SURFACE_SPACING_M = 0.005
"""The object's surface is sampled by subdividing its triangles to edges of at most this length, metres (the
distance to the surface is then overestimated by at most about half of it)."""


def arctic_hand_trajectory(
    sequence: ArcticSequence, side: str, skeleton: Skeleton, model: MANOModel
) -> Trajectory:
    """One hand of an ARCTIC sequence as hinge targets and a wrist root pose (``flat_hand_mean=False``).

    Args:
        sequence: The sequence (:func:`~handsim.io.arctic.sequence.read_arctic_sequence`).
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
class HandContact:
    """How one entry's data meet the object when read by its own model and by the other hand's.

    Attributes:
        side: The entry (``"right"`` or ``"left"``).
        own_fraction: Fraction of frames in which the data, driving the entry's own model, touch the object
            (within :data:`CONTACT_M` of its surface, no deeper than :data:`PENETRATION_M` inside it).
        other_fraction: The same, driving the other hand's model.
        own_closest: Closest approach to the object's surface in the own reading, metres.
        other_closest: The same in the other reading.
        own_inside: Fraction of frames in which the own reading is deeper than :data:`PENETRATION_M` inside.
        other_inside: The same for the other reading.
    """

    side: str
    own_fraction: float
    other_fraction: float
    own_closest: float
    other_closest: float
    own_inside: float
    other_inside: float

    @property
    def reading(self) -> str | None:
        """``"own"`` or ``"other"``: the only reading that touches the object, or None.

        "Touches": in at least :data:`SIDE_CONTACT_FRACTION` of the frames, the other reading in none.
        """
        if self.own_fraction >= SIDE_CONTACT_FRACTION and self.other_fraction == 0.0:
            return "own"
        if self.other_fraction >= SIDE_CONTACT_FRACTION and self.own_fraction == 0.0:
            return "other"
        return None

    def line(self) -> str:
        """One line of evidence."""
        other = HANDS[1 - HANDS.index(self.side)]
        return (
            f"'{self.side}' driving the {self.side} model touches the object in {self.own_fraction:.0%} of "
            f"the frames (closest {self.own_closest * 1000:.0f} mm, inside it in {self.own_inside:.0%}), "
            f"driving the {other} model in {self.other_fraction:.0%} (closest "
            f"{self.other_closest * 1000:.0f} mm, inside it in {self.other_inside:.0%})"
        )


@dataclass(frozen=True)
class SideCheck:
    """Whether a sequence's ``right`` and ``left`` entries hold the hands their keys name (a heuristic).

    Attributes:
        verdict: ``"as stored"`` (a hand touches the object only as stored, and none only mirrored),
            ``"swapped"`` (both hands touch it only when each entry drives the other hand's model: flagged,
            :attr:`flags`) or ``"not judged"``.
        right: The evidence of the ``right`` entry.
        left: The evidence of the ``left`` entry.
        message: One line for the user.
    """

    verdict: str
    right: HandContact
    left: HandContact
    message: str

    @property
    def flags(self) -> tuple[Flag, ...]:
        """The ``hands_swapped`` flag of a ``"swapped"`` verdict (not valid), none for the others.

        A replay of swapped hands drives each MANO model with the other hand's data, so its numbers judge
        nothing; the trajectory carries the flag (:attr:`Trajectory.flags`) into every replay's flags.
        """
        if self.verdict != "swapped":
            return ()
        values = {
            entry.side: {
                "own_fraction": entry.own_fraction,
                "other_fraction": entry.other_fraction,
                "own_closest_mm": entry.own_closest * 1000.0,
                "other_closest_mm": entry.other_closest * 1000.0,
                "own_inside_fraction": entry.own_inside,
                "other_inside_fraction": entry.other_inside,
            }
            for entry in (self.right, self.left)
        }
        return (Flag("hands_swapped", True, self.message, {"verdict": self.verdict, **values}),)


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
    rotation = quat_to_matrix(trajectory.root_pose[:, 3:])
    return trajectory.root_pose[:, None, :3] + local @ np.swapaxes(rotation, 1, 2)


def surface_distances(
    obj: ObjectModel, track: ObjectTrack, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per frame, how close ``points`` (N, P, 3) come to the object's surface and how deep they go into it.

    The root part follows the track's pose; the second part also turns by the articulation about the
    object's hinge (ARCTIC: ``R_z(−θ)`` for the hinge axis (0, 0, −1)). The surface is sampled at the centres
    of its triangles subdivided to :data:`SURFACE_SPACING_M`; a point is inside a watertight part when it
    lies behind the outward normal of its nearest sample (open parts are never entered).

    Returns:
        The smallest distance from any point to the surface, metres (N,), and the largest depth of a point
        inside the object, metres (N,; 0 when none is inside).
    """
    import trimesh  # lazy: trimesh and SciPy (0.2-0.7 s), only where an ARCTIC fit is checked against
    from scipy.spatial import cKDTree  # its object: a glove replay imports this module and needs neither

    n = len(points)
    pos, quat = track.pose[:, :3], track.pose[:, 3:]
    rotation = quat_to_matrix(quat)
    in_object = np.einsum("nji,npj->npi", rotation, points - pos[:, None])  # Rᵀ (p − t)
    closest = np.full(n, np.inf)
    deepest = np.zeros(n)
    for index, part in enumerate(obj.parts):
        vertices, faces = trimesh.remesh.subdivide_to_size(
            part.mesh.vertices, part.mesh.faces, SURFACE_SPACING_M
        )
        surface = trimesh.Trimesh(vertices, faces, process=False)
        local = in_object
        if index > 0 and obj.hinge is not None and track.articulation is not None:
            axis = np.asarray(obj.hinge.axis, dtype=float)
            turn = axis_angle_to_matrix(axis[None, :] * np.asarray(track.articulation)[:, None])
            pivot = np.asarray(obj.hinge.pos, dtype=float)
            local = np.einsum("nji,npj->npi", turn, in_object - pivot) + pivot
        flat = local.reshape(-1, 3)
        distance, nearest = cKDTree(surface.triangles_center).query(flat)
        closest = np.minimum(closest, distance.reshape(n, -1).min(axis=1))
        if part.mesh.watertight:
            offset = flat - surface.triangles_center[nearest]
            behind = -np.einsum("ij,ij->i", offset, surface.face_normals[nearest])
            deepest = np.maximum(deepest, np.maximum(behind, 0.0).reshape(n, -1).max(axis=1))
    return closest, deepest


def hand_contact(
    sequence: ArcticSequence, side: str, hands: Mapping[str, tuple[Skeleton, MANOModel]], obj: ObjectModel
) -> HandContact:
    """How the ``side`` entry's data meet the object, read by its own model and by the other hand's.

    Args:
        sequence: The sequence.
        side: The entry.
        hands: Both hands' skeletons and models (see :func:`hand_side_check`).
        obj: The sequence's object.

    Returns:
        The contact fractions, closest approaches and penetration fractions of both readings.

    Raises:
        TrajectoryError: A hand missing from ``hands``, or a skeleton/model of the wrong side.
        HandsimError: ``side`` is neither ``"right"`` nor ``"left"``.
    """
    seq = sequence.hand(side)
    other = HANDS[1 - HANDS.index(side)]
    for s in HANDS:
        if s not in hands:
            raise TrajectoryError(f"the side check needs both hands; {s!r} is missing")
        skeleton, model = hands[s]
        if skeleton.name != f"mano_{s}" or model.side != s:
            raise TrajectoryError(
                f"hands[{s!r}] holds a {skeleton.name} skeleton and a {model.side} model; "
                f"expected the {s} hand's"
            )
    result = {}
    for reading in (side, other):
        skeleton, model = hands[reading]
        d, depth = surface_distances(obj, sequence.object, hand_points(seq, skeleton, model, sequence.fps))
        touching = float(np.mean((d <= CONTACT_M) & (depth <= PENETRATION_M)))
        result[reading] = (touching, float(d.min()), float(np.mean(depth > PENETRATION_M)))
    (fo, co, io), (ft, ct, it) = result[side], result[other]
    return HandContact(side, fo, ft, co, ct, io, it)


def hand_side_check(
    sequence: ArcticSequence, hands: Mapping[str, tuple[Skeleton, MANOModel]], obj: ObjectModel
) -> SideCheck:
    """Check, heuristically, that the ``right`` and ``left`` entries hold those hands (see the module notes).

    Each entry's data drive its own model and the other hand's (:func:`hand_contact`). A reading that
    touches the object while the other never does is that entry's plausible one. The sequence is flagged
    ``"swapped"`` only when both entries are plausible only mirrored: a hand idle in its own reading can land
    on the object when displaced by the other model, so one entry alone never flags.

    Args:
        sequence: The sequence.
        hands: Both hands' skeletons and models (``{s: (h.skeleton, h.model)}`` of
            :func:`handsim.builders.mano_hand.build_mano_hands`); each entry's mirrored reading uses the
            other hand's skeleton (its betas are the other entry's, a difference of millimetres).
        obj: The sequence's object (:func:`handsim.builders.arctic_objects.arctic_object`).

    Returns:
        The verdict with both entries' evidence.

    Raises:
        TrajectoryError: A hand missing from ``hands``, or a skeleton/model of the wrong side.
    """
    right, left = (hand_contact(sequence, side, hands, obj) for side in HANDS)
    readings = (right.reading, left.reading)
    evidence = f"{right.line()}; {left.line()}"
    where = sequence.mano_path
    if readings == ("other", "other"):
        verdict = "swapped"
        message = (
            f"{where}: 'right' and 'left' look swapped (heuristic): each hand touches the "
            f"{sequence.object_name} only when driving the other hand's model: {evidence}; check the file's "
            "'right'/'left' entries"
        )
    elif "other" in readings:
        verdict = "not judged"
        message = (
            f"{where}: sides not judged: one entry touches the {sequence.object_name} only mirrored, the "
            f"other does not agree (an idle hand's mirror image can land on the object): {evidence}"
        )
    elif "own" in readings:
        verdict = "as stored"
        message = f"{where}: the hands are as stored (heuristic): {evidence}"
    else:
        verdict = "not judged"
        message = (
            f"{where}: sides not judged: neither hand touches the {sequence.object_name} in one reading "
            f"only: {evidence}"
        )
    return SideCheck(verdict, right, left, message)


def arctic_trajectory(
    sequence: ArcticSequence, hands: Mapping[str, tuple[Skeleton, MANOModel]]
) -> Trajectory:
    """Both hands of an ARCTIC sequence as one trajectory for a two-hand scene.

    Each hand's :func:`arctic_hand_trajectory`, joined by
    :func:`handsim.datatypes.trajectory_ops.join_hands`: its DoF
    columns renamed ``<side>/<dof>`` and its root pose under ``hand_roots[side]``; the object track under
    ``sequence.object_name``.

    Args:
        sequence: The sequence.
        hands: Side → the hand's skeleton (built with the sequence's betas for that side) and MANO model; the
            sides given are the hands converted, in this order.

    Returns:
        The trajectory (times ``i / sequence.fps``; ``source`` the ``.mano.npy``, ``sha256`` its hash).

    Raises:
        TrajectoryError: See :func:`arctic_hand_trajectory`.
    """
    return join_hands({side: arctic_hand_trajectory(sequence, side, *hands[side]) for side in hands})
