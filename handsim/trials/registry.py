"""The one list of trial kinds, and what finds, loads and discovers trials through it.

Adding a kind is one module exposing a :class:`~handsim.trials.kind.TrialKind` and one entry in
:data:`KINDS`; no other kind changes.
"""

from __future__ import annotations

import dataclasses
import inspect
from pathlib import Path
from typing import TYPE_CHECKING, Any

from handsim.errors import InputFileError
from handsim.trials import arctic, corrected, graspdb, scripted, tzionas
from handsim.trials.base import LoadedTrial, Trial, TrialError, UnsupportedTrialError
from handsim.trials.discovery import Discovery, discover_with
from handsim.trials.episodes import recording_segmentation
from handsim.trials.kind import TrialKind
from handsim.trials.options import HAND_COLLISIONS, TrialOptions, given_options, option_names, option_spec

if TYPE_CHECKING:
    from handsim.glove.segmentation import GraspSegmentation
    from handsim.sim.replay import ReplayConfig, ReplayResult
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


def _keyword_signature() -> inspect.Signature:
    """:func:`find_trial`'s signature: the path, then each :class:`TrialOptions` field as a keyword."""
    keywords = [
        inspect.Parameter(f.name, inspect.Parameter.KEYWORD_ONLY, default=f.default, annotation=f.type)
        for f in dataclasses.fields(TrialOptions)
    ]
    path = inspect.Parameter("path", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation="str | Path")
    return inspect.Signature([path, *keywords], return_annotation="Trial")


def find_trial(path: str | Path, **options: Any) -> Trial:
    """Find the files of a trial from its recording, the options given as keywords.

    ``find_trial(path, obj="mug", mass=0.1)`` is ``find_with_options(path, TrialOptions(obj="mug",
    mass=0.1))``; its signature lists the keywords, which are :class:`TrialOptions`' fields.

    Args:
        path: A recording of one of :data:`TRIAL_KINDS` (see :func:`find_with_options`).
        **options: :class:`TrialOptions` fields by name (``skeleton``, ``obj`` … ``grasp``).

    Returns:
        The trial.

    Raises:
        TypeError: A keyword that is no trial option (the message lists them).
        HandsimError: As :func:`find_with_options`.
    """
    unknown = sorted(set(options) - set(option_names()))
    if unknown:
        raise TypeError(f"find_trial() got unknown option(s) {unknown}; expected {list(option_names())}")
    return find_with_options(path, TrialOptions(**options))


find_trial.__signature__ = _keyword_signature()  # type: ignore[attr-defined]


def find_with_options(path: str | Path, options: TrialOptions | None = None) -> Trial:
    """Find the files of a trial from its recording.

    Args:
        path: A recording of one of :data:`TRIAL_KINDS` (a GraspDB14 ``.txt``, a Tzionas
            ``Model_Hand_*.MOTION`` or its ``Models/NN`` folder, a scripted grasp ``NAME.grasp.json`` …).
        options: What the user gave besides the recording (each field's meaning: :class:`TrialOptions`);
            default none.

    Returns:
        The trial.

    Raises:
        InputFileError: ``path`` does not exist.
        UnsupportedTrialError: ``path`` is no kind of trial (the message lists the kinds).
        TrialError: An option that does not apply to the kind, or files the kind needs are missing.
        UnknownObjectError: The file name's object id (the scripted grasp's object) is not in the catalogue.
        FormatError: A scripted grasp that does not follow its format.
    """
    options = options or TrialOptions()
    if options.collision is not None and options.collision not in HAND_COLLISIONS:
        raise TrialError(
            f"unknown hand collision {options.collision!r}; expected one of {list(HAND_COLLISIONS)}"
        )
    if options.density is not None and options.mass is not None:
        raise TrialError("give an object density or a mass, not both")
    if options.thumb_rest is not None:
        rest = (float(options.thumb_rest[0]), float(options.thumb_rest[1]))
        options = dataclasses.replace(options, thumb_rest=rest)
    kind = kind_named(trial_kind(path))
    _check_applies(path, kind, options)
    trial = kind.find(Path(path), options)
    if options.grasp is not None:
        trial = dataclasses.replace(trial, grasp=options.grasp)
    return dataclasses.replace(trial, force=True) if options.force else trial


def _check_applies(path: str | Path, kind: TrialKind, options: TrialOptions) -> None:
    """Refuse an option the kind does not take, or a grasp episode that is no whole number ≥ 1."""
    for name in given_options(options):
        spec = option_spec(name)
        if spec.per_kind and name not in kind.options:
            raise TrialError(f"{path}: {spec.label} does not apply to {kind.label}; {kind.brings}")
    grasp = options.grasp
    if grasp is not None and kind.read is None:
        raise TrialError(
            f"{path}: a grasp episode does not apply to {kind.label}: only glove recordings hold them"
        )
    if grasp is not None and (isinstance(grasp, bool) or not isinstance(grasp, int) or grasp < 1):
        raise TrialError(
            f"{path}: a grasp episode is a whole number ≥ 1 (as `handsim inspect` lists them), got {grasp!r}"
        )


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
    return recording_segmentation(kind.read(trial))


def load_trial(
    trial: Trial | str | Path,
    *,
    metrics: MetricSpec | None = None,
    progress: bool = False,
    **options: Any,
) -> LoadedTrial:
    """Read a trial's files and build its scene.

    Args:
        trial: A :class:`~handsim.trials.base.Trial`, or a recording path (then ``options`` go to
            :func:`find_trial`).
        metrics: Thresholds of the glove placement search (default :class:`~handsim.sim.specs.MetricSpec`);
            replay with the same (:func:`replay_trial` checks).
        progress: Show a progress bar while an object's convex decomposition runs (uncached meshes).
        **options: :func:`find_trial`'s keyword arguments, with a path only.

    Returns:
        Scene and trajectory, ready for :func:`replay_trial`.

    Raises:
        HandsimError: A file is missing or malformed, the trajectory does not fit the hand, or the scene
            does not compile (the subclass and message say which).
    """
    if not isinstance(trial, Trial):
        trial = find_trial(trial, **options)
    elif options:
        raise TypeError(f"options {sorted(options)} are for a path; a Trial already holds them")
    return kind_named(trial.kind).load(trial, metrics, progress)


def check_metrics(loaded: LoadedTrial, metrics: MetricSpec) -> None:
    """Refuse to replay a trial with other thresholds than its scene was built with.

    A glove trial's scene is placed by the placement search with the thresholds :func:`load_trial` was
    given; its replay judges the hold with its :class:`~handsim.sim.replay.ReplayConfig`'s. Both must be
    the same spec, or the verdict mixes two definitions.

    Args:
        loaded: The loaded trial (:attr:`~handsim.trials.base.LoadedTrial.metrics`: None when its scene does
            not depend on the thresholds).
        metrics: The thresholds of the replay.

    Raises:
        TrialError: The two differ (the message names the parameters that do).
    """
    built = loaded.metrics
    if built is None or built == metrics:
        return
    have, want = _flat(built.to_dict()), _flat(metrics.to_dict())
    differ = [
        f"{k}: {have.get(k)!r} loaded, {want.get(k)!r} replayed"
        for k in sorted(have)
        if have.get(k) != want.get(k)
    ]
    raise TrialError(
        f"{loaded.trial.trajectory_path}: its scene was built with other metrics than it is replayed with "
        f"({'; '.join(differ) or 'the same values, another spec'}); load it with metrics=config.metrics"
    )


def _flat(value: object, prefix: str = "") -> dict[str, object]:
    """A nested dict as one level, its keys joined by dots."""
    if not isinstance(value, dict):
        return {prefix.rstrip("."): value}
    out: dict[str, object] = {}
    for key, item in value.items():
        out.update(_flat(item, f"{prefix}{key}."))
    return out


def replay_trial(loaded: LoadedTrial, config: ReplayConfig | None = None) -> ReplayResult:
    """Replay a loaded trial (:func:`handsim.sim.replay.replay`) with the thresholds it was loaded with.

    Args:
        loaded: The trial, from :func:`load_trial` with ``metrics=config.metrics``.
        config: Replay parameters (default :class:`~handsim.sim.replay.ReplayConfig`).

    Returns:
        The replay's result.

    Raises:
        TrialError: ``config.metrics`` are not the thresholds the trial's scene was built with
            (:func:`check_metrics`).
        HandsimError: As :func:`handsim.sim.replay.replay`.
    """
    # lazy: the simulation stack, only when replaying
    from handsim.sim.replay import ReplayConfig, replay

    config = config or ReplayConfig()
    check_metrics(loaded, config.metrics)
    return replay(loaded.scene, loaded.trajectory, config)


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
