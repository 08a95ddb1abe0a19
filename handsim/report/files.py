"""The files discovery found besides trials, grouped so that many alike files read as one line.

An ARCTIC root holds a handful of template files per object (``mesh.obj``, ``parts.json``, textures,
keypoints) and two companions per sequence (egocentric camera poses, SMPL-X bodies): hundreds of rows with
the same reason, which would fill a report's first screen. Files that share their reason form one
:class:`FileGroup`: the deepest folder holding them all, how many files, and the first few names right
below that folder. A reason only one file has keeps that file's own row, so a dataset of distinct
companions (a glove recording's annotation, its calibration) is listed as before.
"""

from __future__ import annotations

import posixpath
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from handsim.report.fmt import plural
from handsim.report.records import natural_key

NAMES_SHOWN = 4
"""Names below a group's folder spelled out; the rest are counted (``and 7 more``)."""


@dataclass(frozen=True)
class FileGroup:
    """Files that discovery gave the same reason, or one file.

    Attributes:
        path: The one file's path, or the folder (ending in ``/``; ``./`` for the dataset's root) holding
            every file of the group.
        count: How many files.
        names: The distinct names right below ``path`` that hold the files (a sub-folder ends in ``/``),
            in natural order; empty for one file.
        reason: Why discovery did not replay them.
    """

    path: str
    count: int
    names: tuple[str, ...]
    reason: str

    def count_text(self) -> str:
        """What follows the path: `` (20 files: box/, mixer/, phone/, top/ and 7 more)``; ``""`` for one."""
        if self.count == 1:
            return ""
        shown = ", ".join(self.names[:NAMES_SHOWN])
        more = len(self.names) - NAMES_SHOWN
        return f" ({plural(self.count, 'file')}: {shown}{f' and {more} more' if more > 0 else ''})"

    def what(self) -> str:
        """The group in words: the file's path, or e.g. ``meta/object_vtemplates/ (20 files: box/, …)``."""
        return self.path + self.count_text()


def _below(folder: str, path: str) -> str:
    """The first name of ``path`` below ``folder`` (``""`` = the root), with ``/`` if it is a folder."""
    rest = path[len(folder) + 1 :] if folder else path
    head, sep, _ = rest.partition("/")
    return head + sep


def group_files(entries: Iterable[Mapping[str, object]]) -> list[FileGroup]:
    """Group discovery's companion or unknown files by their reason.

    Args:
        entries: ``{"path": …, "reason": …}`` per file, as ``run.json``'s discovery lists them (paths
            relative to the dataset, ``/``-separated).

    Returns:
        One group per distinct reason, ordered by its first path (natural order: ``s9`` before ``s10``).
    """
    by_reason: dict[str, list[str]] = {}
    for entry in entries:
        by_reason.setdefault(str(entry.get("reason")), []).append(str(entry.get("path")))
    groups = []
    for reason, paths in by_reason.items():
        paths = sorted(paths, key=natural_key)
        if len(paths) == 1:
            groups.append(FileGroup(paths[0], 1, (), reason))
            continue
        folder = posixpath.commonpath([posixpath.dirname(p) for p in paths])
        names = sorted({_below(folder, p) for p in paths}, key=natural_key)
        groups.append(FileGroup(f"{folder}/" if folder else "./", len(paths), tuple(names), reason))
    return sorted(groups, key=lambda g: natural_key(g.path))
