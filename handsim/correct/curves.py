"""A correction's per-frame curves, before and after: what a report plots for each corrected trial.

Per control frame: the objects' distance from their goal in pure replay (``before``) and in the corrected
replay (``after``) — the recorded track's pose, or for a glove scene the pose where the grasp placed the
object, over the frames the goal counts (NaN elsewhere) — and the correction's size (finger RMS and largest
value, wrist position and rotation). The arrays are full-length; a record strides and rounds them.
"""

from __future__ import annotations

import math

import numpy as np

from handsim.correct.reference import Reference
from handsim.correct.score import frame_sizes

CURVE_KEYS = ("time_s", "before_mm", "after_mm", "finger_rms_deg", "finger_max_deg", "wrist_mm", "wrist_deg")
"""The curves' names (units in the names)."""


def goal_distance(reference: Reference, states: np.ndarray | None) -> np.ndarray:
    """The largest distance of an object from its goal per frame, mm (F,); NaN where no goal counts.

    Args:
        reference: The recording and its goals (:attr:`Reference.objects`).
        states: ``qpos`` per frame of a replay (rows up to where it stopped), or None.
    """
    frames = reference.frames
    out = np.full(frames, np.nan)
    if states is None or not reference.objects:
        return out
    rows = min(states.shape[0], frames)
    counted = np.zeros(frames, bool)
    largest = np.zeros(frames)
    for obj in reference.objects:
        distance = np.linalg.norm(states[:rows, obj.qpos : obj.qpos + 3] - obj.pose[:rows, :3], axis=1)
        valid = np.asarray(obj.valid[:rows], bool)
        largest[:rows] = np.maximum(largest[:rows], np.where(valid, distance, 0.0))
        counted[:rows] |= valid
    out[counted] = largest[counted] * 1000.0
    return out


def correction_curves(reference: Reference, residual: np.ndarray, before, after) -> dict[str, np.ndarray]:
    """The curves of a correction (:data:`CURVE_KEYS`), full-length (F,).

    Args:
        reference: The recording.
        residual: The committed residuals (F, D).
        before: Pure replay (a :class:`~handsim.sim.replay.ReplayResult` kept with its states).
        after: The corrected replay.
    """
    sizes = frame_sizes(reference, residual)
    wrist = sizes.wrist_position.shape[1] > 0
    frames = reference.frames
    return {
        "time_s": np.asarray(reference.schedule.times, dtype=float),
        "before_mm": goal_distance(reference, before.states),
        "after_mm": goal_distance(reference, after.states),
        "finger_rms_deg": np.degrees(sizes.finger_rms),
        "finger_max_deg": np.degrees(sizes.finger_max),
        "wrist_mm": sizes.wrist_position.max(axis=1) * 1000.0 if wrist else np.full(frames, math.nan),
        "wrist_deg": np.degrees(sizes.wrist_rotation.max(axis=1)) if wrist else np.full(frames, math.nan),
    }


def goal_window(reference: Reference) -> tuple[float, float] | None:
    """A glove scene's hold frames as trajectory times (release, window end), s; None for recorded tracks."""
    goal = reference.goal
    if goal is None:
        return None
    frames = np.flatnonzero(goal.valid)
    times = reference.schedule.times
    return float(times[frames[0]]), float(times[frames[-1]])
