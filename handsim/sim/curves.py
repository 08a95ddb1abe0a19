"""The per-frame curves of a replay, each defined once, with its name and unit.

Records (:func:`handsim.runner.trial_record.curves`), the replay plots (:mod:`handsim.viz.replay_plots`), the
hold verdict (:func:`handsim.sim.summary.hold_outcome`) and the environments read these functions; nothing
recomputes a curve its own way. :data:`CURVES` names each curve as records and plots write it, with its
unit and the scale from SI.

The summary's scalars (``mean_tracking_error_deg`` …, :mod:`handsim.sim.summary`) are statistics of the
per-frame, per-DoF arrays of :class:`~handsim.sim.metrics.FrameMetrics`, not of these curves; their keys
carry their unit the same way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

MM = 1000.0
"""Millimetres per metre."""
DEG = 180.0 / math.pi
"""Degrees per radian."""


@dataclass(frozen=True)
class Curve:
    """How a per-frame curve is named and shown.

    Attributes:
        key: Its key in records and plot data, unit suffix included (``tracking_error_deg``).
        label: Axis or legend label, unit included.
        scale: Factor from the SI value (m, rad) to the unit of ``key``.
        definition: What one value is, for docs and report help.
    """

    key: str
    label: str
    scale: float
    definition: str


CURVES: dict[str, Curve] = {
    "penetration": Curve(
        "penetration_mm", "penetration (mm)", MM, "deepest hand–object penetration in the frame"
    ),
    "tracking_error": Curve(
        "tracking_error_deg",
        "tracking error RMS (°)",
        DEG,
        "RMS over the hand's DoFs of achieved minus target joint angle",
    ),
    "tip_error": Curve(
        "max_tip_error_mm",
        "worst fingertip (mm)",
        MM,
        "largest distance of a fingertip from where the targets put it",
    ),
    "drift": Curve(
        "drift_mm",
        "object drift (mm)",
        MM,
        "recorded scenario: the largest object position error against its recorded track",
    ),
    "slip": Curve(
        "slip_mm",
        "slip in hand (mm)",
        MM,
        "glove scenario: the object's displacement relative to the hand root since the release",
    ),
    "self_penetration": Curve(
        "self_penetration_mm",
        "hand through itself (mm)",
        MM,
        "hand-only sequence: the deepest penetration of the simulated hand through itself",
    ),
}
"""Every per-frame curve by name."""


def tracking_error(errors: npt.ArrayLike) -> np.ndarray:
    """RMS over the hand's DoFs of achieved minus target joint angle.

    Args:
        errors: Achieved minus target angle, rad (..., dofs): a frame's vector or frames × DoFs.

    Returns:
        The RMS over the last axis, rad (...); NaN where there is no DoF.
    """
    e = np.asarray(errors, dtype=float)
    if e.shape[-1] == 0:
        return np.full(e.shape[:-1], np.nan)
    return np.sqrt(np.mean(e * e, axis=-1))


def row_max(values: npt.ArrayLike) -> np.ndarray:
    """The largest finite value of each row (worst object's drift, worst fingertip).

    Args:
        values: Per frame and item (N, items), NaN where an item has no value.

    Returns:
        Each row's largest finite value (N,); NaN for a row with none (or no items).
    """
    x = np.asarray(values, dtype=float)
    if x.shape[1] == 0:
        return np.full(x.shape[0], np.nan)
    finite = np.isfinite(x)
    return np.where(finite.any(axis=1), np.where(finite, x, -np.inf).max(axis=1), np.nan)


def slip(object_in_hand: npt.ArrayLike, release_index: int) -> np.ndarray:
    """The object's displacement relative to the hand root since the release.

    Args:
        object_in_hand: The object's position in the hand root's frame per frame, m (N, 3).
        release_index: The first frame at or after the release.

    Returns:
        Distance from the release frame's position, m (N,); NaN before the release.
    """
    rel = np.asarray(object_in_hand, dtype=float)
    out = np.full(rel.shape[0], np.nan)
    if release_index < rel.shape[0]:
        out[release_index:] = np.linalg.norm(rel[release_index:] - rel[release_index], axis=1)
    return out
