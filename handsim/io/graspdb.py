"""Reader for GraspDB14 CyberGlove motion files (``*-rad-*.txt``, ``*-raw-*.txt``) and their file names.

A motion file (spec §4.2.2, Table 4.3) has one row per sample, 30 blank-separated entries::

    YYYY MM DD HH mm ss.sssss switch  s0 s1 … s22

the date and time of the sample, the glove's switch state (0/1), then the 23 sensor readings of
:data:`handsim.glove.SENSORS`: joint angles in radians (``rad`` files) or 8-bit sensor counts, integers
0..255 (``raw`` files, and the recorded calibration sequences, same row format). Rows end with a
trailing blank in the original files; it is not required.

``rad`` or ``raw`` is read from the file name (``-rad-``/``-raw-``, :func:`filename_datatype`) and checked
against the values: a ``rad`` file holds no value above :data:`RAW_LIMIT` in magnitude, a ``raw`` file
only integer counts; a disagreement is an error. A ``raw`` file becomes joint angles only with a
calibration (:func:`read_graspdb_glove` with ``calibration=``, see :mod:`handsim.glove.calibration`);
:func:`read_graspdb_raw` returns its counts as they are, e.g. to estimate a calibration.

The sensor → DoF conventions (every angle negated, ``T-TMCJ`` about local y, ``I-AA``/``P-Arch`` kept as
channels, DIPs computed) are those of the GraspDB14 MATLAB tools; see :mod:`handsim.glove.sensors`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import NamedTuple

import numpy as np

from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import Trajectory
from handsim.datatypes.trajectory_ops import with_limit_note
from handsim.errors import FormatError, TrajectoryError
from handsim.glove.calibration import GloveCalibration, apply_calibration
from handsim.glove.sensors import SENSOR_NAMES, SENSORS, computed_dofs, discarded_sensors, driven_dofs
from handsim.io._text import decode_text, parse_float, read_bytes, sha256_of

NTOKENS = 30
"""Entries per motion row: 6 time-stamp fields, the switch, 23 sensors."""

RAW_LIMIT = 7.0
"""A sensor value with a larger magnitude marks a raw-count file (radians satisfy |x| ≤ 2π)."""

RAW_MAX = 255
"""Largest raw sensor count (8 bits)."""

MIN_FRAMES = 3
"""Fewest rows of a recording: two sample intervals, the least that describes a motion (a velocity and its
change); a 1- or 2-row file is a fragment, not a grasp (a GraspDB14 trial has 231 to 282 rows)."""

MIN_SAMPLE_INTERVAL_S = 1.0 / 150.0
"""Shortest time between two rows, s: 150 Hz, above the fastest CyberGlove (the CyberGlove III streams up
to 120 records/s, about 100 Hz for the original glove; GraspDB14 recorded at 60 Hz) with room for 1 ms
time-stamp jitter; see docs/cyberglove.md."""

MAX_SAMPLE_INTERVAL_S = 1.0
"""Longest time between two rows, s: 30 times the largest interval in the GraspDB14 samples (32 ms, one
dropped sample); over a longer hole the replay would interpolate more than a second of invented motion,
as long as a whole reach-to-grasp movement. A longer jump is refused before any resampling (a 1-hour jump
would be 360,000 frames at 100 Hz)."""

STAMP_TOLERANCE_S = 1e-6
"""Rounding allowed when an interval is compared with those bounds, s: a tenth of the files' 10 µs time-stamp
resolution (8.021 s − 7.021 s is 1.0000000000000009 s in floating point, and is 1 s)."""

DEGREES_SHARE = 0.25
"""Share of sensor values above :data:`RAW_LIMIT` from which a file that holds no raw counts is taken to be
in degrees (in the three GraspDB14 sample trials converted to degrees, 53 to 69 % exceed 7)."""

_TIMESTAMP_FIELDS = ("year", "month", "day", "hour", "minute", "second")
FIELDS: tuple[str, ...] = (
    *(f"timestamp {f}" for f in _TIMESTAMP_FIELDS),
    "switch",
    *(f"sensor {n}" for n in SENSOR_NAMES),
)
"""Field name of each of the 30 row entries, as used in error messages."""

_SWITCH = 6
_FIRST_SENSOR = 7
_RAW_ADVICE = (
    "raw files hold uncalibrated 8-bit sensor counts, not radians, and need a calibration to become "
    "joint angles: pass one (read_graspdb_glove(path, calibration=...)), e.g. estimated with "
    "handsim.glove.estimate_calibration from the actor's '_calib-' sequence, or read the matching '-rad-' "
    "file instead"
)
_DIP_SENSORS = tuple(s for s in SENSORS if s.computed)


# --------------------------------------------------------------------------------------------------
# File names


@dataclass(frozen=True)
class GraspDBName:
    """What a GraspDB14 motion (or phase annotation) file name says, spec §4.1.2.

    Attributes:
        object_id: Object grasped or manipulated (Table 4.1), e.g. 1 for the tennis ball.
        scenario: Recording scenario ``exNo`` as written, e.g. ``"01"`` or ``"03-1"``.
        datatype: ``"rad"`` (joint angles in radians) or ``"raw"`` (8-bit sensor counts).
        trial_id: Linear trial counter.
        actor_id: Actor (subject) who performed the task.
        grasp_id: Grasp type after Feix et al. (Table 3.3); present in scenario 3 names.
        action_id: Action (Table 4.2), e.g. ``"i_r"``; present in scenario 2 names.
        annotation: True for a phase annotation file (``…_annot-.txt``).
        prefix: Text before the object id, without its ``_`` (``"r"`` in ``r_01_11_ex03-…``); its meaning
            is not documented in the spec.
    """

    object_id: int
    scenario: str
    datatype: str
    trial_id: int
    actor_id: int
    grasp_id: int | None = None
    action_id: str | None = None
    annotation: bool = False
    prefix: str = ""

    @property
    def scenario_number(self) -> int:
        """The scenario as a number: 1, 2 or 3 (``"03-1"`` → 3)."""
        return int(self.scenario.split("-")[0])


_NAME_RE = re.compile(
    r"""
    (?:(?P<prefix>[a-z]+)_)?             # optional prefix, e.g. "r_"
    (?P<obj>\d+)                         # object id
    (?:_(?P<grasp>\d+)|_(?P<action>[a-z]_[a-z]))?   # grasp id (scenario 3) or action id (scenario 2)
    _ex(?P<ex>\d+(?:-\d+)?)              # scenario, e.g. 03 or 03-1
    -(?P<dtype>rad|raw)
    -(?P<trial>\d+)
    -grasp-su(?P<actor>\d+)
    (?P<annot>_annot-)?
    (?:\.txt)?
    """,
    re.IGNORECASE | re.VERBOSE,
)


def parse_graspdb_filename(name: str | Path) -> GraspDBName | None:
    """Decode a GraspDB14 motion file name (spec §4.1.2).

    Recognised forms (``.txt`` optional, case ignored, any folder part ignored)::

        <objID>_ex<exNo>-<datatype>-<trialID>-grasp-su<actorID>.txt              scenario 1
        <objID>_<actionID>_ex<exNo>-<datatype>-<trialID>-grasp-su<actorID>.txt   scenario 2
        <objID>_<graspID>_ex<exNo>-<datatype>-<trialID>-grasp-su<actorID>.txt    scenario 3

    optionally with a prefix such as ``r_`` before the object id, and with ``_annot-`` before the
    extension for a phase annotation file. Whether a grasp or an action id is present is read from the
    name, not inferred from the scenario number.

    Args:
        name: A file name or path.

    Returns:
        The decoded name, or None when the name does not follow the pattern (not an error: any file may
        be read, whatever its name).
    """
    m = _NAME_RE.fullmatch(Path(name).name)
    if m is None:
        return None
    return GraspDBName(
        object_id=int(m["obj"]),
        scenario=m["ex"],
        datatype=m["dtype"].lower(),
        trial_id=int(m["trial"]),
        actor_id=int(m["actor"]),
        grasp_id=int(m["grasp"]) if m["grasp"] else None,
        action_id=m["action"].lower() if m["action"] else None,
        annotation=m["annot"] is not None,
        prefix=(m["prefix"] or "").lower(),
    )


# --------------------------------------------------------------------------------------------------
# Motion files


def filename_datatype(path: str | Path) -> str | None:
    """What a file name says the values are: ``"rad"``, ``"raw"``, or None when it does not say.

    Args:
        path: A file name or path; a GraspDB14 name (:func:`parse_graspdb_filename`) or any name holding
            ``-rad-`` or ``-raw-`` (case ignored).

    Returns:
        ``"rad"``, ``"raw"`` or None.
    """
    parsed = parse_graspdb_filename(path)
    if parsed is not None:
        return parsed.datatype
    lowered = Path(path).name.lower()
    kinds = [k for k in ("rad", "raw") if f"-{k}-" in lowered]
    return kinds[0] if len(kinds) == 1 else None


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
        InputFileError: The file is missing or unreadable.
    """
    return len(_split_rows(decode_text(read_bytes(Path(path))))[1])


def read_graspdb_raw(path: str | Path) -> RawGloveRecording:
    """Read a raw-count CyberGlove file: a ``*-raw-*`` motion or a recorded calibration sequence.

    Args:
        path: The file (rows as in a motion file, sensor values integer counts 0..255).

    Returns:
        ``(times, switch, counts)``.

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: The file name says ``-rad-`` or ``_annot-``, the file is empty, a row does not have 30
            entries, a time stamp or switch is invalid (as for :func:`read_graspdb_glove`), or a sensor
            value is not an integer count 0..255 (then it is probably a file of angles in radians). The
            message names the file, the 1-based line and the field.
    """
    p = Path(path)
    data = read_bytes(p)
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
    values, times, _ = _parse(p, data, "raw", why)
    return RawGloveRecording(
        times=times,
        switch=values[:, _SWITCH] == 1.0,
        counts=values[:, _FIRST_SENSOR:].astype(np.int64),
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
        InputFileError: The file is missing or unreadable.
        FormatError: The file is empty, a row does not have 30 entries, an entry is not a finite number,
            the switch is not 0 or 1, a time stamp is not a valid date and time or not after the
            previous row's; without a calibration, the file is a raw-count file (``-raw-`` in its name,
            or a sensor value with magnitude above 7); with one, the name says ``-rad-`` or a sensor value
            is not an integer count 0..255. The message names the file, the 1-based line and the field.
        TrajectoryError: ``skeleton`` lacks a DoF the glove drives (the message lists the missing DoFs
            and the skeleton's DoFs).
    """
    p = Path(path)
    data = read_bytes(p)
    _refuse_annotation(p)
    named = filename_datatype(p)
    if calibration is None:
        if named == "raw":
            raise FormatError(p, f"this is a raw-count file ('-raw-' in its name); {_RAW_ADVICE}")
        why = ", although its name says '-rad-'" if named == "rad" else ""
        values, times, rows = _parse(p, data, "rad", why)
        sensors = values[:, _FIRST_SENSOR:]
    else:
        if named == "rad":
            raise FormatError(
                p,
                "the file name says it holds joint angles in radians ('-rad-'), but a calibration was "
                "given: a calibration converts raw-count files only; read it without one",
            )
        why = (
            "the file name says raw ('-raw-'), but this value is not a count: is it a file of angles in "
            "radians?"
            if named == "raw"
            else "a calibration was given, so the file must hold raw counts; a file of angles in radians is "
            "read without a calibration"
        )
        values, times, rows = _parse(p, data, "raw", why)
        sensors = apply_calibration(values[:, _FIRST_SENSOR:], calibration)

    driven = driven_dofs()
    by_dof = {s.dof: s for s in SENSORS if s.dof is not None}
    notes = [f"times are seconds since the first row's time stamp {_stamp(rows[0])}"]
    if calibration is not None:
        notes += _calibration_notes(calibration, values[:, _FIRST_SENSOR:])
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
    if skeleton is None:
        dof_names = driven
        targets = -sensors[:, [by_dof[d].index for d in driven]]
    else:
        dof_names = skeleton.dof_names
        missing = [d for d in driven if d not in dof_names]
        if missing:
            raise TrajectoryError(
                f"{p}: skeleton {skeleton.name!r} lacks DoFs the glove drives: {missing}; "
                f"its DoFs are {list(dof_names)}"
            )
        targets = np.zeros((values.shape[0], len(dof_names)))
        for col, name in enumerate(dof_names):
            if name in by_dof:
                targets[:, col] = -sensors[:, by_dof[name].index]
        held = [d for d in dof_names if d not in by_dof]
        if held:
            notes.append(f"DoFs not driven by the glove are held at 0: {held}")

    trajectory = Trajectory(
        times=times,
        dof_names=tuple(dof_names),
        targets=targets,
        valid=np.ones(targets.shape, dtype=bool),
        switch=values[:, _SWITCH] == 1.0,
        channels={s.name: sensors[:, s.index].copy() for s in discarded_sensors()},
        computed=computed_dofs(),
        source=str(p),
        sha256=sha256_of(data),
        notes=tuple(notes),
    )
    return trajectory if skeleton is None else with_limit_note(trajectory, skeleton)


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


def _parse(p: Path, data: bytes, kind: str, why: str) -> tuple[np.ndarray, np.ndarray, list[list[str]]]:
    """Rows as an (N, 30) array, times since the first row, and the tokens; raises on the first bad row.

    Args:
        p: The file, for messages.
        data: Its bytes.
        kind: ``"rad"`` (sensor values in radians, |x| <= :data:`RAW_LIMIT`) or ``"raw"`` (integer counts
            0..:data:`RAW_MAX`).
        why: Text added to the message of a sensor value that does not fit ``kind``.
    """
    # Text that is not UTF-8 can only sit in a token that is not a number; that error shows it as Latin-1.
    text = decode_text(data)
    linenos, rows = _split_rows(text)
    if not rows:
        what = "23 sensor values in radians" if kind == "rad" else "23 raw sensor counts"
        raise FormatError(
            p,
            f"empty file: expected rows of {NTOKENS} blank-separated entries "
            f"(YYYY MM DD HH mm ss.sssss switch, then {what})",
        )
    values = _fast_parse(rows, kind)
    times = _fast_times(values) if values is not None else None
    if values is None or times is None:
        values = _checked_parse(
            p, linenos, rows, kind, why
        )  # raises a precise FormatError on the first bad row
        times = _fast_times(values)
        if times is None:  # pragma: no cover - the row-by-row check covers every fast-path check
            raise FormatError(p, "rows failed validation, but no single row could be blamed")
    _check_timing(p, linenos, rows, times)
    return values, times, rows


def _check_timing(p: Path, linenos: list[int], rows: list[list[str]], times: np.ndarray) -> None:
    """Refuse too few rows, and sample intervals no CyberGlove produces (see the bounds' docstrings)."""
    if len(times) < MIN_FRAMES:
        raise FormatError(
            p,
            f"{len(times)} row{'s' if len(times) != 1 else ''}: a recording needs at least {MIN_FRAMES} "
            "(two sample intervals) to describe a motion",
        )
    steps = np.diff(times)
    fast = np.flatnonzero(steps < MIN_SAMPLE_INTERVAL_S - STAMP_TOLERANCE_S)
    slow = np.flatnonzero(steps > MAX_SAMPLE_INTERVAL_S + STAMP_TOLERANCE_S)
    first = min((*fast[:1], *slow[:1]), default=None)
    if first is None:
        return
    k = int(first) + 1
    step = float(steps[k - 1])
    after = f"time stamp {_stamp(rows[k])!r} is {step:.6g} s after the previous row's (line {linenos[k - 1]})"
    if step < MIN_SAMPLE_INTERVAL_S - STAMP_TOLERANCE_S:
        reason = (
            f"{after}: closer than {MIN_SAMPLE_INTERVAL_S * 1e3:.3g} ms, a sampling rate above "
            f"{1 / MIN_SAMPLE_INTERVAL_S:g} Hz, faster than any CyberGlove records (at most 120 records/s); "
            "are the time stamps right?"
        )
    else:
        reason = (
            f"{after}: more than the {MAX_SAMPLE_INTERVAL_S:g} s a recording may skip (the replay would "
            "invent the hand's motion over the hole); cut the recording there into two files"
        )
    raise FormatError(p, reason, line=linenos[k], field="timestamp")


def _split_rows(text: str) -> tuple[list[int], list[list[str]]]:
    """Tokens of every non-blank line, with the 1-based line numbers."""
    linenos: list[int] = []
    rows: list[list[str]] = []
    for i, line in enumerate(text.splitlines(), start=1):
        tokens = line.split()
        if tokens:
            linenos.append(i)
            rows.append(tokens)
    return linenos, rows


def _stamp(tokens: list[str]) -> str:
    """The time stamp of a row as written (``YYYY MM DD HH mm ss.sssss``)."""
    return " ".join(tokens[:6])


def _fast_parse(rows: list[list[str]], kind: str) -> np.ndarray | None:
    """All rows as an (N, 30) float array, or None if any row is malformed (then check row by row)."""
    if any(len(r) != NTOKENS for r in rows):
        return None
    try:
        values = np.array(rows, dtype=float)
    except ValueError:
        return None
    if not np.all(np.isfinite(values)):
        return None
    switch = values[:, _SWITCH]
    if not np.all((switch == 0.0) | (switch == 1.0)):
        return None
    sensors = values[:, _FIRST_SENSOR:]
    if kind == "rad" and np.any(np.abs(sensors) > RAW_LIMIT):
        return None
    if kind == "raw" and not np.all((sensors >= 0) & (sensors <= RAW_MAX) & (sensors == np.round(sensors))):
        return None
    return values


def _fast_times(values: np.ndarray) -> np.ndarray | None:
    """Seconds since the first row, or None if a time stamp is invalid or not after the previous one."""
    seconds = values[:, 5]
    if np.any((seconds < 0.0) | (seconds >= 60.0)):
        return None
    minutes, inverse = np.unique(values[:, :5], axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    try:
        stamps = [_minute(row) for row in minutes]
    except (ValueError, OverflowError):
        return None
    base = stamps[int(inverse[0])]
    offsets = np.array([(s - base).total_seconds() for s in stamps])
    times = offsets[inverse] + (seconds - seconds[0])
    if np.any(np.diff(times) <= 0.0):
        return None
    return times


def _minute(fields: np.ndarray | list[float]) -> datetime:
    """The date and time (to the minute) from year, month, day, hour, minute values.

    Raises:
        ValueError: A value is not an integer, or the date or time does not exist.
    """
    ints = []
    for v in fields:
        if not float(v).is_integer():
            raise ValueError(f"{v!r} is not an integer")
        ints.append(int(v))
    return datetime(*ints)


def _not_radians(token: str, rows: list[list[str]], why: str) -> str:
    """Why a sensor value above :data:`RAW_LIMIT` is not an angle in radians, judged on every row.

    Raw counts: every sensor value of the file is an integer 0..:data:`RAW_MAX`. Degrees: not counts, at
    least :data:`DEGREES_SHARE` of the values exceed :data:`RAW_LIMIT` and none exceeds 360 (a GraspDB14
    trial converted to degrees has 53 to 69 % of its values above 7). Anything else is one bad value.
    """
    numbers = []
    for tokens in rows:
        for t in tokens[_FIRST_SENSOR:]:
            try:
                numbers.append(float(t))
            except ValueError:
                continue
    values = np.array(numbers)
    values = values[np.isfinite(values)]
    exceeds = f"value {token} exceeds {RAW_LIMIT:g} in magnitude"
    if np.all((values >= 0) & (values <= RAW_MAX) & (values == np.round(values))):
        radians = "angles in radians satisfy |x| <= 2*pi"
        return f"{exceeds}, so this is a raw-count file ({radians}){why}; {_RAW_ADVICE}"
    magnitude = np.abs(values)
    share = float(np.mean(magnitude > RAW_LIMIT))
    if share >= DEGREES_SHARE and magnitude.max() <= 360.0:
        return (
            f"{exceeds}: the sensor values reach {magnitude.max():g} and {share:.0%} of them exceed 7, so "
            "they look like angles in degrees; GraspDB14 'rad' files hold radians (|x| <= 2*pi): convert "
            "the file's sensor values to radians"
        )
    return f"{exceeds}; expected a joint angle in radians (|x| <= 2*pi)"


def _checked_parse(path: Path, linenos: list[int], rows: list[list[str]], kind: str, why: str) -> np.ndarray:
    """Parse row by row, raising a :class:`FormatError` that names line and field at the first problem.

    This is the slow path, taken only when the vectorised parse found something wrong; it applies the
    same checks in row order so the error points at the first offending row.
    """
    values = np.empty((len(rows), NTOKENS))
    base: datetime | None = None
    first_second = 0.0
    previous: tuple[float, int, list[str]] | None = None
    for k, (line, tokens) in enumerate(zip(linenos, rows, strict=True)):
        if len(tokens) != NTOKENS:
            raise FormatError(
                path,
                f"expected {NTOKENS} blank-separated entries (6 time-stamp fields, switch, 23 sensors), "
                f"got {len(tokens)}",
                line=line,
            )
        row = [parse_float(t, path, line, f) for t, f in zip(tokens, FIELDS, strict=True)]
        for i in range(5):
            if not row[i].is_integer():
                raise FormatError(path, f"expected an integer, got {tokens[i]!r}", line=line, field=FIELDS[i])
        try:
            minute = datetime(*(int(v) for v in row[:5]))
        except (ValueError, OverflowError) as exc:
            raise FormatError(
                path,
                f"time stamp {_stamp(tokens)!r} is not a valid date and time ({exc})",
                line=line,
                field="timestamp",
            ) from None
        second = row[5]
        if not 0.0 <= second < 60.0:
            raise FormatError(
                path, f"expected seconds in [0, 60), got {tokens[5]!r}", line=line, field=FIELDS[5]
            )
        if row[_SWITCH] not in (0.0, 1.0):
            raise FormatError(
                path, f"expected 0 (off) or 1 (on), got {tokens[_SWITCH]!r}", line=line, field="switch"
            )
        for i in range(_FIRST_SENSOR, NTOKENS):
            if kind == "rad" and abs(row[i]) > RAW_LIMIT:
                raise FormatError(path, _not_radians(tokens[i], rows, why), line=line, field=FIELDS[i])
            if kind == "raw" and not (row[i].is_integer() and 0 <= row[i] <= RAW_MAX):
                raise FormatError(
                    path,
                    f"expected a raw sensor count (an integer from 0 to {RAW_MAX}), got {tokens[i]!r}; {why}",
                    line=line,
                    field=FIELDS[i],
                )
        if base is None:
            base, first_second = minute, second
        t = (minute - base).total_seconds() + (second - first_second)
        if previous is not None and not t > previous[0]:
            raise FormatError(
                path,
                f"time stamp {_stamp(tokens)!r} is not after the previous row's {_stamp(previous[2])!r} "
                f"(line {previous[1]}); time stamps must strictly increase",
                line=line,
                field="timestamp",
            )
        previous = (t, line, tokens)
        values[k] = row
    return values


__all__ = [
    "FIELDS",
    "NTOKENS",
    "RAW_LIMIT",
    "RAW_MAX",
    "GraspDBName",
    "RawGloveRecording",
    "filename_datatype",
    "parse_graspdb_filename",
    "read_graspdb_glove",
    "read_graspdb_raw",
]
