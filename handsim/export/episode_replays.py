"""Records' layouts and episodes, made in this process or in spawned worker processes, in record order.

An export makes two passes over its records with one :class:`EpisodeReplays` (one pool of workers, whose
caches the second pass reuses): the layouts first (:func:`~handsim.export.episode.record_layout`: every
trial loaded and checked, nothing replayed), so that trials that cannot share a dataset are refused before
any replay, then the episodes. A record that no longer reproduces (or cannot be replayed) gives
``("mismatch" | "error", message)`` instead: the caller decides whether to skip it or refuse the export.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from types import TracebackType
from typing import TypeVar

from handsim.export.episode import EpisodeLayout, ReplayedEpisode, record_layout, replay_record
from handsim.export.errors import ExportError, RecordMismatchError
from handsim.progress import progress_bar
from handsim.runner.worker import prepare_pool_worker

Made = TypeVar("Made")
Outcome = tuple[str, str]
"""``("mismatch" | "error", message)``: what a record gave instead of a layout or an episode."""


def _outcome(make: Callable[..., Made], record: dict, *args: object) -> Made | Outcome:
    """``make(record, *args)``, or ``("mismatch" | "error", message)`` (picklable, unlike some exceptions)."""
    try:
        return make(record, *args)
    except RecordMismatchError as exc:
        return ("mismatch", str(exc))
    except ExportError as exc:
        return ("error", str(exc))


def _layout(record: dict, root: str | None) -> EpisodeLayout:
    return record_layout(record, root=root)


def _episode(record: dict, root: str | None, rtol: float, atol: float) -> ReplayedEpisode:
    return replay_record(record, root=root, rtol=rtol, atol=atol)


class EpisodeReplays:
    """Makes records' layouts and episodes here (``workers=1``) or in a pool of spawned processes.

    Use as a context manager: leaving it (also on an error, or when a consumer stops early) drops the work
    not started and ends the workers.

    Args:
        root: The dataset folder the records' relative input paths are relative to, or None.
        workers: Processes replaying records (1: in this process).
        rtol: Relative tolerance of the summary comparison with the records.
        atol: Absolute tolerance of that comparison, in each number's unit.
        progress: Show progress bars on stderr when it is a terminal (:mod:`handsim.progress`).
    """

    def __init__(self, root: str | None, workers: int, rtol: float, atol: float, progress: bool) -> None:
        self._root, self._rtol, self._atol, self._progress = root, rtol, atol, progress
        self._pool = None
        if workers > 1:
            context = multiprocessing.get_context("spawn")  # no fork of a process holding MuJoCo/GL state
            self._pool = ProcessPoolExecutor(workers, mp_context=context, initializer=prepare_pool_worker)

    def layouts(self, records: Sequence[dict]) -> Iterator[EpisodeLayout | Outcome]:
        """Each record's layout (its trial loaded and checked, not replayed), in record order."""
        return self._map(_layout, records, (self._root,), "check")

    def episodes(self, records: Sequence[dict]) -> Iterator[ReplayedEpisode | Outcome]:
        """Each record's episode (replayed and checked against the record), in record order."""
        return self._map(_episode, records, (self._root, self._rtol, self._atol), "export")

    def _map(
        self, make: Callable[..., Made], records: Sequence[dict], args: tuple, desc: str
    ) -> Iterator[Made | Outcome]:
        with progress_bar(enabled=self._progress, total=len(records), unit="trial", desc=desc) as bar:
            if self._pool is None:
                for record in records:
                    yield _outcome(make, record, *args)
                    bar.update()
                return
            futures = [self._pool.submit(_outcome, make, record, *args) for record in records]
            try:
                for future in futures:
                    yield future.result()
                    bar.update()
            finally:  # also when the consumer stops early: drop the records not started
                for future in futures:
                    future.cancel()

    def close(self) -> None:
        """Drop the work not started and end the workers."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __enter__(self) -> EpisodeReplays:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()
