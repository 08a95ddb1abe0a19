"""Run every trial of a dataset: in-process, in a local process pool, or as Ray tasks; resumable.

:func:`run_dataset` skips the trials that already have a record in ``OUT/records.jsonl`` (a killed run
restarted with the same command loses nothing and runs no trial twice), runs the others with the chosen
backend, and appends each record as its trial finishes — written by this (the parent) process only, with
the trial's rendered frames written first. A trial that fails is recorded with its error; the run goes
on. Ctrl-C stops the workers and leaves complete lines only.

Backends (:data:`BACKENDS`):

* ``local`` — ``workers=1``: in this process, in id order (debuggable); more: a
  :class:`~concurrent.futures.ProcessPoolExecutor` with the ``spawn`` start method (MuJoCo and EGL are not
  fork-safe), at most ``workers`` trials in flight, each worker with one OpenMP thread. A worker that dies
  (a crash, out of memory) breaks the pool: the pool is restarted and the trials that were in flight run
  again one at a time, so that the one that kills its worker is recorded as an error (``WorkerCrashed``).
* ``ray`` — each trial a ``@ray.remote(num_cpus=1)`` task running the same function
  (:func:`handsim.runner.worker.trial_outcome`); ``address`` connects to a cluster, else a local Ray with
  ``num_cpus=workers`` is started (and shut down after). Needs ``pip install 'handsim[ray]'``.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from handsim.errors import HandsimError
from handsim.runner.portable import dataset_root, portable_record
from handsim.runner.records import (
    RecordWriter,
    load_records,
    record_valid,
    repair_records,
    write_run_info,
)
from handsim.runner.worker import (
    TrialOutcome,
    base_record,
    prepare_pool_worker,
    prepare_worker_process,
    run_parameters,
    run_trial,
    trial_outcome,
    write_outcome_files,
)
from handsim.sim.replay import ReplayConfig
from handsim.trials import Discovery, TrialEntry
from handsim.viz.headless import headless_gl_default

__all__ = [
    "BACKENDS",
    "RunSummary",
    "RunnerError",
    "default_workers",
    "failure_counts",
    "records_line",
    "run_dataset",
    "run_trial",
]

BACKENDS = ("local", "ray")
RAY_INSTALL = "pip install 'handsim[ray]'"


class RunnerError(HandsimError):
    """A dataset run that cannot start (bad option, records of other parameters, Ray missing …)."""


@dataclass(frozen=True)
class RunSummary:
    """What a dataset run did.

    Attributes:
        out: The output folder.
        trials: Trials selected for this run.
        skipped: Of those, already recorded before this call (resumed).
        ran: Ids of the trials run by this call, in the order they finished.
        ok: Selected trials whose record says ``ok``.
        diverged: … ``diverged``.
        failed: … ``error``.
        flagged: Of the ``ok`` and ``diverged`` ones, those flagged not valid (``summary["valid"]`` false).
        held: Valid glove trials whose object was held through the hold window.
        hold_trials: Valid glove trials whose hold was judged (held or not held): the hold rate's
            denominator.
        notes: What was repaired or skipped (a truncated records line …).
        wall_s: Wall-clock time of this call, s.
        failures: The failed trials' errors (:func:`failure_counts`): (error type, trials, first message),
            most frequent first.
        not_judged: Valid glove trials whose hold was not judged (``held`` None: too short a window after
            the release, no feasible placement …); in no rate.
    """

    out: str
    trials: int
    skipped: int
    ran: tuple[str, ...]
    ok: int
    diverged: int
    failed: int
    flagged: int
    held: int
    hold_trials: int
    notes: tuple[str, ...]
    wall_s: float
    failures: tuple[tuple[str, int, str], ...] = ()
    not_judged: int = 0

    @property
    def all_failed(self) -> bool:
        """Every selected trial (one at least) has an ``error`` record: the run produced no result."""
        return self.trials > 0 and self.failed == self.trials

    def line(self) -> str:
        """One line for people: trial counts by status and the hold rate."""
        keys = ("ok", "diverged", "failed", "flagged", "held", "hold_trials", "not_judged")
        counts = {k: getattr(self, k) for k in keys}
        return _line(self.trials, counts)


def failure_counts(records: Sequence[dict]) -> tuple[tuple[str, int, str], ...]:
    """The errors of the failed trials among ``records``, counted by exception type.

    Args:
        records: Records (any status).

    Returns:
        One (error type, trials, first line of the first such trial's message) per type, most frequent
        first (ties by type name).
    """
    found: dict[str, list] = {}
    for record in records:
        if record["status"] != "error":
            continue
        error = record.get("error") or {}
        lines = str(error.get("message") or "").strip().splitlines()
        entry = found.setdefault(str(error.get("type") or "unknown error"), [0, lines[0] if lines else ""])
        entry[0] += 1
    ordered = sorted(found.items(), key=lambda item: (-item[1][0], item[0]))
    return tuple((kind, n, first) for kind, (n, first) in ordered)


def _line(trials: int, counts: dict) -> str:
    text = f"{trials} trials: {counts['ok']} ok, {counts['diverged']} diverged, {counts['failed']} failed"
    if counts["flagged"]:
        text += f" ({counts['flagged']} flagged not valid, left out of the rates)"
    if counts["hold_trials"]:
        rate = 100.0 * counts["held"] / counts["hold_trials"]
        text += f"; held {counts['held']} of {counts['hold_trials']} judged glove trials ({rate:.0f} %)"
    if counts["not_judged"]:
        text += f"; {counts['not_judged']} glove trials not judged (left out of the hold rate)"
    return text


def records_line(records: Sequence[dict]) -> str:
    """One line for people about a run's records: trial counts by status and the hold rate."""
    return _line(len(records), _counts(records, {r["id"] for r in records}))


def default_workers() -> int:
    """The cores this process may use (its CPU affinity where the OS reports one)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


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


def _crash_outcome(entry: TrialEntry, config: ReplayConfig, frames: int, why: str) -> TrialOutcome:
    """The record of a trial whose worker process died (no Python exception to report)."""
    record = base_record(entry, config, frames)
    record["error"] = {"type": "WorkerCrashed", "message": f"{entry.id}: {why}", "traceback": ""}
    record["timing"] = {"load_s": 0.0, "replay_s": 0.0, "render_s": 0.0, "total_s": 0.0}
    return TrialOutcome(record)


def _in_process(todo: Sequence[TrialEntry], config: ReplayConfig, frames: int) -> Iterator[TrialOutcome]:
    for entry in todo:
        yield trial_outcome(entry, config, frames)


@contextlib.contextmanager
def _environment(**values: str) -> Iterator[None]:
    """Set environment variables for processes started inside the block (restored after)."""
    saved = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


class _TrackingContext:
    """The ``spawn`` multiprocessing context, remembering every process the pool starts with it.

    The executor has no public list of its workers before Python 3.14, a broken pool drops them from its
    private one, and it may start one after another: the pool's processes are the ones made here.
    """

    def __init__(self) -> None:
        self._context = multiprocessing.get_context("spawn")
        self.processes: list[multiprocessing.process.BaseProcess] = []

    def __getattr__(self, name: str) -> object:
        return getattr(self._context, name)

    def Process(self, *args: object, **kwargs: object) -> multiprocessing.process.BaseProcess:  # noqa: N802
        process = self._context.Process(*args, **kwargs)
        self.processes.append(process)
        return process


class _Pool:
    """A process pool of spawned workers and the context that started (and remembers) its processes.

    Each worker ends with this process, also under ``kill -9``
    (:func:`~handsim.runner.worker.prepare_pool_worker`).
    """

    def __init__(self, workers: int) -> None:
        self.context = _TrackingContext()
        self.executor = cf.ProcessPoolExecutor(
            workers, mp_context=self.context, initializer=prepare_pool_worker
        )

    def submit(self, fn: Callable[..., object], /, *args: object) -> cf.Future:
        """Schedule ``fn(*args)`` on a worker (the executor starts a worker here while none is idle).

        SIGINT is blocked (not ignored) in this thread meanwhile: a worker started here inherits the blocked
        mask through exec, so a Ctrl-C sent to the whole process group while its interpreter starts (before
        :func:`~handsim.runner.worker.prepare_pool_worker` ignores SIGINT) cannot kill it with "Fatal Python
        error: init_import_site" on the shared stderr, and this process receives the pending Ctrl-C as soon as
        the submit returns, so it is never lost: this process stops the pool.
        """
        in_main_thread = threading.current_thread() is threading.main_thread()
        if not hasattr(signal, "pthread_sigmask") or not in_main_thread:
            return self.executor.submit(fn, *args)
        previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            return self.executor.submit(fn, *args)
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)

    def stop(self) -> None:
        """End the pool now: terminate its workers (running trials are lost), reap them, then shut it down.

        The workers go first, so that the executor's own thread finds them dead and ends: shutting down
        then waits for that thread without a private attribute and without the risk of waiting forever on
        a worker busy in native code.
        """
        processes = list(self.context.processes)
        for process in processes:
            if process.is_alive():
                process.terminate()
        for process in processes:
            process.join(timeout=5)
            if process.is_alive():  # SIGTERM not acted on in time: SIGKILL
                process.kill()
                process.join(timeout=5)
        self.executor.shutdown(wait=True, cancel_futures=True)


POOL_START_TIMEOUT_S = 300.0
"""Longest wait for a new worker process to start and import handsim, s."""


def _new_pool(workers: int) -> _Pool:
    """A started pool of spawned workers; RunnerError when a worker cannot even start.

    A pool whose workers die at start would otherwise look like every trial crashing its worker.
    """
    pool = _Pool(workers)
    try:
        # one task per worker at once: the pool starts a worker per submit while none is idle, so all of
        # them start and import handsim in parallel before the first trial
        started = [pool.submit(os.getpid) for _ in range(workers)]
        for future in started:
            future.result(timeout=POOL_START_TIMEOUT_S)
    except Exception as exc:
        pool.stop()
        raise RunnerError(
            f"the local pool's worker processes do not start ({type(exc).__name__}: {exc}); the spawn start "
            "method re-imports the main script, so run_dataset must be called from an importable script "
            "(under `if __name__ == '__main__':`) or the handsim command; workers=1 runs in this process"
        ) from exc
    return pool


def _pool(
    todo: Sequence[TrialEntry], config: ReplayConfig, frames: int, workers: int
) -> Iterator[TrialOutcome]:
    queue = deque(todo)
    suspects: deque[TrialEntry] = deque()  # in flight when a worker died: run again one at a time
    solo: str | None = None  # the suspect running alone
    with _environment(OMP_NUM_THREADS="1"):
        pool = _new_pool(workers)
        inflight: dict[cf.Future, TrialEntry] = {}
        try:
            while queue or suspects or inflight:
                broken = False
                try:  # submit raises once the pool knows a worker died
                    if suspects and not inflight:
                        inflight[pool.submit(trial_outcome, suspects[0], config, frames)] = suspects[0]
                        solo = suspects.popleft().id
                    while queue and not suspects and solo is None and len(inflight) < workers:
                        inflight[pool.submit(trial_outcome, queue[0], config, frames)] = queue[0]
                        queue.popleft()
                except BrokenProcessPool:
                    broken = True
                done = set() if broken else cf.wait(inflight, return_when=cf.FIRST_COMPLETED).done
                for future in done:
                    try:
                        outcome = future.result()
                    except BrokenProcessPool:
                        broken = True
                        continue
                    entry = inflight.pop(future)
                    solo = None if entry.id == solo else solo
                    yield outcome
                if broken:
                    for entry in inflight.values():
                        if entry.id == solo:
                            why = "its worker process died while running it alone (a crash or out of memory)"
                            yield _crash_outcome(entry, config, frames, why)
                            solo = None
                        else:
                            suspects.append(entry)
                    inflight.clear()
                    pool.stop()
                    pool = _new_pool(workers)
        finally:
            pool.stop()


def _ray(
    todo: Sequence[TrialEntry], config: ReplayConfig, frames: int, workers: int, address: str | None
) -> Iterator[TrialOutcome]:
    ray = _import_ray()
    started = not ray.is_initialized()
    if started:
        env = {"env_vars": {"OMP_NUM_THREADS": "1", **_gl_env()}}
        # "local": a new Ray of our own even where a cluster runs on this machine (ray.init() would join it)
        options = (
            {"address": address}
            if address
            else {"address": "local", "num_cpus": workers, "include_dashboard": False}
        )
        ray.init(runtime_env=env, log_to_driver=False, logging_level=logging.WARNING, **options)
    task = ray.remote(num_cpus=1, max_retries=0)(_ray_trial)
    pending = {task.remote(entry, config, frames): entry for entry in todo}
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                entry = pending.pop(ref)
                try:
                    yield ray.get(ref)
                except ray.exceptions.RayError as exc:  # the task's worker died; Python errors are records
                    yield _crash_outcome(entry, config, frames, f"its Ray worker failed: {exc}")
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
        if started:
            ray.shutdown()


def _import_ray() -> ModuleType:
    """The ``ray`` module, or a RunnerError saying how to install it."""
    try:
        import ray
    except ImportError:
        raise RunnerError(f"the Ray backend needs Ray: {RAY_INSTALL}") from None
    return ray


def _ray_trial(entry: TrialEntry, config: ReplayConfig, frames: int) -> TrialOutcome:
    prepare_worker_process()
    return trial_outcome(entry, config, frames)


def _gl_env() -> dict[str, str]:
    """``MUJOCO_GL`` for the Ray workers: the user's, else the headless default; ours stays untouched."""
    choice = os.environ.get("MUJOCO_GL") or headless_gl_default()
    return {"MUJOCO_GL": choice} if choice else {}


def _counts(records: Sequence[dict], ids: set[str]) -> dict:
    mine = [r for r in records if r["id"] in ids]
    valid = [r for r in mine if record_valid(r)]
    outcomes = [r["summary"]["held"] for r in valid if r.get("summary") and "held" in r["summary"]]
    held = [h for h in outcomes if h is not None]
    return {
        "ok": sum(r["status"] == "ok" for r in mine),
        "diverged": sum(r["status"] == "diverged" for r in mine),
        "failed": sum(r["status"] == "error" for r in mine),
        "flagged": len(mine) - len(valid),
        "held": sum(bool(h) for h in held),
        "hold_trials": len(held),
        "not_judged": len(outcomes) - len(held),
    }


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
) -> RunSummary:
    """Run the trials of a discovery (or a list of trials), appending a record per trial to ``OUT``.

    Args:
        source: A :class:`~handsim.trials.Discovery` (its overview goes into ``run.json``) or
            trial entries.
        out: Output folder (``records.jsonl``, ``run.json``, ``frames/``); created if missing.
        workers: Trials at once; default every core this process may use. 1 runs in this process.
        backend: ``"local"`` or ``"ray"``.
        address: Ray cluster address (``ray`` backend); None starts a local Ray.
        config: Replay parameters; default :class:`~handsim.sim.replay.ReplayConfig` with the stability
            tests at the end of the hold window (``stability_at="grasp"``, glove trials only).
        frames: Frames rendered per trial (0: none).
        progress: Show a progress bar with ETA (tqdm, on stderr).
        command: The command line, for ``run.json`` (default ``sys.argv``).
        on_record: Called with each record after it is written.

    Returns:
        What the run did, with counts over every selected trial's record (resumed ones included).

    Raises:
        RunnerError: An unknown backend, ``workers`` or ``frames`` out of range, Ray missing, ``OUT`` a
            file, or ``OUT`` holding records made with other parameters.
        RecordsError: ``OUT/records.jsonl`` has a malformed line other than a truncated last one.
        KeyboardInterrupt: Ctrl-C; the records written so far are complete lines (run again to resume).
    """
    from tqdm import tqdm

    from handsim.runner.trial_record import versions

    start = time.perf_counter()
    if backend not in BACKENDS:
        raise RunnerError(f"unknown backend {backend!r}; expected one of {list(BACKENDS)}")
    workers = default_workers() if workers is None else workers
    if workers < 1:
        raise RunnerError(f"workers must be ≥ 1, got {workers}")
    if frames < 0:
        raise RunnerError(f"frames must be ≥ 0, got {frames}")
    if backend == "ray":
        _import_ray()  # fail before anything is written
    config = config or ReplayConfig(stability_at="grasp")
    entries, overview = _entries(source)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise RunnerError(f"{out} exists and is not a folder; expected an output folder")
    out.mkdir(parents=True, exist_ok=True)
    notes = list(repair_records(out))
    parameters = run_parameters(config, frames)
    existing = load_records(out).records
    _check_parameters(existing, parameters, out)
    recorded = {r["id"] for r in existing}
    todo = [e for e in entries if e.id not in recorded]
    write_run_info(
        out,
        {
            "command": list(sys.argv if command is None else command),
            "dataset": overview.get("root"),
            "versions": versions(),
            "discovery": overview,
            "parameters": parameters,
            "backend": backend,
            "workers": workers,
            "selected": [e.id for e in entries],
        },
    )
    if backend == "ray":
        outcomes = _ray(todo, config, frames, workers, address)
    elif workers == 1 or not todo:
        outcomes = _in_process(todo, config, frames)
    else:  # a pool even for one trial: records must not depend on how many trials were left
        outcomes = _pool(todo, config, frames, min(workers, len(todo)))
    ran: list[str] = []
    bar = tqdm(total=len(todo), unit="trial", desc="trials", disable=not progress, dynamic_ncols=True)
    status = {"ok": 0, "diverged": 0, "error": 0}
    with contextlib.closing(outcomes), RecordWriter(out) as writer, bar:
        if len(entries) > len(todo):
            bar.write(
                f"{len(entries) - len(todo)} of {len(entries)} trials already recorded in {out}: skipped"
            )
        for outcome in outcomes:
            record = portable_record(outcome.record, overview.get("root"))
            write_outcome_files(out, outcome)
            writer.append(record)
            ran.append(record["id"])
            status[record["status"]] += 1
            bar.set_postfix(status, refresh=False)
            bar.update(1)
            if on_record is not None:
                on_record(record)
    ids = {e.id for e in entries}
    mine = [r for r in load_records(out).records if r["id"] in ids]
    counts = _counts(mine, ids)
    return RunSummary(
        failures=failure_counts(mine),
        out=str(out),
        trials=len(entries),
        skipped=len(entries) - len(todo),
        ran=tuple(ran),
        notes=tuple(notes),
        wall_s=time.perf_counter() - start,
        **counts,
    )
