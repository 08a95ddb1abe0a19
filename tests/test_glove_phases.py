"""Trial phases: switch segments, GraspDB14 phase annotation files, attaching and cutting."""

from __future__ import annotations

import dataclasses
import itertools
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from handsim.datatypes.trajectory import ObjectTrack, Phase, Trajectory
from handsim.errors import FormatError, InputFileError, TrajectoryError
from handsim.glove import AnnotationMatch, PhaseAnnotation, cut, split_by_switch, switch_segments
from handsim.io.graspdb.annotations import (
    annotation_names,
    attach_phases,
    find_annotation_file,
    match_annotation,
    read_phase_annotations,
)
from handsim.io.graspdb.glove import read_graspdb_glove

MOTION = "r_01_11_ex03-rad-004-grasp-su04.txt"
ANNOTATION = "01_11_ex03-rad-004-grasp-su04_annot-.txt"
REAL_PHASES = (
    Phase("rest", 0, 24),
    Phase("reach", 24, 81),
    Phase("grasp", 81, 164),
    Phase("retract", 164, 233),
    Phase("rest", 233, 282),
)


def _trajectory(n: int = 10, switch: list[int] | None = None) -> Trajectory:
    return Trajectory(
        times=np.arange(n) * 0.016,
        dof_names=("a", "b"),
        targets=np.arange(2 * n, dtype=float).reshape(n, 2),
        valid=np.ones((n, 2), dtype=bool),
        switch=None if switch is None else np.array(switch, dtype=bool),
        source="trial.txt",
    )


def _write(tmp_path: Path, text: str, name: str = "x_annot-.txt") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# --------------------------------------------------------------------------------------------------
# Switch segments


def test_switch_segments_are_maximal_runs() -> None:
    assert switch_segments([1, 1, 0, 0, 0, 1, 0]) == (
        Phase("on", 0, 2),
        Phase("off", 2, 5),
        Phase("on", 5, 6),
        Phase("off", 6, 7),
    )
    assert switch_segments(np.zeros(3, dtype=bool)) == (Phase("off", 0, 3),)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.booleans(), min_size=1, max_size=60))
def test_switch_segments_tile_the_frames_and_alternate(switch: list[bool]) -> None:
    segments = switch_segments(switch)
    assert segments[0].start == 0
    assert segments[-1].stop == len(switch)
    for a, b in itertools.pairwise(segments):
        assert a.stop == b.start
        assert a.name != b.name
    for seg in segments:
        assert all(switch[k] == (seg.name == "on") for k in range(seg.start, seg.stop))


@pytest.mark.parametrize(
    ("switch", "message"),
    [
        ([], r"^switch must be a non-empty 1-D array, got shape \(0,\)$"),
        ([[1, 0]], r"^switch must be a non-empty 1-D array, got shape \(1, 2\)$"),
        ([0, 1, 2], r"^switch must hold booleans or 0/1 values; frame 2 holds 2$"),
    ],
)
def test_bad_switch_is_an_error(switch: list, message: str) -> None:
    with pytest.raises(TrajectoryError, match=message):
        switch_segments(switch)


def test_split_by_switch_can_keep_only_the_on_segments() -> None:
    traj = _trajectory(6, [0, 1, 1, 0, 1, 1])
    assert split_by_switch(traj) == (
        Phase("off", 0, 1),
        Phase("on", 1, 3),
        Phase("off", 3, 4),
        Phase("on", 4, 6),
    )
    assert split_by_switch(traj, state=True) == (Phase("on", 1, 3), Phase("on", 4, 6))
    assert split_by_switch(traj, state=False) == (Phase("off", 0, 1), Phase("off", 3, 4))


def test_split_by_switch_without_switch_is_an_error() -> None:
    with pytest.raises(
        TrajectoryError, match=r"^trial.txt has no switch state \(only CyberGlove recordings carry one\)$"
    ):
        split_by_switch(_trajectory())


def test_real_trials_are_switch_on_throughout(graspdb_dir: Path) -> None:
    traj = read_graspdb_glove(graspdb_dir / MOTION)
    assert split_by_switch(traj) == (Phase("on", 0, 282),)


# --------------------------------------------------------------------------------------------------
# Annotation files: the real one


def test_real_annotation_file_reads_five_one_based_inclusive_intervals(graspdb_dir: Path) -> None:
    annotations = read_phase_annotations(graspdb_dir / ANNOTATION)
    assert annotations == (
        PhaseAnnotation(".rest", 0, 24, 2),
        PhaseAnnotation("reach-overopen-closing", 24, 81, 3),
        PhaseAnnotation(".grasp", 81, 164, 4),
        PhaseAnnotation("retract-opening", 164, 233, 5),
        PhaseAnnotation(".rest", 233, 282, 6),
    )
    assert [a.name for a in annotations] == ["rest", "reach", "grasp", "retract", "rest"]
    assert [a.static for a in annotations] == [True, False, True, False, True]
    assert annotations[1].qualifiers == ("overopen", "closing")
    assert tuple(a.to_phase() for a in annotations) == REAL_PHASES


def test_real_annotation_tiles_its_282_frame_motion(graspdb_dir: Path) -> None:
    traj = read_graspdb_glove(graspdb_dir / MOTION)
    annotations = read_phase_annotations(graspdb_dir / ANNOTATION)
    assert annotations[0].start == 0
    assert annotations[-1].stop == traj.nframes == 282
    assert all(a.stop == b.start for a, b in itertools.pairwise(annotations))


def test_annotation_file_is_found_beside_its_prefixed_motion(graspdb_dir: Path) -> None:
    assert find_annotation_file(graspdb_dir / MOTION) == graspdb_dir / ANNOTATION


@pytest.mark.parametrize("name", ["01_ex01-rad-002-grasp-su01.txt", "04_ex01-rad-045-grasp-su03.txt"])
def test_motion_without_annotation_finds_none(graspdb_dir: Path, name: str) -> None:
    assert find_annotation_file(graspdb_dir / name) is None


@pytest.mark.parametrize(
    "motion",
    [
        "01_11_ex03-rad-004-grasp-su04.txt",  # the exact stem
        "01_11_ex03-rad-004-grasp-su04",  # the exact stem, no extension
    ],
)
def test_annotation_file_is_found_for_its_exact_stem(tmp_path: Path, motion: str) -> None:
    annotation = _write(tmp_path, "1 2 .rest\n", ANNOTATION)
    assert find_annotation_file(tmp_path / motion) == annotation


@pytest.mark.parametrize(
    "motion",
    [
        "h_01_11_ex03-rad-004-grasp-su04.txt",  # another prefix
        "VIShand_01_11_ex03-rad-004-grasp-su04.txt",  # another prefix, upper case
        "R_01_11_ex03-rad-004-grasp-su04.txt",  # not the documented r_
        "r_01_11_ex03-raw-004-grasp-su04.txt",  # another stem (the raw twin)
        "01_11_ex03-rad-004-grasp-su04.txt.bak",  # another stem
    ],
)
def test_annotation_file_is_not_found_for_another_recordings_name(tmp_path: Path, motion: str) -> None:
    _write(tmp_path, "1 2 .rest\n", ANNOTATION)
    assert find_annotation_file(tmp_path / motion) is None


def test_annotation_with_prefix_kept_is_found(tmp_path: Path) -> None:
    annotation = _write(tmp_path, "1 2 .rest\n", "r_01_11_ex03-rad-004-grasp-su04_annot-.txt")
    assert find_annotation_file(tmp_path / MOTION) == annotation


def test_annotation_names_drop_only_the_r_prefix() -> None:
    assert annotation_names("x/r_01_11_ex03-rad-004-grasp-su04.txt") == (
        "r_01_11_ex03-rad-004-grasp-su04_annot-.txt",
        "01_11_ex03-rad-004-grasp-su04_annot-.txt",
    )
    assert annotation_names("h_01_ex01-rad-002-grasp-su01.txt") == (
        "h_01_ex01-rad-002-grasp-su01_annot-.txt",
    )


def test_match_annotation_uses_an_annotation_covering_the_recordings_frames(graspdb_dir: Path) -> None:
    match = match_annotation(graspdb_dir / MOTION, 282)
    assert match == AnnotationMatch(
        graspdb_dir / ANNOTATION,
        f"phase annotation {ANNOTATION}: 282 frames, as many as {MOTION} has",
    )
    assert not match.warning


@pytest.mark.parametrize("frames", [276, 10000])
def test_match_annotation_warns_and_uses_none_when_the_frame_counts_differ(
    tmp_path: Path, frames: int
) -> None:
    annotation = _write(tmp_path, "1 24 .rest\n25 282 .grasp\n", ANNOTATION)
    match = match_annotation(tmp_path / MOTION, frames)
    assert match.path is None and match.warning
    assert match.note == (
        f"warning: phase annotation {annotation} is not used: its intervals end at frame 282, but the "
        f"recording {tmp_path / MOTION} has {frames} frames (an annotation covers exactly the frames of the "
        "recording it belongs to; is it another recording's?); the grasp phase is found from the finger "
        "flexion"
    )


def test_match_annotation_says_which_names_were_looked_for(tmp_path: Path) -> None:
    match = match_annotation(tmp_path / MOTION, 282)
    assert match == AnnotationMatch(
        None,
        f"no phase annotation (r_01_11_ex03-rad-004-grasp-su04_annot-.txt or {ANNOTATION}) beside {MOTION}: "
        "the grasp phase is found from the finger flexion",
    )


def test_attach_real_annotation_sets_named_phases(graspdb_dir: Path) -> None:
    traj = attach_phases(read_graspdb_glove(graspdb_dir / MOTION), graspdb_dir / ANNOTATION)
    assert traj.phases == REAL_PHASES
    assert traj.phase("grasp") == Phase("grasp", 81, 164)
    assert traj.notes[-1] == (
        f"phases from {graspdb_dir / ANNOTATION} (frames 0-based, stop exclusive): .rest [0, 24), "
        "reach-overopen-closing [24, 81), .grasp [81, 164), retract-opening [164, 233), .rest [233, 282)"
    )


def test_annotation_longer_than_the_motion_is_an_error(graspdb_dir: Path) -> None:
    traj = read_graspdb_glove(graspdb_dir / "04_ex01-rad-045-grasp-su03.txt")
    with pytest.raises(
        TrajectoryError,
        match=rf"^{graspdb_dir / ANNOTATION}:6: interval 234-282 \(\.rest\) ends after the last frame 276 of "
        rf"{graspdb_dir / '04_ex01-rad-045-grasp-su03.txt'}; is it the annotation of another motion\?$",
    ):
        attach_phases(traj, graspdb_dir / ANNOTATION)


def test_attach_given_phases_notes_uncovered_frames() -> None:
    traj = attach_phases(_trajectory(10), [Phase("reach", 2, 5), PhaseAnnotation(".grasp", 5, 8)])
    assert traj.phases == (Phase("reach", 2, 5), Phase("grasp", 5, 8))
    assert traj.notes[-1] == (
        "phases from given intervals (frames 0-based, stop exclusive): reach [2, 5), .grasp [5, 8); "
        "4 of 10 frames are in no phase"
    )


def test_attach_phase_outside_the_frames_is_an_error() -> None:
    with pytest.raises(TrajectoryError, match=r"^phase 'x' spans frames \[5, 12\), outside \[0, 10\)$"):
        attach_phases(_trajectory(10), [Phase("x", 5, 12)])


# --------------------------------------------------------------------------------------------------
# Annotation files: errors


def test_annotation_comments_blank_lines_and_crlf_are_accepted(tmp_path: Path) -> None:
    path = tmp_path / "a_annot-.txt"
    path.write_bytes(b"# interval annotation\r\n\r\n  1  3  .rest\r\n# more\r\n 4 9 reach\r\n")
    assert read_phase_annotations(path) == (
        PhaseAnnotation(".rest", 0, 3, 3),
        PhaseAnnotation("reach", 3, 9, 5),
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1 24\n", r":1: expected 3 blank-separated entries \(first frame, last frame, label\), got 2"),
        (
            "1 24 .rest extra\n",
            r":1: expected 3 blank-separated entries \(first frame, last frame, label\), got 4",
        ),
        (
            "# c\n1.5 24 .rest\n",
            r":2 \[first frame\]: expected a frame number \(an integer >= 1\), got '1.5'",
        ),
        ("0 24 .rest\n", r":1 \[first frame\]: expected a frame number \(an integer >= 1\), got '0'"),
        ("1 x .rest\n", r":1 \[last frame\]: expected a frame number \(an integer >= 1\), got 'x'"),
        ("5 4 .rest\n", r":1 \[last frame\]: last frame 4 is before first frame 5"),
        ("1 4 re ach\n", r":1: expected 3 blank-separated entries \(first frame, last frame, label\), got 4"),
        (
            "1 4 reach--x\n",
            r":1 \[label\]: expected a phase label such as '\.rest' or 'reach-overopen-closing', "
            r"got 'reach--x'",
        ),
        (
            "1 10 .rest\n10 20 reach\n",
            r":2 \[first frame\]: interval 10-20 does not start after the previous interval 1-10 "
            r"\(line 1\) ends; intervals must be in frame order without overlap",
        ),
        (
            "# only a header\n\n",
            r": no phase intervals: expected lines '<first frame> <last frame> <label>' "
            r"\(1-based, inclusive\)",
        ),
    ],
)
def test_malformed_annotation_names_file_line_and_field(tmp_path: Path, text: str, message: str) -> None:
    path = _write(tmp_path, text)
    with pytest.raises(FormatError, match=rf"^{path}{message}$"):
        read_phase_annotations(path)


def test_missing_annotation_file_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputFileError, match=r"file not found$"):
        read_phase_annotations(tmp_path / "none_annot-.txt")


_label = st.from_regex(r"\.?[a-z][a-z0-9_]{0,6}(-[a-z0-9_]{1,5}){0,2}", fullmatch=True)


@settings(max_examples=60, deadline=None)
@given(
    gaps=st.lists(st.integers(min_value=0, max_value=3), min_size=1, max_size=8),
    lengths=st.lists(st.integers(min_value=1, max_value=50), min_size=8, max_size=8),
    labels=st.lists(_label, min_size=8, max_size=8),
)
def test_random_valid_annotations_read_back(
    tmp_path_factory: pytest.TempPathFactory, gaps: list[int], lengths: list[int], labels: list[str]
) -> None:
    lines, expected, last = ["# interval   annotation"], [], 0
    for k, gap in enumerate(gaps):
        first = last + 1 + gap
        last = first + lengths[k] - 1
        lines.append(f"{first:4d} {last:4d}    {labels[k]}")
        expected.append(PhaseAnnotation(labels[k], first - 1, last, k + 2))
    path = tmp_path_factory.mktemp("annot") / "x_annot-.txt"
    path.write_text("\n".join(lines) + "\n")
    assert read_phase_annotations(path) == tuple(expected)


# --------------------------------------------------------------------------------------------------
# Cutting


def test_cut_slices_every_per_frame_array_and_restarts_time() -> None:
    n = 10
    traj = dataclasses.replace(
        _trajectory(n, [1] * n),
        root_pose=np.tile(np.arange(n, dtype=float)[:, None], (1, 7)),
        channels={"P-Arch": np.arange(n, dtype=float)},
        filled=np.zeros((n, 2), dtype=bool),
        objects={"ball": ObjectTrack(pose=np.zeros((n, 7)), valid=np.ones(n, dtype=bool))},
        phases=(Phase("reach", 0, 4), Phase("grasp", 4, 7), Phase("rest", 7, 10)),
    )
    part = cut(traj, "grasp")
    assert part.nframes == 3
    np.testing.assert_allclose(part.times, [0.0, 0.016, 0.032])
    np.testing.assert_array_equal(part.targets, traj.targets[4:7])
    np.testing.assert_array_equal(part.root_pose[:, 0], [4.0, 5.0, 6.0])  # type: ignore[index]
    np.testing.assert_array_equal(part.channels["P-Arch"], [4.0, 5.0, 6.0])
    assert part.objects["ball"].pose.shape == (3, 7)
    assert part.phases == (Phase("grasp", 0, 3),)
    assert (
        part.notes[-1]
        == "cut to phase 'grasp': frames [4, 7) of the original, whose time 0.06400 s is time 0 here"
    )


def test_cut_clips_overlapping_phases() -> None:
    traj = dataclasses.replace(_trajectory(10), phases=(Phase("a", 0, 6), Phase("b", 6, 10)))
    assert cut(traj, Phase("trial", 3, 8)).phases == (Phase("a", 0, 3), Phase("b", 3, 5))


def test_cut_real_trial_to_its_grasp_phase(graspdb_dir: Path) -> None:
    traj = attach_phases(read_graspdb_glove(graspdb_dir / MOTION), graspdb_dir / ANNOTATION)
    grasp = cut(traj, "grasp")
    assert grasp.nframes == 83
    np.testing.assert_array_equal(grasp.targets, traj.targets[81:164])


def test_cut_unknown_phase_lists_the_phases() -> None:
    traj = dataclasses.replace(_trajectory(10), phases=(Phase("a", 0, 6),))
    with pytest.raises(TrajectoryError, match=r"^no phase 'grasp'; phases are \['a'\]$"):
        cut(traj, "grasp")


def test_cut_outside_the_frames_is_an_error() -> None:
    with pytest.raises(TrajectoryError, match=r"^phase 'x' spans frames \[8, 12\), outside \[0, 10\)$"):
        cut(_trajectory(10), Phase("x", 8, 12))


def test_copied_real_annotation_reads_the_same(graspdb_dir: Path, tmp_path: Path) -> None:
    copy = Path(shutil.copy(graspdb_dir / ANNOTATION, tmp_path / ANNOTATION))
    assert [(a.label, a.start, a.stop) for a in read_phase_annotations(copy)] == [
        (a.label, a.start, a.stop) for a in read_phase_annotations(graspdb_dir / ANNOTATION)
    ]
