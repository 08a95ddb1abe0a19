"""A Minari dataset appears whole or not at all: the staging folder, the swap, and what the next export puts
right after a kill at each step (the states a kill leaves, made here; tests/test_kill_safety.py kills)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from handsim.export.errors import DatasetExistsError, ExportError
from handsim.export.staging import BUILDER_FILE, WORK_FOLDER, DatasetStage, recover, recover_others
from handsim.runner.output_lock import LockHolder, OutputBusyError, OutputLock

ID = "ns/x-v0"
BUILDER = LockHolder(4242, "host", "2000-01-01T00:00:00+0000", ("handsim", "export", "minari", "out"))


def _dataset(folder: Path, content: str) -> Path:
    """A stand-in for a Minari dataset folder (``data/`` with one file saying which it is)."""
    (folder / "data").mkdir(parents=True)
    (folder / "data" / "which").write_text(content)
    return folder


def _which(folder: Path) -> str:
    return (folder / "data" / "which").read_text()


def _work(root: Path, suffix: str) -> Path:
    return root / WORK_FOLDER / f"{ID}{suffix}"


def _partial(root: Path, *, built: bool) -> Path:
    """A staging folder as an export leaves it (with its dataset when ``built``)."""
    partial = _work(root, ".partial")
    partial.mkdir(parents=True)
    (partial / BUILDER_FILE).write_bytes(BUILDER.to_json())
    if built:
        _dataset(partial / ID, "new")
    return partial


def _notes(root: Path, dataset_id: str = ID) -> list[str]:
    notes: list[str] = []
    recover(root, dataset_id, notes.append)
    return notes


def test_an_unfinished_dataset_of_a_killed_export_is_removed_and_named(tmp_path: Path) -> None:
    partial = _partial(tmp_path, built=True)
    assert _notes(tmp_path) == [
        f"removed {partial}: the unfinished dataset 'ns/x-v0' of an export that was killed (pid 4242 on "
        "host, started 2000-01-01T00:00:00+0000: handsim export minari out); it was never in place (Minari "
        "did not list or load it)"
    ]
    assert not partial.exists() and not (tmp_path / ID).exists()


def test_a_dataset_moved_aside_by_a_killed_overwrite_is_moved_back(tmp_path: Path) -> None:
    _partial(tmp_path, built=True)
    replaced = _dataset(_work(tmp_path, ".replaced"), "original")
    (note,) = _notes(tmp_path)
    assert note.startswith(
        f"restored Minari dataset 'ns/x-v0' ({tmp_path / ID}): an export replacing it with "
    )
    assert f"was killed after moving it aside to {replaced}; it is back in place unchanged" in note
    assert _which(tmp_path / ID) == "original"
    assert not replaced.exists() and not _work(tmp_path, ".partial").exists()


def test_the_replaced_dataset_left_after_the_new_one_was_in_place_is_removed(tmp_path: Path) -> None:
    _partial(tmp_path, built=False)  # the new dataset was moved out of it
    _dataset(tmp_path / ID, "new")
    replaced = _dataset(_work(tmp_path, ".replaced"), "original")
    (note,) = _notes(tmp_path)
    assert note.startswith(f"removed {replaced}: the dataset 'ns/x-v0' an export with --overwrite (pid 4242")
    assert _which(tmp_path / ID) == "new" and not replaced.exists()


def test_a_moved_aside_dataset_beside_another_in_place_is_left_for_the_user_to_decide(tmp_path: Path) -> None:
    _partial(tmp_path, built=True)  # the swap never began moving the new one: the one in place is not ours
    _dataset(tmp_path / ID, "someone else's")
    replaced = _dataset(_work(tmp_path, ".replaced"), "original")
    with pytest.raises(ExportError, match=r"holds a Minari dataset 'ns/x-v0' .* keep one"):
        _notes(tmp_path)
    assert _which(replaced) == "original" and _which(tmp_path / ID) == "someone else's"


def test_nothing_left_means_nothing_done(tmp_path: Path) -> None:
    _dataset(tmp_path / ID, "original")
    assert _notes(tmp_path) == []
    assert _which(tmp_path / ID) == "original"


def test_leftovers_of_other_ids_are_put_right_unless_their_export_runs(tmp_path: Path) -> None:
    _dataset(tmp_path / WORK_FOLDER / "a/y-v0.replaced", "y")
    _dataset(tmp_path / WORK_FOLDER / "b/z-v0.replaced", "z")
    notes: list[str] = []
    with OutputLock(tmp_path / WORK_FOLDER / "b/z-v0.lock", what="z"):  # z's export runs: left to it
        recover_others(tmp_path, ID, notes.append)
    assert len(notes) == 1 and notes[0].startswith("restored Minari dataset 'a/y-v0'")
    assert _which(tmp_path / "a/y-v0") == "y" and not (tmp_path / "b/z-v0").exists()


# ---- the stage -------------------------------------------------------------------------------------------


def _build(stage: DatasetStage, content: str) -> None:
    _dataset(stage.build_root / ID, content)


def test_a_committed_dataset_moves_into_place_and_nothing_else_is_left(tmp_path: Path) -> None:
    namespaces = []
    with DatasetStage(tmp_path, ID, overwrite=False, on_note=pytest.fail) as stage:
        builder = LockHolder.from_json((stage.build_root / BUILDER_FILE).read_bytes())
        assert builder.command == LockHolder.this_process().command
        _build(stage, "new")
        assert not (tmp_path / ID).exists()  # nothing in place while it is built
        stage.commit(lambda: namespaces.append(ID))
    assert _which(tmp_path / ID) == "new" and namespaces == [ID]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ns"]  # the work folder is gone


def test_an_overwrite_replaces_the_dataset_only_when_the_new_one_is_complete(tmp_path: Path) -> None:
    _dataset(tmp_path / ID, "original")
    with DatasetStage(tmp_path, ID, overwrite=True, on_note=pytest.fail) as stage:
        _build(stage, "new")
        assert _which(tmp_path / ID) == "original"
        stage.commit(lambda: None)
    assert _which(tmp_path / ID) == "new"
    assert not (tmp_path / WORK_FOLDER).exists()


def test_a_failed_export_leaves_the_dataset_in_place_and_no_work_folder(tmp_path: Path) -> None:
    _dataset(tmp_path / ID, "original")
    with pytest.raises(RuntimeError, match="replay failed"):
        with DatasetStage(tmp_path, ID, overwrite=True, on_note=pytest.fail) as stage:
            _build(stage, "new")
            raise RuntimeError("replay failed")
    assert _which(tmp_path / ID) == "original"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ns"]


@pytest.mark.skipif(
    importlib.util.find_spec("minari") is None,
    reason="the Minari export needs: pip install 'handsim[minari]'",
)
def test_an_existing_dataset_is_refused_without_overwrite_saying_when_handsim_did_not_finish_it(
    tmp_path: Path,
) -> None:
    _dataset(tmp_path / ID, "not minari's")
    with pytest.raises(DatasetExistsError) as caught:
        DatasetStage(tmp_path, ID, overwrite=False, on_note=pytest.fail).__enter__()
    assert str(caught.value) == (
        f"Minari dataset 'ns/x-v0' exists already ({tmp_path / ID}): choose another id or version, or "
        "replace it with --overwrite (overwrite=True); it holds no Minari metadata (data/metadata.json): "
        "not a complete dataset"
    )
    (tmp_path / ID / "data" / "metadata.json").write_text(json.dumps({"dataset_id": ID}))
    with pytest.raises(
        DatasetExistsError, match=r"; it has no metadata\['handsim'\]: not written by handsim"
    ):
        DatasetStage(tmp_path, ID, overwrite=False, on_note=pytest.fail).__enter__()
    assert not (tmp_path / WORK_FOLDER).exists()  # the lock was released


def test_a_second_export_of_the_same_id_is_refused_while_the_first_runs(tmp_path: Path) -> None:
    with DatasetStage(tmp_path, ID, overwrite=False, on_note=pytest.fail, command=["first"]):
        with pytest.raises(OutputBusyError, match=r"Minari dataset 'ns/x-v0' is in use by another run \(pid"):
            DatasetStage(tmp_path, ID, overwrite=False, on_note=pytest.fail).__enter__()
        with DatasetStage(tmp_path, "ns/other-v0", overwrite=False, on_note=pytest.fail):
            pass  # another id of the namespace: its own lock
