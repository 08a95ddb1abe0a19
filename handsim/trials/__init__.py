"""Trials: a recording and the files beside it, as a scene and a trajectory to replay.

One module per kind of trial (:mod:`~handsim.trials.graspdb`, :mod:`~handsim.trials.tzionas`,
:mod:`~handsim.trials.scripted`, :mod:`~handsim.trials.arctic`), one registry of them
(:mod:`~handsim.trials.registry`) that :func:`find_trial`, :func:`load_trial`, dataset discovery
(:func:`discover`, :mod:`~handsim.trials.discovery`), the CLI and the runner use, and one list of the
options a user gives (:class:`TrialOptions`, :mod:`~handsim.trials.options`).

The names below are imported when first used: the command line reads :mod:`~handsim.trials.options` to
build its flags without loading the kinds (MuJoCo, the mesh tools) at start-up.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from handsim.trials.base import (
        LoadedObject,
        LoadedTrial,
        Trial,
        TrialError,
        TrialObject,
        UnsupportedTrialError,
    )
    from handsim.trials.discovery import Discovery, select
    from handsim.trials.kind import TrialKind
    from handsim.trials.options import HAND_COLLISIONS, TrialOptions
    from handsim.trials.registry import (
        KINDS,
        TRIAL_KINDS,
        discover,
        find_trial,
        find_with_options,
        kind_named,
        load_trial,
        replay_trial,
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
    "find_with_options",
    "kind_named",
    "load_trial",
    "replay_trial",
    "select",
    "trial_kind",
]

_MODULES = (
    "handsim.trials.options",
    "handsim.trials.base",
    "handsim.trials.kind",
    "handsim.trials.sorting",
    "handsim.trials.discovery",
    "handsim.trials.registry",
)
"""Where the names of :data:`__all__` are defined, the lightest first (the options need no MuJoCo)."""


def __getattr__(name: str) -> Any:
    """Import a public name of the package from its module on first use."""
    if name in __all__:
        for module in _MODULES:
            value = vars(importlib.import_module(module)).get(name)
            if value is not None:
                globals()[name] = value
                return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """The package's names, the ones not imported yet included."""
    return sorted([*globals(), *__all__])
