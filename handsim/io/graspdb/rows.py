"""Rows of a GraspDB14 CyberGlove motion file: parsed, checked and timed.

A motion file (spec §4.2.2, Table 4.3) has one row per sample, 30 blank-separated entries::

    YYYY MM DD HH mm ss.sssss switch  s0 s1 … s22

the date and time of the sample, the glove's switch state (0/1), then the 23 sensor readings of
:data:`handsim.glove.SENSORS`: joint angles in radians (``rad`` files) or 8-bit sensor counts, integers
0..255 (``raw`` files, and the recorded calibration sequences, same row format). Rows end with a
trailing blank in the original files; it is not required.

:func:`parse_rows` turns the file's bytes into an (N, 30) array and the times since the first row, fast
(vectorised) when every row is good, else row by row to name the first bad line and field. A ``rad`` file
holds no value above :data:`RAW_LIMIT` in magnitude, a ``raw`` file only integer counts; a recording has at
least :data:`MIN_FRAMES` rows, and its sample intervals lie within :data:`MIN_SAMPLE_INTERVAL_S` ..
:data:`MAX_SAMPLE_INTERVAL_S`. The readers are in :mod:`handsim.io.graspdb.glove`.
"""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

import numpy as np

from handsim.errors import FormatError
from handsim.glove.sensors import SENSOR_NAMES
from handsim.io.text_files import decode_text_file, parse_float

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

SWITCH_COLUMN = 6
"""Row entry of the switch state."""
FIRST_SENSOR_COLUMN = 7
"""Row entry of the first sensor value (23 follow)."""
RAW_ADVICE = (
    "raw files hold uncalibrated 8-bit sensor counts, not radians, and need a calibration to become "
    "joint angles: pass one (read_graspdb_glove(path, calibration=...)), e.g. estimated with "
    "handsim.glove.estimate_calibration from the actor's '_calib-' sequence, or read the matching '-rad-' "
    "file instead"
)
"""What to do with a raw-count file read as radians (ends the messages that refuse one)."""


def parse_rows(p: Path, data: bytes, kind: str, why: str) -> tuple[np.ndarray, np.ndarray, list[list[str]]]:
    """Rows as an (N, 30) array, times since the first row, and the tokens; raises on the first bad row.

    Args:
        p: The file, for messages.
        data: Its bytes.
        kind: ``"rad"`` (sensor values in radians, |x| <= :data:`RAW_LIMIT`) or ``"raw"`` (integer counts
            0..:data:`RAW_MAX`).
        why: Text added to the message of a sensor value that does not fit ``kind``.
    """
    # Text that is not UTF-8 can only sit in a token that is not a number; that error shows it as Latin-1.
    text = decode_text_file(data, p)
    linenos, rows = split_rows(text)
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
    after = (
        f"time stamp {row_stamp(rows[k])!r} is {step:.6g} s after the previous row's (line {linenos[k - 1]})"
    )
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


def split_rows(text: str) -> tuple[list[int], list[list[str]]]:
    """Tokens of every non-blank line, with the 1-based line numbers."""
    linenos: list[int] = []
    rows: list[list[str]] = []
    for i, line in enumerate(text.splitlines(), start=1):
        tokens = line.split()
        if tokens:
            linenos.append(i)
            rows.append(tokens)
    return linenos, rows


def row_stamp(tokens: list[str]) -> str:
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
    switch = values[:, SWITCH_COLUMN]
    if not np.all((switch == 0.0) | (switch == 1.0)):
        return None
    sensors = values[:, FIRST_SENSOR_COLUMN:]
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
        for t in tokens[FIRST_SENSOR_COLUMN:]:
            try:
                numbers.append(float(t))
            except ValueError:
                continue
    values = np.array(numbers)
    values = values[np.isfinite(values)]
    exceeds = f"value {token} exceeds {RAW_LIMIT:g} in magnitude"
    if np.all((values >= 0) & (values <= RAW_MAX) & (values == np.round(values))):
        radians = "angles in radians satisfy |x| <= 2*pi"
        return f"{exceeds}, so this is a raw-count file ({radians}){why}; {RAW_ADVICE}"
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
                f"time stamp {row_stamp(tokens)!r} is not a valid date and time ({exc})",
                line=line,
                field="timestamp",
            ) from None
        second = row[5]
        if not 0.0 <= second < 60.0:
            raise FormatError(
                path, f"expected seconds in [0, 60), got {tokens[5]!r}", line=line, field=FIELDS[5]
            )
        if row[SWITCH_COLUMN] not in (0.0, 1.0):
            raise FormatError(
                path, f"expected 0 (off) or 1 (on), got {tokens[SWITCH_COLUMN]!r}", line=line, field="switch"
            )
        for i in range(FIRST_SENSOR_COLUMN, NTOKENS):
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
                f"time stamp {row_stamp(tokens)!r} is not after the previous row's "
                f"{row_stamp(previous[2])!r} "
                f"(line {previous[1]}); time stamps must strictly increase",
                line=line,
                field="timestamp",
            )
        previous = (t, line, tokens)
        values[k] = row
    return values


__all__ = [
    "DEGREES_SHARE",
    "FIELDS",
    "FIRST_SENSOR_COLUMN",
    "MAX_SAMPLE_INTERVAL_S",
    "MIN_FRAMES",
    "MIN_SAMPLE_INTERVAL_S",
    "NTOKENS",
    "RAW_ADVICE",
    "RAW_LIMIT",
    "RAW_MAX",
    "STAMP_TOLERANCE_S",
    "SWITCH_COLUMN",
    "parse_rows",
    "row_stamp",
    "split_rows",
]
