"""Reading a run's output folder: ``records.jsonl`` (one trial per line) and ``run.json``.

The report is rendered from these files alone. Records are returned sorted by trial id (natural order,
``Models/9`` before ``Models/10``), so the order in which a process pool finished the trials does not change
the report.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

from handsim.errors import FormatError, InputFileError

RECORD_SCHEMA = 1
RECORDS_FILE = "records.jsonl"
RUN_FILE = "run.json"
STATUSES: tuple[str, ...] = ("ok", "diverged", "error")


@dataclass(frozen=True)
class RunRecords:
    """What a run wrote, as read back.

    Attributes:
        out_dir: The run's output folder.
        records: One record per trial (the last one written for an id), sorted by :func:`natural_key` of
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


def _check_record(record: object, path: Path, line: int) -> dict:
    if not isinstance(record, dict):
        raise FormatError(path, f"a record must be a JSON object, got {type(record).__name__}", line=line)
    schema = record.get("schema")
    if schema != RECORD_SCHEMA:
        raise FormatError(
            path,
            f"record schema {schema!r} is not supported; expected {RECORD_SCHEMA}",
            line=line,
            field="schema",
        )
    if not isinstance(record.get("id"), str) or not record["id"]:
        raise FormatError(path, "a record needs a non-empty string id", line=line, field="id")
    if record.get("status") not in STATUSES:
        raise FormatError(
            path,
            f"status {record.get('status')!r} is not one of {list(STATUSES)}",
            line=line,
            field="status",
        )
    return record


def parse_records(text: str, path: Path) -> tuple[list[dict], list[str]]:
    """Records from the text of a ``records.jsonl`` file.

    A last line without its newline that is not valid JSON is what a killed run leaves behind: it is
    skipped and noted (the run's resume re-runs that trial). Any other bad line is an error.

    Args:
        text: The file's text.
        path: The file, for messages.

    Returns:
        The records in file order, and notes on what was skipped.

    Raises:
        FormatError: A line is not a JSON object of a supported record schema.
    """
    records, notes = [], []
    lines = text.split("\n")
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as exc:
            if number == len(lines):  # no newline after it: the write was cut off
                notes.append(
                    f"{path.name} line {number} is incomplete (a run stopped while writing it); skipped"
                )
                continue
            raise FormatError(path, f"not valid JSON: {exc.msg} at column {exc.colno}", line=number) from exc
        records.append(_check_record(record, path, number))
    return records, notes


def read_run(out_dir: str | Path) -> RunRecords:
    """Read a run's ``records.jsonl`` and ``run.json``.

    Args:
        out_dir: The folder ``handsim report DATASET -o OUT`` wrote.

    Returns:
        The records (one per trial id, sorted) and the run description.

    Raises:
        InputFileError: The folder or its ``records.jsonl`` does not exist.
        FormatError: A record or ``run.json`` is malformed.
    """
    out_dir = Path(out_dir)
    path = out_dir / RECORDS_FILE
    if not path.is_file():
        raise InputFileError(
            f"{path} does not exist: render a report from the folder a dataset run wrote "
            f"(handsim report DATASET -o OUT)"
        )
    records, notes = parse_records(path.read_text(encoding="utf-8"), path)
    by_id: dict[str, dict] = {}
    for record in records:
        if record["id"] in by_id:
            notes.append(f"trial {record['id']!r} has more than one record; the last one is used")
        by_id[record["id"]] = record
    run = None
    run_path = out_dir / RUN_FILE
    if run_path.is_file():
        try:
            run = json.loads(run_path.read_text(encoding="utf-8"))
        except json.JSONDecodeError as exc:
            raise FormatError(run_path, f"not valid JSON: {exc.msg}", line=exc.lineno) from exc
        if not isinstance(run, dict):
            raise FormatError(run_path, f"expected a JSON object, got {type(run).__name__}")
    else:
        notes.append(f"{RUN_FILE} is absent: no command line, discovery or run parameters to show")
    ordered = tuple(by_id[key] for key in sorted(by_id, key=natural_key))
    return RunRecords(out_dir=out_dir, records=ordered, run=run, notes=tuple(notes))
