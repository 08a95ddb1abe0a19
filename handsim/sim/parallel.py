"""Independent simulation runs on threads, each on its own ``MjData``.

MuJoCo's ``mj_step`` and ``mj_collision`` release the GIL, so runs on separate ``MjData`` (one shared,
read-only ``MjModel``) use every core without copying the model or spawning processes.

Used where one result needs several runs that do not depend on each other: the stability test's seven
gravity runs (:func:`handsim.sim.stability.gravity.stability_test`, hence the replay's test at the release),
the
glove placement's grip tests, taken in rank order until enough hold, the next ones running ahead
(:func:`map_until`), the replays of the robustness ensemble's members
(:func:`handsim.sim.placement.robustness.hold_robustness`) and the placement search's fit-frame collision
queries
(:class:`handsim.sim.placement.search.PlacementSearch`). Each run computes exactly what it computes alone,
in the same order of floating-point operations, so results are bit-for-bit those of running them one
after the other; only the wall time changes. (One exception, by design: which of the search's poses the
collider's probe settles as too deep depends on its worker's earlier queries, so on timing; what is
concluded of each pose does not, nor does the placement: :meth:`PlacementSearch._depths`.)

How many threads: ``$HANDSIM_THREADS`` when set (``1``: everything in the calling thread), else one per
core this process may use. A dataset run's worker processes set it to 1 (the pool already uses every
core: :func:`handsim.runner.worker.prepare_worker_process`).
"""

from __future__ import annotations

import os
import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from typing import TypeVar

from handsim.thread_setting import threads_setting

_INNER = threading.local()  # .serial: this thread runs one of map_until's runs (sim_threads() is 1 there)

T = TypeVar("T")
R = TypeVar("R")
W = TypeVar("W")


def available_cores() -> int:
    """The cores this process may use (its CPU affinity where the OS reports one), at least 1."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def sim_threads() -> int:
    """Threads for independent simulation runs: ``$HANDSIM_THREADS``, else :func:`available_cores`.

    Raises:
        ValueError: ``$HANDSIM_THREADS`` is set but not a positive integer.
    """
    if getattr(_INNER, "serial", False):
        return 1
    threads = threads_setting()
    return available_cores() if threads is None else threads


def map_runs(run: Callable[[T], R], items: Sequence[T], threads: int | None = None) -> list[R]:
    """``[run(item) for item in items]``, the items spread over ``threads`` threads; results in order.

    Args:
        run: One independent run; it must not share mutable state (an ``MjData``) with the others.
        items: Its inputs.
        threads: Threads to use; None: :func:`sim_threads`. With 1, or one item, no thread is started.

    Returns:
        The results, in the order of ``items``. An exception of a run is raised here (the first in
        order), after every run has ended.
    """
    count = min(len(items), sim_threads() if threads is None else max(1, int(threads)))
    if count <= 1:
        return [run(item) for item in items]
    with ThreadPoolExecutor(max_workers=count, thread_name_prefix="handsim-sim") as pool:
        futures = [pool.submit(run, item) for item in items]
    return [future.result() for future in futures]


def map_until(
    run: Callable[[T], R],
    items: Iterable[T],
    enough: Callable[[list[R]], bool],
    threads: int | None = None,
) -> list[R]:
    """``run`` over ``items`` in order until ``enough(results)``; later items run ahead on threads.

    The results are those of the loop ``for item in items: results.append(run(item)); if
    enough(results): break``, in the same order: each run is independent, so running it early changes
    nothing but the wall time. While the first unfinished item runs, up to ``threads - 1`` later ones run
    beside it; those past the stop are waited for and their results (or errors) dropped. Each run sees
    :func:`sim_threads` as 1: the threads are taken by the runs themselves, so nested runs (a grip test's
    stability directions) run one after the other inside each.

    Args:
        run: One independent run (see :func:`map_runs`).
        items: Its inputs, drawn lazily in the calling thread, at most ``threads - 1`` beyond the one whose
            result is awaited: a draw may have side effects (items past the stop were drawn too). An error
            drawing one is raised when its turn comes, as in the loop.
        enough: Asked with the results so far, after each one in order; True stops.
        threads: Runs at once; None: :func:`sim_threads`. With 1, the plain loop (no thread started).

    Returns:
        The results up to and including the one after which ``enough`` said True (all of them if it never
        did). An exception of a run is raised when its turn comes, as in the loop.
    """
    count = sim_threads() if threads is None else max(1, int(threads))
    results: list[R] = []
    source: Iterator[T] | None = iter(items)
    if count <= 1:
        for item in source:
            results.append(run(item))
            if enough(results):
                break
        return results
    with ThreadPoolExecutor(max_workers=count, thread_name_prefix="handsim-sim") as pool:
        pending: deque[Future[R] | BaseException] = deque()  # a draw's error waits for its turn
        try:
            while True:
                while source is not None and len(pending) < count:
                    try:
                        item = next(source)
                    except StopIteration:
                        source = None
                    except Exception as error:  # raised when its turn comes, as the loop would
                        pending.append(error)
                        source = None
                    else:
                        pending.append(pool.submit(_serial_inside, run, item))
                if not pending:
                    break
                head = pending.popleft()
                if isinstance(head, BaseException):
                    raise head
                results.append(head.result())
                if enough(results):
                    break
        finally:  # past the stop (or an error): runs not started are dropped, running ones waited for
            for future in pending:
                if isinstance(future, Future):
                    future.cancel()
    return results


def _serial_inside(run: Callable[[T], R], item: T) -> R:
    _INNER.serial = True
    return run(item)


def map_on_workers(run: Callable[[W, T], R], items: Sequence[T], workers: Sequence[W]) -> list[R]:
    """``[run(worker, item) …]`` with one thread per worker, each item on one worker; results in order.

    For runs that need state of their own (an ``MjData``) but not a fresh one per item: each worker takes
    the next item not yet taken as soon as it is free (runs of different lengths keep every thread busy),
    one after the other on its own thread. Which worker runs an item must not change what the caller makes
    of its result (e.g. a worker's state reset by each run).

    Args:
        run: ``run(worker, item)``; a worker's state is used by one thread only.
        items: The inputs.
        workers: The per-thread states, e.g. ``[first, *(first.fork() for _ in range(n - 1))]``.

    Returns:
        The results, in the order of ``items``. An exception of a run is raised here (the first in order),
        after every item has run (with one worker: at once, as the loop would).
    """
    if len(workers) == 1:  # in the caller, stopping at an error as the loop would
        return [run(workers[0], item) for item in items]
    results: list[R] = [None] * len(items)  # type: ignore[list-item]
    errors: dict[int, Exception] = {}
    taken = iter(range(len(items)))
    lock = threading.Lock()

    def work(worker: W) -> None:
        while True:
            with lock:
                index = next(taken, None)
            if index is None:
                return
            try:
                results[index] = run(worker, items[index])
            except Exception as error:  # raised below, in item order, once every item has run
                errors[index] = error

    map_runs(work, list(workers), len(workers))
    if errors:
        raise errors[min(errors)]
    return results
