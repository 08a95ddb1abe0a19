"""``kill -9`` at chosen moments of ``handsim export minari`` and ``handsim report``: nothing is lost.

Each run is a child process killed with SIGKILL at one exact step (``tests/killing.py`` wraps the call
the step makes: after the N-th episode is added, after each rename of a dataset swap, after the N-th
record is written) or from outside while it writes. After each kill: no partial dataset is ever in place
(Minari loads the old dataset, the whole new one, or none), the dataset an ``--overwrite`` replaces
survives every kill before the swap completes (also two kills in a row), the next run names what the
killed one left and puts it right, and ``records.jsonl`` keeps every finished trial. The trials are three
short scripted grasps (0.8 s each), so that each run takes seconds.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from handsim.runner.output_lock import LOCK_FILE, LockHolder
from handsim.runner.records import load_records
from tests.helpers import write_short_grasp
from tests.processes import ROOT, child_env, linux_only, wait_for

minari = pytest.importorskip("minari", reason="the Minari export needs: pip install 'handsim[minari]'")
pytest.importorskip("h5py", reason="minari's HDF5 storage needs h5py: pip install 'minari[hdf5]'")

pytestmark = [pytest.mark.slow, linux_only]

OBJECTS = ("cube", "cylinder_25mm", "tennis_ball")
RUN_OPTIONS = ["--workers", "1", "--frames", "0", "--stability", "none"]
ADD = "handsim.export.minari_writer:MinariWriter.add"
APPEND = "handsim.runner.records:RecordWriter.append"


def _handsim(args: list[str], env: dict[str, str], kill: tuple = ()) -> subprocess.CompletedProcess:
    """``handsim ARGS`` in a child process, killed as ``kill`` says (``tests/killing.py``) when given."""
    if kill:
        command = [sys.executable, str(ROOT / "tests" / "killing.py"), *map(str, kill), "--", *args]
    else:
        command = [sys.executable, "-m", "handsim.cli", *args]
    return subprocess.run(
        command, capture_output=True, text=True, env=env, cwd=ROOT, timeout=600, check=False
    )


def _notes(done: subprocess.CompletedProcess) -> list[str]:
    return [
        line.removeprefix("note        ") for line in done.stdout.splitlines() if line.startswith("note ")
    ]


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("kills") / "grasps"
    for name in OBJECTS:
        write_short_grasp(folder, name)
    return folder


@pytest.fixture(scope="module")
def run_dir(dataset: Path) -> Path:
    """A dataset run of the three grasps (what an export reads)."""
    from handsim.runner.execute import run_dataset
    from handsim.sim.replay import ReplayConfig
    from handsim.trials import discover

    out = dataset.parent / "run"
    run_dataset(discover(dataset), out, workers=1, frames=0, config=ReplayConfig(), progress=False)
    return out


@pytest.fixture
def root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Minari's datasets folder of the test (here and in the children)."""
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    return tmp_path / "minari"


@pytest.fixture
def env(root: Path) -> dict[str, str]:
    return {**child_env(), "MINARI_DATASETS_PATH": str(root)}


def _episodes(dataset_id: str) -> list[str]:
    """The trial ids of a complete dataset in place (handsim's metadata lists them), or [] when none is."""
    try:
        data = minari.load_dataset(dataset_id)
    except FileNotFoundError:
        return []
    exported = data.storage.metadata["handsim"]["exported"]  # a KeyError: a part of a dataset in place
    assert len(data) == len(exported)
    return exported


def _export(run_dir: Path, dataset_id: str, *options: str) -> list[str]:
    return ["export", "minari", str(run_dir), "--dataset-id", dataset_id, "--workers", "1", *options]


ALL = [f"{name}.grasp.json#1" for name in OBJECTS]  # each holds one grasp episode


def test_a_killed_export_leaves_no_dataset_and_the_next_run_names_and_removes_its_leftover(
    run_dir, root, env
) -> None:
    killed = _handsim(_export(run_dir, "handsim/k-v0"), env, kill=(ADD, 2, "after", "kill"))
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    assert _episodes("handsim/k-v0") == [] and "handsim/k-v0" not in minari.list_local_datasets()
    assert not (root / "handsim").exists()  # not even the namespace: it is registered at the move
    partial = root / ".handsim-export" / "handsim" / "k-v0.partial"
    holder = LockHolder.from_json((partial / "export.json").read_bytes())

    done = _handsim(_export(run_dir, "handsim/k-v0"), env)
    assert done.returncode == 0, done.stderr
    lock, removed = _notes(done)
    assert lock.startswith(
        f"took over the lock {root}/.handsim-export/handsim/k-v0.lock of a run that ended "
    )
    assert lock.endswith(f"; pid {holder.pid} no longer runs)")
    assert removed == (
        f"removed {partial}: the unfinished dataset 'handsim/k-v0' of an export that was killed "
        f"({holder.describe()}); it was never in place (Minari did not list or load it)"
    )
    assert _episodes("handsim/k-v0") == ALL
    assert not (root / ".handsim-export").exists()


def test_the_dataset_an_overwrite_replaces_survives_a_kill_at_every_step_and_two_kills_in_a_row(
    run_dir, root, env
) -> None:
    from handsim.export import export_minari

    export_minari(run_dir, "handsim/o-v0")
    original = _episodes("handsim/o-v0")
    assert original == ALL
    replace = _export(run_dir, "handsim/o-v0", "--overwrite", "--only", "cube*")
    swap_begun = ("os:rename", 1, "after", "kill", ".replaced'))")  # the original moved aside
    swap_done = ("os:rename", 1, "after", "kill", "o-v0.partial/handsim/o-v0'), ")  # the new one in place

    killed = _handsim(replace, env, kill=(ADD, 1, "after", "kill"))  # while the new one is built
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    assert _episodes("handsim/o-v0") == original

    replaced = root / ".handsim-export" / "handsim" / "o-v0.replaced"
    for _ in range(2):  # the second run puts the first's kill right, then is killed at the same step
        killed = _handsim(replace, env, kill=swap_begun)
        assert killed.returncode == -signal.SIGKILL, killed.stderr
        assert _episodes("handsim/o-v0") == []  # none in place: never a part
        assert (replaced / "data" / "main_data.hdf5").is_file()  # the original, moved aside whole
    refused = _handsim(_export(run_dir, "handsim/o-v0"), env)  # any later export puts it back
    assert refused.returncode == 1
    assert refused.stderr.startswith("handsim: error: Minari dataset 'handsim/o-v0' exists already")
    assert _notes(refused)[-1].startswith(f"restored Minari dataset 'handsim/o-v0' ({root / 'handsim/o-v0'})")
    assert _episodes("handsim/o-v0") == original

    killed = _handsim(replace, env, kill=swap_done)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    assert _episodes("handsim/o-v0") == ["cube.grasp.json#1"]  # the new one, whole
    done = _handsim(_export(run_dir, "handsim/other-v0", "--only", "tennis*"), env)  # another id's export
    assert done.returncode == 0, done.stderr
    assert _notes(done)[-1].startswith(
        f"removed {replaced}: the dataset 'handsim/o-v0' an export with --overwrite"
    )
    assert _episodes("handsim/o-v0") == ["cube.grasp.json#1"]
    assert not (root / ".handsim-export").exists()


@pytest.mark.parametrize("delay", [0.0, 0.3])
def test_an_export_killed_from_outside_while_it_writes_leaves_the_whole_dataset_or_none(
    run_dir, root, env, delay
) -> None:
    data = root / ".handsim-export" / "handsim" / "x-v0.partial" / "handsim" / "x-v0" / "data"
    process = subprocess.Popen(
        [sys.executable, "-m", "handsim.cli", *_export(run_dir, "handsim/x-v0")],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=ROOT,
    )  # fmt: skip
    try:
        wait_for(lambda: data.is_dir() or process.poll() is not None, 120, "the export did not start writing")
        time.sleep(delay)
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    assert _episodes("handsim/x-v0") in ([], ALL)  # the whole dataset or none, never a part


def test_a_killed_report_keeps_every_finished_trial_and_the_next_run_takes_over_its_lock(
    dataset, tmp_path, env
) -> None:
    out = tmp_path / "out"
    report = ["report", str(dataset), "-o", str(out), *RUN_OPTIONS]
    killed = _handsim(report, env, kill=(APPEND, 2, "after", "kill"))
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    read = load_records(out)
    assert len(read.records) == 2 and read.valid_bytes == read.size  # both finished trials, whole lines
    holder = LockHolder.from_json((out / LOCK_FILE).read_bytes())
    assert holder.pid > 0 and holder.command[0] == "handsim"

    done = _handsim(report, env)
    assert done.returncode == 0, done.stderr
    assert (
        f"note        took over the lock {out / LOCK_FILE} of a run that ended without releasing it"
        in done.stdout
    )
    assert f"; pid {holder.pid} no longer runs)" in done.stdout
    assert f"records     {out / 'records.jsonl'} (1 run now, 2 resumed)" in done.stdout
    assert sorted(r["id"] for r in load_records(out).records) == ALL
    assert not (out / LOCK_FILE).exists()


def test_a_second_report_into_the_same_folder_is_refused_naming_the_first(dataset, tmp_path, env) -> None:
    out = tmp_path / "out"
    report = ["report", str(dataset), "-o", str(out), *RUN_OPTIONS]
    command = [
        sys.executable,
        str(ROOT / "tests" / "killing.py"),
        APPEND,
        "1",
        "after",
        "stop",
        "--",
        *report,
    ]
    first = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=ROOT)
    try:  # the first run stops itself (SIGSTOP) after its first record, holding the lock
        wait_for(lambda: len(load_records(out).records) == 1, 120, "the first run did not record a trial")
        holder = LockHolder.from_json((out / LOCK_FILE).read_bytes())
        assert (holder.pid, holder.host) == (first.pid, socket.gethostname())
        second = _handsim(report, env)
    finally:
        first.send_signal(signal.SIGKILL)
        first.wait()
    assert second.returncode == 1
    assert second.stderr.splitlines()[0] == (
        f"handsim: error: output folder {out} is in use by another run ({holder.describe()}; lock file "
        f"{out / LOCK_FILE}): wait for it to end, or write to another place"
    )
    assert len(load_records(out).records) == 1  # the refused run wrote nothing
    assert os.path.exists(out / LOCK_FILE)  # the killed holder's, taken over by the next run
