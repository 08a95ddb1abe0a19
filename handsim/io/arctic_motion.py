"""Readers for ARCTIC motion: ``raw_seqs/<subject>/<seq>.mano.npy`` and ``<seq>.object.npy`` (spec ``004_…``).

* ``*.mano.npy`` — ``np.save`` of a dict ``{'left', 'right'}`` (a 0-d object array, read with the restricted
  unpickler of :mod:`handsim.io.safe_pickle`), each ``{'rot' (N, 3) axis-angle, 'pose' (N, 45) axis-angle,
  'trans' (N, 3) metres, 'shape' (10,) (the spec's per-frame (N, 10) is accepted when constant),
  'fitting_err' (N,)}``. ARCTIC's code feeds these to smplx's MANO with ``flat_hand_mean=False``: the
  pose is relative to MANO's mean hand pose.
* ``*.object.npy`` — float32 (N, 7): articulation (rad), axis-angle (3), translation (3) in **millimetres**.
  A template vertex ``v`` (object frame) is at ``R(ω) · v + t`` for the bottom part and
  ``R(ω) · R_z(−θ) · v + t`` for the top part, i.e. the top turns by θ about the object-frame axis
  (0, 0, −1), the hinge of :func:`handsim.io.arctic.read_arctic_template`.

Unit checks (the files declare no units, so implausible magnitudes are errors, not guesses):

* a MANO translation component beyond :data:`MANO_TRANS_LIMIT_M` (5 m) means millimetres were stored;
* object translations all within :data:`OBJECT_TRANS_MIN_MM` (5 mm) of the origin mean metres were stored
  (ARCTIC objects are carried tens of centimetres through a capture volume metres wide);
* an articulation beyond 2π means degrees.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path
from typing import Any

import numpy as np

from handsim.errors import FormatError, HandsimError
from handsim.io.mano import MANOSequence, axis_angle_to_quat
from handsim.io.safe_pickle import load_npy
from handsim.trajectory import ObjectTrack

MANO_TRANS_LIMIT_M = 5.0
"""Largest plausible |MANO translation component| in metres; larger values mean the file holds mm."""

OBJECT_TRANS_MIN_MM = 5.0
"""If every object translation is shorter than this (in the file's mm), the file holds metres."""

ARTICULATION_LIMIT_RAD = 2.0 * math.pi
"""Largest plausible |articulation| in radians; larger values mean degrees."""

MANO_FIELDS = ("rot", "pose", "trans", "shape", "fitting_err")


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _float_field(path: Path, field: str, value: Any, shape: tuple[int | None, ...]) -> np.ndarray:
    """A finite floating-point array of the given shape (None = any length), else a FormatError."""
    if not isinstance(value, np.ndarray):
        raise FormatError(path, f"expected a numpy array, got {type(value).__name__}", field=field)
    if value.dtype.kind != "f":
        raise FormatError(path, f"expected floating-point values, got dtype {value.dtype}", field=field)
    if value.ndim != len(shape) or any(
        s is not None and s != n for s, n in zip(shape, value.shape, strict=True)
    ):
        want = (
            "("
            + ", ".join("N" if s is None else str(s) for s in shape)
            + ("," if len(shape) == 1 else "")
            + ")"
        )
        raise FormatError(path, f"expected shape {want}, got {value.shape}", field=field)
    bad = ~np.isfinite(value)
    if bad.any():
        frame = int(np.argwhere(bad)[0][0])
        raise FormatError(path, f"non-finite value at frame {frame}", field=field)
    return value.astype(float)


def read_arctic_mano(path: str | Path, hand: str = "right") -> MANOSequence:
    """Read one hand of an ARCTIC ``*.mano.npy`` file.

    Args:
        path: The ``.mano.npy`` file.
        hand: ``"right"`` or ``"left"``.

    Returns:
        The hand's MANO parameters (rot and pose in rad, trans in m, shape (10,)); ``side`` = ``hand``.
        Poses are stored relative to MANO's mean pose (convert with ``flat_hand_mean=False``).

    Raises:
        InputFileError: The file does not exist.
        FormatError: Not a pickled ``{'left', 'right'}`` dict, a refused pickle global, a missing field,
            a field of the wrong dtype or shape (pose not 45 values per frame), non-finite values, or
            translations that look like millimetres. The message names the file and the field
            (``right.pose``).
        HandsimError: ``hand`` is neither ``"right"`` nor ``"left"``.
    """
    if hand not in ("right", "left"):
        raise HandsimError(f"hand must be 'right' or 'left', got {hand!r}")
    p = Path(path)
    array = load_npy(p)
    if array.dtype != object or array.shape != ():
        raise FormatError(
            p,
            f"expected a pickled dict {{'left', 'right'}} (0-d object array), "
            f"got {array.dtype} {array.shape}",
        )
    data = array.item()
    if not isinstance(data, dict):
        raise FormatError(p, f"expected a pickled dict {{'left', 'right'}}, got {type(data).__name__}")
    if hand not in data:
        raise FormatError(p, f"no {hand!r} entry; entries are {sorted(map(str, data))}", field=hand)
    entry = data[hand]
    if not isinstance(entry, dict):
        raise FormatError(p, f"expected a dict of MANO fields, got {type(entry).__name__}", field=hand)
    missing = [k for k in MANO_FIELDS[:4] if k not in entry]
    if missing:
        raise FormatError(p, f"missing {missing}; a MANO entry has {list(MANO_FIELDS)}", field=hand)
    rot = _float_field(p, f"{hand}.rot", entry["rot"], (None, 3))
    n = rot.shape[0]
    raw_pose = entry["pose"]
    if isinstance(raw_pose, np.ndarray) and raw_pose.ndim == 2 and raw_pose.shape[1] != 45:
        raise FormatError(
            p,
            f"expected 45 values per frame (15 joints × 3 axis-angle), got {raw_pose.shape[1]}",
            field=f"{hand}.pose",
        )
    pose = _float_field(p, f"{hand}.pose", raw_pose, (n, 45))
    trans = _float_field(p, f"{hand}.trans", entry["trans"], (n, 3))
    notes: list[str] = []
    raw_shape = entry["shape"]
    if isinstance(raw_shape, np.ndarray) and raw_shape.ndim == 2:
        shapes = _float_field(p, f"{hand}.shape", raw_shape, (n, 10))
        spread = float(np.ptp(shapes, axis=0).max()) if n else 0.0
        shape = shapes.mean(axis=0)
        notes.append(f"{hand}.shape given per frame; their mean used (largest spread {spread:.1e})")
    else:
        shape = _float_field(p, f"{hand}.shape", raw_shape, (10,))
    fitting_err = None
    if entry.get("fitting_err") is not None:
        fitting_err = _float_field(p, f"{hand}.fitting_err", entry["fitting_err"], (n,))
    largest = float(np.abs(trans).max()) if n else 0.0
    if largest > MANO_TRANS_LIMIT_M:
        raise FormatError(
            p,
            f"translation component reaches {largest:.4g}; MANO translations are metres and a hand more than "
            f"{MANO_TRANS_LIMIT_M:g} m from the origin means the file holds millimetres",
            field=f"{hand}.trans",
        )
    return MANOSequence(
        rot=rot,
        pose=pose,
        trans=trans,
        shape=shape,
        fitting_err=fitting_err,
        side=hand,
        source=str(p),
        sha256=_sha256(p),
        notes=tuple(notes),
    )


def read_arctic_object(path: str | Path) -> ObjectTrack:
    """Read an ARCTIC ``*.object.npy`` file as an object pose track in SI units.

    Args:
        path: The ``.object.npy`` file, float (N, 7) = [articulation rad, axis-angle (3), translation mm (3)].

    Returns:
        ``pose`` (N, 7): translation in metres and the quaternion (w, x, y, z) of the axis-angle;
        ``articulation`` (N,) in radians about the object-frame axis (0, 0, −1); ``valid`` all True.

    Raises:
        InputFileError: The file does not exist.
        FormatError: A non-float dtype, a shape other than (N, 7), non-finite values, translations that
            look like metres, or an articulation that looks like degrees (message names file and field).
    """
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
    turned = float(np.abs(articulation).max())
    if turned > ARTICULATION_LIMIT_RAD:
        raise FormatError(
            p,
            f"articulation reaches {turned:.4g}; ARCTIC articulations are radians (≤ 2π)",
            field="articulation",
        )
    pose = np.concatenate([translation / 1000.0, axis_angle_to_quat(rotvec)], axis=1)
    return ObjectTrack(pose=pose, articulation=articulation.copy(), valid=np.ones(n, dtype=bool))
