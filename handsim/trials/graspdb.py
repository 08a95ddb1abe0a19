"""Trial kind ``graspdb``: a GraspDB14 CyberGlove recording.

A recording is a ``.txt`` file (GraspDB14's FK-oracle files have no extension). The hand is the parametric
default hand unless a skeleton is given; the object is the one given, else the one whose id the file name
carries (``r_01_11_ex03-…`` → id 1, the tennis ball); phases come from the
recording's ``_annot-`` file beside it when it covers exactly the recording's frames
(:func:`handsim.io.graspdb.annotations.match_annotation`), else from the finger flexion (scenario ``glove``).
Single-sample spikes are marked invalid and filled before the recording is judged
(:func:`handsim.glove.checks.check_recording`).
"""

from __future__ import annotations

from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from handsim.builders import build_hand, default_skeleton
from handsim.builders.graspdb_objects import GRASPDB_OBJECTS, graspdb_object
from handsim.errors import HandsimError
from handsim.glove import apply_thumb_rest, thumb_rest_note
from handsim.glove.checks import check_recording
from handsim.glove.phases import AnnotationMatch
from handsim.io import read_skeleton, read_trajectory
from handsim.io.graspdb.annotations import check_annotation, find_annotation_file, match_annotation
from handsim.io.graspdb.calibration import load_calibration
from handsim.io.graspdb.default_skeleton import DEFAULT_HAND_LENGTH_M
from handsim.io.graspdb.filenames import filename_datatype, parse_graspdb_filename
from handsim.io.graspdb.glove import graspdb_row_count
from handsim.trials.base import LoadedTrial, Trial, TrialError, TrialObject, UnsupportedTrialError
from handsim.trials.episodes import add_episodes
from handsim.trials.glove import glove_loaded, parametric_hand
from handsim.trials.graspdb_names import graspdb_meta
from handsim.trials.kind import TrialKind
from handsim.trials.options import TrialOptions
from handsim.trials.sorting import Sorting, TrialEntry, TrialInput, trial_input

if TYPE_CHECKING:
    from handsim.datatypes.skeleton import Skeleton
    from handsim.datatypes.trajectory import Trajectory
    from handsim.glove.checks import RecordingChecks
    from handsim.sim.specs import MetricSpec

_NAME_HELP = "spec 003 §4.1.2: <objID>[_<graspID>|_<actionID>]_ex<NN>-rad|raw-<trialID>-grasp-su<actorID>.txt"


_CALIBRATION = {
    "raw": (
        "calibration sequence (use `handsim calibrate`): CyberGlove raw counts; the calibration estimated "
        "from it replays -raw- recordings"
    ),
    "rad": (
        "calibration sequence, in radians (already calibrated): not read; `handsim calibrate` takes the "
        "raw-count sequence, and -rad- recordings need none"
    ),
    None: (
        "calibration sequence (use `handsim calibrate` if it holds raw counts; its name says neither -rad- "
        "nor -raw-, and reading it refuses angles)"
    ),
}
"""What a ``_calib-`` file is, by the data type its name says (``filename_datatype``)."""
_RAW_ALONE = (
    "raw sensor counts without their -rad- twin: a dataset run has no glove calibration to turn them into "
    "angles; replay it alone with handsim replay FILE --calibration CAL.json"
)


def _matches(path: Path) -> bool:
    if path.is_dir() or not (path.suffix.lower() == ".txt" or path.suffix == ""):
        return False
    if "_annot-" in path.name:
        raise UnsupportedTrialError(
            f"{path}: a GraspDB14 phase annotation file, not a recording; give the recording it annotates "
            "(found beside it by name)"
        )
    return True


def _find(path: Path, options: TrialOptions) -> Trial:
    if options.skeleton is not None and options.hand_length is not None:
        raise TrialError(
            "a hand length is for the parametric default hand; the skeleton gives the hand's size"
        )
    notes = []
    if options.obj is not None:
        objects = (TrialObject(str(options.obj), "", "given"),)
    else:
        name = parse_graspdb_filename(path)
        if name is None:
            raise TrialError(
                f"{path.name}: the file name carries no GraspDB14 object id (<objID>_…_ex<NN>-rad-…); give "
                "the object: a catalogue name (see `handsim catalog`) or a mesh file"
            )
        entry = graspdb_object(name.object_id)
        objects = (TrialObject(entry.name, "", f"object id {name.object_id} in the file name"),)
        notes.append(f"object {entry.name!r}: id {name.object_id} in the file name ({entry.description})")
    frames = graspdb_row_count(path) if find_annotation_file(path) is not None else 0
    match = match_annotation(path, frames)
    annotation = match.path
    notes.append(match.note)
    return Trial(
        kind="graspdb",
        trajectory_path=str(path),
        skeleton_path=None if options.skeleton is None else str(options.skeleton),
        objects=objects,
        calibration_path=None if options.calibration is None else str(options.calibration),
        annotation_path=None if annotation is None else str(annotation),
        units=options.units,
        density=options.density,
        mass=options.mass,
        hand_length=DEFAULT_HAND_LENGTH_M if options.hand_length is None else float(options.hand_length),
        collision=options.collision or "capsules",
        thumb_rest=options.thumb_rest,
        notes=tuple(notes),
    )


def _skeleton(trial: Trial) -> Skeleton:
    """The trial's hand skeleton: its skeleton file's, else the parametric default hand's."""
    if trial.skeleton_path is None:
        return default_skeleton(trial.hand_length)
    return read_skeleton(trial.skeleton_path)


def _load(trial: Trial, metrics: MetricSpec | None, progress: bool) -> LoadedTrial:
    skeleton = _skeleton(trial)
    if trial.skeleton_path is None:
        _, hand, hand_text = parametric_hand(trial, skeleton)
    else:
        hand = build_hand(skeleton, collision=trial.collision)
        hand_text = f"{Path(trial.skeleton_path).name} ({skeleton.ndof} DoFs, {trial.collision})"
    trajectory, notes, checks = _recording(trial, skeleton)
    return glove_loaded(trial, hand, hand_text, trajectory, metrics, progress, tuple(notes), checks)


def _read(trial: Trial) -> Trajectory:
    """The recording as the trial replays it, without building its scene (its grasp episodes' source)."""
    return _recording(trial, _skeleton(trial))[0]


def _recording(trial: Trial, skeleton: Skeleton) -> tuple[Trajectory, list[str], RecordingChecks]:
    """The recording as joint targets of ``skeleton``, checked, with its phases; the notes; the checks."""
    calibration = None if trial.calibration_path is None else load_calibration(trial.calibration_path)
    trajectory = read_trajectory(trial.trajectory_path, skeleton=skeleton, calibration=calibration)
    if trial.annotation_path is None:
        given = _no_annotation(trial, trajectory.nframes)
    else:
        given = check_annotation(trial.annotation_path, trial.trajectory_path, trajectory.nframes)
    trajectory, checks = check_recording(trajectory, given)
    notes = [*(skeleton.notes if trial.skeleton_path else ())]
    if given.note not in trial.notes:
        notes.append(given.note)
    if checks.spikes:
        notes.append(f"recording checks: {checks.spike_text()}")
    if trial.thumb_rest is not None:
        trajectory = apply_thumb_rest(trajectory, skeleton, *trial.thumb_rest)
        notes.append(thumb_rest_note(*trial.thumb_rest))
    return trajectory, notes, checks


def _no_annotation(trial: Trial, frames: int) -> AnnotationMatch:
    """Why a trial that names no annotation uses none (what :func:`_find` found, or that it names none)."""
    match = match_annotation(trial.trajectory_path, frames)
    if match.path is None:
        return match
    return AnnotationMatch(
        None,
        f"no phase annotation: the trial names none (although {match.path.name} beside the recording would "
        "fit); the grasp phase is found from the finger flexion",
    )


def _inputs(trial: Trial, base: Path) -> tuple[TrialInput, ...]:
    inputs = [trial_input("trajectory", trial.trajectory_path, base)]
    for role, path in (
        ("annotation", trial.annotation_path),
        ("calibration", trial.calibration_path),
        ("skeleton", trial.skeleton_path),
    ):
        if path is not None:
            inputs.append(trial_input(role, path, base))
    inputs += [trial_input("object", o.what, base) for o in trial.objects if Path(o.what).is_file()]
    return tuple(inputs)


def _sort_files(sorting: Sorting) -> None:
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
            sorting.companions[f] = _CALIBRATION[filename_datatype(p.name)]
            continue
        image = _camera_file(p, present)
        if image is not None:
            sorting.companions[f] = image
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
        if parsed.datatype == "raw":
            sorting.companions[f] = _RAW_ALONE
            continue
        try:
            trial = _find(sorting.base / p, TrialOptions())
        except HandsimError as exc:
            sorting.unknown[f] = f"a GraspDB14 recording name, but not a trial: {exc}"
            continue
        meta = graspdb_meta(parsed, names.get(parsed.object_id))
        add_episodes(sorting, TrialEntry(f, trial, meta, _inputs(trial, sorting.base)), _read)
    for f in annotations:
        if f in sorting.claimed:
            continue
        recording = _annotated(f, open_files, sorting.base)
        if recording is None:
            sorting.unknown[f] = (
                "a GraspDB14 phase annotation file, not a recording; no recording of the dataset uses it "
                "(the one it annotates is not in the dataset, or covers another number of frames: that "
                "trial's notes say so)"
            )
        else:
            sorting.companions[f] = (
                f"GraspDB14 phase annotation of {recording}, which is not replayed (its entry says why)"
            )


def _annotated(annotation: str, files: list[str], base: Path) -> str | None:
    """The recording among ``files`` (beside ``annotation``) whose phase annotation it is, or None."""
    folder = PurePosixPath(annotation).parent
    for f in files:
        p = PurePosixPath(f)
        parsed = parse_graspdb_filename(p.name)
        if p.parent != folder or parsed is None or parsed.annotation:
            continue
        found = find_annotation_file(base / p)
        if found is not None and found.name == PurePosixPath(annotation).name:
            return f
    return None


def _camera_file(path: PurePosixPath, present: set[str]) -> str | None:
    """What a GraspDB14 camera calibration file or hand image is (spec 003 §4.1.1, §4.2.1), or None."""
    name = path.name.lower()
    if name.endswith("-rect.xml"):
        return (
            "GraspDB14 camera calibration and hand measurements of a rectified hand image (spec 003 "
            "§4.1.1, §4.2.1): not read"
        )
    if name.endswith("-rect.jpg"):
        return "GraspDB14 rectified image of an actor's hand (spec 003 §4.1.1): not read"
    rectified = path.with_name(f"{path.stem}-rect{path.suffix}").as_posix()
    if path.suffix.lower() == ".jpg" and rectified in present:
        return f"GraspDB14 image of an actor's hand, rectified as {rectified} (spec 003 §4.1.1): not read"
    return None


def _explain_unknown(path: PurePosixPath) -> str | None:
    if path.suffix.lower() != ".txt":
        return None
    return (
        f"a .txt file whose name is not a GraspDB14 motion file name ({_NAME_HELP}) and that is not part of "
        "another dataset's layout"
    )


KIND = TrialKind(
    name="graspdb",
    label="a GraspDB14 recording",
    files="GraspDB14 CyberGlove recording .txt (radians; raw counts with a calibration)",
    options=frozenset(
        {
            "skeleton",
            "obj",
            "calibration",
            "units",
            "density",
            "mass",
            "hand_length",
            "collision",
            "thumb_rest",
        }
    ),
    brings="a glove recording takes the hand's skeleton, the object and the glove calibration",
    matches=_matches,
    find=_find,
    load=_load,
    sort_files=_sort_files,
    explain_unknown=_explain_unknown,
    read=_read,
)
"""The ``graspdb`` kind of trial."""
