"""A trial from files: which recording, hand and objects, and the replayable scene they make.

Two steps, so that a dataset runner can list trials cheaply and load them in worker processes:

* :func:`find_trial` looks at the recording's name and the files beside it (no parsing of motion data)
  and returns a :class:`Trial`: plain paths and names, picklable.
* :func:`load_trial` reads the files, builds the hand and the objects and compiles the scenario's scene
  (:mod:`handsim.sim.scenarios`); its :class:`LoadedTrial` (scene + trajectory) is what
  :func:`handsim.sim.replay.replay` takes, and is picklable too.

Kinds of trial (:data:`TRIAL_KINDS`):

* ``tzionas`` — a Tzionas/Ballan ``Model_Hand_*.MOTION`` (or its ``Models/NN`` folder). The hand is its
  own ``.SKEL`` (+ ``.LIMITS``, ``.OFF``, ``.SKIN`` beside it); the objects are the ``Model_Object_*`` that
  ``Configs/NN/MODELS_INFO.txt`` lists, each following its recorded track (scenario ``recorded``).
* ``graspdb`` — a GraspDB14 CyberGlove recording (``.txt``; GraspDB14's FK-oracle files have no
  extension). The hand is the parametric default hand unless a skeleton is given; the object is the one
  given, else the one whose id the file name carries (``r_01_11_ex03-…`` → id 1, the tennis ball); phases
  come from the ``_annot-`` file beside it (scenario ``glove``).
* ``scripted`` — a synthetic scripted grasp ``NAME.grasp.json`` (:mod:`handsim.io.scripted`): not a
  recording but a closing motion written for handsim. The hand is the parametric default hand of the
  file's ``hand_length``, the object the file's catalogue object unless one is given; its ``grasp`` phase
  is the hold (scenario ``glove``, as for GraspDB14).
"""

from __future__ import annotations

import dataclasses
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from handsim.builders.default_hand import DEFAULT_HAND_LENGTH_M
from handsim.errors import HandsimError, InputFileError
from handsim.sim.compiled import SimScene
from handsim.sim.metrics import MetricSpec
from handsim.trajectory import Trajectory

if TYPE_CHECKING:
    import mujoco

    from handsim.skeleton import Skeleton

TRIAL_KINDS = {
    "tzionas": "Tzionas/Ballan hand motion Model_Hand_*.MOTION (or its Models/NN folder), with the "
    "sequence's Configs/NN/MODELS_INFO.txt",
    "graspdb": "GraspDB14 CyberGlove recording .txt (radians; raw counts with a calibration)",
    "scripted": "handsim scripted grasp NAME.grasp.json (synthetic closing motion of the parametric hand)",
}
"""Kinds of trial and the files that make them."""
HAND_COLLISIONS = ("capsules", "mesh")


class TrialError(HandsimError):
    """The files and options given do not make a trial (an option that does not apply, no object …)."""


class UnsupportedTrialError(TrialError, InputFileError):
    """A file that is no kind of trial handsim replays; the message lists the kinds."""


@dataclass(frozen=True)
class TrialObject:
    """An object of a trial.

    Attributes:
        what: What :func:`handsim.builders.catalog.resolve` takes: a catalogue name, a mesh file, a
            Tzionas ``.SKEL`` or an ARCTIC template folder.
        track: The trajectory's object track it follows (``recorded`` scenario), or "" for none.
        origin: Where it came from, for people (``"given"``, ``"object id 1 in the file name"`` …).
    """

    what: str
    track: str = ""
    origin: str = "given"


@dataclass(frozen=True)
class Trial:
    """What to load for one trial: paths and names only (picklable, cheap).

    Attributes:
        kind: One of :data:`TRIAL_KINDS`.
        trajectory_path: The recording.
        skeleton_path: The hand's skeleton file, or None for the parametric default hand.
        objects: The objects, the first one defining the support (recorded) or being grasped (glove).
        calibration_path: Glove calibration JSON for a raw-count recording, or None.
        annotation_path: GraspDB14 phase annotation file, or None.
        units: Units of a mesh-file object, ``"m"`` or ``"mm"``.
        density: Object density in kg/m³ replacing the objects' own, or None.
        mass: Object mass in kg replacing the objects' own, or None.
        hand_length: Parametric default hand: wrist crease to middle fingertip, m.
        collision: Hand collision shapes, one of :data:`HAND_COLLISIONS`.
        notes: Decisions made while finding the files.
    """

    kind: str
    trajectory_path: str
    skeleton_path: str | None
    objects: tuple[TrialObject, ...]
    calibration_path: str | None = None
    annotation_path: str | None = None
    units: str | None = None
    density: float | None = None
    mass: float | None = None
    hand_length: float = DEFAULT_HAND_LENGTH_M
    collision: str = "capsules"
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        """JSON-ready fields (:meth:`from_dict` gives the trial back)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, fields: dict) -> Trial:
        """The trial whose :meth:`to_dict` gave ``fields`` (as read back from JSON).

        Raises:
            TrialError: ``fields`` are not a trial's (a field missing or unknown).
        """
        names = {f.name for f in dataclasses.fields(cls)}
        unknown, missing = (
            set(fields) - names,
            {"kind", "trajectory_path", "skeleton_path", "objects"} - set(fields),
        )
        if unknown or missing:
            raise TrialError(
                f"not a trial's fields: unknown {sorted(unknown)}, missing {sorted(missing)}; "
                f"expected {sorted(names)}"
            )
        values = dict(fields)
        values["objects"] = tuple(TrialObject(**o) for o in values["objects"])
        values["notes"] = tuple(values.get("notes", ()))
        return cls(**values)


@dataclass(frozen=True)
class LoadedObject:
    """An object as built for the scene.

    Attributes:
        name: The object model's name.
        source: The file or catalogue entry it was made from.
        track: The trajectory's object track it follows, or "".
        origin: Where it came from (:attr:`TrialObject.origin`).
        mass: Total mass, kg.
    """

    name: str
    source: str
    track: str
    origin: str
    mass: float


@dataclass(frozen=True)
class LoadedTrial:
    """A trial read and built: what :func:`handsim.sim.replay.replay` takes (picklable).

    Attributes:
        trial: What was loaded.
        scene: The compiled scene of the trial's scenario.
        trajectory: The recording as joint targets (with phases and object tracks).
        hand: The hand, for people (skeleton file or the parametric hand's size, DoFs).
        objects: The objects as built.
        notes: Decisions made while loading (the scene's own are in ``scene.setup.notes``, the
            trajectory reader's in ``trajectory.notes``).
    """

    trial: Trial
    scene: SimScene
    trajectory: Trajectory
    hand: str
    objects: tuple[LoadedObject, ...]
    notes: tuple[str, ...] = field(default=())


def trial_kind(path: str | Path) -> str:
    """The kind of trial a file (or folder) is, from its name.

    Raises:
        InputFileError: The file does not exist.
        UnsupportedTrialError: No kind of trial handsim replays (the message lists the kinds).
    """
    p = Path(path)
    if not p.exists():
        raise InputFileError(f"{p}: file not found")
    if p.is_dir():
        if any(p.glob("Model_Hand*.MOTION")):
            return "tzionas"
    elif p.suffix.lower() == ".motion":
        return "tzionas"
    elif p.name.lower().endswith(".grasp.json"):
        return "scripted"
    elif "_annot-" in p.name:
        raise UnsupportedTrialError(
            f"{p}: a GraspDB14 phase annotation file, not a recording; give the recording it annotates "
            "(found beside it by name)"
        )
    elif p.suffix.lower() == ".txt" or p.suffix == "":
        return "graspdb"
    kinds = "; ".join(f"{k}: {v}" for k, v in TRIAL_KINDS.items())
    what = "a folder without Model_Hand_*.MOTION" if p.is_dir() else f"file type {p.suffix!r}"
    raise UnsupportedTrialError(f"{p}: {what} is not a trial handsim replays; it replays {kinds}")


def find_trial(
    path: str | Path,
    *,
    skeleton: str | Path | None = None,
    obj: str | Path | None = None,
    calibration: str | Path | None = None,
    units: str | None = None,
    density: float | None = None,
    mass: float | None = None,
    hand_length: float | None = None,
    collision: str = "capsules",
) -> Trial:
    """Find the files of a trial from its recording.

    Args:
        path: A GraspDB14 recording, a Tzionas ``Model_Hand_*.MOTION`` or its ``Models/NN`` folder, or a
            synthetic scripted grasp ``NAME.grasp.json``.
        skeleton: GraspDB14: the hand's skeleton (``.xmlskel`` or ``.SKEL``); default the parametric
            hand. Tzionas: must be the motion's own ``.SKEL`` if given.
        obj: GraspDB14: the object (catalogue name or mesh file); default the object whose id the file
            name carries. Scripted grasp: default the file's object. Not for Tzionas sequences (their
            objects are in ``MODELS_INFO.txt``).
        calibration: GraspDB14 raw-count recording: its glove calibration JSON.
        units: A mesh-file object's units, ``"m"`` or ``"mm"``.
        density: Object density in kg/m³ instead of the objects' own.
        mass: Object mass in kg instead of the objects' own.
        hand_length: Parametric default hand's length, m (default 0.19; a scripted grasp's own); only
            without a skeleton.
        collision: Hand collision shapes: ``"capsules"`` or ``"mesh"`` (skinned skeletons only).

    Returns:
        The trial.

    Raises:
        InputFileError: ``path`` does not exist.
        UnsupportedTrialError: ``path`` is no kind of trial (the message lists the kinds).
        TrialError: An option that does not apply to the kind, no object to replay with, or a Tzionas
            sequence without its ``MODELS_INFO.txt``.
        UnknownObjectError: The file name's object id (the scripted grasp's object) is not in the catalogue.
        FormatError: A scripted grasp that does not follow its format.
    """
    if collision not in HAND_COLLISIONS:
        raise TrialError(f"unknown hand collision {collision!r}; expected one of {list(HAND_COLLISIONS)}")
    if density is not None and mass is not None:
        raise TrialError("give an object density or a mass, not both")
    kind = trial_kind(path)
    common = {"units": units, "density": density, "mass": mass, "collision": collision}
    if kind == "tzionas":
        refused = {"an object": obj, "a calibration": calibration, "a hand length": hand_length}
        for what, value in refused.items():
            if value is not None:
                raise TrialError(
                    f"{path}: {what} is for GraspDB14 recordings; a Tzionas sequence brings its own hand "
                    "and objects (Configs/NN/MODELS_INFO.txt)"
                )
        return _tzionas_trial(Path(path), skeleton, common)
    if kind == "scripted":
        refused = {"a skeleton": skeleton, "a calibration": calibration}
        for what, value in refused.items():
            if value is not None:
                raise TrialError(
                    f"{path}: {what} does not apply to a scripted grasp; it drives the parametric default "
                    "hand (give a hand length to resize it)"
                )
        return _scripted_trial(Path(path), obj, hand_length, common)
    return _graspdb_trial(Path(path), skeleton, obj, calibration, hand_length, common)


def _tzionas_trial(path: Path, skeleton: str | Path | None, common: dict) -> Trial:
    from handsim.io.tzionas_motion import config_dir_of, object_track_name, read_models_info

    models_dir = path if path.is_dir() else path.parent
    info = config_dir_of(models_dir) / "MODELS_INFO.txt"
    if not info.is_file():
        raise TrialError(
            f"{path}: no {info} beside the sequence's Models folder; it lists the sequence's objects, and a "
            "replay needs at least one object with a recorded track"
        )
    models = read_models_info(info)
    if path.is_dir():
        hands = [name for name, _ in models if name.startswith("Model_Hand")]
        if not hands:
            raise TrialError(f"{info}: lists no hand (Model_Hand_*); it lists {[n for n, _ in models]}")
        motion = models_dir / f"{hands[0]}.MOTION"
    else:
        motion = path
        if not motion.stem.startswith("Model_Hand"):
            raise TrialError(f"{motion}: not a hand motion; give the sequence's Model_Hand_*.MOTION")
    own = motion.with_suffix(".SKEL")
    if skeleton is not None and Path(skeleton).resolve() != own.resolve():
        raise TrialError(
            f"{motion}: a Tzionas motion drives its own skeleton {own.name}, not {skeleton}; a skeleton is "
            "given only for GraspDB14 recordings"
        )
    objects = tuple(
        TrialObject(str(models_dir / f"{name}.SKEL"), object_track_name(name), f"{info.name}:{line}")
        for name, line in models
        if name.startswith("Model_Object")
    )
    if not objects:
        raise TrialError(
            f"{info}: lists no object (Model_Object_*); a replay needs at least one object with a recorded "
            f"track; it lists {[n for n, _ in models]}"
        )
    return Trial(
        kind="tzionas",
        trajectory_path=str(motion),
        skeleton_path=str(own),
        objects=objects,
        notes=(f"hand {own.name} and objects {[o.track for o in objects]} from {info}",),
        **common,
    )


def _scripted_trial(path: Path, obj: str | Path | None, hand_length: float | None, common: dict) -> Trial:
    from handsim.builders import catalog
    from handsim.builders.graspdb_objects import UnknownObjectError
    from handsim.io.scripted import SYNTHETIC_NOTE, scripted_grasp_fields

    fields = scripted_grasp_fields(path)
    notes = [f"{SYNTHETIC_NOTE}: {path.name}"]
    if obj is not None:
        objects = (TrialObject(str(obj), "", "given"),)
    else:
        name = fields["object"]
        if name not in catalog.names():
            raise UnknownObjectError(
                f"{path} [object]: unknown object {name!r}; catalogue objects are: "
                f"{', '.join(sorted(catalog.names()))}"
            )
        objects = (TrialObject(name, "", "the scripted grasp's object"),)
        notes.append(f"object {name!r}: named in the scripted grasp")
    if hand_length is None:
        hand_length = fields["hand_length"]
    else:
        notes.append(
            f"hand length {hand_length:g} m given (the scripted grasp says {fields['hand_length']:g} m)"
        )
    return Trial(
        kind="scripted",
        trajectory_path=str(path),
        skeleton_path=None,
        objects=objects,
        hand_length=float(hand_length),
        notes=tuple(notes),
        **common,
    )


def _graspdb_trial(
    path: Path,
    skeleton: str | Path | None,
    obj: str | Path | None,
    calibration: str | Path | None,
    hand_length: float | None,
    common: dict,
) -> Trial:
    from handsim.builders.graspdb_objects import graspdb_object
    from handsim.glove.phases import find_annotation_file
    from handsim.io.graspdb import parse_graspdb_filename

    if skeleton is not None and hand_length is not None:
        raise TrialError(
            "a hand length is for the parametric default hand; the skeleton gives the hand's size"
        )
    notes = []
    if obj is not None:
        objects = (TrialObject(str(obj), "", "given"),)
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
    annotation = find_annotation_file(path)
    if annotation is None:
        notes.append("no _annot- phase file beside the recording: the grasp frame is the peak flexion")
    return Trial(
        kind="graspdb",
        trajectory_path=str(path),
        skeleton_path=None if skeleton is None else str(skeleton),
        objects=objects,
        calibration_path=None if calibration is None else str(calibration),
        annotation_path=None if annotation is None else str(annotation),
        hand_length=DEFAULT_HAND_LENGTH_M if hand_length is None else float(hand_length),
        notes=tuple(notes),
        **common,
    )


def load_trial(
    trial: Trial | str | Path,
    *,
    metrics: MetricSpec | None = None,
    progress: bool = False,
    **options,
) -> LoadedTrial:
    """Read a trial's files and build its scene.

    Args:
        trial: A :class:`Trial`, or a recording path (then ``options`` go to :func:`find_trial`).
        metrics: Thresholds of the glove placement search (default :class:`MetricSpec`); replay with the
            same.
        progress: Show a progress bar while an object's convex decomposition runs (uncached meshes).
        **options: :func:`find_trial`'s keyword arguments, with a path only.

    Returns:
        Scene and trajectory, ready for :func:`handsim.sim.replay.replay`.

    Raises:
        HandsimError: A file is missing or malformed, the trajectory does not fit the hand, or the scene
            does not compile (the subclass and message say which).
    """
    if not isinstance(trial, Trial):
        trial = find_trial(trial, **options)
    elif options:
        raise TypeError(f"options {sorted(options)} are for a path; a Trial already holds them")
    if trial.kind not in TRIAL_KINDS:
        raise TrialError(f"unknown trial kind {trial.kind!r}; expected one of {list(TRIAL_KINDS)}")
    if trial.kind == "tzionas":
        return _load_tzionas(trial, progress)
    if trial.kind == "scripted":
        return _load_scripted(trial, metrics, progress)
    return _load_graspdb(trial, metrics, progress)


def _build_objects(trial: Trial, progress: bool) -> tuple[list, tuple[LoadedObject, ...], list[str]]:
    from handsim.builders.catalog import resolve
    from handsim.builders.objects import object_spec, prepare_object

    specs, loaded, notes = [], [], []
    for item in trial.objects:
        model = resolve(item.what, units=trial.units, density=trial.density, mass=trial.mass)
        prepared = prepare_object(model, progress=progress)
        specs.append(object_spec(prepared))
        loaded.append(LoadedObject(model.name, model.source, item.track, item.origin, prepared.total_mass))
        notes.extend(f"object {model.name!r}: {n}" for n in (*model.notes, *prepared.notes))
    return specs, tuple(loaded), notes


def _load_tzionas(trial: Trial, progress: bool) -> LoadedTrial:
    from handsim.builders import build_hand
    from handsim.io import read_skeleton, read_trajectory
    from handsim.sim.scenarios import recorded_scene

    trajectory = read_trajectory(trial.trajectory_path)
    skeleton = read_skeleton(trial.skeleton_path)
    hand = build_hand(skeleton, collision=trial.collision)
    specs, objects, notes = _build_objects(trial, progress)
    scene = recorded_scene(hand, trajectory, {o.track: s for o, s in zip(objects, specs, strict=True)})
    return LoadedTrial(
        trial=trial,
        scene=scene,
        trajectory=trajectory,
        hand=f"{Path(skeleton.source).name} ({skeleton.ndof} DoFs, {trial.collision})",
        objects=objects,
        notes=(*trial.notes, *skeleton.notes, *notes),
    )


def _parametric_hand(trial: Trial) -> tuple[Skeleton, mujoco.MjSpec, str]:
    """The parametric default hand of the trial's length: skeleton, hand spec, text for people."""
    from handsim.builders import default_hand, default_skeleton

    skeleton = default_skeleton(trial.hand_length)
    hand = default_hand(trial.hand_length, collision=trial.collision)
    return skeleton, hand, f"parametric default hand, {trial.hand_length:g} m ({skeleton.ndof} DoFs)"


def _glove_loaded(
    trial: Trial,
    hand: mujoco.MjSpec,
    hand_text: str,
    trajectory: Trajectory,
    metrics: MetricSpec | None,
    progress: bool,
    notes: tuple[str, ...] = (),
) -> LoadedTrial:
    """The trial's object placed in the hand by the glove scenario, and the loaded trial."""
    from handsim.sim.scenarios import glove_scene

    specs, objects, object_notes = _build_objects(trial, progress)
    scene = glove_scene(hand, trajectory, specs[0], spec=metrics)
    return LoadedTrial(
        trial=trial,
        scene=scene,
        trajectory=trajectory,
        hand=hand_text,
        objects=objects,
        notes=(*trial.notes, *notes, *object_notes),
    )


def _load_graspdb(trial: Trial, metrics: MetricSpec | None, progress: bool) -> LoadedTrial:
    from handsim.builders import build_hand
    from handsim.glove import attach_phases, load_calibration
    from handsim.io import read_skeleton, read_trajectory

    if trial.skeleton_path is None:
        skeleton, hand, hand_text = _parametric_hand(trial)
    else:
        skeleton = read_skeleton(trial.skeleton_path)
        hand = build_hand(skeleton, collision=trial.collision)
        hand_text = f"{Path(trial.skeleton_path).name} ({skeleton.ndof} DoFs, {trial.collision})"
    calibration = None if trial.calibration_path is None else load_calibration(trial.calibration_path)
    trajectory = read_trajectory(trial.trajectory_path, skeleton=skeleton, calibration=calibration)
    if trial.annotation_path is not None and not trajectory.phases:
        trajectory = attach_phases(trajectory, trial.annotation_path)
    skeleton_notes = skeleton.notes if trial.skeleton_path else ()
    return _glove_loaded(trial, hand, hand_text, trajectory, metrics, progress, skeleton_notes)


def _load_scripted(trial: Trial, metrics: MetricSpec | None, progress: bool) -> LoadedTrial:
    from handsim.io.scripted import read_scripted_grasp

    skeleton, hand, hand_text = _parametric_hand(trial)
    trajectory = read_scripted_grasp(trial.trajectory_path, skeleton=skeleton)
    return _glove_loaded(trial, hand, hand_text, trajectory, metrics, progress)
