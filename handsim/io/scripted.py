"""Reader for scripted grasps (``NAME.grasp.json``): synthetic closing motions of the parametric hand.

A scripted grasp is not a recording. It is a small JSON file written for handsim that describes the
parametric default hand closing around a catalogue object, so that the glove scenario can be shown and
tested on data the package may redistribute::

    {"format": "handsim-scripted-grasp", "version": 1, "object": "tennis_ball", "hand_length": 0.19,
     "rate_hz": 60, "rest_s": 0.3, "close_s": 1.0, "hold_s": 1.5, "open_s": 0.5, "closure": 0.6}

Fields (all required except ``hand_length`` and ``description``):

* ``format`` — ``"handsim-scripted-grasp"``; ``version`` — ``1``.
* ``object`` — the catalogue object grasped (``handsim catalog``).
* ``hand_length`` — the parametric default hand's length, m (wrist crease to middle fingertip;
  default 0.19, 0.08–0.30).
* ``rate_hz`` — sample rate, Hz (1–1000).
* ``rest_s``, ``close_s``, ``hold_s``, ``open_s`` — durations of the four phases, s (``close_s`` and
  ``hold_s`` at least one sample, the others may be 0; at most 60 s each).
* ``closure`` — how far the fingers close: each flexion DoF's target at the hold is
  ``closure × upper limit`` (0 < closure ≤ 1).
* ``description`` — optional text for people.

The trajectory holds every DoF at 0 (clipped into its range) except the finger flexion DoFs (``flex`` in
the name, not the wrist's ``root_…``), which follow a cosine ramp from 0 to ``closure × upper`` over the
close phase, hold it, and ramp back to 0 over the open phase. Its phases are ``rest``, ``close`` (up to
first contact), ``grasp`` (from first contact, :data:`CONTACT_LEVEL` of the closing, to the end of the
hold: where the glove scenario places the object, lets the remaining closing grip it, and judges the
hold) and ``release``; phases of no samples are left out.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from handsim.datatypes.trajectory import Phase, Trajectory
from handsim.errors import FormatError
from handsim.io.graspdb.default_skeleton import DEFAULT_HAND_LENGTH_M, default_skeleton
from handsim.io.text_files import decode_utf8, read_bytes, sha256_of

if TYPE_CHECKING:
    from handsim.datatypes.skeleton import Skeleton

SUFFIX = ".grasp.json"
"""File name ending of a scripted grasp."""
FORMAT = "handsim-scripted-grasp"
"""The ``format`` field's value."""
VERSION = 1
"""The format version this reader reads."""
SYNTHETIC_NOTE = "synthetic scripted grasp (not a recording)"
"""The note every scripted grasp's trajectory carries."""
DURATIONS = ("rest_s", "close_s", "hold_s", "open_s")
"""The phase duration fields, in time order."""
PHASE_NAMES = ("rest", "close", "grasp", "release")
"""The phases the durations make, in the order of :data:`DURATIONS`."""
CONTACT_LEVEL = 0.8
"""The ``grasp`` phase starts when the closing ramp reaches this fraction (first contact); the placement
search puts the object there, and the rest of the closing is the grip that presses into it."""
MAX_DURATION_S = 60.0
"""Longest phase, s."""
_REQUIRED = ("format", "version", "object", "rate_hz", *DURATIONS, "closure")
_OPTIONAL = ("hand_length", "description")


def is_scripted_grasp(path: str | Path) -> bool:
    """True if the file name ends in ``.grasp.json`` (any case)."""
    return Path(path).name.lower().endswith(SUFFIX)


def _number(data: dict, key: str, path: Path, low: float, high: float, *, low_open: bool = False) -> float:
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise FormatError(path, f"expected a finite number, got {value!r}", field=key)
    bad_low = value <= low if low_open else value < low
    if bad_low or value > high:
        lower = f"> {low:g}" if low_open else f"≥ {low:g}"
        raise FormatError(path, f"expected a number {lower} and ≤ {high:g}, got {value!r}", field=key)
    return float(value)


def _fields(path: Path, raw: bytes) -> dict:
    try:
        data = json.loads(decode_utf8(raw, path))
    except json.JSONDecodeError as exc:
        raise FormatError(path, f"not a JSON document ({exc})", line=exc.lineno) from None
    if not isinstance(data, dict):
        raise FormatError(path, f"expected a JSON object, got {type(data).__name__}")
    unknown = sorted(set(data) - {*_REQUIRED, *_OPTIONAL})
    if unknown:
        raise FormatError(
            path,
            f"unknown field(s) {unknown}; a scripted grasp has {[*_REQUIRED, *_OPTIONAL]}",
            field=unknown[0],
        )
    missing = [k for k in _REQUIRED if k not in data]
    if missing:
        raise FormatError(
            path, f"missing field(s) {missing}; required are {list(_REQUIRED)}", field=missing[0]
        )
    if data["format"] != FORMAT:
        raise FormatError(path, f"expected {FORMAT!r}, got {data['format']!r}", field="format")
    if isinstance(data["version"], bool) or data["version"] != VERSION:
        raise FormatError(path, f"expected version {VERSION}, got {data['version']!r}", field="version")
    if not isinstance(data["object"], str) or not data["object"].strip():
        raise FormatError(path, f"expected a catalogue object name, got {data['object']!r}", field="object")
    if "description" in data and not isinstance(data["description"], str):
        raise FormatError(path, f"expected text, got {data['description']!r}", field="description")
    return data


def _validated(path: Path, raw: bytes) -> dict:
    """Every field checked; numbers as floats; ``hand_length`` filled in when left out."""
    data = _fields(path, raw)
    data.setdefault("hand_length", DEFAULT_HAND_LENGTH_M)
    data["hand_length"] = _number(data, "hand_length", path, 0.08, 0.30)
    rate = data["rate_hz"] = _number(data, "rate_hz", path, 1.0, 1000.0)
    data["closure"] = _number(data, "closure", path, 0.0, 1.0, low_open=True)
    for key in DURATIONS:
        seconds = data[key] = _number(data, key, path, 0.0, MAX_DURATION_S)
        if key in ("close_s", "hold_s") and round(seconds * rate) < 1:
            raise FormatError(
                path,
                f"expected at least one sample (1 / rate_hz = {1 / rate:g} s), got {seconds!r}",
                field=key,
            )
    return data


def read_scripted_grasp(path: str | Path, skeleton: Skeleton | None = None) -> Trajectory:
    """Read a scripted grasp (``NAME.grasp.json``) as the joint targets of a synthetic closing motion.

    Args:
        path: The scripted grasp file.
        skeleton: The hand whose DoFs become the columns; default the parametric default hand of the
            file's ``hand_length`` (:func:`handsim.io.graspdb.default_skeleton.default_skeleton`).

    Returns:
        The trajectory: times in s, targets in rad, phases ``rest``, ``close``, ``grasp`` (first contact
        to the end of the hold) and ``release``, the file's SHA-256, and the note :data:`SYNTHETIC_NOTE`.

    Raises:
        InputFileError: Missing or unreadable file.
        FormatError: Not JSON, a field unknown, missing, of the wrong type or out of range (the message
            names the file and the field).
    """
    p = Path(path)
    raw = read_bytes(p)
    data = _validated(p, raw)
    hand_length, rate, closure = data["hand_length"], data["rate_hz"], data["closure"]
    counts = [round(data[key] * rate) for key in DURATIONS]
    if skeleton is None:
        skeleton = default_skeleton(hand_length)
    n_rest, n_close, n_hold, n_open = counts
    level = np.concatenate(
        [
            np.zeros(n_rest),
            _ramp(np.arange(1, n_close + 1) / n_close),
            np.ones(n_hold),
            1.0 - _ramp(np.arange(1, n_open + 1) / max(n_open, 1)),
        ]
    )
    limits = np.asarray(skeleton.limits, dtype=float)
    names = skeleton.dof_names
    flex = np.array(["flex" in n and not n.startswith("root") for n in names])
    rest = np.clip(0.0, limits[:, 0], limits[:, 1])
    closed = np.where(flex, closure * limits[:, 1], rest)
    targets = rest[None, :] + level[:, None] * (closed - rest)[None, :]
    # the grasp phase starts at first contact, CONTACT_LEVEL of the way through the closing: the rest of
    # the closing presses the fingers into the object (the grip), as in a recorded grasp
    contact = n_rest + int(np.argmax(level[n_rest : n_rest + n_close] >= CONTACT_LEVEL))
    bounds = [0, n_rest, contact, n_rest + n_close + n_hold, level.shape[0]]
    phases = [
        Phase(name, start, stop)
        for name, start, stop in zip(PHASE_NAMES, bounds[:-1], bounds[1:], strict=True)
        if stop > start
    ]
    notes = [
        SYNTHETIC_NOTE,
        f"object {data['object']!r}; {int(flex.sum())} finger flexion DoFs close to {closure:g} × their "
        f"upper limit, the other {int((~flex).sum())} DoFs stay at 0 (clipped into range)",
    ]
    if "description" in data:
        notes.append(data["description"])
    return Trajectory(
        times=np.arange(level.shape[0]) / rate,
        dof_names=tuple(names),
        targets=targets,
        valid=np.ones(targets.shape, dtype=bool),
        phases=tuple(phases),
        source=str(p),
        sha256=sha256_of(raw),
        notes=tuple(notes),
    )


def scripted_grasp_fields(path: str | Path) -> dict:
    """A scripted grasp's fields, validated, without building the trajectory (cheap: for discovery).

    Returns:
        The file's fields, numbers as floats, with ``hand_length`` filled in (0.19 m) when left out.

    Raises:
        InputFileError: Missing or unreadable file.
        FormatError: Not a valid scripted grasp (the message names the file and the field).
    """
    p = Path(path)
    return _validated(p, read_bytes(p))


def _ramp(u: np.ndarray) -> np.ndarray:
    """Cosine ease from 0 at ``u = 0`` to 1 at ``u = 1``."""
    return 0.5 * (1.0 - np.cos(np.pi * np.clip(u, 0.0, 1.0)))


__all__ = ["FORMAT", "SUFFIX", "SYNTHETIC_NOTE", "VERSION", "is_scripted_grasp", "read_scripted_grasp"]
