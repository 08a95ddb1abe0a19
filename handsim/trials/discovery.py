"""Discovery: a dataset folder (or one recording) as a sorted list of trials, every other file accounted for.

:func:`discover` walks the folder once (sorted; links to folders followed once) and sorts every file into
exactly one of three lists:

* **trials** (:class:`TrialEntry`): a recording handsim replays, with the files it reads (its inputs) and
  its group-by fields. Each kind of trial (:class:`~handsim.trials.base.TrialKind`) claims the files of its
  dataset layout in turn (:attr:`~handsim.trials.base.TrialKind.sort_files`);
* **companions** (:class:`CompanionFile`): files that belong to a dataset's layout but are not replayed,
  each with what it is (``.xmlskel``, Tzionas ``Calibration/``, GraspDB14's ``fk_oracle/``, ARCTIC's
  images …);
* **unknown** (:class:`UnknownFile`): everything else, with the reason it is not a trial (never silently
  skipped).

A trial's id is the dataset-relative POSIX path of its recording (``r_01_11_ex03-rad-004-grasp-su04.txt``,
``Models/20``): stable and unique, the key of a run's records.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from pathlib import Path, PurePosixPath

from handsim.errors import HandsimError, InputFileError
from handsim.trials.base import Trial, TrialKind, TrialOptions

INPUT_ROLES = ("trajectory", "skeleton", "object", "annotation", "calibration", "models_info")
"""Roles of a trial's input files."""
_DOCS = re.compile(
    r"(?:readme|license|licence|copying|notice)(?:\..*)?|.*\.(?:md|rst|pdf|html?)", re.IGNORECASE
)


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
        id: Dataset-relative POSIX path of the recording (a Tzionas sequence: its ``Models/NN`` folder).
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


@dataclass(frozen=True)
class Discovery:
    """The trials of a dataset and every other file in it.

    Attributes:
        root: The folder the ids and paths are relative to (absolute).
        entries: The trials, sorted by id.
        companions: Known files that are not replayed, sorted by path.
        unknown: Files of no known kind, sorted by path.
    """

    root: str
    entries: tuple[TrialEntry, ...]
    companions: tuple[CompanionFile, ...] = ()
    unknown: tuple[UnknownFile, ...] = ()

    def to_dict(self) -> dict:
        """JSON-ready overview of the dataset (``run.json``'s ``discovery``).

        Returns:
            ``root``, ``trials`` (count), ``kinds`` (count per kind), ``companion`` and ``unknown`` (lists
            of ``{"path", "reason"}``).
        """
        kinds: dict[str, int] = {}
        for entry in self.entries:
            kinds[entry.kind] = kinds.get(entry.kind, 0) + 1
        return {
            "root": self.root,
            "trials": len(self.entries),
            "kinds": dict(sorted(kinds.items())),
            "companion": [{"path": c.path, "reason": c.reason} for c in self.companions],
            "unknown": [{"path": u.path, "reason": u.reason} for u in self.unknown],
        }


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


def _walk(root: Path, base: Path, kinds: Sequence[TrialKind], companions: dict[str, str]) -> list[str]:
    """Every file under ``root`` as a path relative to ``base``.

    Links to folders are followed once (a folder reached again through a link is listed, not searched
    twice); hidden folders and the bulk folders of a layout are listed whole.
    """
    bulk = [k.bulk_folder for k in kinds if k.bulk_folder is not None]
    files: list[str] = []
    seen = {os.path.realpath(root)}
    for folder, dirs, names in os.walk(root, followlinks=True):
        here = Path(folder)
        kept = []
        for d in sorted(dirs):
            rel = (here / d).relative_to(base).as_posix() + "/"
            real = os.path.realpath(here / d)
            what = "hidden folder (not searched)" if d.startswith(".") else None
            what = what or next((w for w in (b(here, d) for b in bulk) if w), None)
            if what is None and real in seen:
                what = f"link to a folder searched already ({real})"
            if what is None:
                seen.add(real)
                kept.append(d)
            else:
                companions[rel] = what
        dirs[:] = kept
        files.extend((here / name).relative_to(base).as_posix() for name in sorted(names))
    return sorted(files)


def _is_trial_folder(folder: Path, kinds: Sequence[TrialKind]) -> bool:
    for kind in kinds:
        try:
            if kind.matches(folder):
                return True
        except HandsimError:
            continue
    return False


def _rest(sorting: Sorting, kinds: Sequence[TrialKind]) -> None:
    recordings = "; ".join(f"{k.name}: {k.files}" for k in kinds)
    explain = [k.explain_unknown for k in kinds if k.explain_unknown is not None]
    for f in sorting.open_files():
        p = PurePosixPath(f)
        if p.name.startswith("."):
            sorting.companions[f] = "hidden file (not read)"
        elif _DOCS.fullmatch(p.name):
            sorting.companions[f] = "documentation (not read)"
        else:
            what = f"file type {p.suffix!r}" if p.suffix else "a file without extension"
            reason = next((r for r in (e(p) for e in explain) if r), None)
            sorting.unknown[f] = reason or (
                f"{what}: no recording handsim replays ({recordings}) nor a known companion file"
            )


def discover_with(
    dataset: str | Path, kinds: Sequence[TrialKind], options: TrialOptions | None = None
) -> Discovery:
    """List the trials of a dataset folder, or the one trial of a recording, with the given kinds.

    Args:
        dataset: A dataset folder, a trial folder (a Tzionas ``Models/NN``) or a single recording.
        kinds: The kinds of trial, each claiming its layout's files in this order.
        options: Options the trials of a kind take (:attr:`Sorting.options`); default none.

    Returns:
        The trials (sorted by id) and every other file (companion or unknown, each with its reason).
        For a single recording or trial folder the ids are relative to its parent folder.

    Raises:
        InputFileError: ``dataset`` does not exist.
    """
    root = Path(dataset).resolve()
    if not root.exists():
        raise InputFileError(f"{dataset}: dataset not found (expected a folder or a recording)")
    single = root.is_file() or _is_trial_folder(root, kinds)
    base = root.parent if single else root
    companions: dict[str, str] = {}
    files = [root.relative_to(base).as_posix()] if root.is_file() else _walk(root, base, kinds, companions)
    sorting = Sorting(base=base, files=files, companions=companions, options=options or TrialOptions())
    for kind in kinds:
        kind.sort_files(sorting)
    _rest(sorting, kinds)
    return Discovery(
        root=str(base),
        entries=tuple(sorted(sorting.entries, key=lambda e: e.id)),
        companions=tuple(CompanionFile(p, r) for p, r in sorted(sorting.companions.items())),
        unknown=tuple(UnknownFile(p, r) for p, r in sorted(sorting.unknown.items())),
    )


def select(
    entries: tuple[TrialEntry, ...], only: str | None = None, limit: int | None = None
) -> tuple[TrialEntry, ...]:
    """The entries whose id matches a glob, at most ``limit`` of them (in id order).

    Args:
        entries: Trials, sorted by id.
        only: A shell-style pattern matched against the id (``fnmatch``; ``*`` also matches ``/``), or
            None for all.
        limit: Keep the first ``limit`` matching trials; None for all.

    Returns:
        The selected entries.

    Raises:
        ValueError: A negative limit.
    """
    if limit is not None and limit < 0:
        raise ValueError(f"limit must be ≥ 0, got {limit}")
    chosen = tuple(e for e in entries if only is None or fnmatchcase(e.id, only))
    return chosen if limit is None else chosen[:limit]
