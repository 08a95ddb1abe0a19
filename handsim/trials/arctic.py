"""Trial kind ``arctic``: an ARCTIC sequence and its object.

The sequence is ``raw_seqs/sXX/<seq>.mano.npy`` with its ``<seq>.object.npy`` and the object template
``meta/object_vtemplates/<object>/`` of the same ARCTIC root (or of ``--templates DIR``). Loading builds both
MANO hands from the user's ``MANO_RIGHT.pkl`` / ``MANO_LEFT.pkl`` (``--mano-dir`` or ``$HANDSIM_MANO_DIR``)
with the subject's betas, each wrist following its recorded ``rot``/``trans`` (``flat_hand_mean=False``), and
the two-part object free at its recorded pose and articulation, in ARCTIC's z-up world
(:func:`handsim.sim.arctic_scene.arctic_scene`).
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from handsim.builders.arctic_objects import arctic_object
from handsim.builders.mano_hand import build_mano_hands
from handsim.io.arctic.mano import MANO_DIR_ENV, find_mano_files
from handsim.io.arctic.sequence import HANDS, ArcticSequence, read_arctic_sequence
from handsim.io.arctic.templates import read_arctic_template
from handsim.sim.arctic_scene import arctic_scene
from handsim.trials.arctic_hands import SideCheck, arctic_trajectory, hand_side_check
from handsim.trials.base import LoadedTrial, Trial, TrialObject, build_objects
from handsim.trials.kind import TrialKind
from handsim.trials.options import TrialOptions
from handsim.trials.sorting import Sorting, TrialEntry, group_fields, relative, trial_input

if TYPE_CHECKING:
    from handsim.sim.specs import MetricSpec

MANO_SUFFIX = ".mano.npy"
OBJECT_SUFFIX = ".object.npy"
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


def _sequence(path: Path, templates: str | Path | None = None) -> tuple[str, Path, Path]:
    """The sequence name, its object motion file and its template folder (by the ARCTIC layout)."""
    seq = path.name.removesuffix(MANO_SUFFIX)
    default = path.parent.parent.parent / "meta" / "object_vtemplates"
    folder = default if templates is None else Path(templates)
    return seq, path.parent / f"{seq}{OBJECT_SUFFIX}", folder / seq.split("_")[0]


def _trial(path: Path, options: TrialOptions) -> Trial:
    """The trial of a sequence, nothing checked (``mano_dir``: the option, else ``$HANDSIM_MANO_DIR``)."""
    seq, motion, template = _sequence(path, options.templates)
    name = seq.split("_")[0]
    mano_dir = options.mano_dir or os.environ.get(MANO_DIR_ENV) or None
    return Trial(
        kind="arctic",
        trajectory_path=str(path),
        skeleton_path=None,
        objects=(TrialObject(str(template), name, f"object {name!r} in the sequence name"),),
        density=options.density,
        mass=options.mass,
        collision=options.collision or "capsules",
        notes=(f"object motion {motion}",),
        mano_dir=None if mano_dir is None else str(Path(mano_dir).resolve()),
    )


def _find(path: Path, options: TrialOptions) -> Trial:
    """The trial of a sequence, its files checked before any work.

    Raises:
        InputFileError: The MANO files, the object motion or the object template are missing: the readers'
            own errors, so that every command says the same of the same missing file (a handsim error, exit
            code 1, as ``handsim inspect`` reading the sequence).
    """
    find_mano_files(options.mano_dir)  # says which files are needed and where to put them
    _, motion, template = _sequence(path, options.templates)
    if not motion.is_file():
        read_arctic_sequence(path)  # raises, naming the missing object motion, before reading anything
    if not template.is_dir():
        read_arctic_template(template)  # raises, naming the missing template folder
    return _trial(path, options)


def _load(trial: Trial, metrics: MetricSpec | None, progress: bool) -> LoadedTrial:
    sequence = read_arctic_sequence(trial.trajectory_path)
    hands = build_mano_hands(
        trial.mano_dir, {side: sequence.hand(side).shape for side in HANDS}, collision=trial.collision
    )
    models = {side: (hand.skeleton, hand.model) for side, hand in hands.items()}
    trajectory = arctic_trajectory(sequence, models)
    (item,) = trial.objects
    model = arctic_object(
        item.what, articulation=sequence.object.articulation, mass=trial.mass, density=trial.density
    )
    specs, objects, notes = build_objects(trial, progress, [model])
    scene = arctic_scene({side: hand.spec for side, hand in hands.items()}, trajectory, specs[0], item.track)
    sides = hand_side_check(sequence, models, model)
    return LoadedTrial(
        trial=trial,
        scene=scene,
        trajectory=replace(trajectory, flags=(*trajectory.flags, *sides.flags)),  # swapped: a flag
        hand=f"MANO right + left ({Path(hands['right'].model.source).parent}, the subject's betas, "
        f"{trial.collision})",
        objects=objects,
        notes=(
            *trial.notes,
            *notes,
            *(() if sides.flags else (sides.message,)),
        ),
    )


def sequence_side_check(
    sequence: ArcticSequence, mano_dir: str | Path | None = None, templates: str | Path | None = None
) -> SideCheck:
    """The side check of an ARCTIC sequence, as a replay of it runs it (for ``handsim inspect``).

    Args:
        sequence: The sequence (:func:`~handsim.io.arctic.sequence.read_arctic_sequence`); its object template
            is found as the trial kind finds it.
        mano_dir: The folder with the user's MANO files; None: ``$HANDSIM_MANO_DIR``.
        templates: ARCTIC object templates folder instead of the root's ``meta/object_vtemplates/``.

    Returns:
        The verdict with both entries' evidence (:func:`hand_side_check`).

    Raises:
        InputFileError: The MANO files or the object template are missing (the message says where to put
            or point to them).
        HandsimError: A file is malformed (the readers' errors).
    """
    _, _, template = _sequence(Path(sequence.mano_path), templates)
    hands = build_mano_hands(mano_dir, {side: sequence.hand(side).shape for side in HANDS})
    model = arctic_object(template, articulation=sequence.object.articulation)
    return hand_side_check(sequence, {side: (h.skeleton, h.model) for side, h in hands.items()}, model)


def _template_files(template: Path) -> list[Path]:
    if (template / "top.obj").is_file() and (template / "bottom.obj").is_file():
        return [template / "bottom.obj", template / "top.obj"]
    return [p for p in (template / "mesh.obj", template / "parts.json") if p.is_file()]


def _sort_files(sorting: Sorting) -> None:
    for f in sorting.open_files():
        p = PurePosixPath(f)
        full = sorting.base / p  # the layout judged on the whole path: also a sequence given alone
        if len(full.parts) < 3 or full.parts[-3] != "raw_seqs" or not p.name.endswith(MANO_SUFFIX):
            continue
        seq, motion, template = _sequence(full)
        if not motion.is_file():
            sorting.unknown[f] = f"an ARCTIC MANO sequence without its {motion.name} beside it: not a trial"
            continue
        if not template.is_dir():
            sorting.unknown[f] = (
                f"an ARCTIC sequence whose object template {relative(template, sorting.base)}/ is missing: "
                "not a trial"
            )
            continue
        trial = _trial(full, sorting.options)
        parts = seq.split("_")
        meta = group_fields(
            object=parts[0], action=parts[1] if len(parts) > 2 else None, actor=full.parent.name, sequence=seq
        )
        inputs = (
            trial_input("trajectory", full, sorting.base),
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
    options=frozenset({"density", "mass", "collision", "mano_dir", "templates"}),
    brings="it brings its own hands (MANO, --mano-dir) and object (the sequence's files, --templates)",
    matches=_matches,
    find=_find,
    load=_load,
    sort_files=_sort_files,
    bulk_folder=_bulk_folder,
)
"""The ``arctic`` kind of trial."""
