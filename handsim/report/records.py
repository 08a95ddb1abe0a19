"""Reading a run's output folder: ``records.jsonl`` (one trial per line) and ``run.json``.

The report is rendered from these files alone, read by the runner's own reader
(:func:`handsim.runner.records.load_records`: a cut-off last line is skipped with a note). Records are
returned sorted by trial id (natural order, ``Models/9`` before ``Models/10``), so the order in which a
process pool finished the trials does not change the report.

A value the report reads as a number or a yes/no that is something else (``"max_penetration_mm": "lots"``
in an edited or corrupted file) is shown as missing, as a null is, but also noted, naming the record and
the key (:func:`value_notes`): the report never turns a bad value into "no metrics" silently.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from handsim.errors import InputFileError
from handsim.runner.records import (
    RECORDS_FILE,
    RUN_FILE,
    STATUSES,
    RecordsError,
    load_records,
    read_run_info,
)


@dataclass(frozen=True)
class RunRecords:
    """What a run wrote, as read back.

    Attributes:
        out_dir: The run's output folder.
        records: One record per trial (the first one written for an id), sorted by :func:`natural_key` of
            the id.
        run: The contents of ``run.json``, or None when the file is absent.
        notes: What reading had to decide (a cut-off last line skipped, repeated ids, no ``run.json``, a
            value the report cannot use).
    """

    out_dir: Path
    records: tuple[dict, ...]
    run: dict | None
    notes: tuple[str, ...]


CHECKED_SECTIONS = ("summary", "trajectory_quality")
"""The parts of a record whose values the report reads as numbers and yes/no values."""

NUMBER_KEY_ENDINGS = (
    "_mm", "1mm", "_deg", "_s", "_n", "_nm", "fraction", "robustness", "opposition", "frames", "warnings",
    "violations", "filled", "samples", "_held", "pairs",
)  # fmt: skip
"""Endings of the keys in :data:`CHECKED_SECTIONS` whose values are numbers (a unit: mm, degrees,
seconds, newtons; or a count or fraction), as the record writer names them (``docs/records.md``)."""

YES_NO_KEYS = ("valid", "held", "diverged", "stable")
"""Keys in :data:`CHECKED_SECTIONS` whose values are true or false."""


def number(value: object) -> float | None:
    """``value`` as a finite float, or None (missing, null, boolean, non-numeric, NaN or infinite)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def value_notes(path: Path, number_in_file: int, record: dict) -> list[str]:
    """Notes on the values of a record the report cannot use: not a number, or not yes/no, where it reads one.

    Args:
        path: The records file, for the note.
        number_in_file: The record's 1-based number among the file's records.
        record: The record.

    Returns:
        One note per bad value, naming the record, the section and the key and giving the value.
    """
    notes = []
    for section in CHECKED_SECTIONS:
        values = record.get(section)
        if values is None:
            continue
        where = f"{path}: record {number_in_file} ({record['id']!r})"
        if not isinstance(values, dict):
            notes.append(f"{where}: {section!r} is {values!r}, not an object of values: every one is missing")
            continue
        for key, value in values.items():
            if value is None:
                continue
            if key in YES_NO_KEYS and not isinstance(value, bool):
                expected = "true or false"
            elif not key.endswith(NUMBER_KEY_ENDINGS):
                continue
            elif isinstance(value, list):  # per-frame lists (spike_frames): each a number
                if all(number(v) is not None for v in value):
                    continue
                expected = "a list of finite numbers"
            elif number(value) is None:
                expected = "a finite number"
            else:
                continue
            notes.append(
                f"{where}: {section} {key!r} is {value!r}, expected {expected}: shown as missing and left "
                "out of every statistic"
            )
    return notes


def natural_key(text: str) -> tuple:
    """Sort key putting embedded numbers in numeric order (``a9`` before ``a10``)."""
    return tuple(
        (0, int(part), part) if part.isdigit() else (1, 0, part) for part in re.split(r"(\d+)", text)
    )


def read_run(out_dir: str | Path) -> RunRecords:
    """Read a run's ``records.jsonl`` and ``run.json``.

    Args:
        out_dir: The folder ``handsim report DATASET -o OUT`` wrote.

    Returns:
        The records (one per trial id, sorted) and the run description.

    Raises:
        InputFileError: The folder or its ``records.jsonl`` does not exist.
        RecordsError: A record (a line other than a cut-off last one) or ``run.json`` is malformed.
    """
    out_dir = Path(out_dir)
    path = out_dir / RECORDS_FILE
    if not path.is_file():
        raise InputFileError(
            f"{path} does not exist: render a report from the folder a dataset run wrote "
            f"(handsim report DATASET -o OUT)"
        )
    read = load_records(out_dir)
    notes = list(read.notes)
    for index, record in enumerate(read.records, start=1):
        if record.get("status") not in STATUSES:
            raise RecordsError(
                f"{path}: record {index} ({record['id']!r}): field 'status' is {record.get('status')!r}; "
                f"expected one of {list(STATUSES)}"
            )
        notes += value_notes(path, index, record)
    run = read_run_info(out_dir)
    if run is not None and not isinstance(run, dict):
        raise RecordsError(f"{out_dir / RUN_FILE}: expected a JSON object, got {type(run).__name__}")
    if run is None:
        notes.append(f"{RUN_FILE} is absent: no command line, discovery or run parameters to show")
    ordered = tuple(sorted(read.records, key=lambda r: natural_key(r["id"])))
    return RunRecords(out_dir=out_dir, records=ordered, run=run, notes=tuple(notes))
