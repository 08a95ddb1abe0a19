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

import hashlib
import math
import numbers
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from handsim.datatypes.rotations import axis_angle_to_quat
from handsim.datatypes.trajectory import ObjectTrack
from handsim.errors import FormatError, HandsimError, InputFileError
from handsim.io.arctic.mano_pose import MANOSequence
from handsim.io.safe_pickle import load_npy

ARCTIC_FPS = 30.0
"""Frames per second of ARCTIC's ``raw_seqs`` (one row per image frame of its 30 fps videos). Used for time
stamps and the speed gates; the gates are generous enough that a rate off by 2× does not change a verdict."""

ARCTIC_OBJECTS: tuple[str, ...] = (
    "box",
    "capsulemachine",
    "espressomachine",
    "ketchup",
    "laptop",
    "microwave",
    "mixer",
    "notebook",
    "phone",
    "scissors",
    "waffleiron",
)
"""ARCTIC's 11 objects (``OBJECTS`` of ARCTIC's ``common/object_tensors.py``)."""

HANDS: tuple[str, ...] = ("right", "left")
"""The entries of a ``.mano.npy`` file; both are required."""

MANO_TRANS_LIMIT_M = 5.0
"""Largest plausible |MANO translation component| in metres: ARCTIC's capture volume is a few metres
across. Beyond it in most frames: the file holds millimetres; in a few frames: those frames are corrupted."""

OBJECT_TRANS_MIN_MM = 5.0
"""If every object translation is shorter than this (in the file's mm), the file holds metres."""

OBJECT_TRANS_LIMIT_MM = 5000.0
"""Largest plausible |object translation| in millimetres (the same capture volume as the hands')."""

MAX_HAND_SPEED = 10.0
"""Largest plausible hand speed in m/s between two frames. Reach-to-grasp movements peak near 1–2 m/s and the
fastest arm movements (a boxer's straight punch) near 10 m/s; a ×1000 unit spike or a swapped frame moves
the hand hundreds of m/s."""

MAX_OBJECT_SPEED = 10.0
"""Largest plausible object speed in m/s: the object moves only with the hands that carry it."""

ARTICULATION_LIMIT_RAD = 2.0 * math.pi
"""Largest plausible |articulation| in radians; larger values mean degrees."""

MANO_BETA_LIMIT = 10.0
"""Largest plausible |MANO shape coefficient| (beta). MANO's shape space is PCA-whitened: betas are in
standard deviations of the training scans, so fitted hands lie within a few units of 0 and 10 standard
deviations is already far beyond any human hand. A larger beta is a corrupted or mis-scaled file, and
building it gives a hand metres across whose replay diverges without naming the betas."""

MANO_FIELDS = ("rot", "pose", "trans", "shape", "fitting_err")

PER_FRAME_FIELDS = ("rot", "pose", "trans")
"""The required MANO fields holding one row per frame; their common length is the frame count that
``shape`` (when given per frame) and ``fitting_err`` are checked against."""


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


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _shape_text(shape: tuple[int | None, ...]) -> str:
    inner = ", ".join("N" if s is None else str(s) for s in shape)
    return f"({inner}{',' if len(shape) == 1 else ''})"


def _float_field(
    path: Path, field: str, value: Any, shape: tuple[int | None, ...], axes: tuple[str, ...] = ("frame",)
) -> np.ndarray:
    """A finite floating-point array of the given shape (None = any length), else a FormatError.

    ``axes`` names what the leading indices count, for the message of a non-finite value (``("beta",)``
    for a shape vector: "non-finite value at beta 3", not "at frame 3").
    """
    if not isinstance(value, np.ndarray):
        raise FormatError(path, f"expected a numpy array, got {type(value).__name__}", field=field)
    if value.dtype.kind != "f":
        raise FormatError(path, f"expected floating-point values, got dtype {value.dtype}", field=field)
    if value.ndim != len(shape) or any(
        s is not None and s != n for s, n in zip(shape, value.shape, strict=True)
    ):
        raise FormatError(path, f"expected shape {_shape_text(shape)}, got {value.shape}", field=field)
    bad = ~np.isfinite(value)
    if bad.any():
        index = np.argwhere(bad)[0]
        where = ", ".join(f"{axis} {int(i)}" for axis, i in zip(axes, index, strict=False))
        raise FormatError(path, f"non-finite value at {where}", field=field)
    return value.astype(float)


def _fitting_err(path: Path, field: str, value: Any, n: int) -> np.ndarray:
    """ARCTIC's per-frame fitting error: a list of N floats (real files) or an (N,) float array."""
    if isinstance(value, np.ndarray):
        return _float_field(path, field, value, (n,))
    if not isinstance(value, (list, tuple)):
        raise FormatError(
            path, f"expected a list of {n} floats (one per frame), got {type(value).__name__}", field=field
        )
    for i, item in enumerate(value):
        if isinstance(item, bool) or not isinstance(item, numbers.Real):
            raise FormatError(
                path, f"entry {i} is {type(item).__name__} {item!r}; expected a number", field=field
            )
    if len(value) != n:
        raise FormatError(path, f"expected {n} values (one per frame), got {len(value)}", field=field)
    array = np.asarray(value, dtype=float)
    bad = ~np.isfinite(array)
    if bad.any():
        raise FormatError(path, f"non-finite value at frame {int(np.argmax(bad))}", field=field)
    return array


def _check_track(
    path: Path,
    field: str,
    positions: np.ndarray,
    *,
    limit: float,
    speed: float,
    fps: float,
    unit: str,
    what: str,
) -> None:
    """Refuse a frame outside the capture volume or a jump faster than ``speed`` m/s (positions in unit)."""
    scale = 1000.0 if unit == "mm" else 1.0
    distance = np.linalg.norm(positions, axis=1)
    far = np.flatnonzero(distance > limit)
    if len(far):
        k = int(far[0])
        raise FormatError(
            path,
            f"frame {k}: {what} is {distance[k]:.4g} {unit} from the origin, beyond the {limit:g} {unit} of "
            f"a capture volume ({len(far)} such frame{'s' if len(far) > 1 else ''}); a corrupted or "
            "mis-scaled frame",
            field=field,
        )
    if len(positions) < 2:
        return
    jumps = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    k = int(np.argmax(jumps))
    allowed = speed / fps * scale
    if jumps[k] > allowed:
        raise FormatError(
            path,
            f"frame {k + 1}: {what} jumps {jumps[k]:.4g} {unit} from frame {k} "
            f"({jumps[k] / scale * fps:.4g} m/s at {fps:g} fps); expected at most {allowed:.4g} {unit} per "
            f"frame ({speed:g} m/s)",
            field=field,
        )


def _load_hands(path: Path) -> dict[str, dict]:
    """The ``{'right', 'left'}`` dict of a ``.mano.npy`` file, both entries dicts."""
    array = load_npy(path)
    if array.dtype != object or array.shape != ():
        raise FormatError(
            path,
            "expected a pickled dict {'left', 'right'} (0-d object array), "
            f"got {array.dtype} {array.shape}",
        )
    data = array.item()
    if not isinstance(data, dict):
        raise FormatError(path, f"expected a pickled dict {{'left', 'right'}}, got {type(data).__name__}")
    for hand in HANDS:
        if hand not in data:
            raise FormatError(
                path,
                f"no {hand!r} entry; entries are {sorted(map(str, data))}. ARCTIC sequences are bimanual: "
                "a .mano.npy holds both 'right' and 'left'",
                field=hand,
            )
        if not isinstance(data[hand], dict):
            raise FormatError(
                path, f"expected a dict of MANO fields, got {type(data[hand]).__name__}", field=hand
            )
    return data


def _check_frame_counts(path: Path, hand: str, entry: dict) -> None:
    """Refuse per-frame fields of different lengths, naming the one that differs from the others.

    Fields that are not sized sequences are left to the per-field checks that follow.
    """
    lengths: dict[str, int] = {}
    for name in PER_FRAME_FIELDS:
        value = entry.get(name)
        if isinstance(value, np.ndarray) and value.ndim >= 1:
            lengths[name] = value.shape[0]
        elif isinstance(value, (list, tuple)):
            lengths[name] = len(value)
    if len(set(lengths.values())) < 2:
        return
    counts = list(lengths.values())
    common = max(counts, key=lambda n: (counts.count(n), n))
    odd = next(name for name, n in lengths.items() if n != common)
    others = [f"{hand}.{name}" for name, n in lengths.items() if n == common]
    listed = others[0] if len(others) == 1 else ", ".join(others[:-1]) + " and " + others[-1]
    raise FormatError(
        path,
        f"{lengths[odd]} frames, but {listed} {'has' if len(others) == 1 else 'have'} {common}; expected "
        "one row per frame in every field (a truncated or misaligned field)",
        field=f"{hand}.{odd}",
    )


def _check_betas(path: Path, field: str, betas: np.ndarray, axes: tuple[str, ...]) -> None:
    """Refuse a beta beyond :data:`MANO_BETA_LIMIT`, naming its index (and frame) and value."""
    far = np.abs(betas) > MANO_BETA_LIMIT
    if not far.any():
        return
    index = tuple(int(i) for i in np.argwhere(far)[0])
    where = ", ".join(f"{axis} {i}" for axis, i in zip(axes, index, strict=True))
    raise FormatError(
        path,
        f"{where} is {float(betas[index]):.4g} ({int(far.sum())} beyond the limit); MANO betas are in "
        "standard deviations of its shape space and fitted hands lie within a few units of 0, expected "
        f"|beta| ≤ {MANO_BETA_LIMIT:g}: a corrupted or mis-scaled shape",
        field=field,
    )


def _hand(path: Path, hand: str, entry: dict, fps: float, sha256: str) -> MANOSequence:
    missing = [k for k in MANO_FIELDS[:4] if k not in entry]
    if missing:
        raise FormatError(path, f"missing {missing}; a MANO entry has {list(MANO_FIELDS)}", field=hand)
    _check_frame_counts(path, hand, entry)
    rot = _float_field(path, f"{hand}.rot", entry["rot"], (None, 3))
    n = rot.shape[0]
    if n == 0:
        raise FormatError(path, "no frames", field=f"{hand}.rot")
    raw_pose = entry["pose"]
    if isinstance(raw_pose, np.ndarray) and raw_pose.ndim == 2 and raw_pose.shape[1] != 45:
        raise FormatError(
            path,
            f"expected 45 values per frame (15 joints × 3 axis-angle), got {raw_pose.shape[1]}",
            field=f"{hand}.pose",
        )
    pose = _float_field(path, f"{hand}.pose", raw_pose, (n, 45))
    trans = _float_field(path, f"{hand}.trans", entry["trans"], (n, 3))
    notes: list[str] = []
    raw_shape = entry["shape"]
    if isinstance(raw_shape, np.ndarray) and raw_shape.ndim == 2:
        shapes = _float_field(path, f"{hand}.shape", raw_shape, (n, 10), ("frame", "beta"))
        _check_betas(path, f"{hand}.shape", shapes, ("frame", "beta"))
        spread = float(np.ptp(shapes, axis=0).max())
        shape = shapes.mean(axis=0)
        notes.append(f"{hand}.shape given per frame; their mean used (largest spread {spread:.1e})")
    else:
        shape = _float_field(path, f"{hand}.shape", raw_shape, (10,), ("beta",))
        _check_betas(path, f"{hand}.shape", shape, ("beta",))
    fitting_err = None
    if entry.get("fitting_err") is not None:
        fitting_err = _fitting_err(path, f"{hand}.fitting_err", entry["fitting_err"], n)
    else:
        notes.append(f"{hand}: no fitting_err in the file")
    largest = np.abs(trans).max(axis=1)
    if np.median(largest) > MANO_TRANS_LIMIT_M:
        raise FormatError(
            path,
            f"translation component reaches {float(largest.max()):.4g}; MANO translations are metres and a "
            f"hand more than {MANO_TRANS_LIMIT_M:g} m from the origin means the file holds millimetres",
            field=f"{hand}.trans",
        )
    _check_track(
        path, f"{hand}.trans", trans, limit=MANO_TRANS_LIMIT_M, speed=MAX_HAND_SPEED, fps=fps,
        unit="m", what="the hand",
    )  # fmt: skip
    return MANOSequence(
        rot=rot,
        pose=pose,
        trans=trans,
        shape=shape,
        fitting_err=fitting_err,
        side=hand,
        source=str(path),
        sha256=sha256,
        notes=tuple(notes),
    )


def _read_hands(path: Path, fps: float) -> dict[str, MANOSequence]:
    data = _load_hands(path)
    sha = _sha256(path)
    hands = {hand: _hand(path, hand, data[hand], fps, sha) for hand in HANDS}
    right, left = hands["right"], hands["left"]
    if right.nframes != left.nframes:
        raise FormatError(
            path,
            f"the right hand has {right.nframes} frames and the left {left.nframes}; expected the same",
            field="left.rot",
        )
    if np.array_equal(right.trans, left.trans) and np.array_equal(right.pose, left.pose):
        raise FormatError(
            path,
            "'right' and 'left' hold identical trans and pose in every frame: one hand's data was copied "
            "into the other's entry (two hands cannot share a place); expected each hand's own fit",
            field="right",
        )
    return hands


def _check_fps(fps: float) -> None:
    if not (isinstance(fps, numbers.Real) and math.isfinite(fps) and fps > 0):
        raise HandsimError(f"fps must be a positive number, got {fps!r}")


def read_arctic_mano(path: str | Path, hand: str = "right", *, fps: float = ARCTIC_FPS) -> MANOSequence:
    """Read one hand of an ARCTIC ``*.mano.npy`` file (both hands are validated).

    Args:
        path: The ``.mano.npy`` file.
        hand: ``"right"`` or ``"left"``.
        fps: Frame rate for the speed gate, Hz.

    Returns:
        The hand's MANO parameters (rot and pose in rad, trans in m, shape (10,), fitting_err (N,) as
        stored); ``side`` = ``hand``. Poses are relative to MANO's mean pose (``flat_hand_mean=False``).

    Raises:
        InputFileError: The file does not exist.
        FormatError: Not a pickled ``{'left', 'right'}`` dict, a missing hand, a refused pickle global, a
            missing field, a field of the wrong type, dtype or shape (pose not 45 values per frame;
            fitting_err not one number per frame), non-finite values, translations that look like
            millimetres, a frame outside the capture volume or a jump faster than :data:`MAX_HAND_SPEED`,
            a beta beyond :data:`MANO_BETA_LIMIT`, per-frame fields of different lengths, hands of
            different lengths or identical hands. The message names the file and the field
            (``right.pose``).
        HandsimError: ``hand`` is neither ``"right"`` nor ``"left"``, or a non-positive ``fps``.
    """
    if hand not in HANDS:
        raise HandsimError(f"hand must be 'right' or 'left', got {hand!r}")
    _check_fps(fps)
    return _read_hands(Path(path), fps)[hand]


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
    _check_fps(fps)
    p = Path(path)
    array = load_npy(p)
    values = _float_field(p, "object", array, (None, 7))
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
    _check_track(
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
    _check_fps(fps)
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
    hands = _read_hands(mano, fps)
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
        object_sha256=_sha256(obj),
        notes=tuple(notes),
    )
