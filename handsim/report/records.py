"""Reading a run's output folder: ``records.jsonl`` (one trial per line) and ``run.json``.

The report is rendered from these files alone, read by the runner's own reader
(:func:`handsim.runner.records.load_records`: a cut-off last line is skipped with a note). Records are
returned sorted by trial id (natural order, ``Models/9`` before ``Models/10``), so the order in which a
process pool finished the trials does not change the report.
"""

from __future__ import annotations

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
        notes: What reading had to decide (a cut-off last line skipped, repeated ids, no ``run.json``).
    """

    out_dir: Path
    records: tuple[dict, ...]
    run: dict | None
    notes: tuple[str, ...]


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
    for number, record in enumerate(read.records, start=1):
        if record.get("status") not in STATUSES:
            raise RecordsError(
                f"{path}: record {number} ({record['id']!r}): field 'status' is {record.get('status')!r}; "
                f"expected one of {list(STATUSES)}"
            )
    run = read_run_info(out_dir)
    if run is not None and not isinstance(run, dict):
        raise RecordsError(f"{out_dir / RUN_FILE}: expected a JSON object, got {type(run).__name__}")
    if run is None:
        notes.append(f"{RUN_FILE} is absent: no command line, discovery or run parameters to show")
    ordered = tuple(sorted(read.records, key=lambda r: natural_key(r["id"])))
    return RunRecords(out_dir=out_dir, records=ordered, run=run, notes=tuple(notes))
