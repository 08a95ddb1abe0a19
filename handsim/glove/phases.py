"""Trial phases of CyberGlove recordings: switch segments, GraspDB14 phase annotations, cutting.

Two sources name frame intervals of a recording:

* The glove's **switch** (spec §3.5–3.7): the actors toggled it to mark poses of the calibration
  sequence and the start and end of each task. :func:`switch_segments` / :func:`split_by_switch` turn
  the switch state into ``on``/``off`` :class:`~handsim.datatypes.trajectory.Phase` intervals.
* **Phase annotation files** (``<motion name>_annot-.txt``, not described in the spec; format read off
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

Phases become named frame intervals of a :class:`~handsim.datatypes.trajectory.Trajectory` (``start`` 0-based,
``stop`` exclusive) with :func:`attach_phases`; :func:`cut` slices a trajectory to one phase.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from handsim.datatypes.trajectory import ObjectTrack, Phase, Trajectory
from handsim.errors import FormatError, TrajectoryError

SWITCH_ON = "on"
"""Name of a phase during which the glove switch is ON."""

SWITCH_OFF = "off"
"""Name of a phase during which the glove switch is OFF."""

ANNOTATION_SUFFIX = "_annot-.txt"
"""What a phase annotation file name adds to its motion file's name (without ``.txt``)."""

_LABEL_RE = re.compile(r"\.?[A-Za-z][A-Za-z0-9_]*(?:-[A-Za-z0-9_]+)*")
_FRAME_RE = re.compile(r"\d+")


# --------------------------------------------------------------------------------------------------
# Switch segments


def switch_segments(switch: npt.ArrayLike) -> tuple[Phase, ...]:
    """Split a switch-state series into maximal runs of equal state.

    Args:
        switch: Switch state per frame, shape (T,): booleans or 0/1 numbers.

    Returns:
        The runs in frame order, named :data:`SWITCH_ON` or :data:`SWITCH_OFF`; they tile ``[0, T)``.

    Raises:
        TrajectoryError: ``switch`` is not a non-empty 1-D array of booleans or 0/1 values.
    """
    s = np.asarray(switch)
    if s.ndim != 1 or s.shape[0] == 0:
        raise TrajectoryError(f"switch must be a non-empty 1-D array, got shape {s.shape}")
    if s.dtype != bool:
        if not np.issubdtype(s.dtype, np.number) or not np.all((s == 0) | (s == 1)):
            bad = int(np.argmax(~((s == 0) | (s == 1)))) if np.issubdtype(s.dtype, np.number) else 0
            raise TrajectoryError(
                f"switch must hold booleans or 0/1 values; frame {bad} holds {s[bad].item()!r}"
            )
        s = s == 1
    edges = (np.flatnonzero(s[1:] != s[:-1]) + 1).tolist()
    starts = [0, *edges]
    stops = [*edges, s.shape[0]]
    return tuple(
        Phase(SWITCH_ON if s[a] else SWITCH_OFF, int(a), int(b)) for a, b in zip(starts, stops, strict=True)
    )


def split_by_switch(trajectory: Trajectory, *, state: bool | None = None) -> tuple[Phase, ...]:
    """The switch segments of a CyberGlove recording as phases.

    In the GraspDB14 scenarios the switch is ON while a task is executed (spec §3.6), so
    ``split_by_switch(traj, state=True)`` gives the motion trials of an uncut recording.

    Args:
        trajectory: A recording with a switch state (:attr:`Trajectory.switch`).
        state: Keep only the ON (True) or OFF (False) segments; None keeps all.

    Returns:
        Phases named ``"on"``/``"off"`` in frame order.

    Raises:
        TrajectoryError: The trajectory has no switch state.
    """
    if trajectory.switch is None:
        what = trajectory.source or "the trajectory"
        raise TrajectoryError(f"{what} has no switch state (only CyberGlove recordings carry one)")
    segments = switch_segments(trajectory.switch)
    if state is None:
        return segments
    wanted = SWITCH_ON if state else SWITCH_OFF
    return tuple(p for p in segments if p.name == wanted)


# --------------------------------------------------------------------------------------------------
# Annotation files


@dataclass(frozen=True)
class PhaseAnnotation:
    """One interval of a GraspDB14 phase annotation file.

    Attributes:
        label: The label as written, e.g. ``".rest"`` or ``"reach-overopen-closing"``.
        start: First frame, 0-based (the file's first frame minus 1).
        stop: One past the last frame (the file's last frame, which is 1-based and inclusive).
        line: 1-based line of the file it was read from (0 when not read from a file).
    """

    label: str
    start: int
    stop: int
    line: int = 0

    @property
    def name(self) -> str:
        """Phase name: the label without its leading ``.`` and qualifiers (``"reach"``)."""
        return self.label.lstrip(".").split("-")[0]

    @property
    def static(self) -> bool:
        """True for a static phase (label starts with ``.``: the hand holds a pose)."""
        return self.label.startswith(".")

    @property
    def qualifiers(self) -> tuple[str, ...]:
        """The ``-``-separated words after the name (``("overopen", "closing")``)."""
        return tuple(self.label.lstrip(".").split("-")[1:])

    def to_phase(self) -> Phase:
        """The interval as a trajectory :class:`~handsim.datatypes.trajectory.Phase` named :attr:`name`."""
        return Phase(self.name, self.start, self.stop)


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
    from handsim.io._text import read_text  # lazy: handsim.io imports handsim.glove

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


@dataclass(frozen=True)
class AnnotationMatch:
    """Which phase annotation a recording uses, and why (or why none).

    Attributes:
        path: The annotation file used, or None.
        note: For people: the file and the frames it covers, or why no annotation is used. A file that lies
            beside the recording but is not used gives a note starting with ``warning:``.
    """

    path: Path | None
    note: str

    @property
    def warning(self) -> bool:
        """An annotation lies beside the recording but is not used."""
        return self.note.startswith("warning:")


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
        The annotation with a note, or None with a ``warning:`` note naming both files and both counts.

    Raises:
        InputFileError: The annotation is missing or unreadable.
        FormatError: The annotation is malformed.
    """
    a, m = Path(annotation), Path(motion)
    covered = annotation_frames(a)
    if covered != frames:
        return AnnotationMatch(
            None,
            f"warning: phase annotation {a} is not used: its intervals end at frame {covered}, but the "
            f"recording {m} has {frames} frames (an annotation covers exactly the frames of the recording it "
            "belongs to; is it another recording's?); the grasp phase is found from the finger flexion",
        )
    return AnnotationMatch(a, f"phase annotation {a.name}: {covered} frames, as many as {m.name} has")


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


# --------------------------------------------------------------------------------------------------
# Phases on trajectories


def attach_phases(
    trajectory: Trajectory, annotations: str | Path | Sequence[Phase | PhaseAnnotation]
) -> Trajectory:
    """Set a trajectory's phases from an annotation file or given intervals.

    Args:
        trajectory: The recording the phases belong to.
        annotations: A phase annotation file (read with :func:`read_phase_annotations`), or phases /
            annotations already read (frame numbers 0-based, stop exclusive).

    Returns:
        A copy of the trajectory with :attr:`~Trajectory.phases` replaced (annotations become phases named
        :attr:`PhaseAnnotation.name`) and a note naming the source, each interval's label, and frames no
        phase covers.

    Raises:
        InputFileError: The annotation file is missing or unreadable.
        FormatError: The annotation file is malformed.
        TrajectoryError: An interval ends after the trajectory's last frame (the message names the
            annotation file and line).
    """
    n = trajectory.nframes
    if isinstance(annotations, (str, Path)):
        source = str(annotations)
        items: Sequence[Phase | PhaseAnnotation] = read_phase_annotations(annotations)
    else:
        source = "given intervals"
        items = annotations
    phases: list[Phase] = []
    labels: list[str] = []
    for item in items:
        if isinstance(item, PhaseAnnotation):
            if item.stop > n:
                where = f"{source}:{item.line}" if item.line else source
                raise TrajectoryError(
                    f"{where}: interval {item.start + 1}-{item.stop} ({item.label}) ends after the last "
                    f"frame {n} of {trajectory.source or 'the trajectory'}; is it the annotation of another "
                    "motion?"
                )
            phases.append(item.to_phase())
            labels.append(f"{item.label} [{item.start}, {item.stop})")
        else:
            phases.append(item)
            labels.append(f"{item.name} [{item.start}, {item.stop})")
    covered = np.zeros(n, dtype=bool)
    for phase in phases:
        covered[max(phase.start, 0) : max(phase.stop, 0)] = True
    note = f"phases from {source} (frames 0-based, stop exclusive): {', '.join(labels)}"
    if not covered.all():
        note += f"; {int((~covered).sum())} of {n} frames are in no phase"
    return dataclasses.replace(trajectory, phases=tuple(phases), notes=(*trajectory.notes, note))


def cut(trajectory: Trajectory, phase: Phase | str) -> Trajectory:
    """The part of a trajectory inside one phase, as a trajectory of its own.

    Every per-frame array (targets, validity, switch, root pose, channels, filled mask, object tracks) is
    sliced to ``[phase.start, phase.stop)``; times restart at 0; phases overlapping the interval are
    clipped to it and shifted. A note records the cut.

    Args:
        trajectory: The recording.
        phase: A :class:`~handsim.datatypes.trajectory.Phase`, or the name of one of the trajectory's phases
        (the
            first with that name).

    Returns:
        The cut trajectory.

    Raises:
        TrajectoryError: No phase has that name, or the phase lies outside the trajectory's frames.
    """
    p = trajectory.phase(phase) if isinstance(phase, str) else phase
    n = trajectory.nframes
    if not 0 <= p.start < p.stop <= n:
        raise TrajectoryError(f"phase {p.name!r} spans frames [{p.start}, {p.stop}), outside [0, {n})")
    sl = slice(p.start, p.stop)

    def part(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else np.asarray(a)[sl].copy()

    phases = tuple(
        Phase(q.name, max(q.start, p.start) - p.start, min(q.stop, p.stop) - p.start)
        for q in trajectory.phases
        if q.start < p.stop and q.stop > p.start
    )
    t0 = float(trajectory.times[p.start])
    return dataclasses.replace(
        trajectory,
        times=trajectory.times[sl] - t0,
        targets=trajectory.targets[sl].copy(),
        valid=trajectory.valid[sl].copy(),
        switch=part(trajectory.switch),
        root_pose=part(trajectory.root_pose),
        hand_roots={k: np.asarray(v)[sl].copy() for k, v in trajectory.hand_roots.items()},
        channels={k: np.asarray(v)[sl].copy() for k, v in trajectory.channels.items()},
        filled=part(trajectory.filled),
        phases=phases,
        objects={
            k: ObjectTrack(
                pose=np.asarray(o.pose)[sl].copy(), articulation=part(o.articulation), valid=part(o.valid)
            )
            for k, o in trajectory.objects.items()
        },
        notes=(
            *trajectory.notes,
            f"cut to phase {p.name!r}: frames [{p.start}, {p.stop}) of the original, whose time {t0:.5f} s "
            "is time 0 here",
        ),
    )


__all__ = [
    "ANNOTATED_PREFIX",
    "ANNOTATION_SUFFIX",
    "SWITCH_OFF",
    "SWITCH_ON",
    "AnnotationMatch",
    "PhaseAnnotation",
    "annotation_frames",
    "annotation_names",
    "attach_phases",
    "check_annotation",
    "cut",
    "find_annotation_file",
    "match_annotation",
    "read_phase_annotations",
    "split_by_switch",
    "switch_segments",
]
