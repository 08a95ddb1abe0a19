"""The parts of a trial's record computed from a replay: curves, trajectory quality, inputs, versions.

Everything here is deterministic: the same inputs give bitwise the same JSON. Curves are sampled at a
uniform stride to at most :data:`MAX_CURVE_POINTS` points and rounded to :data:`CURVE_DIGITS` significant
digits (enough for plots; the summary keeps full precision).
"""

from __future__ import annotations

import math
import platform
from pathlib import Path

import mujoco
import numpy as np

from handsim.datatypes.fingers import finger_groups
from handsim.datatypes.trajectory import Trajectory
from handsim.files import sha256_file as file_digest
from handsim.glove.checks import CHECK_FIELDS, RecordingChecks
from handsim.sim.curves import CURVES, DEG, row_max, tracking_error
from handsim.sim.plausibility import limit_violations
from handsim.sim.replay import ReplayResult
from handsim.sim.scene.compiled import SimScene
from handsim.trials import TrialEntry
from handsim.version import __version__

MAX_CURVE_POINTS = 600
"""Most points per curve in a record."""
CURVE_DIGITS = 6
"""Significant digits of curve values."""


def versions() -> dict:
    """Versions that decide a record's numbers: handsim, MuJoCo, NumPy, Python and the platform."""
    return {
        "handsim": __version__,
        "mujoco": mujoco.__version__,
        "numpy": np.__version__,
        "python": platform.python_version(),
        "platform": platform.platform(),
    }


def sha256_file(path: str | Path) -> str | None:
    """SHA-256 of a file's bytes (hex), or None when it cannot be read."""
    try:
        return file_digest(path)
    except OSError:
        return None


def input_hashes(entry: TrialEntry) -> list[dict]:
    """The trial's input files with their role, dataset-relative path and SHA-256 (None if unreadable)."""
    return [{"role": i.role, "path": i.path, "sha256": sha256_file(i.file)} for i in entry.inputs]


def rounded(values: np.ndarray, scale: float = 1.0) -> list:
    """Values times ``scale`` rounded to :data:`CURVE_DIGITS` significant digits; NaN and ±inf as None."""
    out = []
    for v in (np.asarray(values, dtype=float) * scale).tolist():
        out.append(float(f"{v:.{CURVE_DIGITS}g}") if math.isfinite(v) else None)
    return out


def curve_indices(n: int, limit: int = MAX_CURVE_POINTS) -> np.ndarray:
    """Frame indices of a curve of ``n`` frames: every ``ceil(n / limit)``-th frame from frame 0."""
    stride = max(1, math.ceil(n / limit))
    return np.arange(0, n, stride)


def touching_links(result: ReplayResult) -> np.ndarray:
    """Per frame and hand link: the link touches some object part (N, links), bool."""
    count = result.frames.contact_count
    return count.sum(axis=2) > 0 if count.ndim == 3 and count.shape[2] else np.zeros(count.shape[:2], bool)


def curves(result: ReplayResult) -> dict:
    """The record's per-frame curves, strided to at most :data:`MAX_CURVE_POINTS` points.

    Returns:
        ``time_s``; ``penetration_mm`` (None without objects: not judged); ``contacts_per_finger`` (thumb,
        index, middle, ring, little, palm: how many of the group's links touch an object; per hand,
        ``right/thumb`` …, in a two-hand scene; empty without objects); ``drift_mm`` (recorded scenario: the
        largest object position error over the objects, else None); ``tracking_error_deg`` (RMS over the
        hand's DoFs of achieved minus target angle); ``self_penetration_mm`` (without objects: the simulated
        hand through itself, else None); ``stride`` (frames per point).
    """
    f = result.frames
    n = f.times.shape[0]
    idx = curve_indices(n)
    objects = f.object_in_hand.shape[1] > 0
    touching = touching_links(result)[idx]
    groups = finger_groups(result.scene["links"]) if objects else {}
    contacts = {g: touching[:, links].sum(axis=1).astype(int).tolist() for g, links in groups.items()}
    recorded = result.scene["scenario"] == "recorded" and f.object_position_error.shape[1]
    hand_only = None if objects else f.self_penetration[idx]

    def curve(name: str, values: np.ndarray | None) -> list | None:
        """A curve of handsim.sim.curves in its unit; None where it does not exist."""
        return None if values is None else rounded(values, CURVES[name].scale)

    return {
        "time_s": rounded(f.times[idx]),
        CURVES["penetration"].key: curve("penetration", f.penetration[idx] if objects else None),
        "contacts_per_finger": contacts,
        CURVES["drift"].key: curve("drift", row_max(f.object_position_error[idx]) if recorded else None),
        CURVES["tracking_error"].key: curve("tracking_error", tracking_error(f.tracking_error[idx])),
        CURVES["self_penetration"].key: curve("self_penetration", hand_only),
        "stride": int(idx[1] - idx[0]) if idx.size > 1 else 1,
    }


def recording_checks(checks: RecordingChecks | None, scene: SimScene) -> dict:
    """Which phase annotation and phase source a trial used, and the spikes its recording's checks filled.

    Args:
        checks: The recording's checks (:attr:`handsim.trials.LoadedTrial.checks`), or None when its kind
            is not checked.
        scene: The trial's scene; a glove scene's placement names the grasp frames' source.

    Returns:
        ``annotation`` (the annotation file used, or None), ``annotation_note`` (which file and why, or why
        none), ``phase_source`` (``"phase"``: the annotated grasp phase; ``"peak flexion"``: found from the
        finger flexion, :func:`handsim.sim.placement.grasp_frame.grasp_frame`; None without a grasp),
        ``spikes``
        (single-sample spikes filled), ``spike_frames``, ``spike_max_speed_rad_s``; the checks' keys are None
        when the recording was not checked.
    """
    grasp = (scene.setup.placement or {}).get("grasp") or {}
    found = checks.to_dict() if checks is not None else dict.fromkeys(CHECK_FIELDS)
    return {**found, "phase_source": grasp.get("source")}


def trajectory_quality(
    trajectory: Trajectory, scene: SimScene, checks: RecordingChecks | None = None
) -> dict:
    """How good the recording is as joint targets for the scene's hand.

    Args:
        trajectory: The recording as loaded.
        scene: The scene its hand is in; its actuators' control ranges are the hand's joint ranges.
        checks: The recording's checks (annotation, spikes), or None when its kind is not checked.

    Returns:
        ``frames``, ``duration_s``, ``limit_violations`` (valid target samples outside their joint's
        range), ``limit_violation_max_deg`` (the largest excess, 0 without violations), ``gaps_filled``
        (samples filled in by gap filling), ``filled_fraction`` (of all samples), ``invalid_samples``
        (samples still invalid, not filled), and :func:`recording_checks`' keys.
    """
    violations = limit_violations(trajectory, scene.layout).values()
    count = sum(n for n, _ in violations)
    worst = max((e for _, e in violations), default=0.0)
    valid = np.asarray(trajectory.valid, dtype=bool)
    filled = 0 if trajectory.filled is None else int(np.asarray(trajectory.filled).sum())
    times = np.asarray(trajectory.times, dtype=float)
    return {
        "frames": int(times.shape[0]),
        "duration_s": float(times[-1] - times[0]) if times.size else 0.0,
        "limit_violations": count,
        "limit_violation_max_deg": worst * DEG,
        "gaps_filled": filled,
        "filled_fraction": filled / valid.size if valid.size else 0.0,
        "invalid_samples": int((~valid).sum()),
        **recording_checks(checks, scene),
    }
