"""A Minari dataset that appears whole or not at all: built aside, moved into place when complete.

Minari keeps dataset ``NS/NAME-v0`` in ``ROOT/NS/NAME-v0`` (``ROOT``: ``MINARI_DATASETS_PATH``, default
``~/.minari/datasets``) and loads whatever folder it finds there. An export therefore never writes into
that folder. It works in ``ROOT/.handsim-export/`` (Minari skips hidden folders: nothing there is ever
listed or loaded as a dataset):

* ``NS/NAME-v0.lock`` — the lock of the export of that id (:class:`~handsim.runner.output_lock.OutputLock`):
  one export per dataset id at a time; it names its holder.
* ``NS/NAME-v0.partial/`` — the dataset being built, in a Minari datasets folder of its own
  (``.partial/NS/NAME-v0``), with ``export.json`` naming the export that builds it.
* ``NS/NAME-v0.replaced/`` — during ``--overwrite``'s swap only: the dataset being replaced.

:meth:`DatasetStage.commit` moves the finished dataset into place with one ``rename``; to replace a
dataset it renames the old one to ``.replaced``, renames the new one into place, then removes the old one.
Each rename is atomic, so a process killed at any moment (``kill -9``) leaves ``ROOT/NS/NAME-v0`` either
absent, the old dataset or the new one — never a part — and the old one is in ``.replaced`` whenever it is
not in place. The next export of any id puts right what a killed one left (:func:`recover`), with a note
naming it: an unfinished ``.partial`` is removed; an old dataset moved aside is moved back (the replacement
never completed, so the original stays); a ``.replaced`` left after the new dataset was in place is
removed.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from types import TracebackType

from handsim.export.errors import DatasetExistsError, ExportError
from handsim.files import write_atomic
from handsim.runner.output_lock import LockHolder, OutputBusyError, OutputLock

WORK_FOLDER = ".handsim-export"
"""The export's folder in Minari's datasets folder (hidden: Minari never lists it)."""
PARTIAL, REPLACED, LOCK = ".partial", ".replaced", ".lock"
"""Suffixes of a dataset id's entries in the work folder."""
BUILDER_FILE = "export.json"
"""File in a ``.partial`` folder naming the export that builds it (pid, host, start, command)."""


@contextlib.contextmanager
def minari_datasets_path(root: Path) -> Iterator[None]:
    """Let Minari create datasets in ``root`` inside the block (``MINARI_DATASETS_PATH``, restored after).

    Minari creates a dataset where that variable points, nowhere else; only the creation needs it (a
    dataset made is then written through its own path).
    """
    saved = os.environ.get("MINARI_DATASETS_PATH")
    os.environ["MINARI_DATASETS_PATH"] = str(root)
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop("MINARI_DATASETS_PATH", None)
        else:
            os.environ["MINARI_DATASETS_PATH"] = saved


class DatasetStage:
    """The export of one dataset id: its lock, its staging folder, and the move into place.

    Use as a context manager: entering takes the lock, puts right what killed exports left (saying what to
    ``on_note``) and refuses an existing dataset unless ``overwrite``; leaving without :meth:`commit`
    removes the staging folder (the dataset in place is never touched); leaving releases the lock.

    Args:
        root: Minari's datasets folder.
        dataset_id: The dataset id (``NS/NAME-v0``, checked already).
        overwrite: Replace the dataset in place when there is one.
        on_note: Called with each note on what entering found and put right, as it is done (also when
            entering then fails).
        command: The command line named in the lock and the staging folder (default ``sys.argv``).

    Attributes:
        target: Where the dataset goes, ``ROOT/NS/NAME-v0``.
        build_root: The Minari datasets folder to create the dataset in (the staging folder).
    """

    def __init__(
        self,
        root: Path,
        dataset_id: str,
        *,
        overwrite: bool,
        on_note: Callable[[str], None],
        command: Sequence[str] | None = None,
    ) -> None:
        self.root = Path(root)
        self.dataset_id = dataset_id
        self.overwrite = overwrite
        self.target = self.root / dataset_id
        self.build_root = _entry(self.root, dataset_id, PARTIAL)
        self._command = command
        self._lock = OutputLock(
            _entry(self.root, dataset_id, LOCK), what=f"Minari dataset {dataset_id!r}", command=command
        )
        self._committed = False
        self._note = on_note

    def __enter__(self) -> DatasetStage:
        for note in self._lock.acquire():
            self._note(note)
        try:
            recover(self.root, self.dataset_id, self._note)
            recover_others(self.root, self.dataset_id, self._note)
            if self.target.exists() and not self.overwrite:
                raise DatasetExistsError(_exists_message(self.dataset_id, self.target))
            self.build_root.mkdir(parents=True)
            holder = LockHolder.this_process(self._command)
            write_atomic(self.build_root / BUILDER_FILE, holder.to_json())
        except BaseException:
            self._lock.release()
            _remove_empty_parents(self.root, self.dataset_id)
            raise
        return self

    def commit(self, namespace_ready: Callable[[], None]) -> None:
        """Move the finished dataset into place (replacing the one there with ``overwrite``).

        Args:
            namespace_ready: Called just before the move, to register the dataset's namespace with Minari.

        Raises:
            DatasetExistsError: A dataset appeared in place meanwhile (not by handsim) and ``overwrite``
                is False.
            OSError: A rename failed (the dataset in place is kept).
        """
        built = self.build_root / self.dataset_id
        _sync_tree(built)
        namespace_ready()
        self.target.parent.mkdir(parents=True, exist_ok=True)
        if self.target.exists():
            if not self.overwrite:
                raise DatasetExistsError(_exists_message(self.dataset_id, self.target))
            replaced = _entry(self.root, self.dataset_id, REPLACED)
            os.rename(self.target, replaced)
            try:
                os.rename(built, self.target)
            except BaseException:
                os.rename(replaced, self.target)
                raise
            shutil.rmtree(replaced)
        else:
            try:
                os.rename(built, self.target)
            except OSError as exc:
                if self.target.exists():  # a folder appeared there meanwhile
                    raise DatasetExistsError(_exists_message(self.dataset_id, self.target)) from exc
                raise
        self._committed = True
        shutil.rmtree(self.build_root)

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        try:
            if not self._committed:
                shutil.rmtree(self.build_root, ignore_errors=True)
        finally:
            self._lock.release()
            _remove_empty_parents(self.root, self.dataset_id)


def recover(root: Path, dataset_id: str, on_note: Callable[[str], None]) -> None:
    """Put right what a killed export of ``dataset_id`` left in ``root`` (the caller holds its lock).

    Args:
        root: Minari's datasets folder.
        dataset_id: The dataset id.
        on_note: Called with a note on each thing put right, once it is done.

    Raises:
        ExportError: A dataset moved aside by an interrupted ``--overwrite`` lies in ``.replaced`` while
            another dataset is in place: which to keep is the user's to say (the message names both).
    """
    target = root / dataset_id
    partial, replaced = _entry(root, dataset_id, PARTIAL), _entry(root, dataset_id, REPLACED)
    built = partial / dataset_id
    by = _built_by(partial)
    if replaced.exists():
        if not target.exists():  # killed between its two renames: the new dataset never got in place
            target.parent.mkdir(parents=True, exist_ok=True)
            os.rename(replaced, target)
            on_note(
                f"restored Minari dataset {dataset_id!r} ({target}): an export replacing it with --overwrite"
                f"{by} was killed after moving it aside to {replaced}; it is back in place unchanged, and "
                "the replacement that export had built is removed"
            )
        elif partial.exists() and not built.exists():  # killed after the new dataset was in place
            shutil.rmtree(replaced)
            on_note(
                f"removed {replaced}: the dataset {dataset_id!r} an export with --overwrite{by} replaced "
                "before it was killed (the new dataset was in place already)"
            )
        else:
            raise ExportError(
                f"{replaced} holds a Minari dataset {dataset_id!r} that an export with --overwrite moved "
                f"aside before it was killed, and {target} holds another: keep one (load each with "
                "minari), move or remove the other, then export again"
            )
    elif built.exists():
        shutil.rmtree(partial)
        on_note(
            f"removed {partial}: the unfinished dataset {dataset_id!r} of an export that was killed{by}; "
            "it was never in place (Minari did not list or load it)"
        )
    shutil.rmtree(partial, ignore_errors=True)


def recover_others(root: Path, dataset_id: str, on_note: Callable[[str], None]) -> None:
    """:func:`recover` for every other dataset id with leftovers in ``root`` whose lock is free.

    A dataset moved aside by a killed ``--overwrite`` is then back in place even if its id is never
    exported again. Ids whose export runs now (their lock is held) are left to it; a leftover that needs
    the user's decision is noted, not raised.
    """
    for other in _leftover_ids(root):
        if other == dataset_id:
            continue
        lock = OutputLock(_entry(root, other, LOCK), what=f"Minari dataset {other!r}")
        try:
            lock.acquire()
        except OutputBusyError:
            continue
        try:
            recover(root, other, on_note)
        except ExportError as exc:
            on_note(str(exc))
        finally:
            lock.release()
            _remove_empty_parents(root, other)


def _entry(root: Path, dataset_id: str, suffix: str) -> Path:
    """``ROOT/.handsim-export/NS/NAME-v0<suffix>``."""
    return root / WORK_FOLDER / (dataset_id + suffix)


def _leftover_ids(root: Path) -> list[str]:
    """Dataset ids with a ``.partial`` or ``.replaced`` folder in the work folder, sorted."""
    work = root / WORK_FOLDER
    ids = set()
    for folder, dirs, _ in os.walk(work):
        for name in list(dirs):
            for suffix in (PARTIAL, REPLACED):
                if name.endswith(suffix):
                    ids.add((Path(folder) / name[: -len(suffix)]).relative_to(work).as_posix())
                    dirs.remove(name)  # not into the datasets inside
                    break
    return sorted(ids)


def _built_by(partial: Path) -> str:
    """`` (pid … on host, started …: command)``: the export that built ``partial``, or ``""``."""
    try:
        holder = LockHolder.from_json((partial / BUILDER_FILE).read_bytes())
    except OSError:
        return ""
    return f" ({holder.describe()})" if holder is not None else ""


def _exists_message(dataset_id: str, target: Path) -> str:
    """The refusal of an existing dataset, saying when it is no complete handsim export."""
    message = (
        f"Minari dataset {dataset_id!r} exists already ({target}): choose another id or version, or "
        "replace it with --overwrite (overwrite=True)"
    )
    from minari.dataset.minari_storage import MinariStorage  # lazy: optional extra handsim[minari]

    try:
        metadata = MinariStorage.read_raw_metadata(target / "data")
    except (ValueError, OSError):
        return message + "; it holds no Minari metadata (data/metadata.json): not a complete dataset"
    if "handsim" not in metadata:
        message += (
            "; it has no metadata['handsim']: not written by handsim's export, or left unfinished by an "
            "export that wrote into place"
        )
    return message


def _sync_tree(folder: Path) -> None:
    """``fsync`` every file and folder below ``folder`` (the data is on disk before it is moved in place)."""
    for path, _, files in os.walk(folder):
        for name in files:
            fd = os.open(os.path.join(path, name), os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        with contextlib.suppress(OSError):  # folders cannot be opened for fsync everywhere (Windows)
            fd = os.open(path, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)


def _remove_empty_parents(root: Path, dataset_id: str) -> None:
    """Remove the work folders of ``dataset_id``'s entries that are empty, up to the work folder itself."""
    work = root / WORK_FOLDER
    folder = _entry(root, dataset_id, LOCK).parent
    while folder == work or work in folder.parents:
        try:
            folder.rmdir()
        except OSError:  # not empty (other ids' entries), or removed by another export meanwhile
            return
        folder = folder.parent
