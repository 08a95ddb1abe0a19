"""Recordings are checked before they are judged: their own annotation only, spikes filled, provenance said.

Every recording here is synthetic, written in ``tmp_path`` (a smooth closing and opening of the hand in the
GraspDB14 row layout); no GraspDB14 file is copied.
"""

from __future__ import annotations

import json
import re
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np
import pytest

from handsim.cli import main
from handsim.errors import TrajectoryError
from handsim.glove.checks import CHECK_FIELDS, check_recording
from handsim.glove.phases import AnnotationMatch
from handsim.io.graspdb.annotations import match_annotation, read_phase_annotations
from handsim.io.graspdb.glove import read_graspdb_glove
from handsim.runner.trial_record import recording_checks, trajectory_quality
from handsim.sim.replay import ReplayConfig, replay
from handsim.trials import find_trial, load_trial

FRAMES = 150
STEM = "01_11_ex03-rad-004-grasp-su04"
FLEXION_SENSORS = (1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, 16, 17, 18)
"""File columns of the flexion sensors (T-MCPJ … L-DIPJ); a file value is minus the flexion."""
SPIKED = (1, 2, 4, 5, 8, 9)


def _closing(n: int = FRAMES) -> np.ndarray:
    """File values (rad) of a hand that closes over frames 20–70, holds until 110 and opens by 140."""
    f = np.arange(n, dtype=float)
    close = np.clip((f - 20) / 50, 0, 1)
    open_ = np.clip((f - 110) / 30, 0, 1)
    level = 3 * close**2 - 2 * close**3 - (3 * open_**2 - 2 * open_**3)
    values = np.zeros((n, 23))
    values[:, FLEXION_SENSORS] = -1.0 * level[:, None]
    return values


def _write_recording(path: Path, values: np.ndarray) -> Path:
    start = datetime(2014, 9, 15, 8, 2, 9)
    lines = []
    for i, row in enumerate(values):
        d = start + timedelta(milliseconds=16 * i)
        seconds = d.second + d.microsecond / 1e6
        stamp = f"{d.year:04d} {d.month:02d} {d.day:02d} {d.hour:02d} {d.minute:02d} {seconds:08.5f}"
        lines.append(f"{stamp} 1 {' '.join(f'{v:.5f}' for v in row)} ")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")
    return path


def _write_annotation(folder: Path, last: int) -> Path:
    path = folder / f"{STEM}_annot-.txt"
    path.write_text(f"# interval annotation\n1 20 .rest\n21 70 reach\n71 110 .grasp\n111 {last} retract\n")
    return path


def _spiky(tmp_path: Path) -> Path:
    values = _closing()
    values[0, list(SPIKED)] -= 1.5
    values[FRAMES - 1, list(SPIKED)] += 1.2
    return _write_recording(tmp_path / f"r_{STEM}.txt", values)


def test_annotation_of_another_length_is_not_used_and_the_trial_says_why(tmp_path):
    recording = _write_recording(tmp_path / f"r_{STEM}.txt", _closing())
    annotation = _write_annotation(tmp_path, 282)
    trial = find_trial(recording)
    warning = (
        f"warning: phase annotation {annotation} is not used: its intervals end at frame 282, but the "
        f"recording {recording} has {FRAMES} frames (an annotation covers exactly the frames of the "
        "recording it belongs to; is it another recording's?); the grasp phase is found from the finger "
        "flexion"
    )
    assert trial.annotation_path is None
    assert warning in trial.notes
    loaded = load_trial(trial)
    assert loaded.trajectory.phases == ()
    assert loaded.checks.annotation.note == warning
    assert recording_checks(loaded.checks, loaded.scene) == {
        "annotation": None,
        "annotation_note": warning,
        "spikes": 0,
        "spike_frames": [],
        "spike_max_speed_rad_s": pytest.approx(43.633, abs=1e-3),
        "phase_source": "peak flexion",
    }


def test_annotation_covering_the_recordings_frames_gives_the_phases(tmp_path):
    recording = _write_recording(tmp_path / f"r_{STEM}.txt", _closing())
    annotation = _write_annotation(tmp_path, FRAMES)
    loaded = load_trial(recording)
    assert loaded.trial.annotation_path == str(annotation)
    assert [p.name for p in loaded.trajectory.phases] == ["rest", "reach", "grasp", "retract"]
    found = recording_checks(loaded.checks, loaded.scene)
    assert (found["annotation"], found["phase_source"]) == (str(annotation), "phase")
    assert found["annotation_note"] == (
        f"phase annotation {annotation.name}: {FRAMES} frames, as many as {recording.name} has"
    )


def test_matched_annotation_carries_the_intervals_read_from_its_file(tmp_path):
    recording = _write_recording(tmp_path / f"r_{STEM}.txt", _closing())
    annotation = _write_annotation(tmp_path, FRAMES)
    match = match_annotation(recording, FRAMES)
    assert match.path == annotation
    assert match.intervals == read_phase_annotations(annotation)
    checked, _ = check_recording(read_graspdb_glove(recording), match)
    assert [(p.name, p.start, p.stop) for p in checked.phases] == [
        ("rest", 0, 20),
        ("reach", 20, 70),
        ("grasp", 70, 110),
        ("retract", 110, FRAMES),
    ]


def test_check_recording_refuses_an_annotation_match_without_its_intervals(tmp_path):
    recording = _write_recording(tmp_path / f"r_{STEM}.txt", _closing())
    annotation = _write_annotation(tmp_path, FRAMES)
    message = (
        f"phase annotation {annotation}: the match carries none of its intervals; match it with "
        "handsim.io.graspdb.annotations.match_annotation or check_annotation, which read them"
    )
    with pytest.raises(TrajectoryError, match=re.escape(message)):
        check_recording(read_graspdb_glove(recording), AnnotationMatch(annotation, "given by hand"))


def test_same_bytes_under_another_prefix_state_the_phase_source_they_got(tmp_path):
    values = _closing()
    with_r = _write_recording(tmp_path / "a" / f"r_{STEM}.txt", values)
    with_h = _write_recording(tmp_path / "b" / f"h_{STEM}.txt", values)
    _write_annotation(with_r.parent, FRAMES)
    _write_annotation(with_h.parent, FRAMES)
    assert with_r.read_bytes() == with_h.read_bytes()
    r, h = load_trial(with_r), load_trial(with_h)
    assert recording_checks(r.checks, r.scene)["phase_source"] == "phase"
    assert recording_checks(h.checks, h.scene) == {
        "annotation": None,
        "annotation_note": (
            f"no phase annotation (h_{STEM}_annot-.txt) beside h_{STEM}.txt: the grasp phase is found from "
            "the finger flexion"
        ),
        "spikes": 0,
        "spike_frames": [],
        "spike_max_speed_rad_s": pytest.approx(43.633, abs=1e-3),
        "phase_source": "peak flexion",
    }


@pytest.mark.slow
def test_same_bytes_with_and_without_the_r_prefix_beside_a_foreign_annotation_get_the_same_verdict(tmp_path):
    values = _closing()
    paths = [
        _write_recording(tmp_path / "a" / f"r_{STEM}.txt", values),
        _write_recording(tmp_path / "b" / f"{STEM}.txt", values),
    ]
    for path in paths:
        _write_annotation(path.parent, 282)
    outcomes = []
    for path in paths:
        loaded = load_trial(path)
        result = replay(loaded.scene, loaded.trajectory, ReplayConfig(ensemble=False))
        found = recording_checks(loaded.checks, loaded.scene)
        outcomes.append(
            (result.summary, found["annotation"], found["phase_source"], loaded.scene.model_sha256)
        )
    assert outcomes[0] == outcomes[1]
    assert outcomes[0][1:3] == (None, "peak flexion")


def test_spikes_in_the_first_and_last_row_are_filled_and_listed_in_the_trials_notes(tmp_path):
    loaded = load_trial(_spiky(tmp_path))
    assert [s.frame for s in loaded.checks.spikes] == [0, FRAMES - 1]
    assert (
        "recording checks: 2 single-sample spikes at frames 0, 149, marked invalid and filled (linear)"
        in (loaded.notes)
    )
    clean = load_trial(_write_recording(tmp_path / "clean" / f"r_{STEM}.txt", _closing()))
    np.testing.assert_allclose(loaded.trajectory.targets, clean.trajectory.targets, atol=1e-12)
    filled = np.flatnonzero(loaded.trajectory.filled.any(axis=1))
    assert filled.tolist() == [0, FRAMES - 1]
    quality = trajectory_quality(loaded.trajectory, loaded.scene, loaded.checks)
    assert (quality["spikes"], quality["spike_frames"], quality["gaps_filled"]) == (2, [0, 149], 12)
    assert quality["invalid_samples"] == 0


def test_trajectory_quality_without_checks_says_none_for_them(tmp_path):
    loaded = load_trial(_write_recording(tmp_path / f"r_{STEM}.txt", _closing()))
    quality = trajectory_quality(loaded.trajectory, loaded.scene)
    assert all(quality[k] is None for k in CHECK_FIELDS)
    assert quality["phase_source"] == "peak flexion"


def test_inspect_shows_the_annotation_and_the_spikes(capsys, tmp_path):
    path = _spiky(tmp_path)
    assert main(["inspect", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert (
        f"annotation no phase annotation (r_{STEM}_annot-.txt or {STEM}_annot-.txt) beside {path.name}: the "
        "grasp phase is found from the finger flexion" in lines
    )
    assert "spikes     2 single-sample spikes at frames 0, 149, marked invalid and filled (linear)" in lines
    assert (
        "spike      frame 0 (0.000 s): 6 DoFs jump and revert, up to 1.50 rad at 94 rad/s (th_mcp_flex, "
        "th_ip_flex, if_mcp_flex, if_pip_flex, mf_mcp_flex, mf_pip_flex)"
    ) in lines


@pytest.mark.slow
def test_replay_summary_and_json_name_the_annotation_the_phase_source_and_the_spikes(capsys, tmp_path):
    path = _spiky(tmp_path)
    _write_annotation(tmp_path, FRAMES)
    out = tmp_path / "replay.json"
    assert main(["replay", str(path), "--json", str(out)]) in (0, 4)
    lines = capsys.readouterr().out.splitlines()
    assert (
        f"annotation  phase annotation {STEM}_annot-.txt: {FRAMES} frames, as many as {path.name} has"
        in lines
    )
    assert "phases      grasp from the annotated 'grasp' phase" in lines
    assert "spikes      2 single-sample spikes at frames 0, 149, marked invalid and filled (linear)" in lines
    recording = json.loads(out.read_text())["recording"]
    assert recording["annotation"] == str(tmp_path / f"{STEM}_annot-.txt")
    assert (recording["phase_source"], recording["spikes"], recording["spike_frames"]) == (
        "phase",
        2,
        [0, 149],
    )
