"""Trial kind ``arctic``: an ARCTIC sequence and its object.

The sequence is ``raw_seqs/sXX/<seq>.mano.npy`` with its ``<seq>.object.npy`` and the object template
``meta/object_vtemplates/<object>/`` of the same ARCTIC root.
"""

from __future__ import annotations

from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from handsim.trials.base import LoadedTrial, Trial, TrialError, TrialKind, TrialObject, TrialOptions
from handsim.trials.discovery import Sorting, TrialEntry, group_fields, relative, trial_input

if TYPE_CHECKING:
    from handsim.sim.metrics import MetricSpec

MANO_SUFFIX = ".mano.npy"
OBJECT_SUFFIX = ".object.npy"
UNSUPPORTED = (
    "handsim cannot replay ARCTIC sequences yet: ARCTIC stores each hand's pose relative to MANO's mean "
    "pose (hands_mean) and its shape as MANO betas, so the hand needs your MANO model files "
    "(MANO_RIGHT.pkl / MANO_LEFT.pkl from mano.is.tue.mpg.de, MPI licence, not redistributable), and "
    "handsim.trials has no 'arctic' loader that builds a two-hand MANO scene from them yet (the readers "
    "exist: handsim.io.arctic_motion, handsim.io.arctic, handsim.builders.mano_hand)"
)
"""The error an ARCTIC trial records when loaded (it is discovered and listed all the same)."""
BULK = {
    "images": "ARCTIC camera images (not read)",
    "cropped_images": "ARCTIC cropped camera images (not read)",
    "croppped_images": "ARCTIC cropped camera images (not read)",
    "processed_seqs": "ARCTIC sequences processed into camera frames (not read; handsim replays raw_seqs)",
    "splits": "ARCTIC training splits (not read)",
    "splits_json": "ARCTIC training split lists (not read)",
}
"""Folders beside ``raw_seqs/`` listed whole, not file by file (they hold up to millions of files)."""


def _matches(path: Path) -> bool:
    return path.is_file() and path.name.endswith(MANO_SUFFIX)


def _sequence(path: Path) -> tuple[str, Path, Path]:
    """The sequence name, its object motion file and its template folder (by the ARCTIC layout)."""
    seq = path.name.removesuffix(MANO_SUFFIX)
    root = path.parent.parent.parent
    return seq, path.parent / f"{seq}{OBJECT_SUFFIX}", root / "meta" / "object_vtemplates" / seq.split("_")[0]


def _find(path: Path, options: TrialOptions) -> Trial:
    seq, motion, template = _sequence(path)
    if not motion.is_file():
        raise TrialError(f"{path}: an ARCTIC MANO sequence without its {motion.name} beside it")
    if not template.is_dir():
        raise TrialError(
            f"{path}: its object template {template}/ is missing (ARCTIC meta/object_vtemplates)"
        )
    return Trial(
        kind="arctic",
        trajectory_path=str(path),
        skeleton_path=None,
        objects=(TrialObject(str(template), "object", f"object {seq.split('_')[0]!r} in the sequence name"),),
        density=options.density,
        mass=options.mass,
        notes=(f"object motion {motion}",),
    )


def _load(trial: Trial, metrics: MetricSpec | None, progress: bool) -> LoadedTrial:
    raise TrialError(f"{trial.trajectory_path}: {UNSUPPORTED}")


def _template_files(template: Path) -> list[Path]:
    if (template / "top.obj").is_file() and (template / "bottom.obj").is_file():
        return [template / "bottom.obj", template / "top.obj"]
    return [p for p in (template / "mesh.obj", template / "parts.json") if p.is_file()]


def _sort_files(sorting: Sorting) -> None:
    for f in sorting.open_files():
        p = PurePosixPath(f)
        if len(p.parts) < 3 or p.parts[-3] != "raw_seqs" or not p.name.endswith(MANO_SUFFIX):
            continue
        seq, motion, template = _sequence(sorting.base / p)
        if not motion.is_file():
            sorting.unknown[f] = f"an ARCTIC MANO sequence without its {motion.name} beside it: not a trial"
            continue
        if not template.is_dir():
            sorting.unknown[f] = (
                f"an ARCTIC sequence whose object template {relative(template, sorting.base)}/ is missing: "
                "not a trial"
            )
            continue
        trial = _find(sorting.base / p, TrialOptions())
        parts = seq.split("_")
        meta = group_fields(
            object=parts[0], action=parts[1] if len(parts) > 2 else None, actor=p.parent.name, sequence=seq
        )
        inputs = (
            trial_input("trajectory", sorting.base / p, sorting.base),
            trial_input("trajectory", motion, sorting.base),
            *(trial_input("object", t, sorting.base) for t in _template_files(template)),
        )
        sorting.add(TrialEntry(f, trial, meta, inputs))
    for f in sorting.open_files():
        _sort_companion(sorting, PurePosixPath(f))


def _sort_companion(sorting: Sorting, p: PurePosixPath) -> None:
    f = p.as_posix()
    in_raw = len(p.parts) >= 3 and p.parts[-3] == "raw_seqs"
    if in_raw and p.name.endswith(".egocam.dist.npy"):
        sorting.companions[f] = "ARCTIC egocentric camera poses (not read)"
    elif in_raw and p.name.endswith(".smplx.npy"):
        sorting.companions[f] = "ARCTIC SMPL-X body parameters (not read: handsim replays the hands)"
    elif in_raw and p.name.endswith(OBJECT_SUFFIX):
        sorting.unknown[f] = "an ARCTIC object motion without its .mano.npy beside it: not a trial"
    elif "meta" in p.parts[:-1]:
        at = p.parts.index("meta")
        if not (sorting.base / PurePosixPath(*p.parts[:at]) / "raw_seqs").is_dir():
            return
        inner = p.parts[at + 1 :]
        if inner[:1] == ("object_vtemplates",):
            sorting.companions[f] = (
                "ARCTIC object template file not read (handsim reads top.obj + bottom.obj, else mesh.obj + "
                "parts.json), or a template no sequence here uses"
            )
        elif inner[:1] == ("subject_vtemplates",):
            sorting.companions[f] = "ARCTIC personalised subject template (not read)"
        elif inner == ("misc.json",):
            sorting.companions[f] = "ARCTIC camera parameters, sync offsets and image sizes (not read)"
        else:
            sorting.companions[f] = "ARCTIC metadata (not read)"


def _bulk_folder(parent: Path, name: str) -> str | None:
    if name in BULK and (parent / "raw_seqs").is_dir():
        return BULK[name]
    return None


KIND = TrialKind(
    name="arctic",
    label="an ARCTIC sequence",
    files="ARCTIC raw_seqs/sXX/<seq>.mano.npy with its <seq>.object.npy and meta/object_vtemplates/<object>/",
    options=frozenset({"density", "mass"}),
    brings="it brings its own hands and object (the sequence's files)",
    matches=_matches,
    find=_find,
    load=_load,
    sort_files=_sort_files,
    bulk_folder=_bulk_folder,
)
"""The ``arctic`` kind of trial."""
