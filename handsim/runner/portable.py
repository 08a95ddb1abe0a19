"""Records that do not depend on where the dataset lies: paths relative to its root, and back.

A run's records name files relative to the dataset root (the discovery root, ``run.json``'s ``dataset``),
so the same dataset run from two folders, or on two machines, gives the same bytes (``timing`` aside).
:func:`portable_record` makes a record so (the runner's parent process applies it to every record before
writing it); :func:`record_trial` turns a record's ``trial`` back into a loadable
:class:`~handsim.trials.Trial` given the root; :func:`portable_traceback` names source files by their
module path, not where Python or handsim is installed.

Paths outside the dataset root (a ``--mano-dir``, a ``--templates`` folder, a ``--skeleton`` elsewhere) are
kept absolute: records of such runs name them as given.
"""

from __future__ import annotations

import os
import re
import sys
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from handsim.trials import Trial

if TYPE_CHECKING:
    from handsim.trials import Trial, TrialEntry

PATH_FIELDS = ("trajectory_path", "skeleton_path", "calibration_path", "annotation_path", "mano_dir")
"""The fields of a record's ``trial`` that hold a path (besides each object's ``what``)."""
_FRAME = re.compile(r'^(  File ")([^"]+)(")', re.MULTILINE)


def dataset_root(entries: Sequence[TrialEntry]) -> str | None:
    """The folder the trials' input paths are relative to, found from their inputs.

    Each input's ``file`` is its dataset-relative ``path`` below the root; inputs outside the root
    (``path`` starting with ``..``) tell nothing.

    Args:
        entries: Trials of one discovery.

    Returns:
        The root (absolute, as discovery gave it), or None when no input tells it or inputs disagree.
    """
    roots = set()
    for entry in entries:
        for item in entry.inputs:
            relative = item.path.split("/")
            parts = Path(item.file).parts
            if ".." in relative or len(parts) <= len(relative):
                continue
            if Path(*parts[-len(relative) :]).as_posix() == item.path:
                roots.add(str(Path(*parts[: -len(relative)])))
    return roots.pop() if len(roots) == 1 else None


def portable_record(value: Any, root: str | None) -> Any:
    """``value`` (a record, or any part of one) with the dataset root taken out of every string.

    ``ROOT/a/b.txt`` becomes ``a/b.txt`` wherever it appears (paths, notes, error messages); the root
    itself becomes ``.``. Numbers, keys and strings without the root are unchanged.

    Args:
        value: JSON-ready values (dicts, lists, strings, numbers, None).
        root: The dataset root (absolute); None: ``value`` unchanged.

    Returns:
        A copy with the root replaced (``value`` itself when ``root`` is None).
    """
    if root is None:
        return value
    prefix = root.rstrip(os.sep) + os.sep
    return _replace(value, root, prefix)


def _replace(value: Any, root: str, prefix: str) -> Any:
    if isinstance(value, str):
        return "." if value == root else value.replace(prefix, "")
    if isinstance(value, dict):
        return {k: _replace(v, root, prefix) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_replace(v, root, prefix) for v in value]
    return value


def record_trial(record: dict, root: str | Path | None) -> Trial:
    """The trial of a record, its dataset-relative paths joined to ``root`` (loadable from any folder).

    Args:
        record: A record (its ``trial``: :meth:`~handsim.trials.Trial.to_dict` with relative paths).
        root: The dataset root of the run (``run.json``'s ``dataset``); None: paths as recorded (relative
            ones then read from the current folder).

    Returns:
        The trial. An object's ``what`` is joined to ``root`` only when that names an existing file or
        folder there (otherwise it is a catalogue name).

    Raises:
        TrialError: ``record["trial"]`` is not a trial's fields.
    """
    fields = dict(record["trial"])
    if root is not None:
        base = Path(root)
        for key in PATH_FIELDS:
            if isinstance(fields.get(key), str):
                fields[key] = _joined(base, fields[key])
        objects = []
        for item in fields.get("objects") or ():
            item = dict(item)
            what = item.get("what")
            if isinstance(what, str) and not os.path.isabs(what) and (base / what).exists():
                item["what"] = str(base / what)
            objects.append(item)
        fields["objects"] = objects
    return Trial.from_dict(fields)


def _joined(base: Path, path: str) -> str:
    if os.path.isabs(path):
        return path
    return str(base) if path == "." else str(base / path)


def portable_traceback(exc: BaseException) -> str:
    """``exc``'s traceback, each source file named relative to the ``sys.path`` folder it was imported from.

    ``File "/site-packages/handsim/io/graspdb/glove.py"`` becomes ``File "handsim/io/graspdb/glove.py"``: the
    text does
    not depend on where Python, handsim or the virtual environment are installed. Files outside every
    ``sys.path`` folder keep their full name.
    """
    text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    folders = sorted(
        {os.path.abspath(p or os.curdir).rstrip(os.sep) + os.sep for p in sys.path if isinstance(p, str)},
        key=len,
        reverse=True,
    )

    def shorter(match: re.Match) -> str:
        name = match.group(2)
        inside = next((name[len(f) :] for f in folders if name.startswith(f)), name)
        return f"{match.group(1)}{inside}{match.group(3)}"

    return _FRAME.sub(shorter, text)
