"""The local backend of a dataset run: in this process, or a pool of spawned worker processes.

``workers=1`` runs the trials in this process, in id order (debuggable). More: a
:class:`~concurrent.futures.ProcessPoolExecutor` with the ``spawn`` start method (MuJoCo and EGL are not
fork-safe), at most ``workers`` trials in flight, each worker with one OpenMP thread. A worker that dies (a
crash, out of memory) breaks the pool: the pool is restarted and the trials that were in flight run again
one at a time, so that the one that kills its worker is recorded as an error (``WorkerCrashed``). Ctrl-C
reaches this process, never a starting worker (:meth:`_Pool.submit`), and stopping the pool ends its
workers.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing
import os
import signal
import threading
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures.process import BrokenProcessPool

from handsim.runner.errors import RunnerError
from handsim.runner.worker import TrialFunction, TrialOutcome, crashed_outcome, prepare_pool_worker
from handsim.sim.replay import ReplayConfig
from handsim.trials import TrialEntry


def in_process_outcomes(
    todo: Sequence[TrialEntry], run: TrialFunction, config: ReplayConfig, frames: int
) -> Iterator[TrialOutcome]:
    """Run the trials in this process, in order.

    Args:
        todo: The trials.
        run: The function run per trial (:func:`~handsim.runner.worker.trial_outcome`).
        config: Replay parameters.
        frames: Frames rendered per trial.

    Yields:
        Each trial's outcome as it finishes.
    """
    for entry in todo:
        yield run(entry, config, frames)


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


def pool_outcomes(
    todo: Sequence[TrialEntry], run: TrialFunction, config: ReplayConfig, frames: int, workers: int
) -> Iterator[TrialOutcome]:
    """Run the trials on a pool of ``workers`` spawned processes; a trial that kills its worker is an error.

    Args:
        todo: The trials, at most ``workers`` in flight.
        run: The per-trial function, module-level: each worker unpickles it by name.
        config: Replay parameters (the same for every trial).
        frames: Rendered frames per trial.
        workers: Worker processes (and trials in flight at most).

    Yields:
        Each trial's outcome as it finishes (a worker that died running a trial alone: a
        ``WorkerCrashed`` error record).

    Raises:
        RunnerError: The pool's workers cannot start.
    """
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
                        inflight[pool.submit(run, suspects[0], config, frames)] = suspects[0]
                        solo = suspects.popleft().id
                    while queue and not suspects and solo is None and len(inflight) < workers:
                        inflight[pool.submit(run, queue[0], config, frames)] = queue[0]
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
                            yield crashed_outcome(entry, config, frames, why)
                            solo = None
                        else:
                            suspects.append(entry)
                    inflight.clear()
                    pool.stop()
                    pool = _new_pool(workers)
        finally:
            pool.stop()
