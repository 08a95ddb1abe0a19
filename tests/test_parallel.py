"""Independent simulation runs on threads (handsim.sim.parallel): order, errors, the thread setting."""

from __future__ import annotations

import threading

import pytest

from handsim.sim.parallel import THREADS_ENV, available_cores, map_on_workers, map_runs, sim_threads


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
    with pytest.raises(ValueError, match=rf"\$HANDSIM_THREADS must be a positive integer .*{value!r}"):
        sim_threads()


def test_workers_take_every_nth_item_and_results_come_back_in_order() -> None:
    seen: dict[str, set[str]] = {"a": set(), "b": set(), "c": set()}

    def run(worker: str, item: int) -> tuple[str, int]:
        seen[worker].add(threading.current_thread().name)
        return worker, item * 10

    results = map_on_workers(run, list(range(8)), ["a", "b", "c"])
    assert results == [("abc"[i % 3], i * 10) for i in range(8)]
    assert all(len(names) == 1 for names in seen.values())  # a worker's state stays on one thread
