"""A dataset run's replayed trials as a Minari dataset (``handsim export minari``; extra ``handsim[minari]``).

Every selected record of ``OUT/records.jsonl`` is replayed again through ``handsim/Replay-v0`` with zero
residuals and checked against the record (:func:`handsim.export.episode.replay_record`); each becomes one
episode. The dataset is written under Minari's datasets folder (``MINARI_DATASETS_PATH``, default
``~/.minari/datasets``) and loads with ``minari.load_dataset(dataset_id)``. See ``docs/minari.md`` for the
layout. It is built aside and moved into place when complete (:mod:`handsim.export.staging`), so a killed
export leaves no part of a dataset and an interrupted ``--overwrite`` keeps the dataset it would replace.

An episode's observations are the environment's (``metadata["handsim"]["observation_names"]``), its
actions the absolute joint targets applied (not the environment's residuals), its rewards and ``infos``
the environment's, its episode metadata the trial and the record's plausibility numbers.

The environment cannot be recreated from an id alone (its scene is built from the trial's files), so the
dataset has no ``env_spec``: :func:`recover_replay_env` rebuilds an episode's environment from the trial
stored in the episode's metadata.
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from handsim.envs.replay_env import ReplayEnv
from handsim.export.episode import EpisodeLayout, ReplayedEpisode
from handsim.export.episode_replays import EpisodeReplays, Outcome
from handsim.export.errors import ExportError, MissingExtraError, RecordMismatchError
from handsim.export.minari_writer import MinariWriter, check_layouts
from handsim.export.record_checks import replay_config
from handsim.export.run_records import read_run_records, select_records, skip_entry
from handsim.export.staging import DatasetStage
from handsim.runner.trial_record import sha256_file
from handsim.trials import Trial, load_trial

if TYPE_CHECKING:
    import minari

INSTALL_HINT = "pip install 'handsim[minari]'"


def require_minari() -> Any:
    """Import ``minari`` and its HDF5 storage, or say how to install them.

    Raises:
        MissingExtraError: ``minari`` or ``h5py`` is not installed.
    """
    try:
        import minari  # lazy: optional extra handsim[minari]
    except ImportError as exc:
        raise MissingExtraError(f"the Minari export needs the minari package: {INSTALL_HINT}") from exc
    try:
        import h5py  # noqa: F401  (minari's default storage)
    except ImportError as exc:
        raise MissingExtraError(
            f"the Minari export writes Minari's HDF5 storage, which needs h5py: {INSTALL_HINT} "
            "(or pip install 'minari[hdf5]')"
        ) from exc
    return minari


def check_dataset_id(dataset_id: str) -> None:
    """Check that ``dataset_id`` is a Minari id with a version, ``namespace/name-v0``.

    Raises:
        ExportError: It is not.
    """
    from minari.dataset.minari_dataset import parse_dataset_id  # lazy: optional extra handsim[minari]

    try:
        _, _, version = parse_dataset_id(dataset_id)
    except (ValueError, TypeError):
        version = None
    if version is None:
        raise ExportError(
            f"dataset id {dataset_id!r} is not a Minari id with a version: use 'namespace/name-v0' (letters, "
            "digits, '-' and '_'; e.g. 'handsim/tzionas-replay-v0')"
        )


def export_minari(
    out_dir: str | Path,
    dataset_id: str,
    *,
    only: str | Sequence[str] | None = None,
    include_failed: bool = False,
    skip_mismatched: bool = False,
    overwrite: bool = False,
    workers: int = 1,
    rtol: float = 1e-6,
    atol: float = 1e-9,
    author: str | None = None,
    author_email: str | None = None,
    code_permalink: str | None = None,
    progress: bool = False,
    on_note: Callable[[str], None] | None = None,
    command: Sequence[str] | None = None,
) -> minari.MinariDataset:
    """Write the replayed trials of a dataset run as a Minari dataset, one episode per trial.

    Episodes are in the order of the trial ids and hold what this module's docstring lists. Nothing is
    written unless every exported trial reproduces its record, and every trial is loaded and its layout
    compared before any is replayed (when more than one is selected). One export per dataset id runs at a
    time.

    Args:
        out_dir: The folder ``handsim report DATASET -o OUT`` wrote (with ``records.jsonl``).
        dataset_id: The Minari id, ``namespace/name-vN`` (e.g. ``handsim/tzionas-v0``).
        only: Shell patterns on the trial ids to export (default: all).
        include_failed: Export diverged trials too (their episode terminates at the divergence). Trials
            that failed with an error are never exported (nothing was replayed).
        skip_mismatched: Skip (and list) trials whose replay no longer matches their record instead of
            refusing the whole export.
        overwrite: Replace an existing dataset of that id.
        workers: Processes replaying trials (1: in this process).
        rtol: Relative tolerance of the summary comparison with the records.
        atol: Absolute tolerance of that comparison, in each number's unit (mm, deg, N …).
        author: Dataset author(s) for Minari's metadata (left out when None).
        author_email: Their contact (left out when None).
        code_permalink: Link to the code that made the data (left out when None; no link is invented).
        progress: Show progress bars.
        on_note: Called with each note on what the export found and put right (a killed export's
            leftovers, a stale lock); default: a ``UserWarning``.
        command: The command line naming this export in its lock (default ``sys.argv``).

    Returns:
        The dataset (also loadable with ``minari.load_dataset(dataset_id)``); its
        ``storage.metadata["handsim"]`` lists the exported and the skipped trials.

    Raises:
        MissingExtraError: minari (or h5py) is not installed.
        ExportError: Malformed id, no records selected or nothing left to export, a record without what an
            episode needs.
        DatasetExistsError: The dataset exists and ``overwrite`` is False.
        OutputBusyError: Another export of this dataset id runs (the message names it).
        RecordMismatchError: A trial no longer reproduces its record (and ``skip_mismatched`` is False).
        LayoutMismatchError: Trials with different observation layouts, hands or control rates.
        InputFileError: ``out_dir`` has no ``records.jsonl``.
        RecordsError: A line of it is not a record of this handsim's schema.
    """
    minari = require_minari()
    _check_arguments(dataset_id, workers, rtol, atol)
    records_path, notes, root, todo, skipped = _selected(out_dir, only, include_failed)
    stage = DatasetStage(
        _datasets_folder(), dataset_id, overwrite=overwrite, on_note=on_note or _warn, command=command
    )
    with stage, EpisodeReplays(root, min(workers, len(todo)), rtol, atol, progress) as replays:
        if len(todo) > 1:  # every trial loaded and checked before any is replayed
            todo = _fitting(todo, replays.layouts(todo), skipped, skip_mismatched)
        writer = MinariWriter(minari, dataset_id, author, author_email, code_permalink, stage.build_root)
        _write_episodes(writer, todo, replays.episodes(todo), skipped, skip_mismatched)
        writer.finish(_source(records_path, root, notes), skipped, {"rtol": rtol, "atol": atol})
        stage.commit(lambda: _register_namespace(dataset_id))
    return minari.load_dataset(dataset_id)


def _check_arguments(dataset_id: str, workers: int, rtol: float, atol: float) -> None:
    """Refuse a malformed dataset id, no workers, or tolerances that are not finite numbers ≥ 0.

    Raises:
        ExportError: Any of these, naming the value.
    """
    check_dataset_id(dataset_id)
    if workers < 1:
        raise ExportError(f"workers must be ≥ 1, got {workers}")
    if not (rtol >= 0 and atol >= 0 and math.isfinite(rtol) and math.isfinite(atol)):
        raise ExportError(f"rtol and atol must be finite numbers ≥ 0, got rtol={rtol}, atol={atol}")


def _selected(
    out_dir: str | Path, only: str | Sequence[str] | None, include_failed: bool
) -> tuple[Path, tuple[str, ...], str | None, list[dict], list[dict]]:
    """The run's records file, its read notes and dataset root, and the records to export and to skip.

    Raises:
        ExportError: No record is left to export (the message names the first skipped and why).
    """
    records_path, records, notes, root = read_run_records(out_dir)
    todo, skipped = select_records(records, only, include_failed)
    if not todo:
        reasons = "; ".join(f"{s['id']}: {s['reason']}" for s in skipped[:5])
        raise ExportError(f"no trial to export: {len(skipped)} skipped ({reasons})")
    return records_path, notes, root, todo, skipped


def _datasets_folder() -> Path:
    """Minari's datasets folder (``MINARI_DATASETS_PATH``, default ``~/.minari/datasets``)."""
    from minari.storage.datasets_root_dir import get_dataset_path  # lazy: optional extra handsim[minari]

    return Path(get_dataset_path())


def _write_episodes(
    writer: MinariWriter,
    todo: list[dict],
    outcomes: Iterable[ReplayedEpisode | Outcome],
    skipped: list[dict],
    skip_mismatched: bool,
) -> None:
    """Add each record's replayed episode to the dataset, skipping or refusing those that do not reproduce.

    Raises:
        RecordMismatchError: A trial no longer reproduces its record (unless ``skip_mismatched``).
        ExportError: A record without what an episode needs, or no episode was written at all.
    """
    for record, outcome in zip(todo, outcomes, strict=True):
        if isinstance(outcome, ReplayedEpisode):
            writer.add(outcome, record)
        else:
            _skip_or_refuse(record, outcome, skipped, skip_mismatched)
    if writer.dataset is None:
        reasons = "; ".join(f"{s['id']}: {s['reason']}" for s in skipped[:5])
        raise ExportError(f"no trial could be exported: {reasons}")


def _source(records_path: Path, root: str | None, notes: tuple[str, ...]) -> dict:
    """Where the exported records came from, for the dataset's metadata."""
    return {
        "records": str(records_path.resolve()),
        "records_sha256": sha256_file(records_path),
        "dataset_root": root,
        "read_notes": list(notes),
    }


def _fitting(
    todo: list[dict],
    layouts: Iterable[EpisodeLayout | Outcome],
    skipped: list[dict],
    skip_mismatched: bool,
) -> list[dict]:
    """The records whose trial loads and checks, once every such trial is known to share one layout.

    Raises:
        LayoutMismatchError: Trials with different layouts (before anything is replayed).
        RecordMismatchError: A trial that no longer loads as recorded (unless ``skip_mismatched``).
        ExportError: A record without what an episode needs.
    """
    kept, found = [], []
    for record, layout in zip(todo, layouts, strict=True):
        if isinstance(layout, EpisodeLayout):
            kept.append(record)
            found.append((record["id"], layout))
        else:
            _skip_or_refuse(record, layout, skipped, skip_mismatched)
    check_layouts(found)
    return kept


def _skip_or_refuse(record: dict, outcome: Outcome, skipped: list[dict], skip_mismatched: bool) -> None:
    """Skip a record that no longer reproduces (``skip_mismatched``), or raise its error."""
    kind, message = outcome
    if kind == "mismatch" and skip_mismatched:
        skipped.append(skip_entry(record, f"mismatch: {message}"))
        return
    raise (RecordMismatchError if kind == "mismatch" else ExportError)(message)


def _register_namespace(dataset_id: str) -> None:
    """Create the dataset's Minari namespace where it is missing (just before the dataset moves in)."""
    # lazy: optional extra handsim[minari]
    from minari.dataset.minari_dataset import parse_dataset_id
    from minari.namespace import create_namespace, list_local_namespaces

    namespace = parse_dataset_id(dataset_id)[0]
    if namespace is None or namespace in list_local_namespaces():
        return
    try:
        create_namespace(namespace)
    except ValueError:  # created by another export meanwhile
        if namespace not in list_local_namespaces():
            raise


def _warn(note: str) -> None:
    warnings.warn(note, UserWarning, stacklevel=3)


def recover_replay_env(dataset: minari.MinariDataset, episode_index: int, **kwargs: Any) -> ReplayEnv:
    """Rebuild the ``handsim/Replay-v0`` environment an exported episode was stepped in.

    Args:
        dataset: A dataset :func:`export_minari` wrote.
        episode_index: Index of the episode in ``dataset``.
        **kwargs: Further :class:`~handsim.envs.replay_env.ReplayEnv` keywords (``render_mode`` …).

    Returns:
        The environment (its observations with zero residuals are the episode's).

    Raises:
        ExportError: The dataset was not written by :func:`export_minari`, or the index is out of range.
    """
    if "handsim" not in dataset.storage.metadata:
        raise ExportError("the dataset was not written by handsim's Minari export (no metadata['handsim'])")
    if not 0 <= episode_index < len(dataset):
        raise ExportError(f"episode_index must be in [0, {len(dataset) - 1}], got {episode_index}")
    index = int(dataset.episode_indices[episode_index])
    meta = next(iter(dataset.storage.get_episode_metadata([index])))
    config = replay_config({"id": meta["trial_id"], "parameters": {"replay": json.loads(meta["parameters"])}})
    loaded = load_trial(Trial.from_dict(json.loads(meta["trial"])), metrics=config.metrics)
    options = {
        "control_rate": config.control_rate,
        "release_delay": config.metrics.release_delay,
        "max_object_drift": None,
        **kwargs,
    }
    return ReplayEnv(loaded.scene, loaded.trajectory, **options)
