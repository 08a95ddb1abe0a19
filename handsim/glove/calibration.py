"""CyberGlove calibration: raw 8-bit sensor counts → joint angles in radians.

Model (CyberGlove's own per-sensor convention, ``angle = gain · (raw − offset)``), applied by
:func:`apply_calibration` to the 23 sensor columns of a GraspDB14 row:

1. ``angle_i = gain_i · (raw_i − offset_i)`` — gain in rad/count, offset in counts.
2. Abduction cross-coupling: an abduction sensor also reads part of the flexion of the two MCP joints it
   lies between, so ``angle_abd −= k · (angle_flex_a + angle_flex_b) / 2`` (k dimensionless, one per
   abduction sensor, default 0: the spec is silent on it, and the calibration protocol has no pose that
   would measure it).

Angles come out in the sign convention of the GraspDB14 ``rad`` files (what the readers negate into joint
targets): flexion is negative; an abduction angle is positive towards the little-finger side, so the
angle an inter-finger sensor (``MI-AA``, ``RM-AA``, ``LR-AA``) measures is positive when the two fingers
spread. Those three sensors give the angle *between* two fingers; the glove software behind the ``rad``
files instead spreads them over per-finger abductions (see ``docs/cyberglove.md``), which this model does
not reproduce.

A calibration is a :class:`GloveCalibration`, saved to and loaded from a versioned JSON file
(:func:`save_calibration`, :func:`load_calibration`, schema in ``docs/cyberglove.md``), or estimated from a
recorded calibration sequence (:func:`estimate_calibration`, protocol of spec §3.5:
:data:`CALIBRATION_PROTOCOL`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from handsim.errors import FormatError, HandsimError
from handsim.glove.phases import SWITCH_ON, switch_segments
from handsim.glove.sensors import SENSOR_NAMES

FORMAT = "handsim-glove-calibration"
"""Value of the ``format`` key of a calibration JSON file."""

VERSION = 1
"""Schema version written and read."""

NSENSORS = len(SENSOR_NAMES)
"""Sensor columns of a GraspDB14 row (23)."""

RAW_MAX = 255
"""Largest 8-bit raw count."""


class CalibrationError(HandsimError, ValueError):
    """A calibration or the data to estimate one is unusable (wrong shape, sensor not responding, …)."""


# --------------------------------------------------------------------------------------------------
# Defaults

DEFAULT_GAINS: tuple[float, ...] = (
    -0.01584,  # T-TMCJ
    -0.01459,  # T-MCPJ
    -0.01427,  # T-IPJ
    -0.00502,  # TI-AA
    -0.01616,  # I-MCPJ
    -0.01459,  # I-PIPJ
    -0.01459,  # I-DIPJ (not measured by the 18-sensor glove; the I-PIPJ gain)
    0.0,  # I-AA (unsupported by the glove)
    -0.01725,  # M-MCPJ
    -0.01804,  # M-PIPJ
    -0.01804,  # M-DIPJ (M-PIPJ gain)
    0.0045,  # MI-AA
    -0.01757,  # R-MCPJ
    -0.01788,  # R-PIPJ
    -0.01788,  # R-DIPJ (R-PIPJ gain)
    0.00612,  # RM-AA
    -0.01663,  # L-MCPJ
    -0.01820,  # L-PIPJ
    -0.01820,  # L-DIPJ (L-PIPJ gain)
    0.00596,  # LR-AA
    -0.00910,  # P-Arch
    -0.00863,  # W-FE
    0.00392,  # W-AA
)
"""Gains (rad/count) a sensor keeps when the calibration protocol does not excite it.

The magnitudes are those of the glove software that wrote the GraspDB14 sample ``rad`` files: there every
sensor value is an integer multiple of its gain (the same for actors 1, 3 and 4), e.g. I-PIPJ = k · 0.01459
rad. MI-AA and RM-AA values are mixed by the glove software; their gains are the per-count change of the
angle between the two fingers. DIP gains (22-sensor gloves) repeat the finger's PIP gain; I-AA gets 0.
The signs are an assumption: raw counts rise as a sensor bends further (flexion, rotation of the thumb
across the palm, palm arch, wrist flexion, spreading), mapped to the ``rad`` files' signs.
"""


@dataclass(frozen=True)
class AbductionCoupling:
    """Cross-coupling of an abduction sensor on the two MCP flexions beside it.

    Attributes:
        sensor: The abduction sensor, e.g. ``"MI-AA"``.
        flexions: The two flexion sensors it lies between, e.g. ``("I-MCPJ", "M-MCPJ")``.
        k: Coupling coefficient (dimensionless): ``abd −= k · (flex_a + flex_b) / 2``, angles in radians.
    """

    sensor: str
    flexions: tuple[str, str]
    k: float = 0.0


DEFAULT_COUPLING: tuple[AbductionCoupling, ...] = (
    AbductionCoupling("TI-AA", ("T-MCPJ", "I-MCPJ")),
    AbductionCoupling("MI-AA", ("I-MCPJ", "M-MCPJ")),
    AbductionCoupling("RM-AA", ("M-MCPJ", "R-MCPJ")),
    AbductionCoupling("LR-AA", ("R-MCPJ", "L-MCPJ")),
)
"""The four abduction sensors and their neighbouring MCP flexions, all with k = 0."""


# --------------------------------------------------------------------------------------------------
# The calibration


@dataclass(frozen=True)
class GloveCalibration:
    """Per-sensor linear calibration of a CyberGlove, with abduction cross-coupling.

    Attributes:
        gains: Gain per sensor in rad/count, in :data:`~handsim.glove.SENSOR_NAMES` order (23).
        offsets: Offset per sensor in counts (the raw reading at angle 0), same order.
        coupling: Abduction cross-coupling terms (:class:`AbductionCoupling`).
        provenance: Where the calibration comes from (file, estimation, hand-made), for the record.
        residuals: RMS fit error per sensor in radians over the reference samples of an estimation, None
            per sensor without reference samples; None when not estimated.
        fitted: Sensors whose gain was fitted (the others keep a default or given gain).
        notes: Decisions taken while estimating, for the user to see.
        sensor_names: Sensor of each entry; always :data:`~handsim.glove.SENSOR_NAMES`.
    """

    gains: tuple[float, ...]
    offsets: tuple[float, ...]
    coupling: tuple[AbductionCoupling, ...] = DEFAULT_COUPLING
    provenance: str = ""
    residuals: tuple[float | None, ...] | None = None
    fitted: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    sensor_names: tuple[str, ...] = field(default=SENSOR_NAMES)

    def __post_init__(self) -> None:
        object.__setattr__(self, "gains", tuple(float(g) for g in self.gains))
        object.__setattr__(self, "offsets", tuple(float(o) for o in self.offsets))
        if tuple(self.sensor_names) != SENSOR_NAMES:
            raise CalibrationError(f"sensor_names must be the 23 GraspDB14 sensors {list(SENSOR_NAMES)}")
        for what, values in (("gains", self.gains), ("offsets", self.offsets)):
            if len(values) != NSENSORS:
                raise CalibrationError(
                    f"{what} must hold {NSENSORS} values (one per sensor), got {len(values)}"
                )
            bad = [SENSOR_NAMES[i] for i, v in enumerate(values) if not math.isfinite(v)]
            if bad:
                raise CalibrationError(f"{what} must be finite; not finite for {bad}")
        if self.residuals is not None and len(self.residuals) != NSENSORS:
            raise CalibrationError(f"residuals must hold {NSENSORS} values, got {len(self.residuals)}")
        unknown = [s for s in self.fitted if s not in SENSOR_NAMES]
        for c in self.coupling:
            unknown += [s for s in (c.sensor, *c.flexions) if s not in SENSOR_NAMES]
            if len(c.flexions) != 2 or not math.isfinite(c.k):
                raise CalibrationError(
                    f"coupling of {c.sensor}: expected two flexions and a finite k, got {c}"
                )
        if unknown:
            raise CalibrationError(f"unknown sensors {unknown}; sensors are {list(SENSOR_NAMES)}")

    @classmethod
    def default(cls, provenance: str = "handsim default gains, zero offsets") -> GloveCalibration:
        """:data:`DEFAULT_GAINS`, zero offsets, no coupling (k = 0): a starting point, not a calibration."""
        return cls(gains=DEFAULT_GAINS, offsets=(0.0,) * NSENSORS, provenance=provenance)

    @property
    def unfitted(self) -> tuple[str, ...]:
        """Sensors whose gain was not fitted (default or given gain), in row order."""
        return tuple(s for s in SENSOR_NAMES if s not in self.fitted)

    def gain(self, sensor: str) -> float:
        """Gain of one sensor (rad/count).

        Raises:
            CalibrationError: Unknown sensor (the message lists the sensors).
        """
        return self.gains[_index(sensor)]

    def offset(self, sensor: str) -> float:
        """Offset of one sensor (counts).

        Raises:
            CalibrationError: Unknown sensor (the message lists the sensors).
        """
        return self.offsets[_index(sensor)]

    def to_dict(self) -> dict[str, Any]:
        """The calibration as the JSON object of schema :data:`VERSION` (see :func:`save_calibration`)."""
        sensors = []
        for i, name in enumerate(SENSOR_NAMES):
            entry: dict[str, Any] = {"name": name, "gain": self.gains[i], "offset": self.offsets[i]}
            entry["fitted"] = name in self.fitted
            entry["residual"] = None if self.residuals is None else self.residuals[i]
            sensors.append(entry)
        return {
            "format": FORMAT,
            "version": VERSION,
            "model": "angle = gain * (raw - offset); abd -= k * (flex_a + flex_b) / 2",
            "units": {"gain": "rad/count", "offset": "count", "residual": "rad", "k": "1"},
            "provenance": self.provenance,
            "sensors": sensors,
            "abduction_coupling": [
                {"sensor": c.sensor, "flexions": list(c.flexions), "k": c.k} for c in self.coupling
            ],
            "notes": list(self.notes),
        }


def _index(sensor: str) -> int:
    if sensor not in SENSOR_NAMES:
        raise CalibrationError(f"unknown sensor {sensor!r}; sensors are {list(SENSOR_NAMES)}")
    return SENSOR_NAMES.index(sensor)


def apply_calibration(raw_counts: npt.ArrayLike, calibration: GloveCalibration) -> np.ndarray:
    """Convert raw sensor counts to angles in radians.

    Args:
        raw_counts: Raw counts, shape (T, 23) (or (23,) for one sample), columns in
            :data:`~handsim.glove.SENSOR_NAMES` order.
        calibration: The calibration.

    Returns:
        Angles in radians, same shape, in the sign convention of GraspDB14 ``rad`` files (see the module
        docstring).

    Raises:
        CalibrationError: The array does not have 23 columns or holds non-finite values.
    """
    raw = np.asarray(raw_counts, dtype=float)
    if raw.ndim not in (1, 2) or raw.shape[-1] != NSENSORS:
        raise CalibrationError(f"raw counts must have shape (T, {NSENSORS}), got {raw.shape}")
    if not np.all(np.isfinite(raw)):
        raise CalibrationError("raw counts must be finite")
    angles = (raw - np.asarray(calibration.offsets)) * np.asarray(calibration.gains)
    flex = angles.copy()
    for c in calibration.coupling:
        if c.k != 0.0:
            a, b = (SENSOR_NAMES.index(f) for f in c.flexions)
            angles[..., SENSOR_NAMES.index(c.sensor)] -= c.k * (flex[..., a] + flex[..., b]) / 2.0
    return angles


# --------------------------------------------------------------------------------------------------
# JSON files


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
    from handsim.io._text import decode_utf8, read_bytes  # lazy: handsim.io imports handsim.glove

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


# --------------------------------------------------------------------------------------------------
# Estimation from a calibration sequence


@dataclass(frozen=True)
class ReferencePose:
    """A pose of the calibration sequence whose sensor angles are known.

    Attributes:
        name: What the pose is, for messages and notes.
        segment: 0-based switch segment of the sequence (segment 0 starts it, switch ON).
        hold: ``"segment"``: the pose is held during the whole segment (a static pose: the switch is OFF
            while it is held); ``"end"``: the pose is in place when the switch is pressed at the segment's
            end (wedges, table edge).
        angles: ``(sensor, angle in degrees)`` pairs in the ``rad``-file sign convention (flexion negative,
            spread of two fingers positive); sensors not listed are unknown in this pose.
    """

    name: str
    segment: int
    hold: str
    angles: tuple[tuple[str, float], ...]


_FINGER_MCP = ("I-MCPJ", "M-MCPJ", "R-MCPJ", "L-MCPJ")
_FINGER_PIP_DIP = ("I-PIPJ", "I-DIPJ", "M-PIPJ", "M-DIPJ", "R-PIPJ", "R-DIPJ", "L-PIPJ", "L-DIPJ")
_WEDGE = 25.0
_TABLE = -45.0


def _wedges(segment: int, mi: bool, rm: bool, lr: bool) -> ReferencePose:
    between = [n for n, on in (("index-middle", mi), ("middle-ring", rm), ("ring-little", lr)) if on]
    name = f"25° wedges {', '.join(between)}" if between else "wedges removed"
    angles = (("MI-AA", _WEDGE * mi), ("RM-AA", _WEDGE * rm), ("LR-AA", _WEDGE * lr))
    return ReferencePose(name, segment, "end", angles)


CALIBRATION_PROTOCOL: tuple[ReferencePose, ...] = (
    # static poses: ON (moving into the pose) → OFF (pose held) → ON, four times: segments 0..8
    ReferencePose("flat unspread hand", 1, "segment", tuple((s, 0.0) for s in SENSOR_NAMES)),
    ReferencePose(
        "square angle in the MCP joints",
        7,
        "segment",
        tuple((s, -90.0) for s in _FINGER_MCP) + tuple((s, 0.0) for s in _FINGER_PIP_DIP),
    ),
    # 25° wedges put in I-M, M-R, R-L (a press after each), then removed in the same order: 8..14
    _wedges(8, True, False, False),
    _wedges(9, True, True, False),
    _wedges(10, True, True, True),
    _wedges(11, False, True, True),
    _wedges(12, False, False, True),
    _wedges(13, False, False, False),
    # 45° MCP flexion at the table edge, finger pairs T-I, I-M, M-R, R-L (a press after each): 14..18
    ReferencePose("45° MCP flexion, thumb and index", 14, "end", (("T-MCPJ", _TABLE), ("I-MCPJ", _TABLE))),
    ReferencePose("45° MCP flexion, index and middle", 15, "end", (("I-MCPJ", _TABLE), ("M-MCPJ", _TABLE))),
    ReferencePose("45° MCP flexion, middle and ring", 16, "end", (("M-MCPJ", _TABLE), ("R-MCPJ", _TABLE))),
    ReferencePose("45° MCP flexion, ring and little", 17, "end", (("R-MCPJ", _TABLE), ("L-MCPJ", _TABLE))),
    # thumb-to-finger touches (segments 18, 19 and an optional 20) have no known angles
)
"""The reference poses of the GraspDB14 calibration sequence (spec §3.5), by switch segment.

Segments (0-based; the switch is ON at the start): 1 flat unspread hand, 3 flat spread hand, 5 fist
(thumb outside), 7 square angle in the MCP joints (each held while OFF); presses at the ends of 8, 9, 10
with the 25° wedges in I-M, then also M-R, then also R-L; at the ends of 11, 12, 13 with them removed one
by one in the same order; at the ends of 14..17 with the finger pairs T-I, I-M, M-R, R-L flexed 45° in
the MCP joints at the table edge; 18 and 19 thumb-to-fingertip and thumb-to-middle-phalanx touches
(20 or 21 segments in all). The spread hand, the fist and the touches have no known angles and are not
used. The flat hand is the zero of every sensor.
"""

EXPECTED_SEGMENTS = (20, 21)
"""Switch segments of a complete calibration sequence (spec §3.5)."""


def estimate_calibration(
    raw_sequence: npt.ArrayLike,
    switch: npt.ArrayLike,
    *,
    protocol: tuple[ReferencePose, ...] = CALIBRATION_PROTOCOL,
    base: GloveCalibration | None = None,
    hold_frames: int = 12,
    trim_frames: int = 3,
    expected_segments: tuple[int, ...] = EXPECTED_SEGMENTS,
    provenance: str = "estimated from a calibration sequence",
) -> GloveCalibration:
    """Estimate gains and offsets from a recorded calibration sequence (spec §3.5).

    The switch state splits the sequence into segments; each :class:`ReferencePose` of ``protocol`` names
    a segment and the sensor angles it has. Its samples are the segment's frames less ``trim_frames`` at
    each end (``hold="segment"``), or the last ``hold_frames`` frames before the press that ends the
    segment (``hold="end"``). Per sensor, a least-squares fit of ``angle = gain · raw + b`` over all its
    reference samples gives gain and offset ``−b / gain`` when its reference angles take at least two
    values; with one value (the flat hand only) the gain stays that of ``base`` and only the offset is
    fitted; sensors no pose names keep ``base``'s gain and offset. The RMS error of each fit (radians) is
    kept in :attr:`GloveCalibration.residuals`.

    Args:
        raw_sequence: Raw counts of the sequence, shape (T, 23) (:func:`handsim.io.graspdb.read_graspdb_raw`).
        switch: Switch state per frame, shape (T,).
        protocol: The reference poses; the default is the GraspDB14 protocol, :data:`CALIBRATION_PROTOCOL`.
        base: Gains and offsets for what the protocol does not determine, and the abduction coupling to
            keep; default :meth:`GloveCalibration.default`.
        hold_frames: Frames before a press taken as the held pose (12 ≈ 0.2 s at 60 Hz).
        trim_frames: Frames dropped at each end of a static segment (kept when the segment is too short).
        expected_segments: Accepted numbers of switch segments.
        provenance: Recorded in the result.

    Returns:
        The calibration, with ``fitted``, ``residuals`` and notes listing the sensors that kept a default
        gain.

    Raises:
        CalibrationError: Bad shapes or frame counts, a sequence not starting with the switch ON or with
            a number of segments not in ``expected_segments`` (the message lists the segment lengths), a
            pose naming a missing segment or unknown sensor, or a sensor whose counts do not change between
            reference angles (it does not respond).
    """
    if hold_frames < 1 or trim_frames < 0:
        raise CalibrationError(
            f"hold_frames must be >= 1 and trim_frames >= 0, got {hold_frames} and {trim_frames}"
        )
    raw = np.asarray(raw_sequence, dtype=float)
    if raw.ndim != 2 or raw.shape[1] != NSENSORS or raw.shape[0] == 0:
        raise CalibrationError(f"raw sequence must have shape (T, {NSENSORS}), got {raw.shape}")
    if not np.all(np.isfinite(raw)):
        raise CalibrationError("raw sequence must be finite")
    sw = np.asarray(switch)
    if sw.shape != (raw.shape[0],):
        raise CalibrationError(f"switch must have shape ({raw.shape[0]},), got {sw.shape}")
    try:
        segments = switch_segments(sw)
    except HandsimError as exc:
        raise CalibrationError(str(exc)) from None
    lengths = [s.stop - s.start for s in segments]
    if not sw.any():
        raise CalibrationError(
            f"{provenance}: the switch is never ON in its {len(sw)} samples, so the calibration poses cannot "
            "be told apart (spec §3.5: the actor presses the switch at each pose); is this a calibration "
            "sequence?"
        )
    if segments[0].name != SWITCH_ON:
        raise CalibrationError(
            "a calibration sequence starts with the switch ON (spec §3.5); this one starts OFF"
        )
    if len(segments) not in expected_segments:
        raise CalibrationError(
            f"a calibration sequence has {' or '.join(map(str, expected_segments))} switch segments "
            f"(spec §3.5); this one has {len(segments)}, of {lengths} frames"
        )
    base = base if base is not None else GloveCalibration.default()

    samples: dict[int, list[tuple[str, np.ndarray, float]]] = {i: [] for i in range(NSENSORS)}
    for pose in protocol:
        if not 0 <= pose.segment < len(segments):
            raise CalibrationError(
                f"pose {pose.name!r} names segment {pose.segment}; there are {len(segments)}"
            )
        if pose.hold not in ("segment", "end"):
            raise CalibrationError(f"pose {pose.name!r}: hold must be 'segment' or 'end', got {pose.hold!r}")
        seg = segments[pose.segment]
        if pose.hold == "end":
            rows = slice(max(seg.start, seg.stop - hold_frames), seg.stop)
        elif seg.stop - seg.start > 2 * trim_frames:
            rows = slice(seg.start + trim_frames, seg.stop - trim_frames)
        else:
            rows = slice(seg.start, seg.stop)
        for sensor, degrees in pose.angles:
            samples[_index(sensor)].append((pose.name, raw[rows, _index(sensor)], math.radians(degrees)))

    gains, offsets = list(base.gains), list(base.offsets)
    residuals: list[float | None] = [None] * NSENSORS
    fitted: list[str] = []
    for i, name in enumerate(SENSOR_NAMES):
        if not samples[i]:
            continue
        x = np.concatenate([s[1] for s in samples[i]])
        y = np.concatenate([np.full(s[1].shape, s[2]) for s in samples[i]])
        refs = sorted({s[2] for s in samples[i]})
        if len(refs) >= 2:
            means = {ref: np.mean([s[1].mean() for s in samples[i] if s[2] == ref]) for ref in refs}
            if max(means.values()) - min(means.values()) < 1.0:
                listing = ", ".join(f"{math.degrees(r):g}°: {m:.2f}" for r, m in means.items())
                raise CalibrationError(
                    f"sensor {name} does not respond to the calibration poses: its mean counts at the "
                    f"reference angles differ by less than 1 count ({listing})"
                )
            gain, b = np.linalg.lstsq(np.column_stack([x, np.ones_like(x)]), y, rcond=None)[0]
            gains[i], offsets[i] = float(gain), float(-b / gain)
            fitted.append(name)
        else:
            offsets[i] = float(np.mean(x) - (refs[0] / gains[i] if gains[i] != 0.0 else 0.0))
        residuals[i] = float(np.sqrt(np.mean((gains[i] * (x - offsets[i]) - y) ** 2)))

    kept = [s for s in SENSOR_NAMES if s not in fitted]
    notes = (
        f"switch segments: {len(segments)}, of {lengths} frames",
        f"gains fitted for {fitted}",
        f"gains kept from the base calibration ({base.provenance}) for {kept}: the protocol does not move "
        "these sensors through known angles",
    )
    return GloveCalibration(
        gains=tuple(gains),
        offsets=tuple(offsets),
        coupling=base.coupling,
        provenance=provenance,
        residuals=tuple(residuals),
        fitted=tuple(fitted),
        notes=notes,
    )


__all__ = [
    "CALIBRATION_PROTOCOL",
    "DEFAULT_COUPLING",
    "DEFAULT_GAINS",
    "EXPECTED_SEGMENTS",
    "FORMAT",
    "NSENSORS",
    "RAW_MAX",
    "VERSION",
    "AbductionCoupling",
    "CalibrationError",
    "GloveCalibration",
    "ReferencePose",
    "apply_calibration",
    "calibration_from_dict",
    "estimate_calibration",
    "load_calibration",
    "save_calibration",
]
