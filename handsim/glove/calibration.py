"""CyberGlove calibration model: raw 8-bit sensor counts → joint angles in radians.

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

A calibration is a :class:`GloveCalibration`; :meth:`GloveCalibration.to_dict` gives its JSON object
(schema :data:`VERSION`, in ``docs/cyberglove.md``), saved and loaded by
:mod:`handsim.io.graspdb.calibration`.
One is estimated from a recorded calibration sequence by :mod:`handsim.glove.calibration_estimation`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from handsim.errors import HandsimError
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
        return self.gains[sensor_index(sensor)]

    def offset(self, sensor: str) -> float:
        """Offset of one sensor (counts).

        Raises:
            CalibrationError: Unknown sensor (the message lists the sensors).
        """
        return self.offsets[sensor_index(sensor)]

    def to_dict(self) -> dict[str, Any]:
        """The calibration as the JSON object of schema :data:`VERSION`.

        Written and read as a file by :mod:`handsim.io.graspdb.calibration`.
        """
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


def sensor_index(sensor: str) -> int:
    """Column of a sensor in a GraspDB14 row's 23 sensor values.

    Raises:
        CalibrationError: Unknown sensor (the message lists the sensors).
    """
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


__all__ = [
    "DEFAULT_COUPLING",
    "DEFAULT_GAINS",
    "FORMAT",
    "NSENSORS",
    "RAW_MAX",
    "VERSION",
    "AbductionCoupling",
    "CalibrationError",
    "GloveCalibration",
    "apply_calibration",
    "sensor_index",
]
