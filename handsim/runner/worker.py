"""One trial, start to record: load, replay, measure, render a few frames.

:func:`trial_outcome` is what every backend runs (in-process, a process-pool worker, a Ray task): it
writes nothing and returns the record and the rendered frames' bytes, so the parent process alone writes
``OUT/`` (on a cluster the workers need no shared file system). :func:`run_trial` does the same and writes
the frames itself, for use anywhere.

A trial that fails (a malformed file, a trajectory that does not fit, any exception) becomes a record
with ``status`` ``"error"`` and the exception's type, message and traceback; it never stops a run.
Records are deterministic except for ``timing``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import multiprocessing
import multiprocessing.connection
import os
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from handsim import lifeline
from handsim.files import write_atomic
from handsim.runner.portable import portable_traceback
from handsim.runner.records import SCHEMA, json_ready
from handsim.runner.renders import FRAMES_DIR, key_frames, render_pngs, safe_id
from handsim.runner.trial_record import curves, input_hashes, trajectory_quality, versions
from handsim.sim.replay import ReplayConfig
from handsim.thread_setting import THREADS_ENV
from handsim.trials import TrialEntry, load_trial, replay_trial
from handsim.viz.headless import prefer_headless_gl


@dataclass(frozen=True)
class TrialOutcome:
    """What a worker returns for one trial.

    Attributes:
        record: The record (``docs/records.md``).
        files: Rendered frames: ``OUT``-relative path → PNG bytes.
    """

    record: dict
    files: dict[str, bytes] = field(default_factory=dict)


TrialFunction = Callable[[TrialEntry, ReplayConfig, int], TrialOutcome]
"""What a backend runs for each trial, ``(entry, config, frames) → outcome``: :func:`trial_outcome`.

A module-level function: a pool worker or a Ray task unpickles it by name.
"""


def run_parameters(config: ReplayConfig, frames: int) -> dict:
    """The ``parameters`` of a run's records: the replay configuration as used and the frames rendered."""
    used = dataclasses.replace(config, keep_states=frames > 0)
    return json_ready({"replay": used.to_dict(), "render_frames": int(frames)})


def prepare_worker_process() -> None:
    """Settings of a worker process (pool initializer, start of a Ray task).

    One OpenMP thread (CoACD decompositions) and one simulation thread (:mod:`handsim.sim.parallel`), as
    the pool already uses every core; MuJoCo's EGL backend when there is no display (before ``mujoco`` is
    imported); and Ctrl-C left to the parent process, which ends the workers itself.
    """
    os.environ["OMP_NUM_THREADS"] = "1"
    os.environ[THREADS_ENV] = "1"
    prefer_headless_gl()
    if sys.platform != "win32":
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def prepare_pool_worker() -> None:
    """Initializer of a local process-pool worker: :func:`prepare_worker_process`, and no orphan.

    The worker ends when the process that started it dies, even under ``kill -9`` (which leaves the pool
    no chance to stop it): see :mod:`handsim.lifeline` (the kernel's parent-death signal on Linux, a thread
    waiting on the parent's sentinel everywhere). Not for Ray workers, whose lifetime Ray manages.
    """
    prepare_worker_process()
    parent = multiprocessing.parent_process()
    if parent is None:  # not a multiprocessing child: nothing to watch
        return
    lifeline.die_with_parent(parent.pid)
    lifeline.watch(lambda: multiprocessing.connection.wait([parent.sentinel]))


def identity_record(entry: TrialEntry) -> dict:
    """The first fields of every record: schema, the trial's identity and inputs; status ``"error"``."""
    return {
        "schema": SCHEMA,
        "id": entry.id,
        "kind": entry.kind,
        "status": "error",
        "meta": dict(entry.meta),
        "trial": entry.trial.to_dict(),
        "inputs": input_hashes(entry),
    }


def base_record(entry: TrialEntry, config: ReplayConfig, frames: int) -> dict:
    """A trial's record before it runs: identity, inputs, parameters, versions; status ``"error"``."""
    return {
        **identity_record(entry),
        "parameters": run_parameters(config, frames),
        "metric_spec_version": config.metrics.version,
        "versions": versions(),
        "model_sha256": None,
        "scenario": None,
        "summary": None,
        "episode": None,
        "hold": None,
        "grip": None,
        "robustness": None,
        "release_stability": None,
        "stability": None,
        "warnings": [],
        "diverged": None,
        "flags": [],
        "notes": [],
        "trajectory_quality": None,
        "curves": None,
        "renders": [],
        "error": None,
        "timing": None,
    }


def _replay_config(config: ReplayConfig, scene, frames: int, notes: list[str]) -> ReplayConfig:
    """The configuration a trial runs with: states kept for its frames, stability at ``"grasp"`` if it can.

    ``stability_at="grasp"`` is the end of the glove scenario's hold window. A trial of another scenario
    (a Tzionas or ARCTIC recording with its objects' own motion, a hand-only sequence) has no such window by
    its nature, so the tests are skipped without a note; a glove trial without its window says so.
    """
    used = dataclasses.replace(config, keep_states=frames > 0)
    if used.stability_at == "grasp" and scene.setup.hold_window is None:
        if scene.setup.scenario == "glove":
            notes.append(
                "stability tests not run: 'grasp' is the end of the hold window, and this trial has none"
            )
        used = dataclasses.replace(used, stability_at=None)
    return used


def _renders(entry: TrialEntry, loaded, result, frames: int, record: dict) -> dict[str, bytes]:
    chosen = key_frames(result, frames)
    try:
        pngs = render_pngs(loaded.scene, result, chosen)
    except Exception as exc:  # rendering is optional: no OpenGL is a note, not a failed trial
        record["notes"].append(f"frames not rendered: {type(exc).__name__}: {exc}")
        return {}
    files = {}
    folder = f"{FRAMES_DIR}/{safe_id(entry.id)}"
    for frame, png in zip(chosen, pngs, strict=True):
        path = f"{folder}/{frame:05d}.png"
        files[path] = png
        record["renders"].append(
            {
                "frame": frame,
                "time_s": float(result.frames.times[frame]),
                "path": path,
                "sha256": hashlib.sha256(png).hexdigest(),
            }
        )
    return files


def trial_outcome(entry: TrialEntry, config: ReplayConfig, frames: int = 4) -> TrialOutcome:
    """Run one trial and build its record, writing nothing.

    Args:
        entry: The trial.
        config: Replay parameters (``keep_states`` is set when frames are rendered; ``stability_at="grasp"``
            is skipped for trials without a hold window: see :func:`_replay_config`).
        frames: How many frames to render (0: none).

    Returns:
        The record and the rendered frames' bytes.
    """
    start = time.perf_counter()
    timing = {"load_s": 0.0, "replay_s": 0.0, "render_s": 0.0, "total_s": 0.0}
    record = base_record(entry, config, frames)
    files: dict[str, bytes] = {}
    try:
        loaded = load_trial(entry.trial, metrics=config.metrics)
        timing["load_s"] = time.perf_counter() - start
        record["model_sha256"] = loaded.scene.model_sha256
        record["scenario"] = loaded.scene.setup.scenario
        record["trajectory_quality"] = trajectory_quality(loaded.trajectory, loaded.scene, loaded.checks)
        notes = [*loaded.notes, *loaded.scene.setup.notes]
        used = _replay_config(config, loaded.scene, frames, notes)
        result = replay_trial(loaded, used)
        timing["replay_s"] = time.perf_counter() - start - timing["load_s"]
        record.update(
            status="diverged" if result.diverged is not None else "ok",
            summary=result.summary,
            episode=None if loaded.episode is None else loaded.episode.to_dict(),
            hold=None if result.hold is None else result.hold.to_dict(),
            grip=None if result.grip is None else result.grip.to_dict(),
            robustness=None if result.robustness is None else result.robustness.to_dict(),
            release_stability=None
            if result.release_stability is None
            else result.release_stability.to_dict(),
            stability=None if result.stability is None else result.stability.to_dict(),
            warnings=[dataclasses.asdict(w) for w in result.warnings],
            diverged=None if result.diverged is None else dataclasses.asdict(result.diverged),
            flags=[f.to_dict() for f in result.flags],
            notes=[*notes, *result.notes],
            curves=curves(result),
        )
        if frames > 0:
            rendered = time.perf_counter()
            files = _renders(entry, loaded, result, frames, record)
            timing["render_s"] = time.perf_counter() - rendered
    except Exception as exc:  # a failing trial is recorded, never stops the run
        record.update(status="error", error=error_of(exc))
    timing["total_s"] = time.perf_counter() - start
    record["timing"] = {k: round(v, 3) for k, v in timing.items()}
    return TrialOutcome(record, files)


def error_of(exc: BaseException) -> dict:
    """A failed trial's ``error``: the exception's type, message and traceback (paths made portable)."""
    return {"type": type(exc).__name__, "message": str(exc), "traceback": portable_traceback(exc)}


def crashed_outcome(entry: TrialEntry, config: ReplayConfig, frames: int, why: str) -> TrialOutcome:
    """The record of a trial whose worker process died (no Python exception to report).

    Args:
        entry: The trial.
        config: Replay parameters, or a job's own (an object with ``base_record(entry, frames)``: a correction
            run's :class:`~handsim.runner.correction_job.CorrectionJob`).
        frames: Frames the run renders per trial.
        why: How the worker died, for the error's message.
    """
    job = getattr(config, "base_record", None)  # a job of its own (a correction run) builds its record
    record = base_record(entry, config, frames) if job is None else job(entry, frames)
    record["error"] = {"type": "WorkerCrashed", "message": f"{entry.id}: {why}", "traceback": ""}
    record["timing"] = dict.fromkeys(("load_s", "replay_s", "render_s", "total_s"), 0.0)
    return TrialOutcome(record)


def write_outcome_files(out: str | Path, outcome: TrialOutcome) -> None:
    """Write a trial's rendered frames under ``out`` (atomically, before its record is appended)."""
    for path, data in outcome.files.items():
        write_atomic(Path(out) / path, data)


def run_trial(entry: TrialEntry, config: ReplayConfig, out: str | Path, frames: int = 4) -> dict:
    """Run one trial, write its rendered frames under ``out`` and return its record.

    Args:
        entry: The trial.
        config: Replay parameters.
        out: The run's output folder (frames go to ``out/frames/<safe-id>/``).
        frames: How many frames to render (0: none).

    Returns:
        The record (not appended to ``records.jsonl``: :func:`handsim.runner.execute.run_dataset` does that).
    """
    outcome = trial_outcome(entry, config, frames)
    write_outcome_files(out, outcome)
    return outcome.record
