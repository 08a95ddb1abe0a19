"""GraspDB14 CyberGlove motion files: reading, sensor → DoF conventions, file names, and errors."""

from __future__ import annotations

import hashlib
from dataclasses import replace
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from handsim.datatypes.skeleton import Dof, Joint, Skeleton
from handsim.errors import FormatError, InputFileError, TrajectoryError
from handsim.glove import (
    SENSOR_NAMES,
    SENSORS,
    GloveCalibration,
    apply_calibration,
    computed_dofs,
    discarded_sensors,
    driven_dofs,
)
from handsim.io import read_trajectory
from handsim.io.graspdb.filenames import GraspDBName, filename_datatype, parse_graspdb_filename
from handsim.io.graspdb.glove import read_graspdb_glove, read_graspdb_raw

REAL_TRIALS = {
    "r_01_11_ex03-rad-004-grasp-su04.txt": 282,
    "01_ex01-rad-002-grasp-su01.txt": 231,
    "04_ex01-rad-045-grasp-su03.txt": 276,
}
ORACLE_NO_EXT = "fk_oracle/16_14_ex01-rad-004-grasp-su06"
DIP_DOFS = ("if_dip_flex", "mf_dip_flex", "rf_dip_flex", "lf_dip_flex")
NAME = "01_ex01-rad-001-grasp-su01.txt"
RAW_NAME = "01_ex01-raw-001-grasp-su01.txt"
ADVICE = (
    r"raw files hold uncalibrated 8-bit sensor counts, not radians, and need a calibration to become joint "
    r"angles: pass one \(read_graspdb_glove\(path, calibration=\.\.\.\)\), e\.g\. estimated with "
    r"handsim\.glove\.estimate_calibration from the actor's '_calib-' sequence, or read the matching '-rad-' "
    r"file instead"
)

# --------------------------------------------------------------------------------------------------
# Helpers


def _stamp(d: datetime) -> str:
    return (
        f"{d.year:04d} {d.month:02d} {d.day:02d} {d.hour:02d} {d.minute:02d} "
        f"{d.second + d.microsecond / 1e6:08.5f}"
    )


def _row(
    d: datetime = datetime(2014, 9, 15, 8, 2, 9, 24000),
    switch: str = "1",
    sensors: list[str] | None = None,
) -> str:
    values = sensors if sensors is not None else [f"{0.01 * (i + 1):.5f}" for i in range(23)]
    return f"{_stamp(d)} {switch} {' '.join(values)} "


def _rows(n: int = 3, step_ms: int = 16) -> list[str]:
    start = datetime(2014, 9, 15, 8, 2, 9, 24000)
    return [_row(start + timedelta(milliseconds=step_ms * i)) for i in range(n)]


def _write(tmp_path: Path, lines: list[str], name: str = NAME) -> Path:
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def _replace_token(line: str, index: int, token: str) -> str:
    tokens = line.split()
    tokens[index] = token
    return " ".join(tokens) + " "


def _file_values(path: Path) -> np.ndarray:
    """The file's 23 sensor columns, parsed here independently of the reader."""
    rows = [line.split() for line in path.read_text().splitlines() if line.strip()]
    return np.array([[float(tok) for tok in row[7:]] for row in rows])


def _fake_skeleton(dof_names: list[str]) -> Skeleton:
    joint = Joint(name="root", parent=-1, position=np.zeros(3), frame=np.eye(3))
    dofs = tuple(
        Dof(name=n, joint="root", axis=np.array([1.0, 0.0, 0.0]), lower=-3.0, upper=3.0) for n in dof_names
    )
    return Skeleton(name="fake", joints=(joint,), dofs=dofs)


# --------------------------------------------------------------------------------------------------
# Sensor layout


def test_sensor_layout_is_the_23_columns_in_row_order() -> None:
    assert list(SENSOR_NAMES) == (
        "T-TMCJ T-MCPJ T-IPJ TI-AA I-MCPJ I-PIPJ I-DIPJ I-AA M-MCPJ M-PIPJ M-DIPJ MI-AA R-MCPJ R-PIPJ "
        "R-DIPJ RM-AA L-MCPJ L-PIPJ L-DIPJ LR-AA P-Arch W-FE W-AA"
    ).split(" ")
    assert [s.index for s in SENSORS] == list(range(23))
    assert all(s.sign == -1 for s in SENSORS)
    assert all(s.description for s in SENSORS)


def test_sensor_map_follows_the_matlab_code_including_thumb_tmc_about_local_y() -> None:
    dof_of = {s.name: s.dof for s in SENSORS}
    assert dof_of["T-TMCJ"] == "th_tmc_pron"
    assert dof_of["TI-AA"] == "th_mcp_abd"
    assert dof_of["MI-AA"] == "if_mcp_abd"
    assert dof_of["W-FE"] == "root_flex"
    assert dof_of["W-AA"] == "root_abd"
    assert dof_of["I-AA"] is None
    assert dof_of["P-Arch"] is None
    assert len(driven_dofs()) == 21
    assert driven_dofs()[:4] == ("th_tmc_pron", "th_mcp_flex", "th_ip_flex", "th_mcp_abd")
    assert [s.name for s in discarded_sensors()] == ["I-AA", "P-Arch"]


def test_sensors_not_measured_by_18_sensor_glove_are_the_dips_and_iaa() -> None:
    assert [s.name for s in SENSORS if not s.measured] == ["I-DIPJ", "I-AA", "M-DIPJ", "R-DIPJ", "L-DIPJ"]
    assert computed_dofs() == DIP_DOFS


# --------------------------------------------------------------------------------------------------
# Real data


@pytest.mark.parametrize(("name", "frames"), REAL_TRIALS.items())
def test_real_trial_reads_with_expected_frame_count(graspdb_dir: Path, name: str, frames: int) -> None:
    traj = read_graspdb_glove(graspdb_dir / name)
    assert traj.nframes == frames
    assert traj.dof_names == driven_dofs()
    assert traj.targets.shape == (frames, 21)
    assert traj.valid.all()
    assert traj.source == str(graspdb_dir / name)
    assert traj.sha256 == hashlib.sha256((graspdb_dir / name).read_bytes()).hexdigest()


@pytest.mark.parametrize("name", REAL_TRIALS)
def test_real_trial_times_start_at_zero_at_about_60_hz(graspdb_dir: Path, name: str) -> None:
    # The sample files run at ~60 Hz ((N-1)/duration: 60.18, 59.76, 60.04); the MATLAB tool reports
    # N/duration (60.26 for the 282-frame trial, spec §5.2.1).
    traj = read_graspdb_glove(graspdb_dir / name)
    assert traj.times[0] == 0.0
    assert 59.0 < traj.mean_rate < 61.5
    gaps = np.diff(traj.times)
    assert gaps.min() > 0.014
    assert gaps.max() < 0.033


def test_real_trial_duration_matches_its_first_and_last_time_stamps(graspdb_dir: Path) -> None:
    # 2014 09 15 08 02 09.02400 … 08 02 13.70400
    traj = read_graspdb_glove(graspdb_dir / "r_01_11_ex03-rad-004-grasp-su04.txt")
    assert traj.duration == pytest.approx(4.68, abs=1e-9)
    assert traj.mean_rate == pytest.approx(281 / 4.68)


@pytest.mark.parametrize("name", REAL_TRIALS)
def test_real_trial_targets_are_negated_file_values(graspdb_dir: Path, name: str) -> None:
    traj = read_graspdb_glove(graspdb_dir / name)
    values = _file_values(graspdb_dir / name)
    for sensor in SENSORS:
        if sensor.dof is not None:
            np.testing.assert_array_equal(traj.column(sensor.dof), -values[:, sensor.index])
    np.testing.assert_array_equal(traj.column("th_tmc_pron"), -values[:, 0])


@pytest.mark.parametrize("name", REAL_TRIALS)
def test_real_trial_keeps_iaa_and_parch_as_unnegated_channels(graspdb_dir: Path, name: str) -> None:
    traj = read_graspdb_glove(graspdb_dir / name)
    values = _file_values(graspdb_dir / name)
    assert set(traj.channels) == {"I-AA", "P-Arch"}
    np.testing.assert_array_equal(traj.channels["I-AA"], values[:, 7])
    np.testing.assert_array_equal(traj.channels["P-Arch"], values[:, 20])
    assert any("I-AA and P-Arch" in note for note in traj.notes)
    assert any("negated" in note for note in traj.notes)


def test_real_trial_marks_dip_dofs_computed_and_switch_on(graspdb_dir: Path) -> None:
    traj = read_graspdb_glove(graspdb_dir / "01_ex01-rad-002-grasp-su01.txt")
    assert traj.computed == DIP_DOFS
    assert traj.switch is not None
    assert traj.switch.dtype == bool
    assert traj.switch.all()


def test_fk_oracle_motion_without_extension_reads(graspdb_dir: Path) -> None:
    path = graspdb_dir / ORACLE_NO_EXT
    traj = read_trajectory(path)
    assert traj.nframes == 435
    assert traj.times[0] == 0.0  # its first stamp is 00:00:00.01666, not 0
    assert traj.duration == pytest.approx(434 * 0.01666, abs=1e-9)
    np.testing.assert_array_equal(traj.column("root_flex"), -_file_values(path)[:, 21])


def test_dispatcher_reads_real_trial_like_the_reader(graspdb_dir: Path) -> None:
    path = graspdb_dir / "04_ex01-rad-045-grasp-su03.txt"
    np.testing.assert_array_equal(read_trajectory(path).targets, read_graspdb_glove(path).targets)


def test_annotation_file_is_refused_as_not_a_motion(graspdb_dir: Path) -> None:
    with pytest.raises(FormatError, match="phase annotation file"):
        read_graspdb_glove(graspdb_dir / "01_11_ex03-rad-004-grasp-su04_annot-.txt")


# --------------------------------------------------------------------------------------------------
# File names


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        (
            "r_01_11_ex03-rad-004-grasp-su04.txt",
            GraspDBName(1, "03", "rad", 4, 4, grasp_id=11, prefix="r"),
        ),
        ("01_ex01-rad-002-grasp-su01.txt", GraspDBName(1, "01", "rad", 2, 1)),
        ("04_ex01-rad-045-grasp-su03.txt", GraspDBName(4, "01", "rad", 45, 3)),
        (
            "01_11_ex03-rad-004-grasp-su04_annot-.txt",
            GraspDBName(1, "03", "rad", 4, 4, grasp_id=11, annotation=True),
        ),
        ("16_14_ex01-rad-004-grasp-su06", GraspDBName(16, "01", "rad", 4, 6, grasp_id=14)),
        # the spec's examples 4.2 - 4.4
        ("01_ex01-raw-002-grasp-su01.txt", GraspDBName(1, "01", "raw", 2, 1)),
        ("01_i_r_ex02-raw-025-grasp-su01.txt", GraspDBName(1, "02", "raw", 25, 1, action_id="i_r")),
        ("01_11_ex03-1-rad-001-grasp-su04.txt", GraspDBName(1, "03-1", "rad", 1, 4, grasp_id=11)),
    ],
)
def test_filename_parses_to_its_fields(name: str, expected: GraspDBName) -> None:
    assert parse_graspdb_filename(name) == expected
    assert parse_graspdb_filename(Path("/some/folder") / name) == expected


def test_filename_scenario_number_drops_the_sub_scenario() -> None:
    parsed = parse_graspdb_filename("01_11_ex03-1-rad-001-grasp-su04.txt")
    assert parsed is not None
    assert parsed.scenario_number == 3


@pytest.mark.parametrize(
    "name",
    [
        "default.xmlskel",
        "01_11_ex03-rad-004-grasp-su04.txt_w_traj.mat",
        "motion.txt",
        "01_ex01-deg-002-grasp-su01.txt",
    ],
)
def test_filename_of_unknown_pattern_gives_none(name: str) -> None:
    assert parse_graspdb_filename(name) is None


def test_every_real_motion_file_name_parses(graspdb_dir: Path) -> None:
    names = [*REAL_TRIALS, ORACLE_NO_EXT, "fk_oracle/01_11_ex03-rad-004-grasp-su04.txt"]
    for name in names:
        assert (graspdb_dir / name).exists()
        parsed = parse_graspdb_filename(name)
        assert parsed is not None, name
        assert parsed.datatype == "rad"


# --------------------------------------------------------------------------------------------------
# Synthetic files: good ones


def test_synthetic_rows_read_back_negated(tmp_path: Path) -> None:
    traj = read_graspdb_glove(_write(tmp_path, _rows(3)))
    assert traj.nframes == 3
    np.testing.assert_allclose(traj.times, [0.0, 0.016, 0.032], atol=1e-12)
    assert traj.column("th_tmc_pron")[0] == -0.01
    assert traj.column("root_abd")[0] == -0.23
    assert traj.channels["I-AA"][0] == 0.08


def test_day_rollover_gives_continuous_times(tmp_path: Path) -> None:
    lines = [
        _row(datetime(2014, 12, 31, 23, 59, 59, 980000)),
        _row(datetime(2014, 12, 31, 23, 59, 59, 996000)),
        _row(datetime(2015, 1, 1, 0, 0, 0, 12000)),
        _row(datetime(2015, 1, 1, 0, 0, 0, 28000)),
    ]
    traj = read_graspdb_glove(_write(tmp_path, lines))
    np.testing.assert_allclose(traj.times, [0.0, 0.016, 0.032, 0.048], atol=1e-9)


def test_minute_hour_day_and_year_rollover_give_continuous_times(tmp_path: Path) -> None:
    lines = [
        _row(datetime(2014, 12, 31, 23, 59, 59, 990000)),
        _row(datetime(2015, 1, 1, 0, 0, 0, 6000)),
        _row(datetime(2015, 1, 1, 0, 0, 0, 22000)),
    ]
    traj = read_graspdb_glove(_write(tmp_path, lines))
    np.testing.assert_allclose(traj.times, [0.0, 0.016, 0.032], atol=1e-9)


def test_rows_without_trailing_space_blank_lines_and_crlf_read(tmp_path: Path) -> None:
    lines = [line.rstrip() for line in _rows(3)]
    path = tmp_path / NAME
    path.write_bytes(("\r\n".join([lines[0], "", lines[1], "   ", lines[2]]) + "\r\n").encode())
    traj = read_graspdb_glove(path)
    assert traj.nframes == 3


def test_switch_state_is_read_per_row(tmp_path: Path) -> None:
    lines = _rows(3)
    lines[1] = _replace_token(lines[1], 6, "0")
    traj = read_graspdb_glove(_write(tmp_path, lines))
    assert traj.switch is not None
    assert traj.switch.tolist() == [True, False, True]


def test_ten_thousand_rows_read_back(tmp_path: Path) -> None:
    path = _write(tmp_path, _rows(10_000))  # the reading time: benchmarks/io_and_cache.py
    traj = read_graspdb_glove(path)
    assert traj.nframes == 10_000
    np.testing.assert_allclose(traj.times[-1], 9_999 * 0.016, atol=1e-9)


# --------------------------------------------------------------------------------------------------
# Skeleton columns


def test_skeleton_columns_hold_undriven_dofs_at_zero(tmp_path: Path) -> None:
    names = ["extra_rot", *reversed(driven_dofs())]
    skeleton = _fake_skeleton(names)
    path = _write(tmp_path, _rows(3))
    traj = read_graspdb_glove(path, skeleton=skeleton)
    assert traj.dof_names == tuple(names)
    np.testing.assert_array_equal(traj.column("extra_rot"), 0.0)
    np.testing.assert_array_equal(traj.column("th_ip_flex"), -_file_values(path)[:, 2])
    assert traj.computed == DIP_DOFS
    assert any("held at 0: ['extra_rot']" in note for note in traj.notes)


def test_skeleton_missing_a_driven_dof_is_an_error(tmp_path: Path) -> None:
    skeleton = _fake_skeleton([d for d in driven_dofs() if d not in ("root_abd", "th_tmc_pron")])
    with pytest.raises(
        TrajectoryError, match=r"lacks DoFs the glove drives: \['th_tmc_pron', 'root_abd'\]"
    ) as exc:
        read_graspdb_glove(_write(tmp_path, _rows(3)), skeleton=skeleton)
    assert "its DoFs are ['th_mcp_flex'," in str(exc.value)


# --------------------------------------------------------------------------------------------------
# Synthetic files: errors


def test_missing_file_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputFileError, match="file not found"):
        read_graspdb_glove(tmp_path / NAME)


@pytest.mark.parametrize("content", ["", "\n\n   \n"])
def test_empty_file_is_an_error(tmp_path: Path, content: str) -> None:
    path = tmp_path / NAME
    path.write_text(content)
    with pytest.raises(FormatError, match=r"empty file: expected rows of 30 blank-separated entries"):
        read_graspdb_glove(path)


@pytest.mark.parametrize(("drop", "count"), [(1, 29), (-1, 31)])
def test_wrong_column_count_names_line_and_count(tmp_path: Path, drop: int, count: int) -> None:
    lines = _rows(3)
    lines[1] = lines[1] + "0.5" if drop < 0 else " ".join(lines[1].split()[:-1])
    with pytest.raises(FormatError, match=rf"{NAME}:2: expected 30 blank-separated entries .* got {count}"):
        read_graspdb_glove(_write(tmp_path, lines))


def test_line_numbers_count_blank_lines(tmp_path: Path) -> None:
    lines = _rows(3)
    lines[2] = _replace_token(lines[2], 6, "x")
    with pytest.raises(FormatError, match=rf"{NAME}:4 \[switch\]"):
        read_graspdb_glove(_write(tmp_path, [lines[0], "", lines[1], lines[2]]))


@pytest.mark.parametrize(
    ("index", "token", "field"),
    [
        (9, "abc", "sensor T-IPJ"),
        (29, "0.1.2", "sensor W-AA"),
        (5, "09,024", "timestamp second"),
        (0, "Y2014", "timestamp year"),
        (6, "on", "switch"),
    ],
)
def test_non_numeric_token_names_its_field(tmp_path: Path, index: int, token: str, field: str) -> None:
    lines = _rows(3)
    lines[1] = _replace_token(lines[1], index, token)
    with pytest.raises(FormatError, match=rf"{NAME}:2 \[{field}\]: expected a number, got '{token}'"):
        read_graspdb_glove(_write(tmp_path, lines))


@pytest.mark.parametrize("token", ["nan", "inf", "-Infinity"])
def test_non_finite_sensor_value_is_an_error(tmp_path: Path, token: str) -> None:
    lines = _rows(3)
    lines[2] = _replace_token(lines[2], 12, token)
    with pytest.raises(
        FormatError, match=rf"{NAME}:3 \[sensor I-PIPJ\]: expected a finite number, got '{token}'"
    ):
        read_graspdb_glove(_write(tmp_path, lines))


@pytest.mark.parametrize("token", ["2", "-1", "0.5"])
def test_switch_other_than_0_or_1_is_an_error(tmp_path: Path, token: str) -> None:
    lines = _rows(3)
    lines[0] = _replace_token(lines[0], 6, token)
    with pytest.raises(
        FormatError, match=rf"{NAME}:1 \[switch\]: expected 0 \(off\) or 1 \(on\), got '{token}'"
    ):
        read_graspdb_glove(_write(tmp_path, lines))


def test_repeated_time_stamp_is_an_error(tmp_path: Path) -> None:
    lines = _rows(3)
    lines[2] = _replace_token(lines[2], 5, "09.04000")  # the stamp of row 2
    with pytest.raises(
        FormatError,
        match=r":3 \[timestamp\]: time stamp '2014 09 15 08 02 09.04000' is not after the previous row's "
        r"'2014 09 15 08 02 09.04000' \(line 2\); time stamps must strictly increase",
    ):
        read_graspdb_glove(_write(tmp_path, lines))


def test_time_stamp_going_back_across_a_minute_is_an_error(tmp_path: Path) -> None:
    lines = [_row(datetime(2014, 9, 15, 8, 3, 0, 10000)), _row(datetime(2014, 9, 15, 8, 2, 59, 990000))]
    with pytest.raises(
        FormatError, match=r":2 \[timestamp\]: time stamp '2014 09 15 08 02 59.99000' is not after"
    ):
        read_graspdb_glove(_write(tmp_path, lines))


def test_invalid_date_is_an_error(tmp_path: Path) -> None:
    lines = _rows(2)
    lines[1] = _replace_token(lines[1], 1, "13")
    with pytest.raises(
        FormatError, match=r":2 \[timestamp\]: time stamp '2014 13 15 08 02 09.04000' is not a valid date"
    ):
        read_graspdb_glove(_write(tmp_path, lines))


def test_fractional_minute_is_an_error(tmp_path: Path) -> None:
    lines = _rows(2)
    lines[0] = _replace_token(lines[0], 4, "02.5")
    with pytest.raises(FormatError, match=r":1 \[timestamp minute\]: expected an integer, got '02.5'"):
        read_graspdb_glove(_write(tmp_path, lines))


@pytest.mark.parametrize("token", ["60.00000", "-0.01000"])
def test_seconds_outside_a_minute_are_an_error(tmp_path: Path, token: str) -> None:
    lines = _rows(2)
    lines[1] = _replace_token(lines[1], 5, token)
    with pytest.raises(
        FormatError, match=rf":2 \[timestamp second\]: expected seconds in \[0, 60\), got '{token}'"
    ):
        read_graspdb_glove(_write(tmp_path, lines))


def test_raw_file_by_name_is_refused_with_calibration_advice(tmp_path: Path) -> None:
    path = _write(tmp_path, _rows(2), name="01_ex01-raw-002-grasp-su01.txt")
    with pytest.raises(
        FormatError, match=rf"^{path}: this is a raw-count file \('-raw-' in its name\); {ADVICE}$"
    ):
        read_graspdb_glove(path)


def test_raw_counts_in_a_rad_named_file_are_refused(tmp_path: Path) -> None:
    # the spec's example raw row (§4.2.2): 101 114 128 107 136 94 0 0 119 …
    counts = ["101", "114", "128", "107", "136", "94", "0", "0", "119", *(["100"] * 14)]
    lines = [_row(sensors=counts)]
    with pytest.raises(
        FormatError,
        match=r":1 \[sensor T-TMCJ\]: value 101 exceeds 7 in magnitude, so this is a raw-count file "
        r"\(angles in radians satisfy \|x\| <= 2\*pi\), although its name says '-rad-'; " + ADVICE + "$",
    ):
        read_graspdb_glove(_write(tmp_path, lines))


def test_single_value_above_seven_marks_the_file_raw(tmp_path: Path) -> None:
    lines = _rows(3)
    lines[2] = _replace_token(lines[2], 28, "-7.5")
    with pytest.raises(FormatError, match=r":3 \[sensor W-FE\]: value -7.5 exceeds 7 in magnitude"):
        read_graspdb_glove(_write(tmp_path, lines))


def test_first_bad_row_is_reported(tmp_path: Path) -> None:
    lines = _rows(5)
    lines[3] = _replace_token(lines[3], 6, "3")
    lines[1] = _replace_token(lines[1], 11, "nan")
    with pytest.raises(FormatError, match=r":2 \[sensor I-MCPJ\]"):
        read_graspdb_glove(_write(tmp_path, lines))


# --------------------------------------------------------------------------------------------------
# Raw-count files

# the spec's example raw row (§4.2.2) starts 101 114 128 107 136 94 0 0 119; the DIPs and I-AA read 0
RAW_COUNTS = [
    101,
    114,
    128,
    107,
    136,
    94,
    0,
    0,
    119,
    97,
    0,
    88,
    120,
    99,
    0,
    140,
    121,
    93,
    0,
    77,
    131,
    125,
    109,
]
DIP_AND_IAA = [6, 7, 10, 14, 18]


def _raw_rows(n: int = 3) -> list[str]:
    start = datetime(2014, 9, 12, 8, 49, 21, 712000)
    rows = []
    for i in range(n):
        counts = [c + (i if c else 0) for c in RAW_COUNTS]
        rows.append(
            _row(start + timedelta(milliseconds=16 * i), "1" if i % 2 == 0 else "0", [str(c) for c in counts])
        )
    return rows


def _calibration() -> GloveCalibration:
    gains = tuple(-0.015 - 0.0001 * i for i in range(23))
    offsets = tuple(100.0 + i for i in range(23))
    return GloveCalibration(gains=gains, offsets=offsets, provenance="test calibration")


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("01_ex01-raw-002-grasp-su01.txt", "raw"),
        ("r_01_11_ex03-rad-004-grasp-su04.txt", "rad"),
        ("su04_calib-raw-1.txt", "raw"),
        ("motion.txt", None),
        ("su04_calib-.txt", None),
        ("x-rad-raw-y.txt", None),
    ],
)
def test_filename_datatype_reads_rad_or_raw_from_the_name(name: str, kind: str | None) -> None:
    assert filename_datatype(name) == kind


def test_raw_file_with_calibration_reads_as_negated_calibrated_angles(tmp_path: Path) -> None:
    path = _write(tmp_path, _raw_rows(3), name=RAW_NAME)
    cal = _calibration()
    traj = read_graspdb_glove(path, calibration=cal)
    counts = _file_values(path)
    angles = apply_calibration(counts, cal)
    for sensor in SENSORS:
        if sensor.dof is not None:
            np.testing.assert_array_equal(traj.column(sensor.dof), -angles[:, sensor.index])
    np.testing.assert_array_equal(traj.channels["P-Arch"], angles[:, 20])
    assert traj.switch is not None
    assert traj.switch.tolist() == [True, False, True]
    assert traj.computed == DIP_DOFS
    assert traj.notes[1] == (
        "raw 8-bit counts converted to radians with the calibration 'test calibration' "
        "(angle = gain * (raw - offset); no abduction coupling)"
    )
    assert traj.notes[3] == (
        "I-DIPJ, M-DIPJ, R-DIPJ, L-DIPJ counts are 0 in this raw file (the 18-sensor glove does not measure "
        "them), so their DoFs (listed as computed) hold the calibrated 0 counts; infer them with "
        "handsim.glove.couple_dip"
    )


def test_raw_file_without_a_name_hint_reads_with_calibration(tmp_path: Path) -> None:
    path = _write(tmp_path, _raw_rows(3), name="take.txt")
    traj = read_graspdb_glove(path, calibration=_calibration())
    assert traj.nframes == 3


def test_rad_file_with_a_calibration_is_an_error(tmp_path: Path) -> None:
    path = _write(tmp_path, _rows(2))
    with pytest.raises(
        FormatError,
        match=rf"^{path}: the file name says it holds joint angles in radians \('-rad-'\), but a calibration "
        r"was given: a calibration converts raw-count files only; read it without one$",
    ):
        read_graspdb_glove(path, calibration=_calibration())


def test_real_rad_file_with_a_calibration_is_an_error(graspdb_dir: Path) -> None:
    with pytest.raises(
        FormatError,
        match=r"the file name says it holds joint angles in radians \('-rad-'\), but a calibration",
    ):
        read_graspdb_glove(graspdb_dir / "01_ex01-rad-002-grasp-su01.txt", calibration=_calibration())


def test_raw_named_file_holding_radians_is_an_error(tmp_path: Path) -> None:
    path = _write(tmp_path, _rows(2), name=RAW_NAME)
    with pytest.raises(
        FormatError,
        match=rf"^{path}:1 \[sensor T-TMCJ\]: expected a raw sensor count \(an integer from 0 to 255\), "
        r"got '0\.01000'; the file name says raw \('-raw-'\), but this value is not a count: is it a file of "
        r"angles in radians\?$",
    ):
        read_graspdb_glove(path, calibration=_calibration())


def test_unnamed_file_of_radians_with_a_calibration_is_an_error(tmp_path: Path) -> None:
    path = _write(tmp_path, _rows(2), name="take.txt")
    with pytest.raises(
        FormatError,
        match=r":1 \[sensor T-TMCJ\]: expected a raw sensor count \(an integer from 0 to 255\), "
        r"got '0\.01000'; a calibration was given, so the file must hold raw counts; a file of angles in "
        r"radians is read without a calibration$",
    ):
        read_graspdb_glove(path, calibration=_calibration())


@pytest.mark.parametrize(
    ("token", "field"), [("256", "sensor W-AA"), ("-1", "sensor W-AA"), ("12.5", "sensor W-AA")]
)
def test_raw_value_that_is_not_an_8_bit_count_is_an_error(tmp_path: Path, token: str, field: str) -> None:
    lines = _raw_rows(3)
    lines[2] = _replace_token(lines[2], 29, token)
    path = _write(tmp_path, lines, name=RAW_NAME)
    with pytest.raises(
        FormatError,
        match=rf"^{path}:3 \[{field}\]: expected a raw sensor count \(an integer from 0 to 255\), "
        rf"got '{token}'",
    ):
        read_graspdb_raw(path)


def test_read_raw_returns_times_switch_and_integer_counts(tmp_path: Path) -> None:
    path = _write(tmp_path, _raw_rows(3), name="su04_calib-.txt")
    times, switch, counts = read_graspdb_raw(path)
    np.testing.assert_allclose(times, [0.0, 0.016, 0.032], atol=1e-12)
    assert switch.tolist() == [True, False, True]
    assert counts.dtype == np.int64
    assert counts.shape == (3, 23)
    assert counts[0].tolist() == RAW_COUNTS
    assert (counts[:, DIP_AND_IAA] == 0).all()


def test_read_raw_of_a_rad_named_file_is_an_error(tmp_path: Path) -> None:
    path = _write(tmp_path, _raw_rows(2))
    with pytest.raises(
        FormatError,
        match=rf"^{path}: the file name says it holds joint angles in radians \('-rad-'\), not raw counts; "
        r"read it with read_graspdb_glove$",
    ):
        read_graspdb_raw(path)


def test_read_raw_of_real_rad_values_in_an_unnamed_file_is_an_error(
    graspdb_dir: Path, tmp_path: Path
) -> None:
    path = tmp_path / "take.txt"
    path.write_bytes((graspdb_dir / "01_ex01-rad-002-grasp-su01.txt").read_bytes())
    with pytest.raises(
        FormatError,
        match=rf"^{path}:1 \[sensor T-TMCJ\]: expected a raw sensor count \(an integer from 0 to 255\), "
        r"got '-0\.68112'; raw-count files hold 8-bit sensor counts; is this a file of angles in radians "
        r"\(read it with read_graspdb_glove\)\?$",
    ):
        read_graspdb_raw(path)


def test_read_raw_of_an_annotation_file_is_an_error(graspdb_dir: Path) -> None:
    with pytest.raises(FormatError, match=r"phase annotation file \('_annot-' in its name\), not a motion"):
        read_graspdb_raw(graspdb_dir / "01_11_ex03-rad-004-grasp-su04_annot-.txt")


def test_empty_raw_file_says_raw_counts_are_expected(tmp_path: Path) -> None:
    path = tmp_path / RAW_NAME
    path.write_text("\n")
    with pytest.raises(
        FormatError,
        match=rf"^{path}: empty file: expected rows of 30 blank-separated entries "
        r"\(YYYY MM DD HH mm ss\.sssss switch, then 23 raw sensor counts\)$",
    ):
        read_graspdb_raw(path)


def test_ten_thousand_raw_rows_read_back(tmp_path: Path) -> None:
    start = datetime(2014, 9, 12, 8, 49, 21, 712000)
    lines = [
        _row(start + timedelta(milliseconds=16 * i), "1", [str(c) for c in RAW_COUNTS]) for i in range(10_000)
    ]
    path = _write(tmp_path, lines, name=RAW_NAME)  # the reading time: benchmarks/io_and_cache.py
    recording = read_graspdb_raw(path)
    assert recording.counts.shape == (10_000, 23)
    assert recording.counts[-1].tolist() == RAW_COUNTS


# --------------------------------------------------------------------------------------------------
# Property: random valid rows read back exactly

_angles = st.floats(min_value=-2 * np.pi, max_value=2 * np.pi, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(
    start=st.datetimes(min_value=datetime(2000, 1, 1), max_value=datetime(2030, 1, 1)),
    steps_ms=st.lists(st.integers(min_value=7, max_value=1000), min_size=2, max_size=12),
    switches=st.lists(st.booleans(), min_size=13, max_size=13),
    sensors=st.lists(st.lists(_angles, min_size=23, max_size=23), min_size=13, max_size=13),
)
def test_random_valid_rows_read_back_exactly(
    tmp_path_factory: pytest.TempPathFactory,
    start: datetime,
    steps_ms: list[int],
    switches: list[bool],
    sensors: list[list[float]],
) -> None:
    start = start.replace(microsecond=start.microsecond // 1000 * 1000)
    stamps = [start]
    for step in steps_ms:
        stamps.append(stamps[-1] + timedelta(milliseconds=step))
    n = len(stamps)
    lines = [
        _row(d, "1" if sw else "0", [repr(v) for v in row])
        for d, sw, row in zip(stamps, switches[:n], sensors[:n], strict=True)
    ]
    path = _write(tmp_path_factory.mktemp("prop"), lines)

    traj = read_graspdb_glove(path)

    values = np.array(sensors[:n])
    expected_times = [(d - start).total_seconds() for d in stamps]
    np.testing.assert_allclose(traj.times, expected_times, rtol=0, atol=1e-8)
    assert traj.times[0] == 0.0
    for sensor in SENSORS:
        if sensor.dof is not None:
            np.testing.assert_array_equal(traj.column(sensor.dof), -values[:, sensor.index])
        else:
            np.testing.assert_array_equal(traj.channels[sensor.name], values[:, sensor.index])
    assert traj.switch is not None
    assert traj.switch.tolist() == switches[:n]


# --------------------------------------------------------------------------------------------------
# Values that are not radians: raw counts, degrees, or one bad value


def test_a_file_in_degrees_is_called_degrees_not_raw_counts(tmp_path: Path) -> None:
    start = datetime(2014, 9, 15, 8, 2, 9, 24000)
    degrees = [f"{-30.0 + 4.5 * k:.4f}" for k in range(23)]  # -30 .. 69 degrees
    lines = [_row(start + timedelta(milliseconds=16 * i), sensors=degrees) for i in range(4)]
    path = _write(tmp_path, lines)
    with pytest.raises(FormatError) as err:
        read_graspdb_glove(path)
    assert str(err.value) == (
        f"{path}:1 [sensor T-TMCJ]: value -30.0000 exceeds 7 in magnitude: the sensor values reach 69 and "
        "87% of them exceed 7, so they look like angles in degrees; GraspDB14 'rad' files hold radians "
        "(|x| <= 2*pi): convert the file's sensor values to radians"
    )


def test_one_value_beyond_seven_in_a_file_of_radians_is_one_bad_value(tmp_path: Path) -> None:
    lines = _rows(4)
    lines[2] = _replace_token(lines[2], 28, "-7.5")
    path = _write(tmp_path, lines)
    with pytest.raises(FormatError) as err:
        read_graspdb_glove(path)
    assert str(err.value) == (
        f"{path}:3 [sensor W-FE]: value -7.5 exceeds 7 in magnitude; expected a joint angle in radians "
        "(|x| <= 2*pi)"
    )


# --------------------------------------------------------------------------------------------------
# Timing: too few rows, sample intervals no CyberGlove produces


@pytest.mark.parametrize("rows", [1, 2])
def test_a_recording_of_one_or_two_rows_is_refused_with_the_minimum(tmp_path: Path, rows: int) -> None:
    path = _write(tmp_path, _rows(rows))
    with pytest.raises(FormatError) as err:
        read_graspdb_glove(path)
    plural = "s" if rows == 2 else ""
    assert str(err.value) == (
        f"{path}: {rows} row{plural}: a recording needs at least 3 (two sample intervals) to describe a "
        "motion"
    )


def test_a_raw_recording_of_two_rows_is_refused_too(tmp_path: Path) -> None:
    path = _write(tmp_path, _raw_rows(2), name=RAW_NAME)
    with pytest.raises(FormatError, match=r": 2 rows: a recording needs at least 3"):
        read_graspdb_raw(path)


def test_samples_10_microseconds_apart_are_refused_naming_the_line(tmp_path: Path) -> None:
    start = datetime(2014, 9, 15, 8, 2, 9, 24000)
    lines = [_row(start + timedelta(microseconds=10 * i)) for i in range(5)]
    path = _write(tmp_path, lines)
    with pytest.raises(FormatError) as err:
        read_graspdb_glove(path)
    assert str(err.value) == (
        f"{path}:2 [timestamp]: time stamp '2014 09 15 08 02 09.02401' is 1e-05 s after the previous row's "
        "(line 1): closer than 6.67 ms, a sampling rate above 150 Hz, faster than any CyberGlove records "
        "(at most 120 records/s); are the time stamps right?"
    )


def test_a_one_hour_jump_is_refused_before_any_resampling(tmp_path: Path) -> None:
    lines = _rows(6)
    later = datetime(2014, 9, 15, 9, 2, 9, 24000)
    lines[3:] = [_row(later + timedelta(milliseconds=16 * i)) for i in range(3)]
    path = _write(tmp_path, lines)
    with pytest.raises(FormatError) as err:
        read_graspdb_glove(path)
    assert str(err.value) == (
        f"{path}:4 [timestamp]: time stamp '2014 09 15 09 02 09.02400' is 3599.97 s after the previous row's "
        "(line 3): more than the 1 s a recording may skip (the replay would invent the hand's motion over "
        "the hole); cut the recording there into two files"
    )


@pytest.mark.parametrize("step_ms", [7, 16, 32, 1000])
def test_sample_intervals_from_7_ms_to_1_s_are_accepted(tmp_path: Path, step_ms: int) -> None:
    traj = read_graspdb_glove(_write(tmp_path, _rows(4, step_ms=step_ms)))
    np.testing.assert_allclose(np.diff(traj.times), step_ms / 1000, atol=1e-9)


def test_a_1_s_interval_that_rounds_above_1_s_in_floating_point_is_accepted(tmp_path: Path) -> None:
    # found by the property test: 8.021 - 7.021 = 1.0000000000000009
    start = datetime(2000, 1, 1, 0, 0, 7, 0)
    stamps = [start + timedelta(milliseconds=ms) for ms in (0, 7, 14, 21, 1021)]
    traj = read_graspdb_glove(_write(tmp_path, [_row(d) for d in stamps]))
    assert traj.times[-1] - traj.times[-2] > 1.0  # the floating-point difference, accepted
    assert traj.nframes == 5


@pytest.mark.parametrize(
    ("step_us", "accepted"), [(6670, True), (6660, False), (1_000_000, True), (1_000_010, False)]
)
def test_interval_bounds_hold_at_the_files_10_microsecond_resolution(
    tmp_path: Path, step_us: int, accepted: bool
) -> None:
    start = datetime(2014, 9, 15, 8, 2, 9, 24000)
    path = _write(tmp_path, [_row(start + timedelta(microseconds=step_us * i)) for i in range(3)])
    if accepted:
        assert read_graspdb_glove(path).nframes == 3
    else:
        with pytest.raises(FormatError, match=r":2 \[timestamp\]: time stamp "):
            read_graspdb_glove(path)


# --------------------------------------------------------------------------------------------------
# Joint limits on the glove path


def test_targets_beyond_the_skeletons_limits_are_counted_per_dof_in_a_note(tmp_path: Path) -> None:
    lines = [_replace_token(line, 7 + 4, "-2.0") for line in _rows(4)]  # I-MCPJ: if_mcp_flex = +2 rad
    skeleton = _fake_skeleton(list(driven_dofs()))
    limited = replace(skeleton, dofs=tuple(replace(d, lower=-1.0, upper=1.0) for d in skeleton.dofs))
    traj = read_graspdb_glove(_write(tmp_path, lines), skeleton=limited)
    assert traj.notes[-1] == (
        "targets outside the DoF limits of 'fake' in 4 samples (position actuators clamp them to the joint "
        "range): if_mcp_flex 4/4 (up to 57.3° beyond)"
    )


def test_targets_within_the_limits_say_so(tmp_path: Path) -> None:
    traj = read_graspdb_glove(_write(tmp_path, _rows(3)), skeleton=_fake_skeleton(list(driven_dofs())))
    assert traj.notes[-1] == "every valid sample of the targets lies within its DoF limits"
