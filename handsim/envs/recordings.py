"""Recordings chosen by keyword: ``gym.make("handsim/Replay-v0", trajectory=PATH_or_LIST, **trial_options)``.

A recording is any trial :func:`handsim.trials.find_trial` finds (a GraspDB14 ``.txt``, a Tzionas
``Models/NN`` folder or ``Model_Hand_*.MOTION``, an ARCTIC sequence, a scripted ``NAME.grasp.json``);
the trial options are :func:`~handsim.trials.find_trial`'s keywords (``skeleton``, ``obj`` — the CLI's
``--object`` —, ``calibration``, ``units``, ``density``, ``mass``, ``hand_length``, ``collision``,
``thumb_rest``, ``force``, ``mano_dir``, ``templates``). Each (recording, options) pair is read and its
scene built (placement search included) once per process: :func:`load_recording` caches the result, so
the N workers of a vector environment in one process, and every episode that samples a recording again,
share one build. Without recording paths an environment runs the scene and trajectory it is given, or
the bundled Tzionas sequence 20 (:func:`default_replay_inputs`); :func:`recordings_from_keywords` decides.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from handsim.assets import TZIONAS_DIR
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import HandsimError
from handsim.sim.scene.compiled import SimScene
from handsim.trials import load_trial
from handsim.trials.options import option_names

DEFAULT_SEQUENCE = ("Models", "20")
"""The bundled Tzionas sequence under :data:`handsim.assets.TZIONAS_DIR`."""
RecordingsArg = str | os.PathLike | Sequence[str | os.PathLike]


class RecordingError(HandsimError, ValueError):
    """A recording keyword of an environment is wrong (unknown option, empty list, a scene it cannot run)."""


def trial_option_names() -> tuple[str, ...]:
    """The trial option keywords an environment passes to :func:`handsim.trials.find_trial`."""
    return option_names()


_CACHE: dict[tuple, tuple[SimScene, Trajectory]] = {}


def _key(path: Path, options: dict[str, Any]) -> tuple:
    return (str(path.resolve()), tuple(sorted((k, repr(v)) for k, v in options.items())))


def check_trial_options(options: dict[str, Any], owner: str) -> None:
    """Refuse a keyword that is neither an environment's own nor a trial option.

    Args:
        options: The keywords left after the environment's own.
        owner: The environment's name, for the message.

    Raises:
        RecordingError: An unknown keyword (the message lists the trial options).
    """
    known = trial_option_names()
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise RecordingError(
            f"{owner}: unknown keyword(s) {unknown}; besides its own, it takes the trial options "
            f"{list(known)} (handsim.trials.find_trial)"
        )


def recording_paths(trajectory: str | os.PathLike | Sequence[str | os.PathLike]) -> tuple[Path, ...]:
    """The recording path(s) of a ``trajectory`` keyword: one path, or a non-empty list of them.

    Raises:
        RecordingError: An empty list, or an element that is not a path.
    """
    if isinstance(trajectory, (str, os.PathLike)):
        return (Path(trajectory),)
    paths = list(trajectory)
    if not paths:
        raise RecordingError("trajectory: an empty list of recordings; give at least one path")
    bad = [p for p in paths if not isinstance(p, (str, os.PathLike))]
    if bad:
        raise RecordingError(
            f"trajectory: a list of recording paths expected, got {type(bad[0]).__name__} {bad[0]!r}"
        )
    return tuple(Path(p) for p in paths)


def load_recording(path: str | os.PathLike, **options: Any) -> tuple[SimScene, Trajectory]:
    """The scene and trajectory of one recording, built once per process per (path, options).

    Args:
        path: A recording of any trial kind (:data:`handsim.trials.TRIAL_KINDS`).
        **options: :func:`handsim.trials.find_trial`'s keywords.

    Returns:
        The compiled scene (shared: environments copy its model) and the trajectory.

    Raises:
        InputFileError: The recording does not exist.
        UnsupportedTrialError: The path is no kind of trial.
        TrialError: An option that does not apply to the recording's kind, or missing files.
        RecordingError: The scene has two hands (the environments drive one).
        HandsimError: The recording or its scene cannot be built (the subclass says why).
    """
    p = Path(path)
    key = _key(p, options)
    if key not in _CACHE:
        loaded = load_trial(p, **options)
        hands = loaded.scene.layout.hands
        if len(hands) > 1:
            raise RecordingError(
                f"{p}: a scene with {len(hands)} hands ({[h.name for h in hands]}); the environments drive "
                "one hand's actuators with one action vector: replay it with `handsim replay` instead"
            )
        _CACHE[key] = (loaded.scene, loaded.trajectory)
    return _CACHE[key]


def cached_recordings() -> int:
    """How many (recording, options) builds this process holds."""
    return len(_CACHE)


@functools.lru_cache(maxsize=1)
def default_replay_inputs() -> tuple[SimScene, Trajectory]:
    """The default scene and trajectory, built once per process (about 2 s).

    Returns:
        The bundled Tzionas sequence 20 loaded as its trial loads it (:func:`handsim.trials.load_trial`:
        the hand of ``Model_Hand_R.SKEL`` with the fitted skin, the cube following its track) and its
        trajectory.
    """
    loaded = load_trial(TZIONAS_DIR.joinpath(*DEFAULT_SEQUENCE) / "Model_Hand_R.MOTION")
    return loaded.scene, loaded.trajectory


def recordings_from_keywords(
    scene: SimScene | None, trajectory: Trajectory | RecordingsArg | None, trial_options: dict[str, Any]
) -> tuple[tuple[SimScene, Trajectory], ...]:
    """The (scene, trajectory) pairs an environment samples from, from its ``scene``/``trajectory`` keywords.

    Args:
        scene: The environment's ``scene`` keyword.
        trajectory: Its ``trajectory`` keyword: a :class:`Trajectory`, recording path(s) or None.
        trial_options: The keywords left after the environment's own.

    Returns:
        One pair per recording, in the order given; the bundled default when neither is given.

    Raises:
        RecordingError: Unknown keywords, an empty list, trial options without recording paths, or a
            scene with recording paths.
        ValueError: Only one of ``scene`` and a :class:`Trajectory` is given.
    """
    check_trial_options(trial_options, "ReplayEnv")
    if trajectory is not None and not isinstance(trajectory, Trajectory):
        if scene is not None:
            raise RecordingError(
                "give a scene with a Trajectory, or recording paths without a scene (each recording builds "
                "its own)"
            )
        return tuple(load_recording(p, **trial_options) for p in recording_paths(trajectory))
    if trial_options:
        raise RecordingError(
            f"trial options {sorted(trial_options)} need recording paths: trajectory=PATH or a list of paths"
        )
    if scene is None and trajectory is None:
        return (default_replay_inputs(),)
    if scene is None or trajectory is None:
        raise ValueError(
            "pass both scene and trajectory, or neither for the bundled Tzionas sequence 20; "
            f"got scene={'None' if scene is None else 'a scene'}, "
            f"trajectory={'None' if trajectory is None else 'a trajectory'}"
        )
    return ((scene, trajectory),)
