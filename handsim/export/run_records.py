"""The records of a dataset run an export takes: read (sorted by trial id), then selected by id and status."""

from __future__ import annotations

import fnmatch
from collections.abc import Sequence
from pathlib import Path

from handsim.errors import InputFileError
from handsim.export.errors import ExportError
from handsim.runner.records import RECORDS_FILE, load_records, read_run_info


def read_run_records(out_dir: str | Path) -> tuple[Path, list[dict], tuple[str, ...], str | None]:
    """A run's records sorted by trial id, with the notes on what reading ignored and the dataset root.

    Args:
        out_dir: The folder ``handsim report DATASET -o OUT`` wrote.

    Returns:
        The records file, its records (one per id, sorted by id), the reader's notes (a truncated last
        line …), and the dataset folder the records' input paths are relative to (``run.json``), or None.

    Raises:
        InputFileError: There is no ``records.jsonl`` in ``out_dir``.
        ExportError: It holds no record.
        RecordsError: A line is not a record of this handsim's schema.
    """
    path = Path(out_dir) / RECORDS_FILE
    if not path.is_file():
        raise InputFileError(
            f"{path} does not exist: export the folder a dataset run wrote (handsim report DATASET -o OUT)"
        )
    read = load_records(out_dir)
    if not read.records:
        raise ExportError(f"{path} holds no record: nothing to export")
    info = read_run_info(out_dir) or {}
    root = info.get("dataset") if isinstance(info.get("dataset"), str) else None
    return path, sorted(read.records, key=lambda r: r["id"]), read.notes, root


def select_records(
    records: Sequence[dict], only: str | Sequence[str] | None, include_failed: bool
) -> tuple[list[dict], list[dict]]:
    """Split records into those to export and those skipped (with the reason).

    Args:
        records: A run's records (one per trial id).
        only: Shell patterns (``fnmatch``) on the trial id; None: every trial.
        include_failed: Export diverged trials too (their episode ends at the divergence).

    Returns:
        The records to export, and ``{"id", "status", "reason"}`` for each record skipped.

    Raises:
        ExportError: ``only`` matches no trial id.
    """
    patterns = [only] if isinstance(only, str) else list(only or ())
    chosen = [r for r in records if not patterns or any(fnmatch.fnmatchcase(r["id"], p) for p in patterns)]
    if not chosen:
        ids = [r["id"] for r in records]
        raise ExportError(
            f"--only {' '.join(patterns)} matches none of the {len(ids)} trial ids; they are: "
            f"{', '.join(ids[:10])}{' …' if len(ids) > 10 else ''}"
        )
    export, skipped = [], []
    for record in chosen:
        status = record["status"]
        if status == "ok" or (status == "diverged" and include_failed):
            export.append(record)
        elif status == "diverged":
            skipped.append(skip_entry(record, "diverged (export it with --include-failed)"))
        else:
            error = record.get("error") or {}
            message = error.get("message") if isinstance(error, dict) else str(error)
            skipped.append(
                skip_entry(record, f"error: {message or 'no message'}; there is no replay to export")
            )
    return export, skipped


def skip_entry(record: dict, reason: str) -> dict:
    """What an export says of a record it skips: ``{"id", "status", "reason"}``."""
    return {"id": record["id"], "status": record["status"], "reason": reason}
