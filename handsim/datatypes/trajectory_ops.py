"""Operations on whole trajectories, in one import: joint-limit reports, clamping, resampling, two hands.

The public names of :mod:`~handsim.datatypes.trajectory_limits` (:func:`limit_violations`,
:func:`with_limit_note`, :func:`clamp_to_limits`), :mod:`~handsim.datatypes.trajectory_resampling`
(:func:`resample`, :func:`uniform_times`) and :mod:`~handsim.datatypes.two_hand_trajectory`
(:func:`join_hands`); each module's docstring states its rules.
"""

from __future__ import annotations

from handsim.datatypes.trajectory_limits import (
    DofLimitViolation,
    LimitReport,
    clamp_to_limits,
    limit_violations,
    with_limit_note,
)
from handsim.datatypes.trajectory_resampling import (
    RESAMPLE_METHODS,
    ResampleMethod,
    ResampleResult,
    resample,
    uniform_times,
)
from handsim.datatypes.two_hand_trajectory import join_hands

__all__ = [
    "RESAMPLE_METHODS",
    "DofLimitViolation",
    "LimitReport",
    "ResampleMethod",
    "ResampleResult",
    "clamp_to_limits",
    "join_hands",
    "limit_violations",
    "resample",
    "uniform_times",
    "with_limit_note",
]
