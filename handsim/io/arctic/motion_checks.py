"""The plausibility limits of ARCTIC motion files and the checks every field of them goes through.

The files declare no units, so a magnitude outside these limits is an error, never a guess; each check's
message names the file, the field, the frame and what was expected (:mod:`handsim.io.arctic.sequence`
describes the file layout).
"""

from __future__ import annotations

import math
import numbers
from pathlib import Path
from typing import Any

import numpy as np

from handsim.errors import FormatError, HandsimError
from handsim.files import sha256_file

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
"""The fields of one hand's MANO entry; the first four are required."""

PER_FRAME_FIELDS = ("rot", "pose", "trans")
"""The required MANO fields holding one row per frame; their common length is the frame count that
``shape`` (when given per frame) and ``fitting_err`` are checked against."""


def file_sha256(path: Path) -> str:
    """SHA-256 of a file's bytes, hex: the record names exactly which input it replayed."""
    return sha256_file(path)


def shape_text(shape: tuple[int | None, ...]) -> str:
    """An expected array shape as a message writes it, ``N`` for any length: ``(N, 3)``, ``(10,)``."""
    inner = ", ".join("N" if s is None else str(s) for s in shape)
    return f"({inner}{',' if len(shape) == 1 else ''})"


def float_field(
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
        raise FormatError(path, f"expected shape {shape_text(shape)}, got {value.shape}", field=field)
    bad = ~np.isfinite(value)
    if bad.any():
        index = np.argwhere(bad)[0]
        where = ", ".join(f"{axis} {int(i)}" for axis, i in zip(axes, index, strict=False))
        raise FormatError(path, f"non-finite value at {where}", field=field)
    return value.astype(float)


def check_track(
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


def check_fps(fps: float) -> None:
    """Refuse a frame rate that is not a positive finite number (the speed gates divide by it).

    Raises:
        HandsimError: ``fps`` is not a positive finite number.
    """
    if not (isinstance(fps, numbers.Real) and math.isfinite(fps) and fps > 0):
        raise HandsimError(f"fps must be a positive number, got {fps!r}")
