"""The dataset layouts discovery knows: which files make a trial, which are companions, which are unknown.

Each ``_…`` pass below takes the files not yet sorted and claims those of its layout (see
:mod:`handsim.runner.discover` for the three lists). Order: Tzionas sequences, ARCTIC sequences, handsim's
synthetic scripted grasps (``*.grasp.json``), GraspDB14 recordings, documentation, then everything left is
unknown.
"""

from __future__ import annotations

import os
import re
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from handsim.errors import HandsimError
from handsim.sim.trial import Trial, TrialObject, find_trial

if TYPE_CHECKING:
    from handsim.runner.discover import TrialInput, _Sorting

ARCTIC_UNSUPPORTED = (
    "handsim cannot replay ARCTIC sequences yet: ARCTIC stores each hand's pose relative to MANO's mean "
    "pose (hands_mean) and its shape as MANO betas, so the hand needs your MANO model files "
    "(MANO_RIGHT.pkl / MANO_LEFT.pkl from mano.is.tue.mpg.de, MPI licence, not redistributable), and "
    "handsim.sim.trial has no 'arctic' trial kind that builds a two-hand MANO scene from them (the readers "
    "exist: handsim.io.arctic_motion, handsim.io.arctic, handsim.builders.mano_hand)"
)
"""The error an ARCTIC trial records when run (it is discovered and listed all the same)."""

ARCTIC_BULK = {
    "images": "ARCTIC camera images (not read)",
    "cropped_images": "ARCTIC cropped camera images (not read)",
    "croppped_images": "ARCTIC cropped camera images (not read)",
    "processed_seqs": "ARCTIC sequences processed into camera frames (not read; handsim replays raw_seqs)",
    "splits": "ARCTIC training splits (not read)",
    "splits_json": "ARCTIC training split lists (not read)",
}
"""Folders beside ``raw_seqs/`` listed whole, not file by file (they hold up to millions of files)."""

_HAND_MOTION = re.compile(r"Model_Hand.*\.motion", re.IGNORECASE)
_TZIONAS_MODEL = re.compile(
    r"Model_(?:Hand|Object).*\.(?:skel|limits|motion|off|skin|voi|zones)", re.IGNORECASE
)
_TZIONAS_CONFIGS = ("MODELS_INFO.txt", "INDEX_BOUNDS.txt")
_DOCS = re.compile(
    r"(?:readme|license|licence|copying|notice)(?:\..*)?|.*\.(?:md|rst|pdf|html?)", re.IGNORECASE
)
_GRASPDB_NAME_HELP = (
    "spec 003 §4.1.2: <objID>[_<graspID>|_<actionID>]_ex<NN>-rad|raw-<trialID>-grasp-su<actorID>.txt"
)


def has_hand_motion(folder: Path) -> bool:
    """True if ``folder`` is a Tzionas sequence folder (holds a ``Model_Hand_*.MOTION``)."""
    return folder.is_dir() and any(p.is_file() and _HAND_MOTION.fullmatch(p.name) for p in folder.iterdir())


def bulk_folder(parent: Path, name: str) -> str | None:
    """What a folder listed whole is (an ARCTIC image or split folder beside ``raw_seqs/``), or None."""
    if name in ARCTIC_BULK and (parent / "raw_seqs").is_dir():
        return ARCTIC_BULK[name]
    return None


def sort_files(sorting: _Sorting) -> None:
    """Sort every file of ``sorting`` into its trials, companions and unknown files."""
    _tzionas(sorting)
    _tzionas_companions(sorting)
    _arctic(sorting)
    _scripted(sorting)
    _graspdb(sorting)
    _rest(sorting)


def _rel(path: str | Path, base: Path) -> str:
    return PurePosixPath(Path(os.path.relpath(path, base))).as_posix()


def _input(role: str, path: str | Path, base: Path) -> TrialInput:
    from handsim.runner.discover import TrialInput

    return TrialInput(role=role, path=_rel(path, base), file=str(path))


def _meta(**fields) -> dict:
    """Group-by fields: the seven every record has (None by default), then the extras given."""
    meta = dict.fromkeys(("object", "grasp", "grasp_id", "action", "scenario", "actor", "sequence"))
    meta.update(fields)
    return meta


# --------------------------------------------------------------------------------------------------
# Tzionas / Ballan


def _siblings(path: Path, exts: tuple[str, ...]) -> list[Path]:
    """The files beside ``path`` with its stem and one of ``exts`` (either case), in ``exts`` order."""
    found = []
    for ext in exts:
        for candidate in (path.with_suffix("." + ext.upper()), path.with_suffix("." + ext.lower())):
            if candidate.is_file():
                found.append(candidate)
                break
    return found


def _tzionas_inputs(trial: Trial, base: Path) -> tuple[TrialInput, ...]:
    from handsim.io.tzionas_motion import config_dir_of

    motion = Path(trial.trajectory_path)
    configs = config_dir_of(motion.parent)
    inputs = [_input("trajectory", motion, base)]
    if (configs / "INDEX_BOUNDS.txt").is_file():
        inputs.append(_input("trajectory", configs / "INDEX_BOUNDS.txt", base))
    skeleton = Path(trial.skeleton_path or motion.with_suffix(".SKEL"))
    inputs += [
        _input("skeleton", p, base) for p in _siblings(skeleton, ("SKEL", "LIMITS", "OFF", "SKIN", "VOI"))
    ]
    for obj in trial.objects:
        files = _siblings(Path(obj.what), ("SKEL", "LIMITS", "MOTION", "OFF", "SKIN"))
        inputs += [_input("object", p, base) for p in files]
    inputs.append(_input("models_info", configs / "MODELS_INFO.txt", base))
    return tuple(inputs)


def _tzionas(sorting: _Sorting) -> None:
    from handsim.runner.discover import TrialEntry

    folders: dict[str, list[str]] = {}
    for f in sorting.open_files():
        folders.setdefault(PurePosixPath(f).parent.as_posix(), []).append(f)
    for folder, files in sorted(folders.items()):
        hands = [f for f in files if _HAND_MOTION.fullmatch(PurePosixPath(f).name)]
        for hand in hands:
            try:
                trial = find_trial(sorting.base / hand)
            except HandsimError as exc:
                sorting.unknown[hand] = f"a Tzionas hand motion, but not a trial: {exc}"
                continue
            tracks = [o.track for o in trial.objects]
            meta = _meta(object="+".join(tracks), sequence=PurePosixPath(folder).name, objects=tracks)
            trial_id = folder if len(hands) == 1 and folder != "." else hand
            sorting.add(TrialEntry(trial_id, trial, meta, _tzionas_inputs(trial, sorting.base)))


def _tzionas_root(path: PurePosixPath, base: Path) -> bool:
    """True if ``path``'s folder is a Tzionas dataset root (has ``Models/`` and ``Configs/``)."""
    folder = base / path
    return (folder / "Models").is_dir() and (folder / "Configs").is_dir()


def _tzionas_companions(sorting: _Sorting) -> None:
    for f in sorting.open_files():
        p = PurePosixPath(f)
        folder = p.parent
        if _TZIONAS_MODEL.fullmatch(p.name):
            if has_hand_motion(sorting.base / folder) and p.suffix.lower() != ".zones":
                sorting.unknown[f] = (
                    "a Tzionas model file beside a hand motion, not listed in MODELS_INFO.txt"
                )
            elif has_hand_motion(sorting.base / folder):
                sorting.companions[f] = "Tzionas skinning zones (.ZONES; not read by handsim)"
            else:
                sorting.companions[f] = (
                    f"Tzionas/Ballan model of sequence {folder.name}, which has no hand motion here "
                    "(no Model_Hand_*.MOTION): not a trial"
                )
        elif folder.parent.name == "Configs" and p.name in _TZIONAS_CONFIGS:
            sorting.companions[f] = (
                f"Tzionas configuration of sequence {folder.name}, which has no hand motion here: not a trial"
            )
        elif len(p.parts) >= 2 and _tzionas_root(folder.parent, sorting.base):
            if folder.name == "Calibration":
                sorting.companions[f] = (
                    "Tzionas camera calibration (not read: motion times use the sensor's 30 Hz, "
                    "docs/conventions.md)"
                )
            elif folder.name == "VOIs":
                sorting.companions[f] = (
                    "Tzionas vertex-of-interest list of the dataset's models (not read; a hand's own .VOI is)"
                )


# --------------------------------------------------------------------------------------------------
# ARCTIC


def _arctic_template_files(template: Path) -> list[Path]:
    if (template / "top.obj").is_file() and (template / "bottom.obj").is_file():
        return [template / "bottom.obj", template / "top.obj"]
    return [p for p in (template / "mesh.obj", template / "parts.json") if p.is_file()]


def _arctic(sorting: _Sorting) -> None:
    from handsim.runner.discover import TrialEntry

    for f in sorting.open_files():
        p = PurePosixPath(f)
        if len(p.parts) < 3 or p.parts[-3] != "raw_seqs" or not p.name.endswith(".mano.npy"):
            continue
        seq, subject = p.name.removesuffix(".mano.npy"), p.parent.name
        root = sorting.base / p.parent.parent.parent
        obj_motion = sorting.base / p.parent / f"{seq}.object.npy"
        name = seq.split("_")[0]
        template = root / "meta" / "object_vtemplates" / name
        if not obj_motion.is_file():
            sorting.unknown[f] = (
                f"an ARCTIC MANO sequence without its {obj_motion.name} beside it: not a trial"
            )
            continue
        if not template.is_dir():
            sorting.unknown[f] = (
                f"an ARCTIC sequence whose object template {_rel(template, sorting.base)}/ is missing: "
                "not a trial"
            )
            continue
        trial = Trial(
            kind="arctic",
            trajectory_path=str(sorting.base / p),
            skeleton_path=None,
            objects=(TrialObject(str(template), "object", f"object {name!r} in the sequence name"),),
            notes=(f"object motion {obj_motion}",),
        )
        parts = seq.split("_")
        meta = _meta(object=name, action=parts[1] if len(parts) > 2 else None, actor=subject, sequence=seq)
        inputs = (
            _input("trajectory", sorting.base / p, sorting.base),
            _input("trajectory", obj_motion, sorting.base),
            *(_input("object", t, sorting.base) for t in _arctic_template_files(template)),
        )
        sorting.add(TrialEntry(f, trial, meta, inputs))
    for f in sorting.open_files():
        _arctic_companion(sorting, PurePosixPath(f))


def _arctic_companion(sorting: _Sorting, p: PurePosixPath) -> None:
    f = p.as_posix()
    in_raw = len(p.parts) >= 3 and p.parts[-3] == "raw_seqs"
    if in_raw and p.name.endswith(".egocam.dist.npy"):
        sorting.companions[f] = "ARCTIC egocentric camera poses (not read)"
    elif in_raw and p.name.endswith(".smplx.npy"):
        sorting.companions[f] = "ARCTIC SMPL-X body parameters (not read: handsim replays the hands)"
    elif in_raw and p.name.endswith(".object.npy"):
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


# --------------------------------------------------------------------------------------------------
# Scripted grasps (synthetic, written for handsim)


def _scripted(sorting: _Sorting) -> None:
    from handsim.io.scripted import is_scripted_grasp, scripted_grasp_fields
    from handsim.runner.discover import TrialEntry

    for f in sorting.open_files():
        if not is_scripted_grasp(f):
            continue
        path = sorting.base / f
        try:
            trial = find_trial(path)
            fields = scripted_grasp_fields(path)
        except HandsimError as exc:
            sorting.unknown[f] = f"a scripted grasp (.grasp.json), but not a trial: {exc}"
            continue
        meta = _meta(
            object=trial.objects[0].what, grasp="scripted", synthetic=True, closure=fields["closure"]
        )
        sorting.add(TrialEntry(f, trial, meta, (_input("trajectory", path, sorting.base),)))


# --------------------------------------------------------------------------------------------------
# GraspDB14


def _graspdb_inputs(trial: Trial, base: Path) -> tuple[TrialInput, ...]:
    inputs = [_input("trajectory", trial.trajectory_path, base)]
    for role, path in (
        ("annotation", trial.annotation_path),
        ("calibration", trial.calibration_path),
        ("skeleton", trial.skeleton_path),
    ):
        if path is not None:
            inputs.append(_input(role, path, base))
    inputs += [_input("object", o.what, base) for o in trial.objects if Path(o.what).is_file()]
    return tuple(inputs)


def _graspdb(sorting: _Sorting) -> None:
    from handsim.builders.graspdb_objects import GRASPDB_OBJECTS
    from handsim.io.graspdb import parse_graspdb_filename
    from handsim.runner.discover import TrialEntry
    from handsim.runner.graspdb_names import graspdb_meta

    names = {o.graspdb_id: o.name for o in GRASPDB_OBJECTS}
    open_files = sorting.open_files()
    present = set(open_files)
    annotations = []
    for f in open_files:
        p = PurePosixPath(f)
        if "fk_oracle" in p.parts[:-1]:
            sorting.companions[f] = (
                "GraspDB14 tools' forward-kinematics oracle (calcJointTrajectories output and its input "
                "motions): test data for the skeleton, not trials"
            )
            continue
        if p.suffix.lower() == ".xmlskel":
            sorting.companions[f] = (
                "GraspDB14 hand skeleton (.xmlskel); trials replay the parametric default hand "
                "(handsim replay --skeleton uses this one)"
            )
            continue
        if "_calib-" in p.name.lower():
            sorting.companions[f] = (
                "CyberGlove calibration sequence (raw counts): estimate a calibration from it to replay "
                "-raw- recordings (handsim.glove.estimate_calibration)"
            )
            continue
        parsed = parse_graspdb_filename(p.name)
        if parsed is None:
            continue
        if parsed.annotation:
            annotations.append(f)
            continue
        twin = f.replace("-raw-", "-rad-", 1)
        if parsed.datatype == "raw" and twin in present:
            sorting.companions[f] = f"raw sensor counts of {twin}, which is replayed"
            continue
        try:
            trial = find_trial(sorting.base / p)
        except HandsimError as exc:
            sorting.unknown[f] = f"a GraspDB14 recording name, but not a trial: {exc}"
            continue
        meta = graspdb_meta(parsed, names.get(parsed.object_id))
        sorting.add(TrialEntry(f, trial, meta, _graspdb_inputs(trial, sorting.base)))
    for f in annotations:
        if f not in sorting.claimed:
            sorting.unknown[f] = (
                "a GraspDB14 phase annotation file, not a recording; the recording it annotates is not in "
                "the dataset"
            )


# --------------------------------------------------------------------------------------------------
# Everything else


def _rest(sorting: _Sorting) -> None:
    for f in sorting.open_files():
        p = PurePosixPath(f)
        if p.name.startswith("."):
            sorting.companions[f] = "hidden file (not read)"
        elif _DOCS.fullmatch(p.name):
            sorting.companions[f] = "documentation (not read)"
        elif p.suffix.lower() == ".txt":
            sorting.unknown[f] = (
                f"a .txt file whose name is not a GraspDB14 motion file name ({_GRASPDB_NAME_HELP}) and that "
                "is not part of a Tzionas or ARCTIC layout"
            )
        else:
            kind = f"file type {p.suffix!r}" if p.suffix else "a file without extension"
            sorting.unknown[f] = (
                f"{kind}: no recording handsim replays (GraspDB14 .txt, Tzionas Models/NN with "
                "Model_Hand_*.MOTION, ARCTIC raw_seqs/sXX/*.mano.npy, scripted grasp *.grasp.json) nor a "
                "known companion file"
            )
