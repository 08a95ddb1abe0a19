"""A whole Tzionas/Ballan sequence: its hands' trajectories with every object's pose track.

A sequence is a ``Models/NN`` folder whose ``Configs/NN/MODELS_INFO.txt`` lists its models
(:mod:`handsim.io.tzionas.configs`). :func:`read_tzionas_sequence` reads one hand with the objects,
:func:`read_tzionas_hands` both hands of a two-hand sequence; each hand and object motion is read by
:mod:`handsim.io.tzionas.motion` with the sequence's ``INDEX_BOUNDS.txt``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.datatypes.trajectory_ops import join_hands
from handsim.errors import InputFileError, TrajectoryError
from handsim.io.tzionas.configs import config_dir_of, read_models_info
from handsim.io.tzionas.motion import fit_tzionas_object_motion, read_tzionas_motion
from handsim.io.tzionas.skel import read_skel


def object_track_name(model: str) -> str:
    """Key of an object model in :attr:`Trajectory.objects` (``Model_Object_Cube`` → ``cube``).

    It equals the name :func:`~handsim.io.tzionas.objects.read_tzionas_object` gives the object model.
    """
    return model.removeprefix("Model_Object_").lower()


HAND_SIDES = {"Model_Hand_R": "right", "Model_Hand_L": "left"}
"""A two-hand sequence's hand models and the names of their hands in the scene (right first)."""


@dataclass(frozen=True)
class _Sequence:
    directory: Path
    info_path: Path
    models: tuple[tuple[str, int], ...]
    hands: list[tuple[str, int]]
    index_bounds: Path | None


def _sequence(models_dir: str | Path) -> _Sequence:
    directory = Path(models_dir)
    config = config_dir_of(directory)
    info_path = config / "MODELS_INFO.txt"
    models = read_models_info(info_path)
    hands = [(name, ln) for name, ln in models if name.startswith("Model_Hand")]
    bounds = config / "INDEX_BOUNDS.txt"
    return _Sequence(directory, info_path, models, hands, bounds if bounds.is_file() else None)


def _object_tracks(seq: _Sequence) -> tuple[dict[str, ObjectTrack], list[str]]:
    """Every listed object's track by :func:`object_track_name`, and notes (objects', unknown models')."""
    notes: list[str] = []
    objects: dict[str, ObjectTrack] = {}
    for model, ln in seq.models:
        if not model.startswith("Model_Object"):
            if not model.startswith("Model_Hand"):
                notes.append(
                    f"{seq.info_path.name}:{ln}: model {model!r} is neither a hand nor an object: ignored"
                )
            continue
        skel = _listed(seq.directory, model, seq.info_path, ln)
        track, fit = fit_tzionas_object_motion(skel, index_bounds=seq.index_bounds)
        key = object_track_name(model)
        objects[key] = track
        notes.extend(f"object {key!r}: {n}" for n in fit.notes)
    return objects, notes


def read_tzionas_sequence(
    models_dir: str | Path, *, hand: str | None = None, fps: float | None = None
) -> Trajectory:
    """Read a whole Tzionas/Ballan sequence: one hand's trajectory with every object's pose track.

    The models are those of ``Configs/NN/MODELS_INFO.txt`` (beside ``Models/NN``), the aligned frames those
    of ``Configs/NN/INDEX_BOUNDS.txt``. Other hands are ignored (noted); :func:`read_tzionas_hands` reads
    both hands of a two-hand sequence.

    Args:
        models_dir: The sequence's ``Models/NN`` folder.
        hand: The hand model to read (e.g. ``Model_Hand_L``); by default the first ``Model_Hand_*`` listed.
        fps: Frame rate in Hz; None assumes :data:`~handsim.io.tzionas.motion.DEFAULT_FPS`.

    Returns:
        The hand's trajectory (as :func:`~handsim.io.tzionas.motion.read_tzionas_motion`) with ``objects``
        keyed by :func:`object_track_name`; object notes are prefixed with the object's name.

    Raises:
        InputFileError: ``MODELS_INFO.txt`` or a listed model's file is missing or unreadable.
        FormatError: A file does not follow its format (file, line and field are named).
        TrajectoryError: No hand listed, or ``hand`` is not one of the listed hands.
        ValueError: ``fps`` is not a finite number > 0.
    """
    seq = _sequence(models_dir)
    hands, info_path = seq.hands, seq.info_path
    if not hands or (hand is not None and hand not in [h for h, _ in hands]):
        raise TrajectoryError(
            f"{info_path}: {'no hand model' if not hands else f'no hand {hand!r}'} (Model_Hand_*) listed; "
            f"it lists {[name for name, _ in seq.models]}"
        )
    name, line = next((h, ln) for h, ln in hands if hand in (None, h))
    trajectory = read_tzionas_motion(
        _listed(seq.directory, name, seq.info_path, line), fps=fps, index_bounds=seq.index_bounds
    )
    notes = list(trajectory.notes)
    others = [h for h, _ in hands if h != name]
    if others:
        notes.append(f"{seq.info_path.name} also lists {others}: ignored (a trajectory drives one hand)")
    objects, object_notes = _object_tracks(seq)
    return replace(trajectory, objects=objects, notes=(*notes, *object_notes))


def two_hand_models(info_path: Path, models: tuple[tuple[str, int], ...]) -> dict[str, str]:
    """The hands of a sequence listing two: scene name (``right``, ``left``) → model, right first.

    Args:
        info_path: The sequence's ``MODELS_INFO.txt`` (for messages).
        models: Its models (:func:`~handsim.io.tzionas.configs.read_models_info`).

    Returns:
        ``{"right": "Model_Hand_R", "left": "Model_Hand_L"}``.

    Raises:
        TrajectoryError: The hands listed are not exactly :data:`HAND_SIDES` (the message names the lines).
    """
    hands = [(name, ln) for name, ln in models if name.startswith("Model_Hand")]
    if sorted(name for name, _ in hands) != sorted(HAND_SIDES):
        listed = ", ".join(f"{name!r} (line {ln})" for name, ln in hands)
        raise TrajectoryError(
            f"{info_path}: lists the hands {listed}; a two-hand sequence lists exactly "
            f"{' and '.join(HAND_SIDES)}, one each"
        )
    return {side: model for model, side in HAND_SIDES.items()}


def read_tzionas_hands(models_dir: str | Path, *, fps: float | None = None) -> Trajectory:
    """Read a Tzionas/Ballan sequence with two hands: both hands' trajectories and every object's track.

    Each hand is read as :func:`~handsim.io.tzionas.motion.read_tzionas_motion` reads it (aligned frames
    from the sequence's ``INDEX_BOUNDS.txt``) and the two are joined
    (:func:`handsim.datatypes.trajectory_ops.join_hands`): DoF columns ``right/<dof>`` and ``left/<dof>``,
    root poses under ``hand_roots["right"]`` and ``["left"]``.

    Args:
        models_dir: The sequence's ``Models/NN`` folder; its ``Configs/NN/MODELS_INFO.txt`` lists
            ``Model_Hand_R`` and ``Model_Hand_L`` (:func:`two_hand_models`).
        fps: Frame rate in Hz; None assumes :data:`~handsim.io.tzionas.motion.DEFAULT_FPS`.

    Returns:
        The two-hand trajectory (``source`` the ``Models/NN`` folder, no ``sha256``: the run records hash
        each input file) with ``objects`` keyed by :func:`object_track_name`; each hand's notes are prefixed
        with its name, object notes with the object's.

    Raises:
        InputFileError: ``MODELS_INFO.txt`` or a listed model's file is missing or unreadable.
        FormatError: A file does not follow its format (file, line and field are named).
        TrajectoryError: The hands listed are not ``Model_Hand_R`` and ``Model_Hand_L``, or their motions
            have different frame counts (both files and counts are named).
        ValueError: ``fps`` is not a finite number > 0.
    """
    seq = _sequence(models_dir)
    models = two_hand_models(seq.info_path, seq.models)
    lines = dict(seq.hands)
    skels = {
        side: _listed(seq.directory, model, seq.info_path, lines[model]) for side, model in models.items()
    }
    frames = {side: read_skel(skel)[0] for side, skel in skels.items()}
    if len(set(frames.values())) > 1:
        counts = " and ".join(
            f"{skels[side].with_suffix('.MOTION')} has {n} frames ({skels[side].name}'s count)"
            for side, n in frames.items()
        )
        raise TrajectoryError(
            f"the two hands of sequence {seq.directory.name} must share their frames: {counts}"
        )
    parts = {
        side: read_tzionas_motion(skel, fps=fps, index_bounds=seq.index_bounds)
        for side, skel in skels.items()
    }
    objects, object_notes = _object_tracks(seq)
    joined = join_hands(parts, objects=objects, source=str(seq.directory), sha256="")
    return replace(joined, notes=(*joined.notes, *object_notes))


def _listed(directory: Path, model: str, info_path: Path, line: int) -> Path:
    skel = directory / f"{model}.SKEL"
    if not skel.is_file():
        raise InputFileError(f"{skel}: file not found; {info_path}:{line} lists model {model!r}")
    return skel
