"""Discovery: a dataset folder (or one recording) as a sorted list of trials, every other file accounted for.

:func:`discover` walks the folder once (sorted; links to folders followed once) and sorts every file into
exactly one of three lists:

* **trials** (:class:`TrialEntry`): a recording handsim replays, with the files it reads (its inputs) and
  its group-by fields. Each kind of trial (:class:`~handsim.trials.kind.TrialKind`) claims the files of its
  dataset layout in turn (:attr:`~handsim.trials.kind.TrialKind.sort_files`);
* **companions** (:class:`CompanionFile`): files that belong to a dataset's layout but are not replayed,
  each with what it is (``.xmlskel``, Tzionas ``Calibration/``, GraspDB14's ``fk_oracle/``, ARCTIC's
  images …);
* **unknown** (:class:`UnknownFile`): everything else, with the reason it is not a trial (never silently
  skipped).

A trial's id is the dataset-relative POSIX path of its recording (``r_01_11_ex03-rad-004-grasp-su04.txt``,
``Models/20``): stable and unique, the key of a run's records.

**One recording, one trial.** The same recording under several names or folders (copied, or linked) is
replayed once: counting it twice would count one grasp as two in every rate. Two trials are the same when
their replays would be: the same kind, the same bytes in every input file, role by role (a GraspDB14
recording with its annotation and calibration; a Tzionas sequence's hand and object ``.MOTION``, skeleton,
mesh and skin files with its ``MODELS_INFO.txt`` and ``INDEX_BOUNDS.txt``; an ARCTIC ``.mano.npy`` with its
``.object.npy`` and template files; a scripted grasp's file), and the same settings: the grasp episode, the
hand options, and the objects, a catalogue object by its name and an object read from files by those files'
bytes (already among the inputs) and the track it follows. So a recording whose file name names its object
(GraspDB14) is another trial under another object's name, a tennis-ball recording linked under a mug's name
is replayed with the mug too, while a whole sequence folder copied elsewhere is one trial. Names, folders
and the group-by fields read from them (actor, sequence) do not make a replay differ, so they do not count.
The first copy in id order is the trial; each later one (a glove recording's episodes one by one) becomes
a companion whose reason is ``same content as <first id>: replayed once``.

Comparing costs a ``stat`` per input file; only trials whose inputs all have equal sizes are read, in
chunks, for their SHA-256 (each real file once, a link resolved first), so a dataset without copies reads
no file for it.
"""

from __future__ import annotations

import dataclasses
import os
import re
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fnmatch import fnmatchcase
from pathlib import Path, PurePosixPath

from handsim.errors import HandsimError, InputFileError
from handsim.files import sha256_file
from handsim.io.text_files import require_file, special_file
from handsim.trials.base import TrialOptions
from handsim.trials.kind import TrialKind
from handsim.trials.sorting import CompanionFile, Sorting, TrialEntry, UnknownFile

SAME_CONTENT = "same content as "
"""How the reason of a recording's later copy begins (then the first copy's id, ``: replayed once``)."""
_NAMED = ("trajectory_path", "skeleton_path", "calibration_path", "annotation_path", "notes", "objects")
"""Trial fields that name files or record how they were found: compared by the inputs' bytes instead."""

_DOCS = re.compile(
    r"(?:readme|license|licence|copying|notice)(?:\..*)?|.*\.(?:md|rst|pdf|html?)", re.IGNORECASE
)


@dataclass(frozen=True)
class Discovery:
    """The trials of a dataset and every other file in it.

    Attributes:
        root: The folder the ids and paths are relative to (absolute).
        entries: The trials, sorted by id (a recording's grasp episodes ``<path>#<k>`` in episode order).
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

    @property
    def copies(self) -> tuple[CompanionFile, ...]:
        """The companions that are later copies of a trial's recording (replayed once, as that trial)."""
        return tuple(c for c in self.companions if c.reason.startswith(SAME_CONTENT))


def _walk(
    root: Path, base: Path, kinds: Sequence[TrialKind], companions: dict[str, str], unknown: dict[str, str]
) -> list[str]:
    """Every regular file under ``root`` as a path relative to ``base``.

    Links to folders are followed once (a folder reached again through a link is listed, not searched
    twice); hidden folders and the bulk folders of a layout are listed whole. Named pipes, devices and
    sockets (or links to them) go to ``unknown`` with what they are: no kind may open them, as reading one
    could block forever or never end.
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
        for name in sorted(names):
            rel = (here / name).relative_to(base).as_posix()
            special = special_file(here / name)
            if special is None:
                files.append(rel)
            else:
                unknown[rel] = f"{special}, not a regular file (not read: it could block or never end)"
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
        InputFileError: ``dataset`` does not exist, or is a named pipe, a device or a socket.
    """
    root = Path(dataset).resolve()
    if not root.exists():
        raise InputFileError(f"{dataset}: dataset not found (expected a folder or a recording)")
    if not root.is_dir():
        require_file(dataset)  # a regular file, not a pipe or device that a kind's reader would block on
    single = root.is_file() or _is_trial_folder(root, kinds)
    base = root.parent if single else root
    companions: dict[str, str] = {}
    unknown: dict[str, str] = {}
    if root.is_file():
        files = [root.relative_to(base).as_posix()]
    else:
        files = _walk(root, base, kinds, companions, unknown)
    sorting = Sorting(
        base=base, files=files, companions=companions, unknown=unknown, options=options or TrialOptions()
    )
    for kind in kinds:
        kind.sort_files(sorting)
    _rest(sorting, kinds)
    entries = _replayed_once(sorted(sorting.entries, key=lambda e: _episode_order(e.id)), sorting.companions)
    return Discovery(
        root=str(base),
        entries=tuple(entries),
        companions=tuple(
            CompanionFile(p, r)
            for p, r in sorted(sorting.companions.items(), key=lambda c: _episode_order(c[0]))
        ),
        unknown=tuple(UnknownFile(p, r) for p, r in sorted(sorting.unknown.items())),
    )


def _replayed_once(entries: list[TrialEntry], companions: dict[str, str]) -> list[TrialEntry]:
    """The entries (sorted by id) less the later copies of a recording, which go to ``companions``.

    Sizes first: only entries whose every input has the size of another entry's are hashed.
    """
    sizes = [_recording_key(entry, os.path.getsize) for entry in entries]
    shared = {key for key, n in Counter(sizes).items() if key is not None and n > 1}
    digests: dict[str, str] = {}
    first: dict[tuple, str] = {}
    kept = []
    for entry, size in zip(entries, sizes, strict=True):
        key = _recording_key(entry, lambda f: _sha256(f, digests)) if size in shared else None
        if key in first:
            companions[entry.id] = f"{SAME_CONTENT}{first[key]}: replayed once"
            continue
        if key is not None:
            first[key] = entry.id
        kept.append(entry)
    return kept


def _recording_key(entry: TrialEntry, measure: Callable[[str], object]) -> tuple | None:
    """What makes two trials the same replay (the module docstring), each input file by ``measure``.

    None for a trial without inputs or with one that cannot be read (its own replay says why).
    """
    try:
        files = tuple((i.role, measure(i.file)) for i in entry.inputs)
    except OSError:
        return None
    if not files:
        return None
    trial = entry.trial
    settings = tuple(
        (f.name, getattr(trial, f.name)) for f in dataclasses.fields(trial) if f.name not in _NAMED
    )
    objects = tuple(("" if os.path.isabs(o.what) else o.what, o.track) for o in trial.objects)
    return (entry.kind, files, settings, objects)


def _sha256(path: str, digests: dict[str, str]) -> str:
    """The SHA-256 of a file's bytes; ``digests`` keeps each real file's (links resolved)."""
    real = os.path.realpath(path)
    if real not in digests:
        digests[real] = sha256_file(real)
    return digests[real]


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


def _episode_order(item: str) -> tuple[str, int]:
    """Sort key: the path, then a grasp episode's number (``#2`` before ``#10``); 0 for a whole file."""
    path, sep, number = item.rpartition("#")
    return (path, int(number)) if sep and number.isdigit() else (item, 0)
