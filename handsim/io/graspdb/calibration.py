"""Glove calibration JSON files (schema :data:`~handsim.glove.calibration.VERSION`): write, read, validate.

The file is the JSON object of :meth:`handsim.glove.calibration.GloveCalibration.to_dict` (schema in
``docs/cyberglove.md``); :func:`load_calibration` checks every field and names the bad one.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from handsim.errors import FormatError
from handsim.glove.calibration import (
    DEFAULT_COUPLING,
    FORMAT,
    NSENSORS,
    VERSION,
    AbductionCoupling,
    GloveCalibration,
)
from handsim.glove.sensors import SENSOR_NAMES
from handsim.io.text_files import decode_utf8, read_bytes


def save_calibration(calibration: GloveCalibration, path: str | Path) -> Path:
    """Write a calibration as a JSON file (schema :data:`VERSION`, documented in ``docs/cyberglove.md``).

    Args:
        calibration: The calibration.
        path: The file to write (replaced if it exists).

    Returns:
        The path written.
    """
    p = Path(path)
    p.write_text(json.dumps(calibration.to_dict(), indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return p


def load_calibration(path: str | Path) -> GloveCalibration:
    """Read a calibration JSON file written by :func:`save_calibration` (or by hand, same schema).

    Args:
        path: The file.

    Returns:
        The calibration.

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: The file is not JSON, or does not follow the schema; the message names the field,
            e.g. ``sensors[3].gain``.
    """
    p = Path(path)
    text = decode_utf8(read_bytes(p), p)
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise FormatError(p, f"invalid JSON: {exc.msg} (column {exc.colno})", line=exc.lineno) from None
    return calibration_from_dict(obj, p)


_TOP_KEYS = {"format", "version", "model", "units", "provenance", "sensors", "abduction_coupling", "notes"}
_SENSOR_KEYS = {"name", "gain", "offset", "fitted", "residual"}
_COUPLING_KEYS = {"sensor", "flexions", "k"}


def calibration_from_dict(obj: object, source: str | Path = "<calibration>") -> GloveCalibration:
    """Build a calibration from its JSON object (see :meth:`GloveCalibration.to_dict`).

    Args:
        obj: The parsed JSON.
        source: File name for error messages.

    Returns:
        The calibration.

    Raises:
        FormatError: The object does not follow the schema (the message names the field).
    """
    top = _object(obj, source, None, _TOP_KEYS, required=("format", "version", "sensors"))
    if top["format"] != FORMAT:
        raise FormatError(source, f"expected {FORMAT!r}, got {top['format']!r}", field="format")
    version = top["version"]
    if not isinstance(version, int) or isinstance(version, bool) or version != VERSION:
        raise FormatError(
            source,
            f"unsupported schema version {version!r}; this handsim reads version {VERSION}",
            field="version",
        )
    sensors = top["sensors"]
    if not isinstance(sensors, list):
        raise FormatError(source, f"expected a list of {NSENSORS} sensor objects", field="sensors")
    gains: dict[str, float] = {}
    offsets: dict[str, float] = {}
    residuals: dict[str, float | None] = {}
    fitted: list[str] = []
    for i, item in enumerate(sensors):
        where = f"sensors[{i}]"
        entry = _object(item, source, where, _SENSOR_KEYS, required=("name", "gain", "offset"))
        name = entry["name"]
        if name not in SENSOR_NAMES:
            raise FormatError(
                source, f"unknown sensor {name!r}; sensors are {list(SENSOR_NAMES)}", field=f"{where}.name"
            )
        if name in gains:
            raise FormatError(source, f"sensor {name!r} is listed twice", field=f"{where}.name")
        gains[name] = _number(entry["gain"], source, f"{where}.gain")
        offsets[name] = _number(entry["offset"], source, f"{where}.offset")
        flag = entry.get("fitted", False)
        if not isinstance(flag, bool):
            raise FormatError(source, f"expected true or false, got {flag!r}", field=f"{where}.fitted")
        if flag:
            fitted.append(name)
        res = entry.get("residual")
        residuals[name] = None if res is None else _number(res, source, f"{where}.residual", nonnegative=True)
    missing = [s for s in SENSOR_NAMES if s not in gains]
    if missing:
        raise FormatError(
            source, f"missing sensors {missing}; all {NSENSORS} must be listed", field="sensors"
        )
    coupling = DEFAULT_COUPLING
    if "abduction_coupling" in top:
        coupling = _coupling(top["abduction_coupling"], source)
    provenance = top.get("provenance", "")
    if not isinstance(provenance, str):
        raise FormatError(source, f"expected a string, got {provenance!r}", field="provenance")
    notes = top.get("notes", [])
    if not isinstance(notes, list) or not all(isinstance(n, str) for n in notes):
        raise FormatError(source, "expected a list of strings", field="notes")
    any_residual = any(r is not None for r in residuals.values())
    return GloveCalibration(
        gains=tuple(gains[s] for s in SENSOR_NAMES),
        offsets=tuple(offsets[s] for s in SENSOR_NAMES),
        coupling=coupling,
        provenance=provenance,
        residuals=tuple(residuals[s] for s in SENSOR_NAMES) if any_residual else None,
        fitted=tuple(s for s in SENSOR_NAMES if s in fitted),
        notes=tuple(notes),
    )


def _object(
    obj: object, source: str | Path, where: str | None, keys: set[str], required: tuple[str, ...]
) -> dict[str, Any]:
    """A JSON object with only known keys and all required ones."""
    if not isinstance(obj, dict):
        raise FormatError(source, f"expected a JSON object, got {type(obj).__name__}", field=where)
    unknown = sorted(k for k in obj if k not in keys)
    if unknown:
        raise FormatError(source, f"unknown keys {unknown}; known keys are {sorted(keys)}", field=where)
    for key in required:
        if key not in obj:
            name = key if where is None else f"{where}.{key}"
            raise FormatError(source, "missing", field=name)
    return obj


def _number(value: object, source: str | Path, where: str, *, nonnegative: bool = False) -> float:
    """A finite JSON number (not a boolean)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise FormatError(source, f"expected a finite number, got {value!r}", field=where)
    if nonnegative and value < 0:
        raise FormatError(source, f"expected a number >= 0, got {value!r}", field=where)
    return float(value)


def _coupling(items: object, source: str | Path) -> tuple[AbductionCoupling, ...]:
    if not isinstance(items, list):
        raise FormatError(source, "expected a list of coupling objects", field="abduction_coupling")
    result = []
    for i, item in enumerate(items):
        where = f"abduction_coupling[{i}]"
        entry = _object(item, source, where, _COUPLING_KEYS, required=("sensor", "flexions", "k"))
        sensor, flexions = entry["sensor"], entry["flexions"]
        if sensor not in SENSOR_NAMES:
            raise FormatError(
                source,
                f"unknown sensor {sensor!r}; sensors are {list(SENSOR_NAMES)}",
                field=f"{where}.sensor",
            )
        if (
            not isinstance(flexions, list)
            or len(flexions) != 2
            or not all(isinstance(f, str) and f in SENSOR_NAMES for f in flexions)
        ):
            raise FormatError(
                source, f"expected a list of two sensor names, got {flexions!r}", field=f"{where}.flexions"
            )
        result.append(
            AbductionCoupling(sensor, (flexions[0], flexions[1]), _number(entry["k"], source, f"{where}.k"))
        )
    return tuple(result)


__all__ = ["calibration_from_dict", "load_calibration", "save_calibration"]
