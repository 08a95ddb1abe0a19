"""Recognising a recorded CyberGlove calibration sequence (spec 003 §3.5), so it is not taken for grasps.

A calibration sequence is no motion trial: its flexion rises and falls as the actor makes a fist, bends the
fingers over a table edge and touches the thumb to each finger, and a grasp segmentation would list those
as grasps. It is recognised by either of two signs:

* **Its name**: GraspDB14 names the sequences ``<nn>_calib-<rad|raw>-su<actor>.txt``
  (``00_calib-rad-su01.txt``); :data:`CALIBRATION_NAME_MARK` in the file name.
* **Its content**: the switch splits it into :data:`~handsim.glove.calibration_estimation.EXPECTED_SEGMENTS`
  (20 or 21) ON/OFF segments starting ON, as the protocol presses it (§3.5), **and** in at least one of the
  two thumb-to-finger touch segments (:data:`TOUCH_SEGMENTS`: thumb to each fingertip, then to each middle
  phalanx) the fingers flex one after the other in the protocol's order, index → middle → ring → little:
  each finger's flexion (its measured MCP + PIP sensors) peaks later than the previous finger's. Both are
  needed: a session whose switch happens to give 20 segments is no calibration sequence unless its
  touches follow the protocol, and the chance that four fingers peak in this order by accident is 1 in 24
  per segment.

In GraspDB14's ``00_calib-rad-su01.txt`` (21 segments) the fingers peak at 99.1, 99.9, 100.3 and 100.9 s
in the fingertip touches and at 103.4, 104.0, 104.6 and 105.1 s in the phalanx touches.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.datatypes.trajectory import Phase, Trajectory
from handsim.glove.calibration_estimation import EXPECTED_SEGMENTS
from handsim.glove.phases import SWITCH_ON, switch_segments
from handsim.glove.sensors import SENSORS

CALIBRATION_NAME_MARK = "_calib-"
"""What a GraspDB14 calibration sequence's file name holds (case ignored): ``00_calib-rad-su01.txt``."""

TOUCH_SEGMENTS = (18, 19)
"""0-based switch segments of the thumb-to-finger touches (spec §3.5): fingertips, then middle phalanges."""

FINGER_ORDER: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("index", ("I-MCPJ", "I-PIPJ")),
    ("middle", ("M-MCPJ", "M-PIPJ")),
    ("ring", ("R-MCPJ", "R-PIPJ")),
    ("little", ("L-MCPJ", "L-PIPJ")),
)
"""The fingers in the order the thumb touches them, each with its measured flexion sensors."""

CALIBRATE_HINT = "calibration sequence (use `handsim calibrate`)"
"""What a recognised calibration sequence is listed as instead of grasps."""


@dataclass(frozen=True)
class CalibrationSequence:
    """Why a recording is taken for a CyberGlove calibration sequence.

    Attributes:
        by_name: Its file name holds :data:`CALIBRATION_NAME_MARK`.
        by_content: Its switch segments and thumb-to-finger touches follow the protocol.
        note: For people: what was found (names the segments and the touch times, or why the content does
            not match).
    """

    by_name: bool
    by_content: bool
    note: str

    def text(self) -> str:
        """One line: :data:`CALIBRATE_HINT` and the evidence."""
        return f"{CALIBRATE_HINT}: {self.note}"


def recognise_calibration_sequence(trajectory: Trajectory) -> CalibrationSequence | None:
    """Whether a glove recording is a calibration sequence, by its name or its content.

    Args:
        trajectory: A recording as read; its :attr:`~Trajectory.source` is the file name looked at, its
            switch state and the finger flexion DoFs of :data:`FINGER_ORDER` the content.

    Returns:
        The evidence, or None when neither the name nor the content says calibration sequence.
    """
    by_name = CALIBRATION_NAME_MARK in Path(trajectory.source).name.lower()
    touches, why = _touch_pattern(trajectory)
    if not by_name and touches is None:
        return None
    name = Path(trajectory.source).name
    parts = []
    if by_name:
        parts.append(f"the file name {name} holds {CALIBRATION_NAME_MARK!r}")
    if touches is not None:
        parts.append(touches)
    else:
        parts.append(f"its content does not show the protocol ({why})")
    return CalibrationSequence(by_name, touches is not None, "; ".join(parts))


def _touch_pattern(trajectory: Trajectory) -> tuple[str | None, str]:
    """The protocol's content (a description) or None, and why not."""
    if trajectory.switch is None:
        return None, "no switch state"
    segments = switch_segments(trajectory.switch)
    counts = " or ".join(str(n) for n in EXPECTED_SEGMENTS)
    if segments[0].name != SWITCH_ON or len(segments) not in EXPECTED_SEGMENTS:
        first = segments[0].name.upper()
        return None, f"{len(segments)} switch segments starting {first}, not {counts} starting ON"
    columns = _finger_columns(trajectory.dof_names)
    if columns is None:
        return None, "no flexion DoFs of the four fingers"
    found = []
    for k in TOUCH_SEGMENTS:
        peaks = _finger_peaks(trajectory, columns, segments[k])
        if all(a < b for a, b in itertools.pairwise(peaks)):
            times = ", ".join(f"{trajectory.times[p]:.1f}" for p in peaks)
            found.append(f"segment {k} (index, middle, ring, little flex at {times} s)")
    if not found:
        return None, (
            f"in the touch segments {' and '.join(map(str, TOUCH_SEGMENTS))} the fingers do not flex in the "
            "order index, middle, ring, little"
        )
    return (
        f"{len(segments)} switch segments starting ON and the thumb-to-finger touches of spec §3.5 in "
        f"{' and '.join(found)}"
    ), ""


def _finger_columns(dof_names: tuple[str, ...]) -> list[list[int]] | None:
    """Per finger of :data:`FINGER_ORDER`, the columns of its measured flexion DoFs; None if one has none."""
    dof_of = {s.name: s.dof for s in SENSORS}
    columns = []
    for _, sensors in FINGER_ORDER:
        cols = [dof_names.index(dof_of[s]) for s in sensors if dof_of[s] in dof_names]
        if not cols:
            return None
        columns.append(cols)
    return columns


def _finger_peaks(trajectory: Trajectory, columns: list[list[int]], segment: Phase) -> list[int]:
    """The frame at which each finger's summed flexion peaks within a segment."""
    rows = np.asarray(trajectory.targets[segment.start : segment.stop], dtype=float)
    return [segment.start + int(np.argmax(rows[:, cols].sum(axis=1))) for cols in columns]


__all__ = [
    "CALIBRATE_HINT",
    "CALIBRATION_NAME_MARK",
    "FINGER_ORDER",
    "TOUCH_SEGMENTS",
    "CalibrationSequence",
    "recognise_calibration_sequence",
]
