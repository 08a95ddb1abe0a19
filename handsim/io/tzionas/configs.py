"""The sequence configuration files of the Tzionas/Ballan dataset, in ``Configs/NN`` beside ``Models/NN``.

* ``INDEX_BOUNDS.txt`` (:func:`read_index_bounds`): which ``.MOTION`` rows and video frames are aligned —
  ``TotalAlligned N``, ``MotionnOffset m``, ``VideoooOffset v`` (the dataset's spelling).
* ``MODELS_INFO.txt`` (:func:`read_models_info`): the number of models, then one model name per line
  (``Model_Hand_R``, ``Model_Object_Cube`` …).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from handsim.errors import FormatError
from handsim.io.text_files import numbered_lines, parse_int, read_text

INDEX_BOUNDS_KEYS = ("TotalAlligned", "MotionnOffset", "VideoooOffset")
"""The keys of ``INDEX_BOUNDS.txt``, in the dataset's spelling."""


@dataclass(frozen=True)
class IndexBounds:
    """The content of a sequence's ``INDEX_BOUNDS.txt``.

    Attributes:
        total_aligned: Number of aligned frames.
        motion_offset: ``.MOTION`` row of aligned frame 0 (row 0 is the rigging pose).
        video_offset: Video frame of aligned frame 0.
        source: The file, or "" when the values are defaults.
        lines: 1-based lines of the three values (0 for defaults).
    """

    total_aligned: int
    motion_offset: int
    video_offset: int
    source: str = ""
    lines: tuple[int, int, int] = (0, 0, 0)


def read_index_bounds(path: str | Path) -> IndexBounds:
    """Read a sequence's ``INDEX_BOUNDS.txt``: ``TotalAlligned N``, ``MotionnOffset m``, ``VideoooOffset v``.

    Args:
        path: The file.

    Returns:
        The three values (TotalAlligned ≥ 1, offsets ≥ 0).

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: A line is not one of the three keys and an integer, a key is repeated or missing.
    """
    p = Path(path)
    values: dict[str, tuple[int, int]] = {}
    lines = numbered_lines(read_text(p))
    for ln, text in lines:
        tokens = text.split()
        if len(tokens) != 2 or tokens[0] not in INDEX_BOUNDS_KEYS:
            msg = f"expected '<key> <integer>' with key one of {list(INDEX_BOUNDS_KEYS)}, got {text!r}"
            raise FormatError(p, msg, line=ln, field="key")
        key = tokens[0]
        if key in values:
            msg = f"second {key!r} (first at line {values[key][1]})"
            raise FormatError(p, msg, line=ln, field=key)
        values[key] = (parse_int(tokens[1], p, ln, key, 1 if key == "TotalAlligned" else 0), ln)
    missing = [k for k in INDEX_BOUNDS_KEYS if k not in values]
    if missing:
        msg = f"no {missing[0]!r} line; expected the keys {list(INDEX_BOUNDS_KEYS)}, one per line"
        raise FormatError(p, msg, line=lines[-1][0] if lines else 1, field=missing[0])
    (total, l1), (motion, l2), (video, l3) = (values[k] for k in INDEX_BOUNDS_KEYS)
    return IndexBounds(total, motion, video, str(p), (l1, l2, l3))


def read_models_info(path: str | Path) -> tuple[tuple[str, int], ...]:
    """Read a sequence's ``MODELS_INFO.txt``: the model count, then one model name per line.

    Args:
        path: The file.

    Returns:
        The model names (e.g. ``Model_Hand_R``) with their 1-based lines.

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: The count is not an integer ≥ 1 or does not match the names that follow.
    """
    p = Path(path)
    lines = numbered_lines(read_text(p))
    if not lines:
        raise FormatError(p, "empty file; expected the number of models", line=1, field="model count")
    count = parse_int(lines[0][1], p, lines[0][0], "model count", 1)
    names = lines[1:]
    if len(names) != count:
        msg = f"{len(names)} model names follow, expected {count} (the count on line {lines[0][0]})"
        raise FormatError(p, msg, line=(names[-1] if names else lines[0])[0], field="model names")
    return tuple((name, ln) for ln, name in names)


def config_dir_of(models_dir: str | Path) -> Path:
    """The ``Configs/NN`` folder that belongs to ``Models/NN`` (the dataset's layout)."""
    m = Path(models_dir)
    return m.parent.parent / "Configs" / m.name
