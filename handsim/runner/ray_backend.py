"""The Ray backend of a dataset run: each trial a ``@ray.remote(num_cpus=1)`` task.

Each task runs the same function as the local backend (:func:`handsim.runner.worker.trial_outcome`);
``address`` connects to a cluster, else a local Ray with ``num_cpus=workers`` is started (and shut down
after). Needs ``pip install 'handsim[ray]'``.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator, Sequence
from types import ModuleType

from handsim.runner.errors import RunnerError
from handsim.runner.worker import TrialFunction, TrialOutcome, crashed_outcome, prepare_worker_process
from handsim.sim.replay import ReplayConfig
from handsim.trials import TrialEntry
from handsim.viz.headless import headless_gl_default

RAY_INSTALL = "pip install 'handsim[ray]'"


def ray_outcomes(
    todo: Sequence[TrialEntry],
    run: TrialFunction,
    config: ReplayConfig,
    frames: int,
    workers: int,
    address: str | None,
) -> Iterator[TrialOutcome]:
    """Run the trials as Ray tasks, all submitted at once; a task whose worker dies is an error record.

    Args:
        todo: The trials, one task each.
        run: What each task runs, unpickled by name in Ray's worker
            (:func:`~handsim.runner.worker.trial_outcome`).
        config: Every trial's replay parameters.
        frames: How many frames each trial renders.
        workers: CPUs of the local Ray started when ``address`` is None and no Ray runs yet.
        address: A Ray cluster's address, or None.

    Yields:
        Each trial's outcome as it finishes; closing the generator cancels the pending tasks.

    Raises:
        RunnerError: Ray is not installed.
    """
    ray = import_ray()
    started = not ray.is_initialized()
    if started:
        # "local": a new Ray of our own even where a cluster runs on this machine (ray.init() would join it)
        options = (
            {"address": address}
            if address
            else {"address": "local", "num_cpus": workers, "include_dashboard": False}
        )
        ray.init(log_to_driver=False, logging_level=logging.WARNING, **options)
    task = ray.remote(num_cpus=1, max_retries=0)(_ray_trial)
    env = {"OMP_NUM_THREADS": "1", **_gl_env()}  # set by each task (_ray_trial), not a runtime_env
    pending = {task.remote(run, entry, config, frames, env): entry for entry in todo}
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                entry = pending.pop(ref)
                try:
                    yield ray.get(ref)
                except ray.exceptions.RayError as exc:  # the task's worker died; Python errors are records
                    yield crashed_outcome(entry, config, frames, f"its Ray worker failed: {exc}")
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
        if started:
            ray.shutdown()


def import_ray() -> ModuleType:
    """The ``ray`` module, or a RunnerError saying how to install it."""
    try:
        import ray  # lazy: optional extra handsim[ray]
    except ImportError:
        raise RunnerError(f"the Ray backend needs Ray: {RAY_INSTALL}") from None
    return ray


def _ray_trial(
    run: TrialFunction, entry: TrialEntry, config: ReplayConfig, frames: int, env: dict[str, str]
) -> TrialOutcome:
    """One trial in a Ray worker, with the driver's choices for the worker's environment set first.

    The variables come with the task rather than as a Ray ``runtime_env``: a runtime environment of its
    own makes Ray start new worker processes for the run (0.8 s before the first task on a 2-core
    machine), where without one the cluster's already started workers take the tasks at once (0.14 s).
    Set here, after MuJoCo may have been imported, ``MUJOCO_GL`` still decides each renderer's backend
    (:func:`handsim.viz.headless.offscreen_renderer` reads it when it renders), and ``OMP_NUM_THREADS``
    (which Ray already sets to a task's CPUs) reaches the CoACD processes a trial starts.
    """
    os.environ.update(env)
    prepare_worker_process()
    return run(entry, config, frames)


def _gl_env() -> dict[str, str]:
    """``MUJOCO_GL`` for the Ray workers: the user's, else the headless default; ours stays untouched."""
    choice = os.environ.get("MUJOCO_GL") or headless_gl_default()
    return {"MUJOCO_GL": choice} if choice else {}
