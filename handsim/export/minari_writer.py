"""Writing a Minari dataset of replayed episodes: the dataset's spaces, description and metadata.

:class:`MinariWriter` creates the dataset with the first episode and appends the others, checking that
they share its layout; :meth:`MinariWriter.finish` writes handsim's metadata (``docs/minari.md``).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
from gymnasium import spaces

from handsim.export.episode import ENV_ID, INFO_DOCS, RESET_SEED, EpisodeLayout, ReplayedEpisode
from handsim.export.errors import LayoutMismatchError
from handsim.export.staging import minari_datasets_path
from handsim.version import __version__

if TYPE_CHECKING:
    import minari

EXPORT_FORMAT = 1
"""Version of the layout this module writes (``metadata["handsim"]["format"]``)."""
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


class MinariWriter:
    """Creates the dataset with the first episode and appends the others, checking they share its layout.

    Args:
        minari: The ``minari`` module (:func:`~handsim.export.minari_dataset.require_minari`).
        dataset_id: The Minari id.
        author: Dataset author(s), or None.
        author_email: Their contact, or None.
        code_permalink: Link to the code that made the data, or None.
        datasets_root: The Minari datasets folder the dataset is created in (the export's staging folder,
            :class:`~handsim.export.staging.DatasetStage`, not the user's: it is moved there when complete).

    Attributes:
        dataset: The dataset, once the first episode is added.
    """

    def __init__(
        self,
        minari: Any,
        dataset_id: str,
        author: str | None,
        author_email: str | None,
        code_permalink: str | None,
        datasets_root: Path,
    ) -> None:
        self._minari = minari
        self._id = dataset_id
        self._root = datasets_root
        self._author, self._email, self._permalink = author, author_email, code_permalink
        self.dataset: minari.MinariDataset | None = None
        self._first: ReplayedEpisode | None = None
        self._exported: list[str] = []

    def add(self, episode: ReplayedEpisode, record: dict) -> None:
        """Add ``episode`` (the dataset is created with the first) with its metadata.

        Raises:
            LayoutMismatchError: Its observation layout, hand or control rate differs from the first's.
        """
        from minari.data_collector import EpisodeBuffer  # lazy: optional extra handsim[minari]

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
            with minari_datasets_path(self._root):
                self.dataset = self._create(episode, buffer)
        else:
            check_layouts([(self._first.trial_id, self._first.layout), (episode.trial_id, episode.layout)])
            self.dataset.update_dataset_from_buffer([buffer])
        index = len(self._exported)
        self.dataset.storage.update_episode_metadata([episode.metadata], [index])
        self._exported.append(episode.trial_id)

    def _create(self, episode: ReplayedEpisode, buffer: Any) -> minari.MinariDataset:
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
                requirements=[f"handsim=={__version__}", f"mujoco=={mujoco.__version__}"],
            )

    def finish(self, source: dict, skipped: list[dict], comparison: dict) -> None:
        """Write handsim's dataset metadata: the source records, the layout, the skipped trials.

        Args:
            source: Where the records came from (file, SHA-256, dataset root, read notes).
            skipped: ``{"id", "status", "reason"}`` per trial not exported.
            comparison: The tolerances of the summary comparison.
        """
        layout = self._first.layout
        self.dataset.storage.update_metadata(
            {
                "handsim": {
                    "format": EXPORT_FORMAT,
                    "handsim_version": __version__,
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


def check_layouts(layouts: Sequence[tuple[str, EpisodeLayout]]) -> None:
    """Check that trials share one layout (a Minari dataset has one observation and one action space).

    Args:
        layouts: ``(trial id, layout)`` of every trial, in export order; the first begins the dataset.

    Raises:
        LayoutMismatchError: Some differ: names the first that does not fit the first trial and what
            differs, and (for more than two trials) how many trials have each layout.
    """
    if not layouts:
        return
    first_id, first = layouts[0]
    groups: dict[EpisodeLayout, list[str]] = {}
    for trial_id, layout in layouts:
        groups.setdefault(layout, []).append(trial_id)
    if len(groups) == 1:
        return
    other_id, other = next((t, lay) for t, lay in layouts if lay != first)
    message = (
        f"trial {other_id!r} does not fit the dataset begun with trial {first_id!r}: "
        f"{'; '.join(first.differences(other))}."
    )
    if len(layouts) > 2:
        kinds = ", ".join(
            f"{len(ids)} like {ids[0]!r} ({len(layout.dof_names)} DoFs, {len(layout.observation_names)} "
            "observations)"
            for layout, ids in groups.items()
        )
        message += f" The {len(layouts)} trials have {len(groups)} layouts: {kinds}."
    raise LayoutMismatchError(
        f"{message} A Minari dataset has one observation and action space: export such trials as separate "
        "datasets (--only)"
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
