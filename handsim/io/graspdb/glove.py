"""Reader for GraspDB14 CyberGlove motion files (``*-rad-*.txt``, ``*-raw-*.txt``).

A motion file holds one row per sample: a time stamp, the glove's switch state and the 23 sensor readings
(rows parsed and checked by :mod:`handsim.io.graspdb.rows`).

``rad`` or ``raw`` is read from the file name (``-rad-``/``-raw-``,
:func:`~handsim.io.graspdb.filenames.filename_datatype`) and checked against the values: a ``rad`` file
holds no value above :data:`~handsim.io.graspdb.rows.RAW_LIMIT` in magnitude, a ``raw`` file only integer
counts; a disagreement is an error. A ``raw`` file becomes joint angles only with a calibration
(:func:`read_graspdb_glove` with ``calibration=``, see :mod:`handsim.glove.calibration`);
:func:`read_graspdb_raw` returns its counts as they are, e.g. to estimate a calibration.

The sensor → DoF conventions (every angle negated, ``T-TMCJ`` about local y, ``I-AA``/``P-Arch`` kept as
channels, DIPs computed) are those of the GraspDB14 MATLAB tools; see :mod:`handsim.glove.sensors`.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import Trajectory
from handsim.datatypes.trajectory_ops import with_limit_note
from handsim.errors import FormatError, TrajectoryError
from handsim.glove.calibration import GloveCalibration, apply_calibration
from handsim.glove.sensors import SENSORS, computed_dofs, discarded_sensors, driven_dofs
from handsim.io.graspdb.filenames import filename_datatype
from handsim.io.graspdb.rows import (
    FIRST_SENSOR_COLUMN,
    RAW_ADVICE,
    RAW_LIMIT,
    SWITCH_COLUMN,
    parse_rows,
    row_stamp,
    split_rows,
)
from handsim.io.text_files import MAX_RECORDING_BYTES, decode_text_file, read_bytes, sha256_of

_DIP_SENSORS = tuple(s for s in SENSORS if s.computed)


class RawGloveRecording(NamedTuple):
    """The content of a raw-count CyberGlove file (motion or calibration sequence).

    Attributes:
        times: Seconds since the first row, shape (T,).
        switch: Switch state per row, shape (T,), bool.
        counts: Raw 8-bit sensor counts, shape (T, 23), int64, columns in
            :data:`~handsim.glove.SENSOR_NAMES` order.
    """

    times: np.ndarray
    switch: np.ndarray
    counts: np.ndarray


def graspdb_row_count(path: str | Path) -> int:
    """How many rows (non-blank lines) a GraspDB14 motion file holds: its frame count once it reads.

    Args:
        path: The file.

    Returns:
        The number of rows, without parsing them.

    Raises:
        InputFileError: The file is missing, not a regular file, unreadable or too large
            (:func:`read_recording`).
        FormatError: It is not UTF-8 text (UTF-16, or NUL bytes).
    """
    return len(split_rows(decode_text_file(read_recording(path), path))[1])


def read_recording(path: str | Path) -> bytes:
    """The bytes of a glove recording, bounded by :data:`~handsim.io.text_files.MAX_RECORDING_BYTES`.

    Raises:
        InputFileError: Missing, not a regular file, unreadable, or larger than the limit (the message
            advises cutting it).
    """
    return read_bytes(
        path,
        MAX_RECORDING_BYTES,
        "a glove recording",
        " (about 80 minutes at 60 Hz; reading and replaying it takes memory in proportion): cut it into "
        "shorter recordings",
    )


def read_graspdb_raw(path: str | Path) -> RawGloveRecording:
    """Read a raw-count CyberGlove file: a ``*-raw-*`` motion or a recorded calibration sequence.

    Args:
        path: The file (rows as in a motion file, sensor values integer counts 0..255).

    Returns:
        ``(times, switch, counts)``.

    Raises:
        InputFileError: The file is missing, not a regular file, unreadable or too large
            (:func:`read_recording`).
        FormatError: The file name says ``-rad-`` or ``_annot-``, the file is empty, a row does not have 30
            entries, a time stamp or switch is invalid (as for :func:`read_graspdb_glove`), or a sensor
            value is not an integer count 0..255 (then it is probably a file of angles in radians). The
            message names the file, the 1-based line and the field.
    """
    p = Path(path)
    data = read_recording(p)
    _refuse_annotation(p)
    if filename_datatype(p) == "rad":
        raise FormatError(
            p,
            "the file name says it holds joint angles in radians ('-rad-'), not raw counts; "
            "read it with read_graspdb_glove",
        )
    why = (
        "the file name says raw ('-raw-'), but this value is not a count: is it a file of angles in radians?"
        if filename_datatype(p) == "raw"
        else "raw-count files hold 8-bit sensor counts; is this a file of angles in radians (read it with "
        "read_graspdb_glove)?"
    )
    values, times, _ = parse_rows(p, data, "raw", why)
    return RawGloveRecording(
        times=times,
        switch=values[:, SWITCH_COLUMN] == 1.0,
        counts=values[:, FIRST_SENSOR_COLUMN:].astype(np.int64),
    )


def read_graspdb_glove(
    path: str | Path, skeleton: Skeleton | None = None, calibration: GloveCalibration | None = None
) -> Trajectory:
    """Read a GraspDB14 CyberGlove recording as joint-angle targets.

    A ``rad`` file is read as it is. A ``raw`` file needs ``calibration``: its counts become angles with
    :func:`handsim.glove.apply_calibration`, then the same conventions apply.

    Conventions (those of the GraspDB14 MATLAB tools, see :mod:`handsim.glove.sensors`):

    * Every sensor angle is negated: ``target = -value``.
    * ``T-TMCJ`` drives ``th_tmc_pron``, i.e. the thumb TMC joint's local **y** axis, as the MATLAB code
      does, although the report's Table 5.1 says local z.
    * ``I-AA`` and ``P-Arch`` drive no DoF; their values (as in the file, not negated) are kept in
      :attr:`Trajectory.channels` under the sensor names.
    * ``I-DIPJ``, ``M-DIPJ``, ``R-DIPJ`` and ``L-DIPJ`` are not measured by the 18-sensor glove; their DoFs
      are listed in :attr:`Trajectory.computed`. A ``rad`` file holds the glove software's inferred
      values; a ``raw`` file holds 0 counts there, so after calibration they are 0 until
      :func:`handsim.glove.couple_dip` infers them (a note says so).

    Times are seconds since the first row, from the full date and time of each row (minute, hour and
    day changes are handled). All targets are marked valid.

    Args:
        path: The recording (``*-rad-*.txt`` or, with a calibration, ``*-raw-*.txt``; any name, with or
            without extension, is accepted: the values then tell ``rad`` from ``raw``).
        skeleton: The hand the targets are for. When given, the columns are ``skeleton.dof_names`` and
            DoFs the glove does not drive are held at 0 (listed in ``notes``). Without it, the columns
            are :func:`handsim.glove.driven_dofs` in sensor order.
        calibration: Converts a raw-count file; must be None for a file in radians.

    Returns:
        The trajectory, with ``switch``, ``source`` and ``sha256`` of the file bytes set.

    Raises:
        InputFileError: The file is missing, not a regular file, unreadable or too large
            (:func:`read_recording`).
        FormatError: The file is empty, a row does not have 30 entries, an entry is not a finite number,
            the switch is not 0 or 1, a time stamp is not a valid date and time or not after the
            previous row's; without a calibration, the file is a raw-count file (``-raw-`` in its name,
            or a sensor value with magnitude above 7); with one, the name says ``-rad-``, a sensor value
            is not an integer count 0..255, or a calibrated angle exceeds 7 rad in magnitude (the bound of
            ``rad`` files: a calibration that does not fit the glove). The message names the file, the
            1-based line and the field.
        TrajectoryError: ``skeleton`` lacks a DoF the glove drives (the message lists the missing DoFs
            and the skeleton's DoFs).
    """
    p = Path(path)
    data = read_recording(p)
    _refuse_annotation(p)
    values, times, rows, sensors = _sensor_angles(p, data, calibration)
    notes = _reading_notes(rows, calibration, values[:, FIRST_SENSOR_COLUMN:])
    dof_names, targets, held = _glove_targets(p, skeleton, sensors)
    if held:
        notes.append(f"DoFs not driven by the glove are held at 0: {held}")
    trajectory = Trajectory(
        times=times,
        dof_names=tuple(dof_names),
        targets=targets,
        valid=np.ones(targets.shape, dtype=bool),
        switch=values[:, SWITCH_COLUMN] == 1.0,
        channels={s.name: sensors[:, s.index].copy() for s in discarded_sensors()},
        computed=computed_dofs(),
        source=str(p),
        sha256=sha256_of(data),
        notes=tuple(notes),
    )
    return trajectory if skeleton is None else with_limit_note(trajectory, skeleton)


def _sensor_angles(
    p: Path, data: bytes, calibration: GloveCalibration | None
) -> tuple[np.ndarray, np.ndarray, list[list[str]], np.ndarray]:
    """The file's rows (values, times, raw rows) and its sensor angles in radians, calibrated if raw.

    Raises:
        FormatError: The file's name or values contradict whether a calibration was given, or a row is
            malformed (:func:`handsim.io.graspdb.rows.parse_rows`).
    """
    named = filename_datatype(p)
    if calibration is None:
        if named == "raw":
            raise FormatError(p, f"this is a raw-count file ('-raw-' in its name); {RAW_ADVICE}")
        why = ", although its name says '-rad-'" if named == "rad" else ""
        values, times, rows = parse_rows(p, data, "rad", why)
        return values, times, rows, values[:, FIRST_SENSOR_COLUMN:]
    if named == "rad":
        raise FormatError(
            p,
            "the file name says it holds joint angles in radians ('-rad-'), but a calibration was "
            "given: a calibration converts raw-count files only; read it without one",
        )
    why = (
        "the file name says raw ('-raw-'), but this value is not a count: is it a file of angles in radians?"
        if named == "raw"
        else "a calibration was given, so the file must hold raw counts; a file of angles in radians is "
        "read without a calibration"
    )
    values, times, rows = parse_rows(p, data, "raw", why)
    sensors = apply_calibration(values[:, FIRST_SENSOR_COLUMN:], calibration)
    _check_calibrated(p, data, values[:, FIRST_SENSOR_COLUMN:], sensors, calibration)
    return values, times, rows, sensors


def _reading_notes(
    rows: list[list[str]], calibration: GloveCalibration | None, counts: np.ndarray
) -> list[str]:
    """The notes on how the file was read: the time origin, the calibration, the GraspDB14 conventions."""
    notes = [f"times are seconds since the first row's time stamp {row_stamp(rows[0])}"]
    if calibration is not None:
        notes += _calibration_notes(calibration, counts)
    notes += [
        "every sensor angle was negated (target = -file value), as in the GraspDB14 MATLAB tools",
        "T-TMCJ drives th_tmc_pron (the thumb TMC joint's local y axis, as the GraspDB14 MATLAB code "
        "does; the report's Table 5.1 says z)",
        "I-AA and P-Arch drive no DoF (discarded by the GraspDB14 sensor map); their file values, not "
        "negated, are kept in channels",
    ]
    if calibration is None:
        notes.append(
            f"{', '.join(s.name for s in _DIP_SENSORS)} are not measured by the 18-sensor glove "
            "(the glove software infers them); their DoFs are listed as computed"
        )
    return notes


def _glove_targets(
    p: Path, skeleton: Skeleton | None, sensors: np.ndarray
) -> tuple[tuple[str, ...], np.ndarray, list[str]]:
    """The DoF names, the negated sensor angles as targets, and the skeleton's DoFs held at 0.

    Without a skeleton the columns are the driven DoFs in sensor order; with one, its DoFs.

    Raises:
        TrajectoryError: ``skeleton`` lacks a DoF the glove drives.
    """
    driven = driven_dofs()
    by_dof = {s.dof: s for s in SENSORS if s.dof is not None}
    if skeleton is None:
        return driven, -sensors[:, [by_dof[d].index for d in driven]], []
    dof_names = skeleton.dof_names
    missing = [d for d in driven if d not in dof_names]
    if missing:
        raise TrajectoryError(
            f"{p}: skeleton {skeleton.name!r} lacks DoFs the glove drives: {missing}; "
            f"its DoFs are {list(dof_names)}"
        )
    targets = np.zeros((sensors.shape[0], len(dof_names)))
    for col, name in enumerate(dof_names):
        if name in by_dof:
            targets[:, col] = -sensors[:, by_dof[name].index]
    return dof_names, targets, [d for d in dof_names if d not in by_dof]


def _check_calibrated(
    p: Path, data: bytes, counts: np.ndarray, angles: np.ndarray, calibration: GloveCalibration
) -> None:
    """Refuse calibrated angles beyond :data:`~handsim.io.graspdb.rows.RAW_LIMIT`, the bound of ``rad`` files.

    No joint turns more than a full turn (|angle| ≤ 2π); a calibrated angle beyond 7 rad comes from a gain
    or offset that does not fit the glove (a gain of −1000 rad/count instead of about −0.01), and would be
    replayed as targets clamped to the joint limits, judged as if it were motion.

    Raises:
        FormatError: The first such value, naming the line, the sensor, its count and the calibration's
            gain and offset for it.
    """
    beyond = np.abs(angles) > RAW_LIMIT
    if not beyond.any():
        return
    row, column = (int(i) for i in np.argwhere(beyond)[0])
    name = SENSORS[column].name
    linenos, _ = split_rows(decode_text_file(data, p))
    raise FormatError(
        p,
        f"count {counts[row, column]:g} becomes {angles[row, column]:.6g} rad with the calibration "
        f"'{calibration.provenance}' (gain {calibration.gains[column]:g} rad/count, offset "
        f"{calibration.offsets[column]:g}), beyond the {RAW_LIMIT:g} rad no joint angle exceeds (|angle| ≤ "
        f"2π; {int(beyond.sum())} calibrated values are): is the calibration this glove's?",
        line=linenos[row],
        field=f"sensor {name}",
    )


def _calibration_notes(calibration: GloveCalibration, counts: np.ndarray) -> list[str]:
    """Notes on a raw file converted with a calibration."""
    coupled = [f"{c.sensor} k={c.k:g}" for c in calibration.coupling if c.k != 0.0]
    notes = [
        f"raw 8-bit counts converted to radians with the calibration '{calibration.provenance}' "
        "(angle = gain * (raw - offset)"
        + (f"; abduction coupling {', '.join(coupled)})" if coupled else "; no abduction coupling)"),
        "MI-AA, RM-AA and LR-AA are the calibrated angles between two fingers; the glove software behind "
        "the rad files spreads them over per-finger abductions instead (docs/cyberglove.md)",
    ]
    dips = [s.index for s in _DIP_SENSORS]
    names = ", ".join(s.name for s in _DIP_SENSORS)
    if np.all(counts[:, dips] == 0):
        notes.append(
            f"{names} counts are 0 in this raw file (the 18-sensor glove does not measure them), so their "
            "DoFs (listed as computed) hold the calibrated 0 counts; infer them with handsim.glove.couple_dip"
        )
    else:
        notes.append(
            f"{names} counts are not all 0 (a 22-sensor glove?); their DoFs are still listed as computed"
        )
    return notes


def _refuse_annotation(p: Path) -> None:
    if "_annot-" in p.name.lower():
        raise FormatError(
            p, "this is a GraspDB14 phase annotation file ('_annot-' in its name), not a motion recording"
        )


__all__ = ["RawGloveRecording", "graspdb_row_count", "read_graspdb_glove", "read_graspdb_raw"]
