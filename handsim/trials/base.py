"""What every kind of trial shares: the plain trial records, the errors, and the kind interface.

A trial is loaded in two steps, so that a dataset runner can list trials cheaply and load them in worker
processes:

* ``find`` looks at the recording's name and the files beside it (no parsing of motion data; a GraspDB14
  recording's rows are counted when a phase annotation lies beside it) and returns a :class:`Trial`: plain
  paths and names, picklable.
* ``load`` reads the files, builds the hand and the objects and compiles the scenario's scene; its
  :class:`LoadedTrial` (scene + trajectory) is what :func:`handsim.sim.replay.replay` takes, and is picklable
  too.

Each kind of trial is one module of :mod:`handsim.trials` exposing a :class:`TrialKind`; the registry
(:mod:`handsim.trials.registry`) is the one list of kinds that :func:`~handsim.trials.find_trial`, the CLI,
dataset discovery and the runner use.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

from handsim.builders.catalog import resolve
from handsim.builders.objects import object_spec, prepare_object
from handsim.errors import HandsimError, InputFileError
from handsim.io.graspdb.default_skeleton import DEFAULT_HAND_LENGTH_M
from handsim.trials.options import HAND_COLLISIONS, TrialOptions

if TYPE_CHECKING:
    from handsim.datatypes.object_model import ObjectModel
    from handsim.datatypes.trajectory import Trajectory
    from handsim.glove.checks import RecordingChecks
    from handsim.glove.segmentation import GraspEpisode
    from handsim.sim.scene.compiled import SimScene
    from handsim.sim.specs import MetricSpec

__all__ = [
    "HAND_COLLISIONS",
    "LoadedObject",
    "LoadedTrial",
    "Trial",
    "TrialError",
    "TrialObject",
    "TrialOptions",
    "UnsupportedTrialError",
    "build_objects",
]


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
        kind: The name of its :class:`TrialKind` (``graspdb``, ``tzionas`` …).
        trajectory_path: The recording.
        skeleton_path: The hand's skeleton file, or None for the kind's default hand.
        objects: The objects, the first one defining the support (recorded) or being grasped (glove); empty
            for a hand-only sequence.
        calibration_path: Glove calibration JSON for a raw-count recording, or None.
        annotation_path: GraspDB14 phase annotation file, or None.
        units: Units of a mesh-file object, ``"m"`` or ``"mm"``.
        density: Object density in kg/m³ replacing the objects' own, or None.
        mass: Object mass in kg replacing the objects' own, or None.
        hand_length: Parametric default hand: wrist crease to middle fingertip, m.
        collision: Hand collision shapes, one of :data:`HAND_COLLISIONS`.
        thumb_rest: Glove recordings: ``(abduction, flexion)`` in degrees of the thumb TMC DoFs no sensor
            drives, or None to leave them at the skeleton's rest pose (the GraspDB14 tools' choice).
        force: Accept an object density or mass outside its documented range
            (:mod:`handsim.datatypes.physical_ranges`).
        notes: Decisions made while finding the files.
        mano_dir: The folder with the user's ``MANO_RIGHT.pkl`` / ``MANO_LEFT.pkl`` (ARCTIC), or None.
        grasp: Glove recordings: the grasp episode replayed (1-based, in the order
            :func:`handsim.glove.segmentation.segment_grasps` lists them; ``handsim inspect`` prints them):
            the recording cut to it (:mod:`handsim.trials.episodes`). None: the whole recording, its grasp
            window around the highest flexion (or its annotated grasp phase).
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
    thumb_rest: tuple[float, float] | None = None
    force: bool = False
    notes: tuple[str, ...] = ()
    mano_dir: str | None = None
    grasp: int | None = None

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
        if values.get("thumb_rest") is not None:
            values["thumb_rest"] = tuple(values["thumb_rest"])
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
        checks: What the recording's checks found and did (phase annotation used, spikes filled:
            :class:`~handsim.glove.checks.RecordingChecks`), or None for a kind whose recordings are not
            checked.
        episode: The grasp episode replayed (:attr:`Trial.grasp`), its frames the recording's, or None.
        metrics: The thresholds its scene was built with (the glove placement search's), which its replay
            must use too (:func:`~handsim.trials.registry.replay_trial` checks); None for a kind whose scene
            does not depend on them.
    """

    trial: Trial
    scene: SimScene
    trajectory: Trajectory
    hand: str
    objects: tuple[LoadedObject, ...]
    notes: tuple[str, ...] = field(default=())
    checks: RecordingChecks | None = None
    episode: GraspEpisode | None = None
    metrics: MetricSpec | None = None


def build_objects(
    trial: Trial, progress: bool, models: Sequence[ObjectModel] | None = None
) -> tuple[list, tuple[LoadedObject, ...], list[str]]:
    """Build a trial's objects: their specs, what was built, and the builders' notes.

    Args:
        trial: The trial (its objects, units, density or mass).
        progress: Show a progress bar while an uncached convex decomposition runs.
        models: The object models of ``trial.objects`` when the kind made them itself (e.g. an ARCTIC
            object with its recorded hinge range); None: :func:`handsim.builders.catalog.resolve` each.
    """
    if models is None:
        models = [
            resolve(o.what, units=trial.units, density=trial.density, mass=trial.mass, force=trial.force)
            for o in trial.objects
        ]
    specs, loaded, notes = [], [], []
    for item, model in zip(trial.objects, models, strict=True):
        prepared = prepare_object(model, progress=progress, force=trial.force)
        specs.append(object_spec(prepared))
        loaded.append(LoadedObject(model.name, model.source, item.track, item.origin, prepared.total_mass))
        notes.extend(f"object {model.name!r}: {n}" for n in (*model.notes, *prepared.notes))
    return specs, tuple(loaded), notes
