"""Independent simulation runs on threads (handsim.sim.parallel): order, errors, the thread setting."""

from __future__ import annotations

import threading

import pytest

from handsim.sim.parallel import available_cores, map_on_workers, map_runs, map_until, sim_threads
from handsim.thread_setting import THREADS_ENV, threads_setting


def test_results_come_back_in_the_order_of_the_items() -> None:
    assert map_runs(lambda x: x * x, list(range(20)), threads=3) == [x * x for x in range(20)]


def test_runs_use_several_threads_when_asked() -> None:
    barrier = threading.Barrier(2, timeout=10)  # both runs must be in flight at once to pass it

    def run(_: int) -> str:
        barrier.wait()
        return threading.current_thread().name

    names = map_runs(run, [0, 1], threads=2)
    assert len(set(names)) == 2 and all(n.startswith("handsim-sim") for n in names)


def test_one_thread_runs_in_the_caller() -> None:
    caller = threading.current_thread().name
    assert map_runs(lambda _: threading.current_thread().name, [0, 1, 2], threads=1) == [caller] * 3


def test_the_first_error_in_order_is_raised_after_every_run_ended() -> None:
    finished = []

    def run(x: int) -> int:
        if x in (1, 3):
            raise ValueError(f"run {x}")
        finished.append(x)
        return x

    with pytest.raises(ValueError, match="run 1"):
        map_runs(run, [0, 1, 2, 3, 4], threads=2)
    assert sorted(finished) == [0, 2, 4]


def test_thread_setting_from_the_environment(monkeypatch) -> None:
    monkeypatch.delenv(THREADS_ENV, raising=False)
    assert sim_threads() == available_cores() >= 1
    monkeypatch.setenv(THREADS_ENV, "3")
    assert sim_threads() == 3


@pytest.mark.parametrize("value", ["0", "-2", "two", "1.5"])
def test_a_bad_thread_setting_is_a_clear_error(monkeypatch, value: str) -> None:
    monkeypatch.setenv(THREADS_ENV, value)
    for read in (sim_threads, threads_setting):
        with pytest.raises(ValueError, match=rf"\$HANDSIM_THREADS must be a positive integer .*{value!r}"):
            read()


@pytest.mark.parametrize(("value", "expected"), [(None, None), ("", None), (" 3 ", 3), ("1", 1)])
def test_the_thread_setting_as_read(monkeypatch, value: str | None, expected: int | None) -> None:
    if value is None:
        monkeypatch.delenv(THREADS_ENV, raising=False)
    else:
        monkeypatch.setenv(THREADS_ENV, value)
    assert threads_setting() == expected


def test_workers_take_the_next_item_when_free_and_results_come_back_in_order() -> None:
    seen: dict[str, set[str]] = {"a": set(), "b": set(), "c": set()}
    done: dict[str, list[int]] = {"a": [], "b": [], "c": []}
    rest = threading.Event()
    lock = threading.Lock()

    def run(worker: str, item: int) -> int:
        seen[worker].add(threading.current_thread().name)
        if item == 0:  # a long run: it ends only once the other workers have taken every other item
            assert rest.wait(timeout=10)
        with lock:
            done[worker].append(item)
            if sum(map(len, done.values())) == 7 and 0 not in done[worker]:
                rest.set()
        return item * 10

    results = map_on_workers(run, list(range(8)), ["a", "b", "c"])
    assert results == [i * 10 for i in range(8)]
    assert all(len(names) <= 1 for names in seen.values())  # a worker's state stays on one thread
    assert sorted(i for items in done.values() for i in items) == list(range(8))  # each item once
    slow = next(w for w, items in done.items() if 0 in items)
    assert done[slow] == [0]  # the worker busy with the long run took nothing else


def test_workers_raise_the_first_error_in_order_after_every_item_ran() -> None:
    ran = []

    def run(worker: str, item: int) -> int:
        ran.append(item)
        if item in (2, 5):
            raise ValueError(f"item {item}")
        return item

    with pytest.raises(ValueError, match="item 2"):
        map_on_workers(run, list(range(7)), ["a", "b"])
    assert sorted(ran) == list(range(7))
    ran.clear()
    with pytest.raises(ValueError, match="item 2"):  # one worker: in the caller, stopping there
        map_on_workers(run, list(range(7)), ["a"])
    assert ran == [0, 1, 2]


def _loop(run, items, enough):
    results = []
    for item in items:
        results.append(run(item))
        if enough(results):
            break
    return results


@pytest.mark.parametrize("threads", [1, 2, 4])
@pytest.mark.parametrize("stop_after", [1, 3, 7, 100])
def test_map_until_gives_the_loops_results(threads: int, stop_after: int) -> None:
    def enough(results: list[int]) -> bool:
        return sum(r % 3 == 0 for r in results) >= stop_after

    items = list(range(1, 40))
    expected = _loop(lambda x: x * 7 % 11, items, enough)
    assert map_until(lambda x: x * 7 % 11, items, enough, threads) == expected


def test_map_until_draws_at_most_threads_ahead_and_runs_them_at_once() -> None:
    drawn = []
    barrier = threading.Barrier(3, timeout=10)  # three runs must be in flight at once to pass it

    def items():
        for i in range(10):
            drawn.append(i)
            yield i

    def run(x: int) -> tuple[int, int]:
        if x < 3:
            barrier.wait()
        return x, sim_threads()

    results = map_until(run, items(), lambda r: len(r) == 4, threads=3)
    assert results == [(0, 1), (1, 1), (2, 1), (3, 1)]  # each run on one thread: the threads are in use
    assert drawn == list(range(6))  # up to the one looked at last (3), and two more beside it


def test_map_until_raises_errors_in_turn_and_drops_those_past_the_stop() -> None:
    def run(x: int) -> int:
        if x in (2, 5):
            raise ValueError(f"run {x}")
        return x

    with pytest.raises(ValueError, match="run 2"):
        map_until(run, range(8), lambda r: False, threads=3)
    assert map_until(run, range(8), lambda r: r == [0, 1], threads=3) == [
        0,
        1,
    ]  # run 2 ran, its error dropped


def test_map_until_raises_an_error_drawing_an_item_only_when_its_turn_comes() -> None:
    def items():
        yield 0
        yield 1
        raise KeyError("no third item")

    assert map_until(lambda x: x, items(), lambda r: len(r) == 2, threads=4) == [0, 1]
    with pytest.raises(KeyError, match="no third item"):
        map_until(lambda x: x, items(), lambda r: False, threads=4)
