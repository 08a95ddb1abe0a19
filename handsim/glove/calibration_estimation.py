"""Estimating a CyberGlove calibration from a recorded calibration sequence (spec §3.5).

The switch state splits the sequence into segments; the reference poses of :data:`CALIBRATION_PROTOCOL`
name a segment and the sensor angles it has; :func:`estimate_calibration` fits gains and offsets of the
model of :mod:`handsim.glove.calibration` to them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from handsim.datatypes.trajectory import Phase
from handsim.errors import HandsimError
from handsim.glove.calibration import NSENSORS, CalibrationError, GloveCalibration, sensor_index
from handsim.glove.phases import SWITCH_ON, switch_segments
from handsim.glove.sensors import SENSOR_NAMES


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
        raw_sequence: Raw counts of the sequence, shape (T, 23)
        (:func:`handsim.io.graspdb.glove.read_graspdb_raw`).
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
    raw, sw = _checked_inputs(raw_sequence, switch, hold_frames, trim_frames)
    segments, lengths = _calibration_segments(sw, provenance, expected_segments)
    base = base if base is not None else GloveCalibration.default()
    samples = _reference_samples(raw, segments, protocol, hold_frames, trim_frames)
    gains, offsets, residuals, fitted = _fit_sensors(samples, base)
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


def _checked_inputs(
    raw_sequence: npt.ArrayLike, switch: npt.ArrayLike, hold_frames: int, trim_frames: int
) -> tuple[np.ndarray, np.ndarray]:
    """The raw counts (T, 23) as floats and the switch states (T,), checked.

    Raises:
        CalibrationError: Bad frame counts to hold or trim, or arrays of the wrong shape or not finite.
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
    return raw, sw


def _calibration_segments(
    sw: np.ndarray, provenance: str, expected_segments: tuple[int, ...]
) -> tuple[tuple[Phase, ...], list[int]]:
    """The switch segments of a calibration sequence and their lengths in frames.

    Raises:
        CalibrationError: The switch is never ON, the sequence starts OFF, or it has a number of segments
            not in ``expected_segments``.
    """
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
    return segments, lengths


def _reference_samples(
    raw: np.ndarray,
    segments: tuple[Phase, ...],
    protocol: tuple[ReferencePose, ...],
    hold_frames: int,
    trim_frames: int,
) -> dict[int, list[tuple[str, np.ndarray, float]]]:
    """Per sensor index, each reference pose's name, the raw counts held in it and its angle in radians.

    Raises:
        CalibrationError: A pose names a missing segment, an unknown hold or an unknown sensor.
    """
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
            samples[sensor_index(sensor)].append(
                (pose.name, raw[rows, sensor_index(sensor)], math.radians(degrees))
            )
    return samples


def _fit_sensors(
    samples: dict[int, list[tuple[str, np.ndarray, float]]], base: GloveCalibration
) -> tuple[list[float], list[float], list[float | None], list[str]]:
    """Gains, offsets and RMS residuals (rad) per sensor, and the sensors whose gain was fitted.

    A sensor with reference angles of two or more values gets a least-squares gain and offset; with one
    value only its offset is fitted (``base``'s gain kept); without samples it keeps ``base``'s both.

    Raises:
        CalibrationError: A sensor whose mean counts at its reference angles differ by under 1 count.
    """
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
            _check_responds(name, samples[i], refs)
            gain, b = np.linalg.lstsq(np.column_stack([x, np.ones_like(x)]), y, rcond=None)[0]
            gains[i], offsets[i] = float(gain), float(-b / gain)
            fitted.append(name)
        else:
            offsets[i] = float(np.mean(x) - (refs[0] / gains[i] if gains[i] != 0.0 else 0.0))
        residuals[i] = float(np.sqrt(np.mean((gains[i] * (x - offsets[i]) - y) ** 2)))
    return gains, offsets, residuals, fitted


def _check_responds(name: str, samples: list[tuple[str, np.ndarray, float]], refs: list[float]) -> None:
    """Refuse a sensor whose mean counts at its reference angles differ by less than one count.

    Raises:
        CalibrationError: The sensor does not respond (the message lists its mean count per angle).
    """
    means = {ref: np.mean([s[1].mean() for s in samples if s[2] == ref]) for ref in refs}
    if max(means.values()) - min(means.values()) < 1.0:
        listing = ", ".join(f"{math.degrees(r):g}°: {m:.2f}" for r, m in means.items())
        raise CalibrationError(
            f"sensor {name} does not respond to the calibration poses: its mean counts at the "
            f"reference angles differ by less than 1 count ({listing})"
        )


__all__ = ["CALIBRATION_PROTOCOL", "EXPECTED_SEGMENTS", "ReferencePose", "estimate_calibration"]
