"""Run every trial of a dataset: in-process, in a local process pool, or as Ray tasks; resumable.

:func:`run_dataset` skips the trials that already have a record in ``OUT/records.jsonl`` (a killed run
restarted with the same command loses nothing and runs no trial twice), runs the others with the chosen
backend, and appends each record as its trial finishes — written by this (the parent) process only, with
the trial's rendered frames written first. A trial that fails is recorded with its error; the run goes
on. Ctrl-C stops the workers and leaves complete lines only. One run at a time writes to an output folder
(:mod:`handsim.runner.output_lock`: the lock file ``OUT/.handsim.lock`` names the run holding it).

Backends (:data:`BACKENDS`): ``local`` (:mod:`handsim.runner.local_backend`: in this process with
``workers=1``, else a pool of spawned processes) and ``ray`` (:mod:`handsim.runner.ray_backend`). Each
runs :func:`handsim.runner.worker.trial_outcome` per trial; what the run did is a
:class:`~handsim.runner.run_summary.RunSummary`.
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

from handsim.progress import progress_bar
from handsim.runner.correction_job import CorrectionJob, correction_outcome
from handsim.runner.errors import RunnerError
from handsim.runner.local_backend import in_process_outcomes, pool_outcomes
from handsim.runner.output_lock import LOCK_FILE, OutputLock
from handsim.runner.portable import dataset_root, portable_record
from handsim.runner.ray_backend import import_ray, ray_outcomes
from handsim.runner.records import (
    RecordWriter,
    load_records,
    repair_records,
    write_run_info,
)
from handsim.runner.run_summary import RunSummary, failure_counts, status_counts
from handsim.runner.trial_record import versions
from handsim.runner.worker import TrialOutcome, run_parameters, trial_outcome, write_outcome_files
from handsim.sim.parallel import available_cores
from handsim.sim.replay import ReplayConfig
from handsim.trials import Discovery, TrialEntry

__all__ = ["BACKENDS", "RunSummary", "RunnerError", "default_workers", "run_dataset"]

BACKENDS = ("local", "ray")


def default_workers() -> int:
    """The cores this process may use (its CPU affinity where the OS reports one)."""
    return available_cores()


def _entries(source: Discovery | Sequence[TrialEntry]) -> tuple[tuple[TrialEntry, ...], dict]:
    if isinstance(source, Discovery):
        return source.entries, source.to_dict()
    entries = tuple(source)
    return entries, {"root": dataset_root(entries), "trials": len(entries)}


def _flat(value: object, prefix: str = "") -> dict[str, object]:
    if isinstance(value, dict):
        out: dict[str, object] = {}
        for key, item in value.items():
            out.update(_flat(item, f"{prefix}{key}."))
        return out
    return {prefix.rstrip("."): value}


def _check_parameters(records: Sequence[dict], parameters: dict, out: Path) -> None:
    want = _flat(parameters)
    for record in records:
        have = _flat(record.get("parameters"))
        if have != want:
            keys = sorted(k for k in set(have) | set(want) if have.get(k) != want.get(k))
            diff = [f"{k}: {have.get(k)!r} there, {want.get(k)!r} now" for k in keys]
            raise RunnerError(
                f"{out}: holds records made with other parameters (first: trial {record['id']!r}; "
                f"{'; '.join(diff)}). Resume with the same options, or write to another output folder"
            )


def _checked(backend: str, workers: int | None, frames: int) -> int:
    """The workers a run uses, after checking its backend, workers and frames (Ray importable).

    Raises:
        RunnerError: An unknown backend, ``workers`` or ``frames`` out of range, Ray missing.
    """
    if backend not in BACKENDS:
        raise RunnerError(f"unknown backend {backend!r}; expected one of {list(BACKENDS)}")
    workers = default_workers() if workers is None else workers
    if workers < 1:
        raise RunnerError(f"workers must be ≥ 1, got {workers}")
    if frames < 0:
        raise RunnerError(f"frames must be ≥ 0, got {frames}")
    if backend == "ray":
        import_ray()  # fail before anything is written
    return workers


def _outcomes(
    backend: str, todo: list[TrialEntry], job: tuple, workers: int, address: str | None
) -> Iterator[TrialOutcome]:
    """The outcomes of the trials to run, from the backend: ``job`` is (function, its parameters, frames)."""
    run, conf, frames = job
    if backend == "ray":
        return ray_outcomes(todo, run, conf, frames, workers, address)
    if workers == 1 or not todo:
        return in_process_outcomes(todo, run, conf, frames)
    # a pool even for one trial: records must not depend on how many trials were left
    return pool_outcomes(todo, run, conf, frames, min(workers, len(todo)))


def _write_outcomes(
    outcomes: Iterator[TrialOutcome],
    out: Path,
    root: str | None,
    skipped: tuple[int, int],
    progress: bool,
    on_record: Callable[[dict], None] | None,
) -> list[str]:
    """Write each outcome as it comes (its files, then its record) and return the ids run, in order.

    Args:
        outcomes: The backend's outcomes (closed at the end, also on Ctrl-C).
        out: The output folder.
        root: The dataset root taken out of the records' paths.
        skipped: Trials already recorded, of how many selected (said on the progress bar).
        progress: Show the progress bar on a terminal.
        on_record: Called with each record after it is written.
    """
    todo = skipped[1] - skipped[0]
    ran: list[str] = []
    bar = progress_bar(enabled=progress, total=todo, unit="trial", desc="trials", dynamic_ncols=True)
    status = {"ok": 0, "diverged": 0, "error": 0}
    with contextlib.closing(outcomes), RecordWriter(out) as writer, bar:
        if skipped[0]:
            bar.write(f"{skipped[0]} of {skipped[1]} trials already recorded in {out}: skipped")
        for outcome in outcomes:
            record = portable_record(outcome.record, root)
            write_outcome_files(out, outcome)
            writer.append(record)
            ran.append(record["id"])
            status[record["status"]] += 1
            bar.set_postfix(status, refresh=False)
            bar.update(1)
            if on_record is not None:
                on_record(record)
    return ran


def run_dataset(
    source: Discovery | Sequence[TrialEntry],
    out: str | Path,
    *,
    workers: int | None = None,
    backend: str = "local",
    address: str | None = None,
    config: ReplayConfig | None = None,
    frames: int = 4,
    progress: bool = True,
    command: Sequence[str] | None = None,
    on_record: Callable[[dict], None] | None = None,
    job: CorrectionJob | None = None,
) -> RunSummary:
    """Run the trials of a discovery (or a list of trials), appending a record per trial to ``OUT``.

    Args:
        source: A :class:`~handsim.trials.Discovery` (its overview goes into ``run.json``) or entries.
        out: Output folder (``records.jsonl``, ``run.json``, ``frames/``); created if missing.
        workers: Trials at once; default every core this process may use. 1 runs in this process.
        backend: ``"local"`` or ``"ray"``.
        address: Ray cluster address (``ray`` backend); None starts a local Ray.
        config: Replay parameters; default :class:`~handsim.sim.replay.ReplayConfig` with the stability
            tests at the end of the hold window (``stability_at="grasp"``, glove trials only).
        frames: Frames rendered per trial (0: none).
        progress: Show a progress bar with ETA on stderr when it is a terminal (:mod:`handsim.progress`:
            nothing in a log).
        command: The command line, for ``run.json`` (default ``sys.argv``).
        on_record: Called with each record after it is written.
        job: A correction run (``handsim correct DATASET``): each trial corrected with the job's parameters
            (:mod:`handsim.runner.correction_job`) instead of replayed; ``config`` and ``frames`` unused.

    Returns:
        What the run did, with counts over every selected trial's record (resumed ones included).

    Raises:
        RunnerError: An unknown backend, ``workers`` or ``frames`` out of range, Ray missing, ``OUT`` a
            file, or ``OUT`` holding records made with other parameters.
        OutputBusyError: Another run writes to ``OUT`` (it holds ``OUT/.handsim.lock``; the message names
            its pid, host, start time and command). The lock of a run that ended without releasing it is
            taken over, with a note in the summary.
        RecordsError: ``OUT/records.jsonl`` has a malformed line other than a truncated last one.
        KeyboardInterrupt: Ctrl-C; the records written so far are complete lines (run again to resume).
    """
    start = time.perf_counter()
    workers = _checked(backend, workers, frames)
    config = config or ReplayConfig(stability_at="grasp")
    run, conf = (trial_outcome, config) if job is None else (correction_outcome, job)
    entries, overview = _entries(source)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise RunnerError(f"{out} exists and is not a folder; expected an output folder")
    out.mkdir(parents=True, exist_ok=True)
    with OutputLock(out / LOCK_FILE, what=f"output folder {out}", command=command) as lock:
        notes = [*lock.notes, *repair_records(out)]
        parameters = run_parameters(config, frames) if job is None else job.parameters(frames)
        existing = load_records(out).records
        _check_parameters(existing, parameters, out)
        recorded = {r["id"] for r in existing}
        todo = [e for e in entries if e.id not in recorded]
        info = {"command": list(sys.argv if command is None else command), "dataset": overview.get("root")}
        info.update(versions=versions(), discovery=overview, parameters=parameters, backend=backend)
        write_run_info(out, {**info, "workers": workers, "selected": [e.id for e in entries]})
        outcomes = _outcomes(backend, todo, (run, conf, frames), workers, address)
        skipped = len(entries) - len(todo)
        counts_before = (skipped, len(entries))
        ran = _write_outcomes(outcomes, out, overview.get("root"), counts_before, progress, on_record)
        ids = {e.id for e in entries}
        mine = [r for r in load_records(out).records if r["id"] in ids]
        counts = status_counts(mine, ids)
        return RunSummary(
            failures=failure_counts(mine),
            out=str(out),
            trials=len(entries),
            skipped=skipped,
            ran=tuple(ran),
            notes=tuple(notes),
            wall_s=time.perf_counter() - start,
            **counts,
        )
