"""Reader for GraspDB14 phase annotation files, and which annotation a recording uses.

**Phase annotation files** (``<motion name>_annot-.txt``, not described in the spec; format read off
the GraspDB14 sample ``01_11_ex03-rad-004-grasp-su04_annot-.txt``)::

    # interval   annotation
       1   24    .rest
      25   81    reach-overopen-closing
      82  164    .grasp
     165  233    retract-opening
     234  282    .rest

One interval per line: first frame, last frame (1-based, inclusive: the sample's five intervals tile
frames 1..282 of its 282-frame motion exactly), label. A leading ``.`` marks a static phase (the hand
holds a pose); ``-`` separates a phase name from qualifiers (``reach`` with ``overopen``, ``closing``).
Lines starting with ``#`` are comments.

:func:`read_phase_annotations` reads one into :class:`~handsim.glove.phases.PhaseAnnotation` intervals;
:func:`find_annotation_file` / :func:`match_annotation` find the one that belongs to a recording and use
it only when it covers the recording's frames; :func:`attach_phases` sets a trajectory's phases from a file
(the phase logic on plain data is :mod:`handsim.glove.phases`).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

from handsim.datatypes.trajectory import Phase, Trajectory
from handsim.errors import FormatError
from handsim.glove.phases import AnnotationMatch, PhaseAnnotation, with_phases
from handsim.io.text_files import read_text

ANNOTATION_SUFFIX = "_annot-.txt"
"""What a phase annotation file name adds to its motion file's name (without ``.txt``)."""

_LABEL_RE = re.compile(r"\.?[A-Za-z][A-Za-z0-9_]*(?:-[A-Za-z0-9_]+)*")
_FRAME_RE = re.compile(r"\d+")


def read_phase_annotations(path: str | Path) -> tuple[PhaseAnnotation, ...]:
    """Read a GraspDB14 phase annotation file (``*_annot-.txt``).

    Args:
        path: The annotation file.

    Returns:
        The intervals in file order (frame order, without overlaps).

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: A line does not hold ``<first frame> <last frame> <label>``, a frame number is not an
            integer >= 1, the last frame precedes the first, a label is malformed, an interval does not
            start after the previous one ends, or the file holds no interval. The message names the file,
            the 1-based line and the field.
    """
    p = Path(path)
    text = read_text(p)
    result: list[PhaseAnnotation] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        tokens = line.split()
        if len(tokens) != 3:
            raise FormatError(
                p,
                f"expected 3 blank-separated entries (first frame, last frame, label), got {len(tokens)}",
                line=lineno,
            )
        first = _frame(p, lineno, tokens[0], "first frame")
        last = _frame(p, lineno, tokens[1], "last frame")
        if last < first:
            raise FormatError(
                p, f"last frame {last} is before first frame {first}", line=lineno, field="last frame"
            )
        if not _LABEL_RE.fullmatch(tokens[2]):
            raise FormatError(
                p,
                f"expected a phase label such as '.rest' or 'reach-overopen-closing', got {tokens[2]!r}",
                line=lineno,
                field="label",
            )
        if result and first <= result[-1].stop:
            prev = result[-1]
            raise FormatError(
                p,
                f"interval {first}-{last} does not start after the previous interval "
                f"{prev.start + 1}-{prev.stop} (line {prev.line}) ends; intervals must be in frame order "
                "without overlap",
                line=lineno,
                field="first frame",
            )
        result.append(PhaseAnnotation(tokens[2], first - 1, last, lineno))
    if not result:
        raise FormatError(
            p, "no phase intervals: expected lines '<first frame> <last frame> <label>' (1-based, inclusive)"
        )
    return tuple(result)


def _frame(path: Path, line: int, token: str, field: str) -> int:
    """A 1-based frame number, or a :class:`FormatError` naming line and field."""
    if not _FRAME_RE.fullmatch(token) or int(token) < 1:
        raise FormatError(
            path, f"expected a frame number (an integer >= 1), got {token!r}", line=line, field=field
        )
    return int(token)


ANNOTATED_PREFIX = "r_"
"""The one motion-file prefix an annotation name leaves out: GraspDB14's sample pair is
``r_01_11_ex03-rad-004-grasp-su04.txt`` ↔ ``01_11_ex03-rad-004-grasp-su04_annot-.txt``."""


def _motion_stem(path: Path) -> str:
    return path.name[:-4] if path.name.lower().endswith(".txt") else path.name


def annotation_names(motion_path: str | Path) -> tuple[str, ...]:
    """The names a motion file's phase annotation may have, in the order they are looked for.

    The motion's exact stem (its name without ``.txt``) followed by ``_annot-.txt``, then, for a name
    starting with ``r_``, the same without that prefix (the GraspDB14 sample pair). No other prefix is
    dropped and no other name is tried: an annotation belongs to one recording only.

    Args:
        motion_path: A motion file (it need not exist).

    Returns:
        One or two file names.
    """
    stem = _motion_stem(Path(motion_path))
    names = [f"{stem}{ANNOTATION_SUFFIX}"]
    if stem.startswith(ANNOTATED_PREFIX) and len(stem) > len(ANNOTATED_PREFIX):
        names.append(f"{stem[len(ANNOTATED_PREFIX) :]}{ANNOTATION_SUFFIX}")
    return tuple(names)


def find_annotation_file(motion_path: str | Path) -> Path | None:
    """The phase annotation file of a GraspDB14 motion file, if it lies beside it.

    Only the names of :func:`annotation_names` count: ``r_01_11_ex03-rad-004-grasp-su04.txt`` →
    ``r_01_11_ex03-rad-004-grasp-su04_annot-.txt`` or ``01_11_ex03-rad-004-grasp-su04_annot-.txt``;
    ``h_01_11_…`` or ``VIShand_01_11_…`` find neither. Whether the file found agrees with the recording's
    frame count is :func:`match_annotation`'s job.

    Args:
        motion_path: A motion file (``rad`` or ``raw``; it need not exist).

    Returns:
        The first candidate that exists in the motion file's folder, or None. An annotation file given as
        the motion is itself.
    """
    p = Path(motion_path)
    if _motion_stem(p).endswith("_annot-"):
        return p if p.exists() else None
    for name in annotation_names(p):
        candidate = p.parent / name
        if candidate.is_file():
            return candidate
    return None


def annotation_frames(path: str | Path) -> int:
    """How many frames an annotation file covers: its last interval's last frame (1-based, inclusive).

    Raises:
        InputFileError: The file is missing or unreadable.
        FormatError: The file is malformed (see :func:`read_phase_annotations`).
    """
    return read_phase_annotations(path)[-1].stop


def check_annotation(annotation: str | Path, motion: str | Path, frames: int) -> AnnotationMatch:
    """Use an annotation file for a recording only when it covers exactly the recording's frames.

    Args:
        annotation: The annotation file.
        motion: The recording, for the note.
        frames: The recording's frame count.

    Returns:
        The annotation with a note and its intervals, or None with a ``warning:`` note naming both files and
        both counts.

    Raises:
        InputFileError: The annotation is missing or unreadable.
        FormatError: The annotation is malformed.
    """
    a, m = Path(annotation), Path(motion)
    intervals = read_phase_annotations(a)
    covered = intervals[-1].stop
    if covered != frames:
        return AnnotationMatch(
            None,
            f"warning: phase annotation {a} is not used: its intervals end at frame {covered}, but the "
            f"recording {m} has {frames} frames (an annotation covers exactly the frames of the recording it "
            "belongs to; is it another recording's?); the grasp phase is found from the finger flexion",
        )
    return AnnotationMatch(
        a, f"phase annotation {a.name}: {covered} frames, as many as {m.name} has", intervals=intervals
    )


def match_annotation(motion_path: str | Path, frames: int) -> AnnotationMatch:
    """The phase annotation a recording uses: the one beside it by name, if it agrees with its frames.

    Args:
        motion_path: The recording.
        frames: Its frame count.

    Returns:
        The annotation (:func:`find_annotation_file`) and a note; None with the reason when no file of
        :func:`annotation_names` lies beside it, or with a ``warning:`` when the one there covers another
        number of frames (:func:`check_annotation`).

    Raises:
        InputFileError: The annotation is unreadable.
        FormatError: The annotation is malformed.
    """
    p = Path(motion_path)
    found = find_annotation_file(p)
    if found is None:
        names = " or ".join(annotation_names(p))
        return AnnotationMatch(
            None,
            f"no phase annotation ({names}) beside {p.name}: the grasp phase is found from the finger "
            "flexion",
        )
    return check_annotation(found, p, frames)


def attach_phases(
    trajectory: Trajectory, annotations: str | Path | Sequence[Phase | PhaseAnnotation]
) -> Trajectory:
    """Set a trajectory's phases from an annotation file or given intervals.

    Args:
        trajectory: The recording the phases belong to.
        annotations: A phase annotation file (read with :func:`read_phase_annotations`), or phases /
            annotations already read (frame numbers 0-based, stop exclusive).

    Returns:
        A copy of the trajectory with :attr:`~Trajectory.phases` replaced (see
        :func:`handsim.glove.phases.with_phases`: annotations become phases named
        :attr:`~handsim.glove.phases.PhaseAnnotation.name`, and a note names the source, each interval's
        label, and frames no phase covers).

    Raises:
        InputFileError: The annotation file is missing or unreadable.
        FormatError: The annotation file is malformed.
        TrajectoryError: An interval ends after the trajectory's last frame (the message names the
            annotation file and line).
    """
    if isinstance(annotations, (str, Path)):
        return with_phases(trajectory, read_phase_annotations(annotations), source=str(annotations))
    return with_phases(trajectory, annotations)


__all__ = [
    "ANNOTATED_PREFIX",
    "ANNOTATION_SUFFIX",
    "annotation_frames",
    "annotation_names",
    "attach_phases",
    "check_annotation",
    "find_annotation_file",
    "match_annotation",
    "read_phase_annotations",
]
