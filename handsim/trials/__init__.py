"""Trials: a recording and the files beside it, as a scene and a trajectory to replay.

One module per kind of trial (:mod:`~handsim.trials.graspdb`, :mod:`~handsim.trials.tzionas`,
:mod:`~handsim.trials.scripted`, :mod:`~handsim.trials.arctic`), one registry of them
(:mod:`~handsim.trials.registry`) that :func:`find_trial`, :func:`load_trial`, dataset discovery
(:func:`discover`, :mod:`~handsim.trials.discovery`), the CLI and the runner use.
"""

from handsim.trials.base import (
    HAND_COLLISIONS,
    LoadedObject,
    LoadedTrial,
    Trial,
    TrialError,
    TrialObject,
    TrialOptions,
    UnsupportedTrialError,
)
from handsim.trials.discovery import Discovery, select
from handsim.trials.kind import TrialKind
from handsim.trials.registry import (
    KINDS,
    TRIAL_KINDS,
    discover,
    find_trial,
    kind_named,
    load_trial,
    trial_kind,
)
from handsim.trials.sorting import CompanionFile, TrialEntry, TrialInput, UnknownFile

__all__ = [
    "HAND_COLLISIONS",
    "KINDS",
    "TRIAL_KINDS",
    "CompanionFile",
    "Discovery",
    "LoadedObject",
    "LoadedTrial",
    "Trial",
    "TrialEntry",
    "TrialError",
    "TrialInput",
    "TrialKind",
    "TrialObject",
    "TrialOptions",
    "UnknownFile",
    "UnsupportedTrialError",
    "discover",
    "find_trial",
    "kind_named",
    "load_trial",
    "select",
    "trial_kind",
]
