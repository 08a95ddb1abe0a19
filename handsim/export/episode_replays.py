"""The episodes of many records, replayed in this process or in spawned worker processes, in record order.

A record that no longer reproduces (or cannot be replayed) gives ``("mismatch" | "error", message)``
instead of an episode: the caller decides whether to skip it or refuse the export.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor

from tqdm import tqdm

from handsim.export.episode import ReplayedEpisode, replay_record
from handsim.export.errors import ExportError, RecordMismatchError


def _outcome(record: dict, root: str | None, rtol: float, atol: float) -> ReplayedEpisode | tuple[str, str]:
    """An episode, or ``("mismatch" | "error", message)`` (picklable, unlike some exceptions)."""
    try:
        return replay_record(record, root=root, rtol=rtol, atol=atol)
    except RecordMismatchError as exc:
        return ("mismatch", str(exc))
    except ExportError as exc:
        return ("error", str(exc))


def replayed_episodes(
    records: list[dict], root: str | None, workers: int, rtol: float, atol: float, progress: bool
) -> Iterator[ReplayedEpisode | tuple[str, str]]:
    """The records' outcomes in their order, made here or in ``workers`` spawned processes.

    Args:
        records: The records to replay.
        root: The dataset folder the records' input paths are relative to, or None.
        workers: Processes replaying records (1: in this process).
        rtol: Relative tolerance of the summary comparison with the records.
        atol: Absolute tolerance of that comparison, in each number's unit.
        progress: Show a progress bar.

    Yields:
        Each record's episode, or ``("mismatch" | "error", message)``; closing the generator drops the
        records not started.
    """
    bar = tqdm(total=len(records), unit="trial", desc="export", disable=not progress)
    workers = min(workers, len(records))
    try:
        if workers == 1:
            for record in records:
                yield _outcome(record, root, rtol, atol)
                bar.update()
            return
        context = multiprocessing.get_context("spawn")  # no fork of a process holding MuJoCo/GL state
        pool = ProcessPoolExecutor(workers, mp_context=context)
        try:
            futures = [pool.submit(_outcome, record, root, rtol, atol) for record in records]
            for future in futures:
                yield future.result()
                bar.update()
        finally:  # also when the consumer stops early: drop the trials not started
            pool.shutdown(wait=True, cancel_futures=True)
    finally:
        bar.close()
