"""The one list of trial kinds, and what finds, loads and discovers trials through it.

Adding a kind is one module exposing a :class:`~handsim.trials.kind.TrialKind` and one entry in
:data:`KINDS`; no other kind changes.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

from handsim.errors import InputFileError
from handsim.trials import arctic, corrected, graspdb, scripted, tzionas
from handsim.trials.base import (
    HAND_COLLISIONS,
    OPTION_LABELS,
    LoadedTrial,
    Trial,
    TrialError,
    TrialOptions,
    UnsupportedTrialError,
)
from handsim.trials.discovery import Discovery, discover_with
from handsim.trials.kind import TrialKind

if TYPE_CHECKING:
    from handsim.glove.segmentation import GraspSegmentation
    from handsim.sim.specs import MetricSpec


def _load_source(trial: Trial, metrics: MetricSpec | None, progress: bool) -> LoadedTrial:
    """Load the trial a corrected trial was made from, by its own kind."""
    return kind_named(trial.kind).load(trial, metrics, progress)


KINDS: tuple[TrialKind, ...] = (
    tzionas.KIND,
    arctic.KIND,
    scripted.KIND,
    graspdb.KIND,
    corrected.corrected_kind(_load_source),
)
"""Every kind of trial, in the order discovery lets them claim a dataset's files."""
TRIAL_KINDS: dict[str, str] = {k.name: k.files for k in KINDS}
"""Kinds of trial and the files that make them."""


def kind_named(name: str) -> TrialKind:
    """The kind called ``name``.

    Raises:
        TrialError: No kind has that name (the message lists the kinds).
    """
    for kind in KINDS:
        if kind.name == name:
            return kind
    raise TrialError(f"unknown trial kind {name!r}; expected one of {list(TRIAL_KINDS)}")


def trial_kind(path: str | Path) -> str:
    """The kind of trial a file (or folder) is, from its name.

    Raises:
        InputFileError: The file does not exist.
        UnsupportedTrialError: No kind of trial handsim replays (the message lists the kinds).
    """
    p = Path(path)
    if not p.exists():
        raise InputFileError(f"{p}: file not found")
    for kind in KINDS:
        if kind.matches(p):
            return kind.name
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
    collision: str | None = None,
    thumb_rest: tuple[float, float] | None = None,
    force: bool = False,
    mano_dir: str | Path | None = None,
    templates: str | Path | None = None,
    grasp: int | None = None,
) -> Trial:
    """Find the files of a trial from its recording.

    Args:
        path: A recording of one of :data:`TRIAL_KINDS` (a GraspDB14 ``.txt``, a Tzionas
            ``Model_Hand_*.MOTION`` or its ``Models/NN`` folder, a scripted grasp ``NAME.grasp.json`` …).
        skeleton: GraspDB14: the hand's skeleton (``.xmlskel`` or ``.SKEL``); default the parametric
            hand. Tzionas: must be the motion's own ``.SKEL`` if given.
        obj: GraspDB14: the object (catalogue name or mesh file); default the object whose id the file
            name carries. Scripted grasp: default the file's object.
        calibration: GraspDB14 raw-count recording: its glove calibration JSON.
        units: A mesh-file object's units, ``"m"`` or ``"mm"``.
        density: Object density in kg/m³ instead of the objects' own.
        mass: Object mass in kg instead of the objects' own.
        hand_length: Parametric default hand's length, m (default 0.19; a scripted grasp's own); only
            without a skeleton.
        collision: Hand collision shapes: ``"capsules"`` (default) or ``"mesh"`` (skinned skeletons and
            MANO hands).
        mano_dir: ARCTIC: the folder with ``MANO_RIGHT.pkl`` and ``MANO_LEFT.pkl`` (default
            ``$HANDSIM_MANO_DIR``).
        templates: ARCTIC: a folder of object templates (``<object>/``) instead of the sequence's
            ``meta/object_vtemplates/``.
        thumb_rest: GraspDB14: ``(abduction, flexion)`` in degrees at which to hold the thumb TMC DoFs no
            glove sensor drives (default: left at 0, as the GraspDB14 tools do).
        force: Accept an object density or mass outside its documented range (every kind's objects).
        grasp: Glove recordings (GraspDB14, scripted grasps): replay this grasp episode (1-based, as
            :func:`grasp_episodes` and ``handsim inspect`` list them), the recording cut to it; None: the
            whole recording.

    Returns:
        The trial.

    Raises:
        InputFileError: ``path`` does not exist.
        UnsupportedTrialError: ``path`` is no kind of trial (the message lists the kinds).
        TrialError: An option that does not apply to the kind, or files the kind needs are missing.
        UnknownObjectError: The file name's object id (the scripted grasp's object) is not in the catalogue.
        FormatError: A scripted grasp that does not follow its format.
    """
    if collision is not None and collision not in HAND_COLLISIONS:
        raise TrialError(f"unknown hand collision {collision!r}; expected one of {list(HAND_COLLISIONS)}")
    if density is not None and mass is not None:
        raise TrialError("give an object density or a mass, not both")
    options = TrialOptions(
        skeleton=skeleton,
        obj=obj,
        calibration=calibration,
        units=units,
        density=density,
        mass=mass,
        hand_length=hand_length,
        collision=collision,
        thumb_rest=None if thumb_rest is None else (float(thumb_rest[0]), float(thumb_rest[1])),
        mano_dir=mano_dir,
        templates=templates,
    )
    kind = kind_named(trial_kind(path))
    for option in dataclasses.fields(TrialOptions):
        if getattr(options, option.name) is not None and option.name not in kind.options:
            raise TrialError(
                f"{path}: {OPTION_LABELS[option.name]} does not apply to {kind.label}; {kind.brings}"
            )
    if grasp is not None and kind.read is None:
        raise TrialError(
            f"{path}: a grasp episode does not apply to {kind.label}: only glove recordings hold them"
        )
    if grasp is not None and (isinstance(grasp, bool) or not isinstance(grasp, int) or grasp < 1):
        raise TrialError(
            f"{path}: a grasp episode is a whole number ≥ 1 (as `handsim inspect` lists them), got {grasp!r}"
        )
    trial = kind.find(Path(path), options)
    if grasp is not None:
        trial = dataclasses.replace(trial, grasp=grasp)
    return dataclasses.replace(trial, force=True) if force else trial


def grasp_episodes(trial: Trial) -> GraspSegmentation:
    """The grasp episodes of a glove trial's recording (read and checked as the trial replays it).

    Args:
        trial: A trial of a glove kind (GraspDB14, scripted grasp).

    Raises:
        TrialError: The trial's kind holds no grasp episodes (Tzionas, ARCTIC: one sequence each).
        HandsimError: The recording cannot be read (the subclass and message say why).
    """
    kind = kind_named(trial.kind)
    if kind.read is None:
        raise TrialError(
            f"{trial.trajectory_path}: {kind.label} is one sequence, not a glove recording of grasps"
        )
    from handsim.glove.segmentation import segment_grasps  # numpy only, but not at the CLI's start-up

    return segment_grasps(kind.read(trial))


def load_trial(
    trial: Trial | str | Path,
    *,
    metrics: MetricSpec | None = None,
    progress: bool = False,
    **options,
) -> LoadedTrial:
    """Read a trial's files and build its scene.

    Args:
        trial: A :class:`~handsim.trials.base.Trial`, or a recording path (then ``options`` go to
            :func:`find_trial`).
        metrics: Thresholds of the glove placement search (default :class:`~handsim.sim.specs.MetricSpec`);
            replay with the same.
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
    return kind_named(trial.kind).load(trial, metrics, progress)


def discover(dataset: str | Path, options: TrialOptions | None = None) -> Discovery:
    """List the trials of a dataset folder, or the one trial of a recording (every kind of :data:`KINDS`).

    Args:
        dataset: A dataset folder (GraspDB14 recordings, a Tzionas root with ``Models/`` and ``Configs/``,
            an ARCTIC root with ``raw_seqs/`` and ``meta/``, or a folder holding several of them), a
            Tzionas ``Models/NN`` folder, or a single recording.
        options: Options for the trials of the kinds that take them (``mano_dir`` for ARCTIC sequences);
            default none.

    Returns:
        The trials (sorted by id) and every other file (companion or unknown, each with its reason).

    Raises:
        InputFileError: ``dataset`` does not exist.
    """
    return discover_with(dataset, KINDS, options)
