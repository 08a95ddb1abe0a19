"""A kind of trial: which files make it, how to find, load and discover it (one module per kind)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from handsim.trials.base import LoadedTrial, Trial
from handsim.trials.options import TrialOptions
from handsim.trials.sorting import Sorting

if TYPE_CHECKING:  # an annotation only: the trial registry loads without MuJoCo (start-up time)
    from handsim.datatypes.trajectory import Trajectory
    from handsim.sim.specs import MetricSpec


@dataclass(frozen=True)
class TrialKind:
    """One kind of trial: which files make it, how to find its inputs, load it and discover it in a dataset.

    Attributes:
        name: The kind's name (:attr:`Trial.kind`).
        label: The kind for people, with an article (``"a GraspDB14 recording"``).
        files: The files that make a trial of this kind (listed in messages and ``--help``).
        options: The :class:`~handsim.trials.options.TrialOptions` fields it takes, of those each kind
            chooses (:attr:`~handsim.trials.options.OptionSpec.per_kind`); the others given are refused
            before ``find`` runs, in a message naming them by their label.
        brings: Why it takes no other options (the end of a refusal message).
        matches: True when a path (which exists) is a trial of this kind, judged by its name; may raise
            :class:`~handsim.trials.base.UnsupportedTrialError` for a file of the kind's dataset that is
            not a recording.
        find: The trial of a path, given the options (only those in ``options`` are set).
        load: Read and build a :class:`Trial` of this kind: ``load(trial, metrics, progress)``.
        sort_files: Dataset discovery: claim the files of this kind's layout
            (:class:`~handsim.trials.sorting.Sorting`) as trials, companions or unknown files.
        bulk_folder: Discovery: what a folder listed whole (not searched) is, or None.
        explain_unknown: Discovery: why a file no kind claimed, whose name looks like this kind's, is not
            a trial (or None to leave the general reason).
        read: Glove kinds: the recording as a trial of this kind replays it (joint targets of its hand,
            checked, with its annotated phases), without building a scene: what its grasp episodes are
            found in. None: the kind's recordings are not segmented into grasp episodes.
    """

    name: str
    label: str
    files: str
    options: frozenset[str]
    brings: str
    matches: Callable[[Path], bool]
    find: Callable[[Path, TrialOptions], Trial]
    load: Callable[[Trial, MetricSpec | None, bool], LoadedTrial]
    sort_files: Callable[[Sorting], None]
    bulk_folder: Callable[[Path, str], str | None] | None = None
    explain_unknown: Callable[[PurePosixPath], str | None] | None = None
    read: Callable[[Trial], Trajectory] | None = None
