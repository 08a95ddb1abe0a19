"""Reading and checking the ``.MOTION`` recording of a Tzionas/Ballan model, and its aligned rows.

Every rotation row is checked: ``max |RᵀR − I| >`` :data:`ROTATION_ERROR_TOL` or ``det R < 0`` is an error
naming bone, row and line; smaller deviations are removed by SVD and noted. Which rows are aligned frames
comes from the sequence's ``INDEX_BOUNDS.txt`` (:mod:`handsim.io.tzionas.motion` fits them to a skeleton).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.errors import FormatError, InputFileError
from handsim.io.text_files import numbered_lines, read_bytes, read_text, sha256_of
from handsim.io.tzionas.configs import IndexBounds, config_dir_of, read_index_bounds
from handsim.io.tzionas.motion_file import read_motion
from handsim.io.tzionas.skel import SkelBone

ROTATION_ERROR_TOL = 1e-3
"""Largest ``max |RᵀR − I|`` of a ``.MOTION`` rotation that is repaired; beyond it the row is an error."""


@dataclass(frozen=True)
class Recording:
    """A checked ``.MOTION``: orthonormal rotations (z, 3, 3) and origins (z, 3) in metres per bone."""

    path: Path
    sha256: str
    rotations: dict[str, np.ndarray]
    origins: dict[str, np.ndarray]
    notes: tuple[str, ...]


def _sibling(path: Path, ext: str) -> Path:
    """The file beside ``path`` with extension ``ext``: in the case of ``path``'s suffix, else the other."""
    upper, lower = path.with_suffix("." + ext.upper()), path.with_suffix("." + ext.lower())
    first, second = (lower, upper) if path.suffix.islower() else (upper, lower)
    return second if not first.is_file() and second.is_file() else first


def _row_line(path: Path, bone: str, row: int) -> int:
    """1-based line of row ``row`` of ``bone``'s block (the file is known to be well formed)."""
    lines = numbered_lines(read_text(path))
    start = next(i for i, (_, s) in enumerate(lines) if s == bone.strip())
    return lines[start + 1 + row][0]


def read_recording(skel: Path, frames: int, bones: list[SkelBone]) -> Recording:
    """The ``.MOTION`` beside ``skel``, every bone's rotations checked and re-orthonormalised.

    Raises:
        InputFileError: No ``.MOTION`` beside the ``.SKEL``.
        FormatError: A bone without a block, or a row that is no rotation (named by bone, row and line).
    """
    motion = _sibling(skel, "MOTION")
    if not motion.exists():
        raise InputFileError(f"{motion}: file not found; a motion needs the .MOTION beside the .SKEL {skel}")
    data = read_bytes(motion)
    blocks = read_motion(motion, [b.name for b in bones], frames)
    for b in bones:
        if b.name not in blocks:
            msg = f"no block for bone {b.name!r} ({skel}:{b.line}); expected one block per .SKEL bone"
            raise FormatError(motion, msg, field="bone name")
    rotations, origins, worst = {}, {}, 0.0
    for name, (r, t) in blocks.items():
        deviation = np.abs(np.einsum("kji,kjl->kil", r, r) - np.eye(3)).max(axis=(1, 2))
        det = np.linalg.det(r)
        bad = np.flatnonzero((deviation > ROTATION_ERROR_TOL) | ~np.isfinite(deviation) | (det <= 0))
        if len(bad):
            k = int(bad[0])
            what = (
                f"det R = {det[k]:.6g}, a reflection"
                if deviation[k] <= ROTATION_ERROR_TOL
                else f"max |RᵀR − I| = {deviation[k]:.3g} > {ROTATION_ERROR_TOL:g}"
            )
            msg = f"bone {name!r} row {k}: {what}; expected a rotation matrix (R row-major, then T)"
            raise FormatError(motion, msg, line=_row_line(motion, name, k), field="R")
        u, _, vt = np.linalg.svd(r)
        rotations[name], origins[name] = u @ vt, t
        worst = max(worst, float(deviation.max()))
    note = (
        f"{motion.name}: every R re-orthonormalised by SVD (max |RᵀR − I| {worst:.2g} ≤ "
        f"{ROTATION_ERROR_TOL:g}, the file's printing precision)"
    )
    return Recording(motion, sha256_of(data), rotations, origins, (note,) if worst > 1e-12 else ())


def aligned_bounds(
    skel: Path, frames: int, index_bounds: str | Path | None, motion: str
) -> tuple[IndexBounds, list[str]]:
    """INDEX_BOUNDS given or found from ``Models/NN``; defaults (all rows after the rigging pose) else."""
    path = Path(index_bounds) if index_bounds is not None else config_dir_of(skel.parent) / "INDEX_BOUNDS.txt"
    if index_bounds is None and not path.is_file():
        note = f"no {path}: aligned frame k = MOTION row k + 1 for every row after the rigging pose"
        return IndexBounds(frames - 1, 1, 0), [note]
    bounds = read_index_bounds(path)
    needed = bounds.total_aligned + bounds.motion_offset
    if needed > frames:
        msg = (
            f"TotalAlligned {bounds.total_aligned} + MotionnOffset {bounds.motion_offset} = {needed} rows "
            f"needed, but {motion} has {frames} rows per bone (the .SKEL frame "
            f"count); expected TotalAlligned + MotionnOffset ≤ {frames}"
        )
        raise FormatError(path, msg, line=bounds.lines[0], field="TotalAlligned")
    notes = []
    if bounds.motion_offset == 0:
        notes.append(f"{path}: MotionnOffset 0 makes aligned frame 0 the rigging pose (the dataset uses 1)")
    return bounds, notes
