"""Reader of corrected trials (``NAME.corrected.npz``): what ``handsim correct`` writes (docs/correct.md).

A corrected trial is a NumPy ``.npz`` archive (no pickled objects) holding a recording's corrected motion
at the control rate, the recording it was corrected from (at the same rate), the committed simulation and
the correction's size per frame; its ``header`` array is UTF-8 JSON with the provenance. Arrays (F frames,
``ndof`` DoF columns named by ``header["dof_names"]``, H welded hands named by ``header["hands"]``, O
recorded objects named by ``header["objects"]``):

=============================  ==================  ===========================================================
array                          shape, dtype        content
=============================  ==================  ===========================================================
``header``                     (bytes,) uint8      UTF-8 JSON: :data:`HEADER_KEYS`
``times``                      (F,) float64        control frame times, s (the recording's time)
``targets``                    (F, ndof) float64   corrected joint targets, rad
``recorded_targets``           (F, ndof) float64   the recording's targets at the same frames, rad
``valid``                      (F, ndof) bool      the recording's validity of each target
``root_pose``                  (F, H, 7) float64   corrected wrist (root) poses in the recording's frame,
                                                   m and quaternion (w, x, y, z)
``recorded_root_pose``         (F, H, 7) float64   the recording's
``object_pose``                (F, O, 7) float64   recorded object poses in the recording's frame
``object_valid``               (F, O) bool         frames with a recorded object pose
``object_articulation``        (F, O) float64      recorded hinge angle, rad (NaN for a rigid object)
``simulated_qpos``             (F, nq) float64     the committed simulation's state at each frame
``simulated_object_pose``      (F, O, 7) float64   its objects' poses in the scene's world
``finger_correction_rms``      (F,) float64        RMS over the corrected finger targets, rad
``finger_correction_max``      (F,) float64        largest absolute finger correction, rad
``wrist_position_correction``  (F, H) float64      wrist position correction, m
``wrist_rotation_correction``  (F, H) float64      wrist rotation correction, rad
=============================  ==================  ===========================================================

The reader checks every array's presence, shape and type and the header's fields, and names the file and the
field at fault.
"""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.errors import FormatError
from handsim.io.text_files import decode_utf8, read_bytes, sha256_of

SUFFIX = ".corrected.npz"
"""File name ending of a corrected trial."""
FORMAT = "handsim-corrected-trial"
"""The header's ``format``."""
VERSION = 1
"""The format version this reader reads (the header's ``version``)."""
HEADER_KEYS = (
    "format",
    "version",
    "source",
    "model_sha256",
    "control_rate",
    "substeps",
    "dof_names",
    "hands",
    "objects",
    "method",
    "backend",
    "versions",
    "score",
)
"""The header's fields: ``source`` (``trial``: the trial's fields, ``sha256``: its recording's SHA-256),
``model_sha256`` (the scene's compiled model), ``control_rate`` (Hz) and ``substeps`` (MuJoCo steps per
frame), the names of the columns, ``method`` (the correction's parameters, its seed among them), ``backend``
(the rollout backend), ``versions`` (handsim, MuJoCo, NumPy) and ``score`` (the plausibility score)."""
ARRAYS: dict[str, tuple[str, str]] = {
    "times": ("F", "f"),
    "targets": ("F,D", "f"),
    "recorded_targets": ("F,D", "f"),
    "valid": ("F,D", "b"),
    "root_pose": ("F,H,7", "f"),
    "recorded_root_pose": ("F,H,7", "f"),
    "object_pose": ("F,O,7", "f"),
    "object_valid": ("F,O", "b"),
    "object_articulation": ("F,O", "f"),
    "simulated_qpos": ("F,Q", "f"),
    "simulated_object_pose": ("F,O,7", "f"),
    "finger_correction_rms": ("F", "f"),
    "finger_correction_max": ("F", "f"),
    "wrist_position_correction": ("F,H", "f"),
    "wrist_rotation_correction": ("F,H", "f"),
}
"""Every array besides the header: its shape (F frames, D DoF columns, H hands, O objects, Q = nq) and kind
(``f`` float64, ``b`` bool)."""


def is_corrected_trial(path: str | Path) -> bool:
    """Whether a file's name is that of a corrected trial (``NAME.corrected.npz``)."""
    return Path(path).name.lower().endswith(SUFFIX)


@dataclass(frozen=True)
class CorrectedFile:
    """A corrected trial as read.

    Attributes:
        path: The file.
        sha256: SHA-256 of its bytes.
        header: The header (JSON).
        arrays: Every array of :data:`ARRAYS`, checked.
    """

    path: str
    sha256: str
    header: dict
    arrays: dict[str, np.ndarray]


def read_corrected_header(path: str | Path) -> dict:
    """Only the header of a corrected trial (cheap: the arrays are not read).

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: It is not a corrected trial (not an archive, no header, a header field wrong).
    """
    with _archive(path, read_bytes(path)) as archive:
        return _header(path, archive)


def read_corrected(path: str | Path) -> CorrectedFile:
    """Read and check a corrected trial.

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: An array or header field is missing or of the wrong shape or type (named).
    """
    data = read_bytes(path)
    with _archive(path, data) as archive:
        header = _header(path, archive)
        arrays = {name: _array(path, archive, name) for name in ARRAYS}
    sizes = {
        "F": arrays["times"].shape[0] if arrays["times"].ndim == 1 else -1,
        "D": len(header["dof_names"]),
        "H": len(header["hands"]),
        "O": len(header["objects"]),
        "Q": arrays["simulated_qpos"].shape[-1] if arrays["simulated_qpos"].ndim == 2 else -1,
    }
    for name, (shape, kind) in ARRAYS.items():
        expected = tuple(int(d) if d.isdigit() else sizes[d] for d in shape.split(","))
        value = arrays[name]
        if value.shape != expected:
            raise FormatError(path, f"shape {value.shape}, expected {expected} ({shape})", field=name)
        if value.dtype.kind != kind:
            raise FormatError(
                path, f"dtype {value.dtype}, expected {'float64' if kind == 'f' else 'bool'}", field=name
            )
    if sizes["F"] < 2 or np.any(np.diff(arrays["times"]) <= 0):
        raise FormatError(path, "times must hold at least two strictly increasing frame times", field="times")
    for name in ("times", "targets", "root_pose", "object_pose"):
        if not np.all(np.isfinite(arrays[name])):
            frame = int(np.argwhere(~np.isfinite(arrays[name]))[0][0])
            raise FormatError(path, f"a non-finite value at frame {frame}", field=name)
    return CorrectedFile(path=str(path), sha256=sha256_of(data), header=header, arrays=arrays)


def _archive(path: str | Path, data: bytes) -> zipfile.ZipFile:
    try:
        return zipfile.ZipFile(io.BytesIO(data))
    except zipfile.BadZipFile:
        raise FormatError(path, "not a corrected trial: not an .npz archive") from None


def _array(path: str | Path, archive: zipfile.ZipFile, name: str) -> np.ndarray:
    try:
        raw = archive.read(f"{name}.npy")
    except KeyError:
        raise FormatError(path, "missing array", field=name) from None
    try:
        return np.lib.format.read_array(io.BytesIO(raw), allow_pickle=False)
    except ValueError as exc:
        raise FormatError(path, f"not a plain .npy array ({exc})", field=name) from None


def _header(path: str | Path, archive: zipfile.ZipFile) -> dict:
    raw = _array(path, archive, "header")
    if raw.dtype != np.uint8 or raw.ndim != 1:
        raise FormatError(path, f"expected UTF-8 bytes (uint8), got {raw.dtype} {raw.shape}", field="header")
    try:
        header = json.loads(decode_utf8(raw.tobytes(), path))
    except json.JSONDecodeError as exc:
        raise FormatError(path, f"not JSON ({exc.msg} at character {exc.pos})", field="header") from None
    if not isinstance(header, dict):
        raise FormatError(path, "expected a JSON object", field="header")
    missing = [k for k in HEADER_KEYS if k not in header]
    if missing:
        raise FormatError(
            path, f"missing {missing}; a corrected trial's header has {list(HEADER_KEYS)}", field="header"
        )
    if header["format"] != FORMAT:
        raise FormatError(path, f"expected {FORMAT!r}, got {header['format']!r}", field="header.format")
    if header["version"] != VERSION:
        raise FormatError(
            path,
            f"version {header['version']!r}; this handsim reads version {VERSION}",
            field="header.version",
        )
    for key in ("dof_names", "hands", "objects"):
        if not (isinstance(header[key], list) and all(isinstance(n, str) for n in header[key])):
            raise FormatError(path, "expected a list of names", field=f"header.{key}")
    source = header["source"]
    if not (
        isinstance(source, dict)
        and isinstance(source.get("trial"), dict)
        and isinstance(source.get("sha256"), str)
    ):
        raise FormatError(path, "expected {'trial': {...}, 'sha256': '...'}", field="header.source")
    rate = header["control_rate"]
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not rate > 0:
        raise FormatError(
            path, f"expected a positive number of Hz, got {rate!r}", field="header.control_rate"
        )
    return header
