"""Trial kind ``tzionas``: a Tzionas/Ballan sequence (``Models/NN`` with ``Configs/NN/MODELS_INFO.txt``).

The hand is the motion's own ``.SKEL`` (+ ``.LIMITS``, ``.OFF``, ``.SKIN`` beside it); the objects are the
``Model_Object_*`` that ``Configs/NN/MODELS_INFO.txt`` lists, each following its recorded track (scenario
``recorded``).

A sequence whose ``MODELS_INFO.txt`` lists two hands (``Model_Hand_R`` and ``Model_Hand_L``) is one trial
whose recording is its ``Models/NN`` folder: both hands in one scene (``hand/right/``, ``hand/left/``), each
root following its own recorded pose and its DoFs driven by its own motion
(:func:`~handsim.io.tzionas.sequence.read_tzionas_hands`), the objects as for one hand. Either hand's
``.MOTION`` given as the recording finds the whole sequence (a note says so).
"""

from __future__ import annotations

import re
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from handsim.builders import build_hand
from handsim.builders.surfaces import FITTED_SKIN
from handsim.errors import HandsimError
from handsim.io import read_skeleton, read_trajectory
from handsim.io.tzionas.configs import config_dir_of, read_models_info
from handsim.io.tzionas.sequence import object_track_name, read_tzionas_hands, two_hand_models
from handsim.sim.scenarios import recorded_scene
from handsim.trials.base import LoadedTrial, Trial, TrialError, TrialObject, build_objects
from handsim.trials.kind import TrialKind
from handsim.trials.options import TrialOptions
from handsim.trials.sorting import Sorting, TrialEntry, TrialInput, group_fields, trial_input

if TYPE_CHECKING:
    from handsim.sim.specs import MetricSpec

_HAND_MOTION = re.compile(r"Model_Hand.*\.motion", re.IGNORECASE)
_MODEL_FILE = re.compile(r"Model_(?:Hand|Object).*\.(?:skel|limits|motion|off|skin|voi|zones)", re.IGNORECASE)
_CONFIGS = ("MODELS_INFO.txt", "INDEX_BOUNDS.txt")


def has_hand_motion(folder: Path) -> bool:
    """True if ``folder`` is a Tzionas sequence folder (holds a ``Model_Hand_*.MOTION``)."""
    return folder.is_dir() and any(p.is_file() and _HAND_MOTION.fullmatch(p.name) for p in folder.iterdir())


def _matches(path: Path) -> bool:
    return has_hand_motion(path) if path.is_dir() else path.suffix.lower() == ".motion"


def _find(path: Path, options: TrialOptions) -> Trial:
    models_dir = path if path.is_dir() else path.parent
    info = config_dir_of(models_dir) / "MODELS_INFO.txt"
    if not info.is_file():
        raise TrialError(
            f"{path}: no {info} beside the sequence's Models folder; it lists the sequence's hand and objects"
        )
    models = read_models_info(info)
    hands = [name for name, _ in models if name.startswith("Model_Hand")]
    if not path.is_dir() and not path.stem.startswith("Model_Hand"):
        raise TrialError(f"{path}: not a hand motion; give the sequence's Model_Hand_*.MOTION")
    if len(hands) > 1 and (path.is_dir() or path.stem in hands):
        return _two_hand_trial(path, models_dir, info, models, options)
    if path.is_dir():
        if not hands:
            raise TrialError(f"{info}: lists no hand (Model_Hand_*); it lists {[n for n, _ in models]}")
        motion = models_dir / f"{hands[0]}.MOTION"
    else:
        motion = path
    own = motion.with_suffix(".SKEL")
    _check_skeleton(motion, [own], options)
    objects = _objects(models_dir, info, models)
    listed = [o.track for o in objects]
    return _trial(motion, own, objects, options, (f"hand {own.name} and objects {listed} from {info}",))


def _trial(
    recording: Path,
    skeleton: Path | None,
    objects: tuple[TrialObject, ...],
    options: TrialOptions,
    notes: tuple[str, ...],
) -> Trial:
    return Trial(
        kind="tzionas",
        trajectory_path=str(recording),
        skeleton_path=None if skeleton is None else str(skeleton),
        objects=objects,
        density=options.density,
        mass=options.mass,
        collision=options.collision or "capsules",
        notes=notes,
    )


def _check_skeleton(recording: Path, own: list[Path], options: TrialOptions) -> None:
    """Refuse a skeleton option other than the sequence's own hand skeleton(s)."""
    if options.skeleton is None or Path(options.skeleton).resolve() in {p.resolve() for p in own}:
        return
    names = " and ".join(p.name for p in own)
    what = (
        "a Tzionas motion drives its own skeleton"
        if len(own) == 1
        else "a Tzionas sequence drives its own skeletons"
    )
    raise TrialError(
        f"{recording}: {what} {names}, not {options.skeleton}; a skeleton is given only for GraspDB14 "
        "recordings"
    )


def _objects(models_dir: Path, info: Path, models: tuple[tuple[str, int], ...]) -> tuple[TrialObject, ...]:
    return tuple(
        TrialObject(str(models_dir / f"{name}.SKEL"), object_track_name(name), f"{info.name}:{line}")
        for name, line in models
        if name.startswith("Model_Object")
    )


def _two_hand_trial(
    path: Path, models_dir: Path, info: Path, models: tuple[tuple[str, int], ...], options: TrialOptions
) -> Trial:
    """The trial of a sequence listing two hands: its ``Models/NN`` folder is the recording."""
    skeletons = _hand_skeletons(models_dir, two_hand_models(info, models))
    lines = dict(models)
    for side, skel in skeletons.items():
        model = skel.stem
        missing = [f"{model}.{ext}" for ext in ("SKEL", "MOTION") if not _siblings(skel, (ext,))]
        if missing:
            raise TrialError(
                f"{models_dir}: {info.name}:{lines[model]} lists the {side} hand {model!r}, but "
                f"{' and '.join(missing)} {'is' if len(missing) == 1 else 'are'} not in the folder"
            )
    _check_skeleton(path, list(skeletons.values()), options)
    objects = _objects(models_dir, info, models)
    hands = ", ".join(f"{side} {skel.name}" for side, skel in skeletons.items())
    notes = [f"hands {hands} and objects {[o.track for o in objects]} from {info}"]
    if not path.is_dir():
        notes.append(
            f"{path.name} given: {info.name} lists two hands, so the trial is the whole sequence "
            f"{models_dir} with both"
        )
    return _trial(models_dir, None, objects, options, tuple(notes))


def _hand_skeletons(models_dir: Path, sides: dict[str, str]) -> dict[str, Path]:
    """Each hand's ``.SKEL`` by scene name, in the order of ``sides``."""
    return {side: models_dir / f"{model}.SKEL" for side, model in sides.items()}


def _is_two_hand(trial: Trial) -> bool:
    """True if a ``tzionas`` trial is a two-hand sequence (its recording is the ``Models/NN`` folder)."""
    return Path(trial.trajectory_path).is_dir()


def _hands_of(trial: Trial) -> dict[str, tuple[Path, Path]]:
    """The trial's hands: scene name ("" for the only one) → (its ``.MOTION``, its ``.SKEL``)."""
    if not _is_two_hand(trial):
        motion = Path(trial.trajectory_path)
        return {"": (motion, Path(trial.skeleton_path or motion.with_suffix(".SKEL")))}

    folder = Path(trial.trajectory_path)
    info = config_dir_of(folder) / "MODELS_INFO.txt"
    skeletons = _hand_skeletons(folder, two_hand_models(info, read_models_info(info)))
    return {
        side: ((_siblings(skel, ("MOTION",)) or [skel.with_suffix(".MOTION")])[0], skel)
        for side, skel in skeletons.items()
    }


def _load(trial: Trial, metrics: MetricSpec | None, progress: bool) -> LoadedTrial:
    two = _is_two_hand(trial)
    trajectory = read_tzionas_hands(trial.trajectory_path) if two else read_trajectory(trial.trajectory_path)
    skeletons = {side: read_skeleton(skel) for side, (_, skel) in _hands_of(trial).items()}
    # The Tzionas hands were fitted to observed skin: their pads' rest surface lies outside the mesh.
    hands = {
        side: build_hand(sk, collision=trial.collision, skin=FITTED_SKIN) for side, sk in skeletons.items()
    }
    specs, objects, notes = build_objects(trial, progress)
    tracks = {o.track: s for o, s in zip(objects, specs, strict=True)}
    scene = recorded_scene(hands if two else hands[""], trajectory, tracks)
    described = [f"{Path(sk.source).name} ({sk.ndof} DoFs" for sk in skeletons.values()]
    if two:
        hand = ", ".join(f"{side} {d})" for side, d in zip(skeletons, described, strict=True))
        hand += f"; {trial.collision}"
    else:
        hand = f"{described[0]}, {trial.collision})"
    return LoadedTrial(
        trial=trial,
        scene=scene,
        trajectory=trajectory,
        hand=hand,
        objects=objects,
        notes=(
            *trial.notes,
            *(f"{side + ' hand: ' if side else ''}{n}" for side, sk in skeletons.items() for n in sk.notes),
            f"skin: the finger pads' rest surface lies {FITTED_SKIN.margin * 1000:g} mm outside the fitted "
            "hand mesh (the fit is the compressed skin; docs/physics.md, fitted skin)",
            *notes,
        ),
    )


def _siblings(path: Path, exts: tuple[str, ...]) -> list[Path]:
    """The files beside ``path`` with its stem and one of ``exts`` (either case), in ``exts`` order."""
    found = []
    for ext in exts:
        for candidate in (path.with_suffix("." + ext.upper()), path.with_suffix("." + ext.lower())):
            if candidate.is_file():
                found.append(candidate)
                break
    return found


def _inputs(trial: Trial, base: Path) -> tuple[TrialInput, ...]:
    hands = _hands_of(trial)
    motion, _ = next(iter(hands.values()))
    configs = config_dir_of(motion.parent)
    inputs = [trial_input("trajectory", m, base) for m, _ in hands.values()]
    if (configs / "INDEX_BOUNDS.txt").is_file():
        inputs.append(trial_input("trajectory", configs / "INDEX_BOUNDS.txt", base))
    for _, skeleton in hands.values():
        inputs += [
            trial_input("skeleton", p, base)
            for p in _siblings(skeleton, ("SKEL", "LIMITS", "OFF", "SKIN", "VOI"))
        ]
    for obj in trial.objects:
        files = _siblings(Path(obj.what), ("SKEL", "LIMITS", "MOTION", "OFF", "SKIN"))
        inputs += [trial_input("object", p, base) for p in files]
    inputs.append(trial_input("models_info", configs / "MODELS_INFO.txt", base))
    return tuple(inputs)


def _sort_sequences(sorting: Sorting) -> tuple[dict[str, set[str]], dict[str, str]]:
    """Claim each hand motion as a trial (or an unknown file, with why it is not one).

    Returns:
        Per sequence folder, the models its trials read (``Model_Hand_R``, ``Model_Object_Cube`` …); and per
        folder whose hand motion is not a trial, that motion's path.
    """
    folders: dict[str, list[str]] = {}
    for f in sorting.open_files():
        folders.setdefault(PurePosixPath(f).parent.as_posix(), []).append(f)
    listed: dict[str, set[str]] = {}
    failed: dict[str, str] = {}
    for folder, files in sorted(folders.items()):
        hands = [f for f in files if _HAND_MOTION.fullmatch(PurePosixPath(f).name)]
        found: set[str] = set()
        for hand in hands:
            try:
                trial = _find(sorting.base / hand, TrialOptions())
            except HandsimError as exc:
                sorting.unknown[hand] = f"a Tzionas hand motion, but not a trial: {exc}"
                failed.setdefault(folder, hand)
                continue
            if trial.trajectory_path in found:
                continue  # the other hand of a two-hand sequence, already its trial
            found.add(trial.trajectory_path)
            tracks = [o.track for o in trial.objects]
            meta = group_fields(
                object="+".join(tracks) if tracks else None,
                sequence=PurePosixPath(folder).name,
                objects=tracks,
            )
            whole = len(hands) == 1 or _is_two_hand(trial)
            trial_id = folder if whole and folder != "." else hand
            sorting.add(TrialEntry(trial_id, trial, meta, _inputs(trial, sorting.base)))
            models = {
                *(s.stem for _, s in _hands_of(trial).values()),
                *(Path(o.what).stem for o in trial.objects),
            }
            listed.setdefault(folder, set()).update(models)
    return listed, failed


def _is_root(path: PurePosixPath, base: Path) -> bool:
    """True if ``path``'s folder is a Tzionas dataset root (has ``Models/`` and ``Configs/``)."""
    folder = base / path
    return (folder / "Models").is_dir() and (folder / "Configs").is_dir()


def _model_reason(
    p: PurePosixPath, base: Path, listed: dict[str, set[str]], failed: dict[str, str]
) -> tuple[bool, str]:
    """Why a ``Model_*`` file no trial reads is not one: ``(companion, reason)``."""
    folder, model, ext = p.parent, p.stem, p.suffix.upper()
    sequence = f"sequence {folder.name}"
    if not has_hand_motion(base / folder):
        return True, (
            f"Tzionas/Ballan model of {sequence}, which has no hand motion here (no Model_Hand_*.MOTION): "
            "not a trial"
        )
    if ext == ".ZONES":
        return True, "Tzionas skinning zones (.ZONES; not read by handsim)"
    if folder.as_posix() in failed:
        return False, (
            f"Tzionas model {model} of {sequence}, whose hand motion {failed[folder.as_posix()]} is not a "
            "trial (its entry says why)"
        )
    if model in listed.get(folder.as_posix(), set()):
        return True, (
            f"Tzionas {ext} of {model}, which {sequence} replays: not read (handsim reads a hand's .SKEL, "
            ".LIMITS, .MOTION, .OFF, .SKIN, .VOI and an object's .SKEL, .LIMITS, .MOTION, .OFF, .SKIN)"
        )
    return False, (
        f"Tzionas model {model} beside the hand motion of {sequence}, not listed in its "
        f"Configs/{folder.name}/MODELS_INFO.txt: not part of the trial"
    )


def _config_reason(p: PurePosixPath, base: Path) -> tuple[bool, str] | None:
    """Why a file of a ``Configs/NN`` folder no trial reads is not one, or None outside such a folder."""
    folder = p.parent
    if folder.parent.name != "Configs" or not _is_root(folder.parent.parent, base):
        return None
    sequence = f"sequence {folder.name}"
    if p.name not in _CONFIGS:
        return False, (
            f"a file of Tzionas {sequence}'s configuration folder other than {' and '.join(_CONFIGS)} (the "
            "files handsim reads there): not read"
        )
    models = folder.parent.parent / "Models" / folder.name
    if has_hand_motion(base / models):
        return True, (
            f"Tzionas configuration of {sequence}, whose hand motion is not a trial (the entry of its "
            f"{models.as_posix()}/Model_Hand_*.MOTION says why)"
        )
    return True, f"Tzionas configuration of {sequence}, which has no hand motion here: not a trial"


_ROOT_FOLDERS = {
    "Calibration": (
        "Tzionas camera calibration (not read: motion times use the sensor's 30 Hz, docs/conventions.md)"
    ),
    "VOIs": "Tzionas vertex-of-interest list of the dataset's models (not read; a hand's own .VOI is)",
}
"""Companion folders of a Tzionas dataset root, and what their files are."""


def _sort_companions(sorting: Sorting, listed: dict[str, set[str]], failed: dict[str, str]) -> None:
    for f in sorting.open_files():
        p = PurePosixPath(f)
        found = (
            _model_reason(p, sorting.base, listed, failed)
            if _MODEL_FILE.fullmatch(p.name)
            else _config_reason(p, sorting.base)
        )
        if found is None and len(p.parts) >= 2 and _is_root(p.parent.parent, sorting.base):
            what = _ROOT_FOLDERS.get(p.parent.name)
            found = None if what is None else (True, what)
        if found is not None:
            companion, reason = found
            (sorting.companions if companion else sorting.unknown)[f] = reason


def _sort_files(sorting: Sorting) -> None:
    listed, failed = _sort_sequences(sorting)
    _sort_companions(sorting, listed, failed)


KIND = TrialKind(
    name="tzionas",
    label="a Tzionas sequence",
    files="Tzionas/Ballan hand motion Model_Hand_*.MOTION (or its Models/NN folder), with the sequence's "
    "Configs/NN/MODELS_INFO.txt",
    options=frozenset({"skeleton", "density", "mass", "collision"}),
    brings="it brings its own hand and objects (Configs/NN/MODELS_INFO.txt)",
    matches=_matches,
    find=_find,
    load=_load,
    sort_files=_sort_files,
)
"""The ``tzionas`` kind of trial."""
