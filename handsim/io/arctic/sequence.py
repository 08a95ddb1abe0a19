"""Readers for ARCTIC motion: ``raw_seqs/<subject>/<seq>.mano.npy`` and ``<seq>.object.npy`` (spec ``004_…``).

The layout below is that of the real files (``../shared/data/SOURCES.md``, checked against ARCTIC's loader):

* ``*.mano.npy`` — ``np.save`` of a dict ``{'left', 'right'}`` (a 0-d object array, read with the restricted
  unpickler of :mod:`handsim.io.safe_pickle`). Sequences are bimanual: **both hands are always present**.
  Each hand is ``{'rot' (N, 3) axis-angle, 'pose' (N, 45) axis-angle, 'trans' (N, 3) metres, 'shape' (10,)
  (the spec's per-frame (N, 10) is accepted when constant), 'fitting_err'}``; ``fitting_err`` is a **plain
  Python list of N floats** in the real files (an array is accepted too). ARCTIC's code feeds these to
  smplx's MANO with ``flat_hand_mean=False``: the pose is relative to MANO's mean hand pose.
* ``*.object.npy`` — float32 (N, 7): articulation (rad), axis-angle (3), translation (3) in **millimetres**.
  A template vertex ``v`` (object frame) is at ``R(ω) · v + t`` for the bottom part and
  ``R(ω) · R_z(−θ) · v + t`` for the top part, i.e. the top turns by θ about the object-frame axis
  (0, 0, −1), the hinge of :func:`handsim.io.arctic.templates.read_arctic_template`. The world is z-up.

Plausibility gates (the files declare no units, so an implausible magnitude is an error, never a guess;
every message names the file, the field, the frame and what was expected):

* units: MANO translations beyond :data:`MANO_TRANS_LIMIT_M` in most frames mean millimetres; object
  translations all within :data:`OBJECT_TRANS_MIN_MM` of the origin mean metres; an articulation beyond
  2π means degrees;
* capture volume: a single frame beyond :data:`MANO_TRANS_LIMIT_M` (hands) or :data:`OBJECT_TRANS_LIMIT_MM`
  (objects) is a corrupted frame (e.g. a ×1000 spike);
* speed: a hand or the object moving faster than :data:`MAX_HAND_SPEED` / :data:`MAX_OBJECT_SPEED` between
  two frames (at :data:`ARCTIC_FPS`) is a jump no human motion makes;
* shape: a beta beyond :data:`MANO_BETA_LIMIT` is a corrupted or mis-scaled shape;
* frame counts: per-frame fields of different lengths name the field that differs from the others;
* the two hands holding identical data (one hand's data copied into the other's entry) is refused.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.datatypes.rotations import axis_angle_to_quat
from handsim.datatypes.trajectory import ObjectTrack
from handsim.errors import FormatError, HandsimError, InputFileError
from handsim.io.arctic.mano_file import read_arctic_mano, read_hands
from handsim.io.arctic.mano_pose import MANOSequence
from handsim.io.arctic.motion_checks import (
    ARCTIC_FPS,
    ARCTIC_OBJECTS,
    ARTICULATION_LIMIT_RAD,
    HANDS,
    MANO_BETA_LIMIT,
    MANO_FIELDS,
    MANO_TRANS_LIMIT_M,
    MAX_HAND_SPEED,
    MAX_OBJECT_SPEED,
    OBJECT_TRANS_LIMIT_MM,
    OBJECT_TRANS_MIN_MM,
    PER_FRAME_FIELDS,
    check_fps,
    check_track,
    file_sha256,
    float_field,
)
from handsim.io.safe_pickle import load_npy

__all__ = [
    "ARCTIC_FPS",
    "ARCTIC_OBJECTS",
    "ARTICULATION_LIMIT_RAD",
    "HANDS",
    "MANO_BETA_LIMIT",
    "MANO_FIELDS",
    "MANO_TRANS_LIMIT_M",
    "MAX_HAND_SPEED",
    "MAX_OBJECT_SPEED",
    "OBJECT_TRANS_LIMIT_MM",
    "OBJECT_TRANS_MIN_MM",
    "PER_FRAME_FIELDS",
    "ArcticSequence",
    "object_motion_path",
    "read_arctic_mano",
    "read_arctic_object",
    "read_arctic_sequence",
]


@dataclass(frozen=True)
class ArcticSequence:
    """One ARCTIC sequence: both hands' MANO parameters and the object's pose and articulation.

    Attributes:
        right: The right hand (``side="right"``).
        left: The left hand (``side="left"``).
        object: The object track: pose (N, 7) in metres and quaternions (w, x, y, z), articulation (N,) rad.
        object_name: The object, from the file name (``box_grab_01`` → ``box``).
        subject: The subject folder (``s01``), or "".
        fps: Frames per second the time stamps and speed gates use.
        mano_path: The ``.mano.npy`` file.
        object_path: The ``.object.npy`` file.
        object_sha256: SHA-256 of the object file (the hands carry their file's hash).
        notes: Decisions made while reading.
    """

    right: MANOSequence
    left: MANOSequence
    object: ObjectTrack
    object_name: str
    subject: str
    fps: float
    mano_path: str
    object_path: str
    object_sha256: str
    notes: tuple[str, ...] = ()

    @property
    def nframes(self) -> int:
        """Number of frames N."""
        return self.right.nframes

    @property
    def name(self) -> str:
        """The sequence name (``box_grab_01``)."""
        return Path(self.mano_path).name.removesuffix(".mano.npy")

    def hand(self, side: str) -> MANOSequence:
        """The ``"right"`` or ``"left"`` hand.

        Raises:
            HandsimError: ``side`` is neither.
        """
        if side not in HANDS:
            raise HandsimError(f"hand must be 'right' or 'left', got {side!r}")
        return self.right if side == "right" else self.left

    @property
    def articulation_range(self) -> tuple[float, float]:
        """Smallest and largest recorded articulation, radians."""
        art = np.asarray(self.object.articulation, dtype=float)
        return float(art.min()), float(art.max())


def read_arctic_object(path: str | Path, *, fps: float = ARCTIC_FPS) -> ObjectTrack:
    """Read an ARCTIC ``*.object.npy`` file as an object pose track in SI units.

    Args:
        path: The ``.object.npy`` file, float (N, 7) = [articulation rad, axis-angle (3), translation mm (3)].
        fps: Frame rate for the speed gate, Hz.

    Returns:
        ``pose`` (N, 7): translation in metres and the quaternion (w, x, y, z) of the axis-angle;
        ``articulation`` (N,) in radians about the object-frame axis (0, 0, −1); ``valid`` all True.

    Raises:
        InputFileError: The file does not exist.
        FormatError: A non-float dtype, a shape other than (N, 7), no frames, non-finite values,
            translations that look like metres, a frame beyond :data:`OBJECT_TRANS_LIMIT_MM`, a jump
            faster than :data:`MAX_OBJECT_SPEED`, or an articulation that looks like degrees (the message
            names file, field and frame).
        HandsimError: A non-positive ``fps``.
    """
    check_fps(fps)
    p = Path(path)
    array = load_npy(p)
    values = float_field(p, "object", array, (None, 7))
    articulation, rotvec, translation = values[:, 0], values[:, 1:4], values[:, 4:7]
    n = len(values)
    if n == 0:
        raise FormatError(p, "no frames", field="object")
    largest = float(np.linalg.norm(translation, axis=1).max())
    if largest < OBJECT_TRANS_MIN_MM:
        raise FormatError(
            p,
            f"every translation is shorter than {OBJECT_TRANS_MIN_MM:g} (largest {largest:.4g}); "
            "ARCTIC object translations are millimetres, so these look like metres",
            field="translation",
        )
    check_track(
        p, "translation", translation, limit=OBJECT_TRANS_LIMIT_MM, speed=MAX_OBJECT_SPEED, fps=fps,
        unit="mm", what="the object",
    )  # fmt: skip
    turned = float(np.abs(articulation).max())
    if turned > ARTICULATION_LIMIT_RAD:
        raise FormatError(
            p,
            f"articulation reaches {turned:.4g}; ARCTIC articulations are radians (≤ 2π)",
            field="articulation",
        )
    pose = np.concatenate([translation / 1000.0, axis_angle_to_quat(rotvec)], axis=1)
    return ObjectTrack(pose=pose, articulation=articulation.copy(), valid=np.ones(n, dtype=bool))


def object_motion_path(mano_path: str | Path) -> Path:
    """The ``<seq>.object.npy`` beside a ``<seq>.mano.npy``."""
    p = Path(mano_path)
    return p.with_name(p.name.removesuffix(".mano.npy") + ".object.npy")


def read_arctic_sequence(
    mano_path: str | Path, object_path: str | Path | None = None, *, fps: float = ARCTIC_FPS
) -> ArcticSequence:
    """Read an ARCTIC sequence: both hands and the object, validated together.

    Args:
        mano_path: ``raw_seqs/<subject>/<seq>.mano.npy``.
        object_path: The object motion; by default ``<seq>.object.npy`` beside ``mano_path``.
        fps: Frame rate, Hz (time stamps and speed gates).

    Returns:
        The sequence; the object name is the file name's first ``_``-separated word.

    Raises:
        InputFileError: Either file is missing (the message says which file the sequence needs).
        FormatError: Anything :func:`read_arctic_mano` or :func:`read_arctic_object` refuses, or hands and
            object of different frame counts.
        HandsimError: A non-positive ``fps``.
    """
    check_fps(fps)
    mano = Path(mano_path)
    if not mano.name.endswith(".mano.npy"):
        raise InputFileError(f"{mano}: not an ARCTIC MANO sequence (expected <seq>.mano.npy)")
    if not mano.is_file():
        raise InputFileError(f"{mano}: file not found")
    obj = Path(object_path) if object_path is not None else object_motion_path(mano)
    if not obj.is_file():
        raise InputFileError(
            f"{obj}: file not found; the ARCTIC sequence {mano.name} needs its object motion "
            f"{obj.name} (from the same raw_seqs folder)"
        )
    hands = read_hands(mano, fps)
    track = read_arctic_object(obj, fps=fps)
    n = hands["right"].nframes
    if len(track.pose) != n:
        raise FormatError(
            obj,
            f"{len(track.pose)} frames, but {mano.name} has {n}; expected one object pose per hand frame",
            field="object",
        )
    stem = mano.name.removesuffix(".mano.npy")
    name = stem.split("_")[0]
    notes = []
    if name not in ARCTIC_OBJECTS:
        notes.append(f"object {name!r} (from the file name) is not one of ARCTIC's {len(ARCTIC_OBJECTS)}")
    return ArcticSequence(
        right=hands["right"],
        left=hands["left"],
        object=track,
        object_name=name,
        subject=mano.parent.name,
        fps=float(fps),
        mano_path=str(mano),
        object_path=str(obj),
        object_sha256=file_sha256(obj),
        notes=tuple(notes),
    )
