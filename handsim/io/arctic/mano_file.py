"""The MANO half of an ARCTIC sequence: both hands of a ``<seq>.mano.npy`` file, each validated.

A ``.mano.npy`` is a pickled ``{'left', 'right'}`` dict of MANO fields (:mod:`handsim.io.arctic.sequence`
describes the layout); both hands are read and checked together, since identical hands or hands of
different lengths are errors only the pair shows.
"""

from __future__ import annotations

import numbers
from pathlib import Path
from typing import Any

import numpy as np

from handsim.errors import FormatError, HandsimError
from handsim.io.arctic.mano_pose import MANOSequence
from handsim.io.arctic.motion_checks import (
    ARCTIC_FPS,
    HANDS,
    MANO_BETA_LIMIT,
    MANO_FIELDS,
    MANO_TRANS_LIMIT_M,
    MAX_HAND_SPEED,
    PER_FRAME_FIELDS,
    check_fps,
    check_track,
    file_sha256,
    float_field,
)
from handsim.io.safe_pickle import load_npy


def _fitting_err(path: Path, field: str, value: Any, n: int) -> np.ndarray:
    """ARCTIC's per-frame fitting error: a list of N floats (real files) or an (N,) float array."""
    if isinstance(value, np.ndarray):
        return float_field(path, field, value, (n,))
    if not isinstance(value, (list, tuple)):
        raise FormatError(
            path, f"expected a list of {n} floats (one per frame), got {type(value).__name__}", field=field
        )
    for i, item in enumerate(value):
        if isinstance(item, bool) or not isinstance(item, numbers.Real):
            raise FormatError(
                path, f"entry {i} is {type(item).__name__} {item!r}; expected a number", field=field
            )
    if len(value) != n:
        raise FormatError(path, f"expected {n} values (one per frame), got {len(value)}", field=field)
    array = np.asarray(value, dtype=float)
    bad = ~np.isfinite(array)
    if bad.any():
        raise FormatError(path, f"non-finite value at frame {int(np.argmax(bad))}", field=field)
    return array


def _load_hands(path: Path) -> dict[str, dict]:
    """The ``{'right', 'left'}`` dict of a ``.mano.npy`` file, both entries dicts."""
    array = load_npy(path)
    if array.dtype != object or array.shape != ():
        raise FormatError(
            path,
            "expected a pickled dict {'left', 'right'} (0-d object array), "
            f"got {array.dtype} {array.shape}",
        )
    data = array.item()
    if not isinstance(data, dict):
        raise FormatError(path, f"expected a pickled dict {{'left', 'right'}}, got {type(data).__name__}")
    for hand in HANDS:
        if hand not in data:
            raise FormatError(
                path,
                f"no {hand!r} entry; entries are {sorted(map(str, data))}. ARCTIC sequences are bimanual: "
                "a .mano.npy holds both 'right' and 'left'",
                field=hand,
            )
        if not isinstance(data[hand], dict):
            raise FormatError(
                path, f"expected a dict of MANO fields, got {type(data[hand]).__name__}", field=hand
            )
    return data


def _check_frame_counts(path: Path, hand: str, entry: dict) -> None:
    """Refuse per-frame fields of different lengths, naming the one that differs from the others.

    Fields that are not sized sequences are left to the per-field checks that follow.
    """
    lengths: dict[str, int] = {}
    for name in PER_FRAME_FIELDS:
        value = entry.get(name)
        if isinstance(value, np.ndarray) and value.ndim >= 1:
            lengths[name] = value.shape[0]
        elif isinstance(value, (list, tuple)):
            lengths[name] = len(value)
    if len(set(lengths.values())) < 2:
        return
    counts = list(lengths.values())
    common = max(counts, key=lambda n: (counts.count(n), n))
    odd = next(name for name, n in lengths.items() if n != common)
    others = [f"{hand}.{name}" for name, n in lengths.items() if n == common]
    listed = others[0] if len(others) == 1 else ", ".join(others[:-1]) + " and " + others[-1]
    raise FormatError(
        path,
        f"{lengths[odd]} frames, but {listed} {'has' if len(others) == 1 else 'have'} {common}; expected "
        "one row per frame in every field (a truncated or misaligned field)",
        field=f"{hand}.{odd}",
    )


def _check_betas(path: Path, field: str, betas: np.ndarray, axes: tuple[str, ...]) -> None:
    """Refuse a beta beyond :data:`MANO_BETA_LIMIT`, naming its index (and frame) and value."""
    far = np.abs(betas) > MANO_BETA_LIMIT
    if not far.any():
        return
    index = tuple(int(i) for i in np.argwhere(far)[0])
    where = ", ".join(f"{axis} {i}" for axis, i in zip(axes, index, strict=True))
    raise FormatError(
        path,
        f"{where} is {float(betas[index]):.4g} ({int(far.sum())} beyond the limit); MANO betas are in "
        "standard deviations of its shape space and fitted hands lie within a few units of 0, expected "
        f"|beta| ≤ {MANO_BETA_LIMIT:g}: a corrupted or mis-scaled shape",
        field=field,
    )


def _hand(path: Path, hand: str, entry: dict, fps: float, sha256: str) -> MANOSequence:
    missing = [k for k in MANO_FIELDS[:4] if k not in entry]
    if missing:
        raise FormatError(path, f"missing {missing}; a MANO entry has {list(MANO_FIELDS)}", field=hand)
    _check_frame_counts(path, hand, entry)
    rot = float_field(path, f"{hand}.rot", entry["rot"], (None, 3))
    n = rot.shape[0]
    if n == 0:
        raise FormatError(path, "no frames", field=f"{hand}.rot")
    raw_pose = entry["pose"]
    if isinstance(raw_pose, np.ndarray) and raw_pose.ndim == 2 and raw_pose.shape[1] != 45:
        raise FormatError(
            path,
            f"expected 45 values per frame (15 joints × 3 axis-angle), got {raw_pose.shape[1]}",
            field=f"{hand}.pose",
        )
    pose = float_field(path, f"{hand}.pose", raw_pose, (n, 45))
    trans = float_field(path, f"{hand}.trans", entry["trans"], (n, 3))
    notes: list[str] = []
    raw_shape = entry["shape"]
    if isinstance(raw_shape, np.ndarray) and raw_shape.ndim == 2:
        shapes = float_field(path, f"{hand}.shape", raw_shape, (n, 10), ("frame", "beta"))
        _check_betas(path, f"{hand}.shape", shapes, ("frame", "beta"))
        spread = float(np.ptp(shapes, axis=0).max())
        shape = shapes.mean(axis=0)
        notes.append(f"{hand}.shape given per frame; their mean used (largest spread {spread:.1e})")
    else:
        shape = float_field(path, f"{hand}.shape", raw_shape, (10,), ("beta",))
        _check_betas(path, f"{hand}.shape", shape, ("beta",))
    fitting_err = None
    if entry.get("fitting_err") is not None:
        fitting_err = _fitting_err(path, f"{hand}.fitting_err", entry["fitting_err"], n)
    else:
        notes.append(f"{hand}: no fitting_err in the file")
    largest = np.abs(trans).max(axis=1)
    if np.median(largest) > MANO_TRANS_LIMIT_M:
        raise FormatError(
            path,
            f"translation component reaches {float(largest.max()):.4g}; MANO translations are metres and a "
            f"hand more than {MANO_TRANS_LIMIT_M:g} m from the origin means the file holds millimetres",
            field=f"{hand}.trans",
        )
    check_track(
        path, f"{hand}.trans", trans, limit=MANO_TRANS_LIMIT_M, speed=MAX_HAND_SPEED, fps=fps,
        unit="m", what="the hand",
    )  # fmt: skip
    return MANOSequence(
        rot=rot,
        pose=pose,
        trans=trans,
        shape=shape,
        fitting_err=fitting_err,
        side=hand,
        source=str(path),
        sha256=sha256,
        notes=tuple(notes),
    )


def read_hands(path: Path, fps: float) -> dict[str, MANOSequence]:
    """Both hands of a ``.mano.npy`` file, each validated, then checked against each other.

    Raises:
        FormatError: Anything a hand's checks refuse, hands of different lengths or identical hands.
    """
    data = _load_hands(path)
    sha = file_sha256(path)
    hands = {hand: _hand(path, hand, data[hand], fps, sha) for hand in HANDS}
    right, left = hands["right"], hands["left"]
    if right.nframes != left.nframes:
        raise FormatError(
            path,
            f"the right hand has {right.nframes} frames and the left {left.nframes}; expected the same",
            field="left.rot",
        )
    if np.array_equal(right.trans, left.trans) and np.array_equal(right.pose, left.pose):
        raise FormatError(
            path,
            "'right' and 'left' hold identical trans and pose in every frame: one hand's data was copied "
            "into the other's entry (two hands cannot share a place); expected each hand's own fit",
            field="right",
        )
    return hands


def read_arctic_mano(path: str | Path, hand: str = "right", *, fps: float = ARCTIC_FPS) -> MANOSequence:
    """Read one hand of an ARCTIC ``*.mano.npy`` file (both hands are validated).

    Args:
        path: The ``.mano.npy`` file.
        hand: ``"right"`` or ``"left"``.
        fps: Frame rate for the speed gate, Hz.

    Returns:
        The hand's MANO parameters (rot and pose in rad, trans in m, shape (10,), fitting_err (N,) as
        stored); ``side`` = ``hand``. Poses are relative to MANO's mean pose (``flat_hand_mean=False``).

    Raises:
        InputFileError: The file does not exist.
        FormatError: Not a pickled ``{'left', 'right'}`` dict, a missing hand, a refused pickle global, a
            missing field, a field of the wrong type, dtype or shape (pose not 45 values per frame;
            fitting_err not one number per frame), non-finite values, translations that look like
            millimetres, a frame outside the capture volume or a jump faster than :data:`MAX_HAND_SPEED`,
            a beta beyond :data:`MANO_BETA_LIMIT`, per-frame fields of different lengths, hands of
            different lengths or identical hands. The message names the file and the field
            (``right.pose``).
        HandsimError: ``hand`` is neither ``"right"`` nor ``"left"``, or a non-positive ``fps``.
    """
    if hand not in HANDS:
        raise HandsimError(f"hand must be 'right' or 'left', got {hand!r}")
    check_fps(fps)
    return read_hands(Path(path), fps)[hand]
