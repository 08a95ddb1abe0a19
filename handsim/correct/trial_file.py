"""Writing a corrected trial (``NAME.corrected.npz``; the format is :mod:`handsim.io.corrected`'s).

The archive is built byte for byte the same from the same correction: its members in a fixed order, each
stamped with the same date (1980-01-01, the earliest a zip can hold), stored uncompressed, with no time of
writing anywhere in it. So the same trial corrected with the same seed gives a bitwise identical file.
"""

from __future__ import annotations

import io
import json
import math
import zipfile
from pathlib import Path
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from handsim.correct.score import frame_sizes
from handsim.files import write_atomic
from handsim.io.corrected import ARRAYS, FORMAT, SUFFIX, VERSION
from handsim.version import __version__

if TYPE_CHECKING:
    from handsim.correct.correction import Correction

_DATE = (1980, 1, 1, 0, 0, 0)


def corrected_header(correction: Correction) -> dict:
    """The header of a correction's file (JSON-ready): provenance, column names, the score."""
    reference, loaded = correction.reference, correction.loaded
    trajectory = loaded.trajectory
    return {
        "format": FORMAT,
        "version": VERSION,
        "source": {
            "trial": loaded.trial.to_dict(),
            "sha256": trajectory.sha256,
            "flags": [f.to_dict() for f in trajectory.flags],
        },
        "model_sha256": loaded.scene.model_sha256,
        "control_rate": 1.0 / reference.schedule.frame_dt,
        "substeps": reference.schedule.substeps,
        "dof_names": list(reference.resampled.dof_names),
        "hands": list(reference.welded),
        "objects": list(reference.resampled.objects),
        "method": {
            **correction.config.to_dict(),
            "planning_steps": correction.plan.planning_steps,
            "rollouts": correction.plan.rollouts,
            "rollout_steps": correction.plan.steps,
        },
        "backend": correction.backend,
        "versions": {
            "handsim": __version__,
            "mujoco": mujoco.__version__,
            "numpy": np.__version__,
            **_backend_versions(correction.backend),
        },
        "score": _finite(correction.score.to_dict()),
    }


def corrected_arrays(correction: Correction) -> dict[str, np.ndarray]:
    """The arrays of a correction's file (:data:`handsim.io.corrected.ARRAYS`)."""
    reference, plan = correction.reference, correction.plan
    recorded, corrected = reference.resampled, plan.trajectory
    frames = reference.frames
    names = list(recorded.objects)
    layout = reference.scene.layout
    world_index = {track: i for i, track in enumerate(reference.scene.setup.object_tracks) if track}
    simulated = np.zeros((frames, len(names), 7))
    for i, name in enumerate(names):
        if name in world_index:
            adr = layout.objects[world_index[name]].free_qpos
            simulated[:, i] = plan.qpos[:, adr : adr + 7]
        else:
            simulated[:, i] = np.nan
    sizes = frame_sizes(reference, plan.residual)
    tracks = [recorded.objects[n] for n in names]
    return {
        "times": np.asarray(corrected.times, dtype=float),
        "targets": np.asarray(corrected.targets, dtype=float),
        "recorded_targets": np.asarray(recorded.targets, dtype=float),
        "valid": np.asarray(recorded.valid, dtype=bool),
        "root_pose": _roots(corrected, reference.welded),
        "recorded_root_pose": _roots(recorded, reference.welded),
        "object_pose": _stack([np.asarray(t.pose, dtype=float) for t in tracks], (frames, 0, 7), float),
        "object_valid": _stack(
            [np.ones(frames, bool) if t.valid is None else np.asarray(t.valid, bool) for t in tracks],
            (frames, 0),
            bool,
        ),
        "object_articulation": _stack(
            [
                np.full(frames, np.nan) if t.articulation is None else np.asarray(t.articulation, float)
                for t in tracks
            ],
            (frames, 0),
            float,
        ),
        "simulated_qpos": plan.qpos,
        "simulated_object_pose": simulated,
        "finger_correction_rms": sizes.finger_rms,
        "finger_correction_max": sizes.finger_max,
        "wrist_position_correction": _hands(sizes.wrist_position, frames, len(reference.welded)),
        "wrist_rotation_correction": _hands(sizes.wrist_rotation, frames, len(reference.welded)),
    }


def corrected_bytes(correction: Correction) -> bytes:
    """The file's bytes: the header and :func:`corrected_arrays` as a deterministic ``.npz`` archive."""
    header = json.dumps(corrected_header(correction), sort_keys=True, allow_nan=False).encode("utf-8")
    values = corrected_arrays(correction)
    arrays = {"header": np.frombuffer(header, dtype=np.uint8), **{name: values[name] for name in ARRAYS}}
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_STORED) as archive:
        for name, value in arrays.items():
            member = io.BytesIO()
            np.lib.format.write_array(member, np.ascontiguousarray(value), allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_DATE)
            info.external_attr = 0o644 << 16
            archive.writestr(info, member.getvalue())
    return buffer.getvalue()


def write_corrected(path: str | Path, correction: Correction) -> Path:
    """Write a correction as a corrected trial (atomically).

    Args:
        path: The file; its name must end in ``.corrected.npz`` (how ``handsim replay`` knows it).
        correction: The correction.

    Raises:
        ValueError: The name does not end in ``.corrected.npz``.
        OSError: The file cannot be written.
    """
    target = Path(path)
    if not target.name.lower().endswith(SUFFIX):
        raise ValueError(f"{target}: a corrected trial's name ends in {SUFFIX!r}")
    return write_atomic(target, corrected_bytes(correction))


def _roots(trajectory, hands: tuple[str, ...]) -> np.ndarray:
    frames = trajectory.times.shape[0]
    if not hands:
        return np.zeros((frames, 0, 7))
    if hands == ("",):
        return np.asarray(trajectory.root_pose, dtype=float)[:, None]
    return np.stack([np.asarray(trajectory.hand_roots[h], dtype=float) for h in hands], axis=1)


def _stack(columns: list[np.ndarray], empty: tuple[int, ...], dtype: type) -> np.ndarray:
    """Per-object columns side by side (F, O, …); an empty array of shape ``empty`` without objects."""
    return np.stack(columns, axis=1).astype(dtype, copy=False) if columns else np.zeros(empty, dtype=dtype)


def _hands(values: np.ndarray, frames: int, hands: int) -> np.ndarray:
    """Per-hand wrist sizes (F, H): zeros where the wrist was not corrected."""
    return values if values.shape[1] == hands else np.zeros((frames, hands))


def _finite(value):
    """JSON-ready: infinities and NaN as None (the header is strict JSON)."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _backend_versions(backend: str) -> dict[str, str]:
    """The versions of an optional rollout backend's packages (MuJoCo Warp's), for the provenance."""
    if backend != "warp":
        return {}
    from importlib.metadata import version

    return {"mujoco_warp": version("mujoco-warp"), "warp": version("warp-lang")}
