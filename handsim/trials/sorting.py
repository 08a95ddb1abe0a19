"""What discovery sorts a dataset's files into: trials with their inputs, companion and unknown files.

The records :func:`handsim.trials.discover` returns (:class:`TrialEntry`, :class:`CompanionFile`,
:class:`UnknownFile`) and :class:`Sorting`, the state each kind's discovery pass fills in
(:attr:`handsim.trials.kind.TrialKind.sort_files`), with the helpers the kinds build entries with.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

from handsim.trials.base import Trial
from handsim.trials.options import TrialOptions

INPUT_ROLES = ("trajectory", "skeleton", "object", "annotation", "calibration", "models_info")
"""Roles of a trial's input files."""


@dataclass(frozen=True)
class TrialInput:
    """A file a trial reads.

    Attributes:
        role: One of :data:`INPUT_ROLES`.
        path: Dataset-relative POSIX path.
        file: The path to read it from.
    """

    role: str
    path: str
    file: str


@dataclass(frozen=True)
class TrialEntry:
    """One trial of a dataset (picklable: a worker process or Ray task gets it whole).

    Attributes:
        id: Dataset-relative POSIX path of the recording (a Tzionas sequence: its ``Models/NN`` folder; a
            glove recording's grasp episode: the path, ``#`` and the episode's number).
        trial: What :func:`handsim.trials.load_trial` takes.
        meta: Group-by fields: ``object``, ``grasp``, ``grasp_id``, ``action``, ``scenario``, ``actor``,
            ``sequence`` (None where not applicable), and kind-specific extras.
        inputs: The files the trial reads.
    """

    id: str
    trial: Trial
    meta: dict
    inputs: tuple[TrialInput, ...] = ()

    @property
    def kind(self) -> str:
        """The trial's kind (``graspdb``, ``tzionas``, ``arctic`` …)."""
        return self.trial.kind


@dataclass(frozen=True)
class CompanionFile:
    """A file (or a whole folder, path ending in ``/``) of a known layout that is not replayed.

    Attributes:
        path: Dataset-relative POSIX path.
        reason: What it is and why it is not a trial.
    """

    path: str
    reason: str


@dataclass(frozen=True)
class UnknownFile:
    """A file that is neither part of a trial nor a known companion file.

    Attributes:
        path: Dataset-relative POSIX path.
        reason: Why it is not a trial.
    """

    path: str
    reason: str


@dataclass
class Sorting:
    """Where each file of a walk went: what the kinds' discovery passes fill in.

    Attributes:
        base: The folder the file paths are relative to.
        files: Every file of the walk (dataset-relative POSIX paths, sorted).
        entries: Trials found so far.
        companions: Companion files so far, path → reason.
        unknown: Unknown files so far, path → reason.
        claimed: Files that are inputs of a trial.
        options: The user's options the kinds' trials take (e.g. ARCTIC's MANO folder); their ``find`` is
            not run on them, so nothing is checked here: a trial that cannot load fails when it runs.
    """

    base: Path
    files: list[str]
    entries: list[TrialEntry] = field(default_factory=list)
    companions: dict[str, str] = field(default_factory=dict)
    unknown: dict[str, str] = field(default_factory=dict)
    claimed: set[str] = field(default_factory=set)
    options: TrialOptions = field(default_factory=TrialOptions)

    def open_files(self) -> list[str]:
        """Files not yet sorted."""
        done = self.claimed | self.companions.keys() | self.unknown.keys()
        return [f for f in self.files if f not in done]

    def add(self, entry: TrialEntry) -> None:
        """Add a trial and claim its inputs."""
        self.entries.append(entry)
        self.claimed.update(i.path for i in entry.inputs)


def relative(path: str | Path, base: Path) -> str:
    """``path`` relative to ``base`` as a POSIX path."""
    return PurePosixPath(Path(os.path.relpath(path, base))).as_posix()


def trial_input(role: str, path: str | Path, base: Path) -> TrialInput:
    """A trial's input file ``path`` in the role ``role``, with its path relative to ``base``."""
    return TrialInput(role=role, path=relative(path, base), file=str(path))


def group_fields(**fields) -> dict:
    """Group-by fields: the seven every record has (None by default), then the extras given."""
    meta = dict.fromkeys(("object", "grasp", "grasp_id", "action", "scenario", "actor", "sequence"))
    meta.update(fields)
    return meta
