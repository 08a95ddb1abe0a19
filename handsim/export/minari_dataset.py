"""A dataset run's replayed trials as a Minari dataset (``handsim export minari``; extra ``handsim[minari]``).

Every selected record of ``OUT/records.jsonl`` is replayed again through ``handsim/Replay-v0`` with zero
residuals and checked against the record (:func:`handsim.export.episode.replay_record`); each becomes one
episode. The dataset is written under Minari's datasets folder (``MINARI_DATASETS_PATH``, default
``~/.minari/datasets``) and loads with ``minari.load_dataset(dataset_id)``. See ``docs/minari.md`` for the
layout.

The environment cannot be recreated from an id alone (its scene is built from the trial's files), so the
dataset has no ``env_spec``: :func:`recover_replay_env` rebuilds an episode's environment from the trial
stored in the episode's metadata.
"""

from __future__ import annotations

import fnmatch
import json
import math
import multiprocessing
import shutil
import warnings
from collections.abc import Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from handsim.errors import InputFileError
from handsim.export.episode import (
    ENV_ID,
    INFO_DOCS,
    RESET_SEED,
    ReplayedEpisode,
    replay_config,
    replay_record,
)
from handsim.export.errors import (
    DatasetExistsError,
    ExportError,
    LayoutMismatchError,
    MissingExtraError,
    RecordMismatchError,
)
from handsim.runner.trial_record import sha256_file

if TYPE_CHECKING:
    import minari

    from handsim.envs.replay_env import ReplayEnv

EXPORT_FORMAT = 1
"""Version of the layout this module writes (``metadata["handsim"]["format"]``)."""
INSTALL_HINT = "pip install 'handsim[minari]'"
ALGORITHM = "recorded human hand motion replayed in MuJoCo (handsim, zero residual on the recorded targets)"
ACTION_DOC = (
    "absolute joint position targets the hand's actuators held during the step (MuJoCo data.ctrl, rad, "
    "actuator order = action_names): the recorded targets of the frame the step drives to, clipped to "
    "the actuators' control ranges. These are NOT the actions of handsim/Replay-v0, which are residuals "
    "in [-1, 1] added to these targets (all zero here)."
)
EPISODE_METADATA_DOCS = {
    "trial_id": "the record's trial id",
    "status": "the record's status (ok, or diverged with include_failed)",
    "kind": "kind of trial (tzionas, graspdb)",
    "trial": "JSON of handsim.trials.Trial.to_dict(): the files to load (Trial.from_dict gives it back)",
    "inputs": "JSON of the record's input files with their SHA-256 (checked before export)",
    "parameters": "JSON of the run's replay parameters (ReplayConfig.to_dict())",
    "model_sha256": "hash of the compiled scene (checked against the record)",
    "scenario": "recorded (objects follow their recording) or glove (object placed, released, held)",
    "hand": "the hand model",
    "objects": "JSON list of the object names",
    "meta/...": "the record's meta fields (object, grasp, actor ...)",
    "summary/...": "the record's per-trial plausibility numbers (held, max_slip_mm, mean_drift_mm, "
    "max_penetration_mm ...; checked against the new replay)",
    "hold/...": "glove scenario: the record's hold outcome",
    "warnings": "number of MuJoCo warnings in the replay",
    "warning_messages": "JSON list of the first warnings",
    "diverged_at": "the divergence that ended the episode (diverged trials only)",
}
_NONE_WARNINGS = (
    r"`code_permalink` is set to None",
    r"`author` is set to None",
    r"`author_email` is set to None",
    r"`eval_env` is set to None",
    r"env_spec is None",
)
"""Minari's warnings about fields this export leaves out on purpose (no env spec; no invented links)."""


def require_minari() -> Any:
    """Import ``minari`` and its HDF5 storage, or say how to install them.

    Raises:
        MissingExtraError: ``minari`` or ``h5py`` is not installed.
    """
    try:
        import minari
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
    from minari.dataset.minari_dataset import parse_dataset_id

    try:
        _, _, version = parse_dataset_id(dataset_id)
    except (ValueError, TypeError):
        version = None
    if version is None:
        raise ExportError(
            f"dataset id {dataset_id!r} is not a Minari id with a version: use 'namespace/name-v0' (letters, "
            "digits, '-' and '_'; e.g. 'handsim/tzionas-replay-v0')"
        )


def read_run_records(out_dir: str | Path) -> tuple[Path, list[dict], tuple[str, ...], str | None]:
    """A run's records sorted by trial id, with the notes on what reading ignored and the dataset root.

    Args:
        out_dir: The folder ``handsim report DATASET -o OUT`` wrote.

    Returns:
        The records file, its records (one per id, sorted by id), the reader's notes (a truncated last
        line …), and the dataset folder the records' input paths are relative to (``run.json``), or None.

    Raises:
        InputFileError: There is no ``records.jsonl`` in ``out_dir``.
        ExportError: It holds no record.
        RecordsError: A line is not a record of this handsim's schema.
    """
    from handsim.runner.records import RECORDS_FILE, load_records, read_run_info

    path = Path(out_dir) / RECORDS_FILE
    if not path.is_file():
        raise InputFileError(
            f"{path} does not exist: export the folder a dataset run wrote (handsim report DATASET -o OUT)"
        )
    read = load_records(out_dir)
    if not read.records:
        raise ExportError(f"{path} holds no record: nothing to export")
    info = read_run_info(out_dir) or {}
    root = info.get("dataset") if isinstance(info.get("dataset"), str) else None
    return path, sorted(read.records, key=lambda r: r["id"]), read.notes, root


def select_records(
    records: Sequence[dict], only: str | Sequence[str] | None, include_failed: bool
) -> tuple[list[dict], list[dict]]:
    """Split records into those to export and those skipped (with the reason).

    Args:
        records: A run's records (one per trial id).
        only: Shell patterns (``fnmatch``) on the trial id; None: every trial.
        include_failed: Export diverged trials too (their episode ends at the divergence).

    Returns:
        The records to export, and ``{"id", "status", "reason"}`` for each record skipped.

    Raises:
        ExportError: ``only`` matches no trial id.
    """
    patterns = [only] if isinstance(only, str) else list(only or ())
    chosen = [r for r in records if not patterns or any(fnmatch.fnmatchcase(r["id"], p) for p in patterns)]
    if not chosen:
        ids = [r["id"] for r in records]
        raise ExportError(
            f"--only {' '.join(patterns)} matches none of the {len(ids)} trial ids; they are: "
            f"{', '.join(ids[:10])}{' …' if len(ids) > 10 else ''}"
        )
    export, skipped = [], []
    for record in chosen:
        status = record["status"]
        if status == "ok" or (status == "diverged" and include_failed):
            export.append(record)
        elif status == "diverged":
            skipped.append(_skip(record, "diverged (export it with --include-failed)"))
        else:
            error = record.get("error") or {}
            message = error.get("message") if isinstance(error, dict) else str(error)
            skipped.append(_skip(record, f"error: {message or 'no message'}; there is no replay to export"))
    return export, skipped


def _skip(record: dict, reason: str) -> dict:
    return {"id": record["id"], "status": record["status"], "reason": reason}


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
) -> minari.MinariDataset:
    """Write the replayed trials of a dataset run as a Minari dataset.

    Each exported trial is one episode, in the order of the trial ids: its observations are the
    environment's (``metadata["handsim"]["observation_names"]``), its actions the absolute joint targets
    applied (not the environment's residuals), its rewards and ``infos`` the environment's, its episode
    metadata the trial and the record's plausibility numbers. Nothing is written unless every exported
    trial reproduces its record (the partial dataset is removed, a replaced one restored).

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
        progress: Show a progress bar.

    Returns:
        The dataset (also loadable with ``minari.load_dataset(dataset_id)``); its
        ``storage.metadata["handsim"]`` lists the exported and the skipped trials.

    Raises:
        MissingExtraError: minari (or h5py) is not installed.
        ExportError: Malformed id, no records selected or nothing left to export, a record without what an
            episode needs.
        DatasetExistsError: The dataset exists and ``overwrite`` is False.
        RecordMismatchError: A trial no longer reproduces its record (and ``skip_mismatched`` is False).
        LayoutMismatchError: Trials with different observation layouts, hands or control rates.
        InputFileError: ``out_dir`` has no ``records.jsonl``.
        RecordsError: A line of it is not a record of this handsim's schema.
    """
    minari = require_minari()
    from minari.storage.datasets_root_dir import get_dataset_path

    check_dataset_id(dataset_id)
    if workers < 1:
        raise ExportError(f"workers must be ≥ 1, got {workers}")
    if not (rtol >= 0 and atol >= 0 and math.isfinite(rtol) and math.isfinite(atol)):
        raise ExportError(f"rtol and atol must be finite numbers ≥ 0, got rtol={rtol}, atol={atol}")
    records_path, records, notes, root = read_run_records(out_dir)
    todo, skipped = select_records(records, only, include_failed)
    if not todo:
        reasons = "; ".join(f"{s['id']}: {s['reason']}" for s in skipped[:5])
        raise ExportError(f"no trial to export: {len(skipped)} skipped ({reasons})")
    path = Path(get_dataset_path(dataset_id))
    if path.exists() and not overwrite:
        raise DatasetExistsError(
            f"Minari dataset {dataset_id!r} exists already ({path}): choose another id or version, or "
            "replace it with --overwrite (overwrite=True)"
        )
    backup = path.with_name(f".{path.name}.replaced") if path.exists() else None
    if backup is not None:
        shutil.rmtree(backup, ignore_errors=True)
        path.rename(backup)
    writer = _Writer(minari, dataset_id, author, author_email, code_permalink)
    outcomes = _episodes(todo, root, workers, rtol, atol, progress)
    try:
        for record, outcome in zip(todo, outcomes, strict=True):
            if isinstance(outcome, ReplayedEpisode):
                writer.add(outcome, record)
            elif outcome[0] == "mismatch" and skip_mismatched:
                skipped.append(_skip(record, f"mismatch: {outcome[1]}"))
            else:
                raise (RecordMismatchError if outcome[0] == "mismatch" else ExportError)(outcome[1])
        if writer.dataset is None:
            reasons = "; ".join(f"{s['id']}: {s['reason']}" for s in skipped[:5])
            raise ExportError(f"no trial could be exported: {reasons}")
        writer.finish(
            {
                "records": str(records_path.resolve()),
                "records_sha256": sha256_file(records_path),
                "dataset_root": root,
                "read_notes": list(notes),
            },
            skipped,
            {"rtol": rtol, "atol": atol},
        )
    except BaseException:
        outcomes.close()
        shutil.rmtree(path, ignore_errors=True)
        if backup is not None:
            backup.rename(path)
        raise
    if backup is not None:
        shutil.rmtree(backup, ignore_errors=True)
    return writer.dataset


def _outcome(record: dict, root: str | None, rtol: float, atol: float) -> ReplayedEpisode | tuple[str, str]:
    """An episode, or ``("mismatch" | "error", message)`` (picklable, unlike some exceptions)."""
    try:
        return replay_record(record, root=root, rtol=rtol, atol=atol)
    except RecordMismatchError as exc:
        return ("mismatch", str(exc))
    except ExportError as exc:
        return ("error", str(exc))


def _episodes(
    records: list[dict], root: str | None, workers: int, rtol: float, atol: float, progress: bool
) -> Iterator[ReplayedEpisode | tuple[str, str]]:
    """The records' outcomes in their order, made here or in ``workers`` spawned processes."""
    from tqdm import tqdm

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


class _Writer:
    """Creates the dataset with the first episode and appends the others, checking they share its layout."""

    def __init__(
        self,
        minari: Any,
        dataset_id: str,
        author: str | None,
        author_email: str | None,
        code_permalink: str | None,
    ) -> None:
        self._minari = minari
        self._id = dataset_id
        self._author, self._email, self._permalink = author, author_email, code_permalink
        self.dataset: minari.MinariDataset | None = None
        self._first: ReplayedEpisode | None = None
        self._exported: list[str] = []

    def add(self, episode: ReplayedEpisode, record: dict) -> None:
        from minari.data_collector import EpisodeBuffer

        buffer = EpisodeBuffer(
            seed=RESET_SEED,
            observations=episode.observations,
            actions=episode.actions,
            rewards=episode.rewards,
            terminations=episode.terminations,
            truncations=episode.truncations,
            infos=episode.infos,
        )
        if self._first is None:
            self._first = episode
            self.dataset = self._create(episode, buffer)
        else:
            differences = self._first.layout.differences(episode.layout)
            if differences:
                raise LayoutMismatchError(
                    f"trial {episode.trial_id!r} does not fit the dataset begun with trial "
                    f"{self._first.trial_id!r}: {'; '.join(differences)}. A Minari dataset has one "
                    "observation and action space: export such trials as separate datasets (--only)"
                )
            self.dataset.update_dataset_from_buffer([buffer])
        index = len(self._exported)
        self.dataset.storage.update_episode_metadata([episode.metadata], [index])
        self._exported.append(episode.trial_id)

    def _create(self, episode: ReplayedEpisode, buffer: Any) -> minari.MinariDataset:
        import mujoco
        from gymnasium import spaces

        import handsim

        layout = episode.layout
        ranges = np.asarray(layout.ctrl_range, dtype=np.float64)
        with warnings.catch_warnings():
            for message in _NONE_WARNINGS:
                warnings.filterwarnings("ignore", message=message, category=UserWarning)
            return self._minari.create_dataset_from_buffers(
                dataset_id=self._id,
                buffer=[buffer],
                env=None,
                eval_env=None,
                algorithm_name=ALGORITHM,
                author=self._author,
                author_email=self._email,
                code_permalink=self._permalink,
                observation_space=spaces.Box(-np.inf, np.inf, (len(layout.observation_names),), np.float64),
                action_space=spaces.Box(ranges[:, 0], ranges[:, 1], dtype=np.float64),
                description=describe(layout),
                requirements=[f"handsim=={handsim.__version__}", f"mujoco=={mujoco.__version__}"],
            )

    def finish(self, source: dict, skipped: list[dict], comparison: dict) -> None:
        import mujoco

        import handsim

        layout = self._first.layout
        self.dataset.storage.update_metadata(
            {
                "handsim": {
                    "format": EXPORT_FORMAT,
                    "handsim_version": handsim.__version__,
                    "mujoco_version": mujoco.__version__,
                    "source": source,
                    "env": {
                        "id": ENV_ID,
                        "kwargs": "per episode: control_rate and release_delay from its 'parameters'; "
                        "max_object_drift=None (the whole recording, as the run replayed it); zero "
                        "residual actions",
                        "recover": "handsim.export.recover_replay_env(dataset, episode_index)",
                    },
                    "dt": layout.dt,
                    "observation_names": list(layout.observation_names),
                    "observation_slices": {g: [a, b] for g, a, b in layout.observation_slices},
                    "action": ACTION_DOC,
                    "action_names": list(layout.dof_names),
                    "action_ctrl_range": [list(r) for r in layout.ctrl_range],
                    "link_names": list(layout.link_names),
                    "infos": dict(INFO_DOCS),
                    "episode_metadata": dict(EPISODE_METADATA_DOCS),
                    "exported": list(self._exported),
                    "skipped": skipped,
                    "summary_comparison": comparison,
                }
            }
        )


def describe(layout: Any) -> str:
    """The dataset's description: what an episode is and the layout of observations, actions and infos."""
    groups = ", ".join(f"{g} [{a}:{b}]" for g, a, b in layout.observation_slices)
    return (
        "Captured human hand motion replayed in MuJoCo by handsim: each episode is one trial of a dataset "
        f"run, stepped through {ENV_ID} with zero residuals (the recorded joint targets; {layout.dt:g} s "
        "per step) and checked against the run's record.\n"
        f"Observations ({len(layout.observation_names)} float64, the environment's): {groups}; every "
        "element is named in metadata['handsim']['observation_names'].\n"
        f"Actions ({len(layout.dof_names)} float64): {ACTION_DOC}\n"
        "Rewards, terminations (divergence) and truncations (last frame) are the environment's. Infos have "
        "one row per observation (row 0: the reset state): " + ", ".join(INFO_DOCS) + ".\n"
        "Episode metadata: trial_id, the trial's files (trial), and the run's plausibility numbers "
        "(summary/..., e.g. held, max_slip_mm, mean_drift_mm, max_penetration_mm)."
    )


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
    from handsim.envs.replay_env import ReplayEnv
    from handsim.trials import Trial, load_trial

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
