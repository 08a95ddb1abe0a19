"""Joint-limit reports, explicit clamping and uniform resampling of trajectories."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from handsim.datatypes.rotations import slerp
from handsim.datatypes.skeleton import Dof, Joint, Skeleton
from handsim.datatypes.trajectory import ObjectTrack, Phase, Trajectory
from handsim.datatypes.trajectory_ops import (
    RESAMPLE_METHODS,
    clamp_to_limits,
    limit_violations,
    resample,
    uniform_times,
)
from handsim.errors import TrajectoryError
from handsim.io import read_skeleton, read_trajectory
from handsim.io.graspdb.annotations import attach_phases

_X = np.array([1.0, 0.0, 0.0])


def _skeleton(limits: dict[str, tuple[float, float]]) -> Skeleton:
    joints = (Joint("root", -1, np.zeros(3), np.eye(3)), Joint("j", 0, np.array([0.0, 0.01, 0.0]), np.eye(3)))
    dofs = tuple(Dof(name, "j", _X, lo, hi, "flex") for name, (lo, hi) in limits.items())
    return Skeleton("test hand", joints, dofs)


def _trajectory(times, columns: dict[str, list[float]], valid=None, **kwargs) -> Trajectory:
    targets = np.array(list(columns.values()), dtype=float).T.reshape(len(times), len(columns))
    return Trajectory(
        times=np.asarray(times, dtype=float),
        dof_names=tuple(columns),
        targets=targets,
        valid=np.ones(targets.shape, bool) if valid is None else np.asarray(valid, bool),
        **kwargs,
    )


def _quat_z(angle: float) -> np.ndarray:
    return np.array([math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)])


# --------------------------------------------------------------------------------------------------
# Joint limits

SKEL = _skeleton({"a": (-1.0, 1.0), "b": (0.0, 2.0), "c": (-0.5, 0.5)})


def _limits_case() -> Trajectory:
    # frame:            0     1     2     3      4     5
    a = [0.0, -1.5, 1.0, 1.25, -1.0, 9.0]  # 1 below (0.5), 1 above (0.25); 1.0/-1.0 at the limits; 9 invalid
    b = [3.0, 1.0, -0.5, np.nan, 0.0, 2.0]  # 1 above (1.0) at frame 0, 1 below (0.5); NaN not checked
    valid = np.ones((6, 2), bool)
    valid[5, 0] = False
    return _trajectory(np.arange(6) * 0.1, {"a": a, "b": b}, valid, source="case.txt")


def test_limit_violations_counts_valid_samples_below_and_above_per_dof() -> None:
    report = limit_violations(_limits_case(), SKEL)
    a, b = report.dof("a"), report.dof("b")
    assert (a.below, a.above, a.worst_below, a.worst_above, a.first_frame) == (1, 1, 0.5, 0.25, 1)
    assert (b.below, b.above, b.worst_below, b.worst_above, b.first_frame) == (1, 1, 0.5, 1.0, 0)
    assert (a.lower, a.upper, b.lower, b.upper) == (-1.0, 1.0, 0.0, 2.0)
    assert a.worst == 0.5 and b.worst_deg == pytest.approx(math.degrees(1.0))
    assert (report.below, report.above, report.total) == (2, 2, 4)
    assert (report.nframes, report.checked) == (6, 10)
    assert [d.name for d in report.violating] == ["a", "b"]


def test_limit_report_lines_are_readable_with_degrees() -> None:
    assert limit_violations(_limits_case(), SKEL).lines() == [
        "limit check of case.txt against skeleton 'test hand': 4 of 10 valid samples outside the limits "
        "(2 below, 2 above) in 2 of 2 DoFs",
        "  a      1 below  -57.30°      1 above   57.30°  worst  28.65° outside  first frame 1",
        "  b      1 below    0.00°      1 above  114.59°  worst  57.30° outside  first frame 0",
    ]


def test_limit_report_of_a_trajectory_inside_its_limits_says_so() -> None:
    report = limit_violations(_trajectory([0.0, 1.0], {"c": [0.5, -0.5]}), SKEL)
    assert report.total == 0 and report.violating == ()
    assert report.dof("c").first_frame is None
    assert report.lines() == [
        "limit check of 'test hand': all 2 valid samples of 1 DoFs are within the limits"
    ]


def test_limit_violations_matches_columns_to_skeleton_dofs_by_name() -> None:
    report = limit_violations(_trajectory([0.0], {"c": [0.75], "a": [0.75]}), SKEL)
    assert [(d.name, d.above) for d in report.dofs] == [("c", 1), ("a", 0)]


def test_limit_violations_raises_error_if_trajectory_dofs_are_not_in_the_skeleton() -> None:
    with pytest.raises(TrajectoryError) as err:
        limit_violations(_trajectory([0.0], {"a": [0.0], "x": [0.0], "y": [0.0]}), SKEL)
    assert str(err.value) == (
        "trajectory DoFs ['x', 'y'] are not in skeleton 'test hand'; its DoFs are ['a', 'b', 'c']"
    )


def test_limit_report_dof_raises_error_listing_the_dofs_if_name_is_unknown() -> None:
    with pytest.raises(TrajectoryError, match=r"^no DoF 'z' in the limit report; DoFs are \['a', 'b'\]$"):
        limit_violations(_limits_case(), SKEL).dof("z")


def test_clamp_to_limits_clamps_valid_samples_and_notes_the_counts() -> None:
    original = _limits_case()
    clamped = clamp_to_limits(original, SKEL)
    np.testing.assert_array_equal(clamped.targets[:, 0], [0.0, -1.0, 1.0, 1.0, -1.0, 9.0])  # invalid kept
    np.testing.assert_array_equal(clamped.targets[:, 1], [2.0, 1.0, 0.0, np.nan, 0.0, 2.0])
    np.testing.assert_array_equal(clamped.valid, original.valid)
    assert original.targets[0, 1] == 3.0  # the input is not changed
    assert clamped.notes[-1] == (
        "clamped 4 samples of 2 DoFs to the limits of skeleton 'test hand': "
        "a (1 below by up to 28.65°, 1 above by up to 14.32°), b (1 below by up to 28.65°, 1 above by up to "
        "57.30°)"
    )
    assert limit_violations(clamped, SKEL).total == 0


def test_clamp_to_limits_of_a_trajectory_inside_its_limits_only_adds_a_note() -> None:
    original = _trajectory([0.0, 1.0], {"c": [0.5, -0.5]})
    clamped = clamp_to_limits(original, SKEL)
    np.testing.assert_array_equal(clamped.targets, original.targets)
    assert clamped.notes == (
        "clamped 0 samples: every valid target is within the limits of skeleton 'test hand'",
    )


# --------------------------------------------------------------------------------------------------
# Resampling: times, errors


def test_uniform_times_end_at_or_before_the_stop_time() -> None:
    np.testing.assert_array_equal(uniform_times(0.0, 0.35, 10.0), [0.0, 0.1, 0.2, 0.3])
    np.testing.assert_array_equal(uniform_times(0.0, 0.5, 4.0), [0.0, 0.25, 0.5])
    np.testing.assert_array_equal(uniform_times(1.0, 1.0, 100.0), [1.0])
    t = uniform_times(0.0, 4.68, 100.0)  # 4.68 * 100 rounds to 467.99999999999994
    assert t.shape == (469,) and t[-1] == 4.68


@pytest.mark.parametrize("rate", [0, -100.0, math.nan, math.inf, True, "100", None])
def test_resample_raises_error_if_rate_is_not_positive_and_finite(rate) -> None:
    traj = _trajectory([0.0, 1.0], {"a": [0.0, 1.0]})
    with pytest.raises(ValueError) as err:
        resample(traj, rate)
    assert str(err.value) == f"rate_hz must be a positive, finite number of samples per second, got {rate!r}"


def test_resample_raises_error_listing_methods_if_method_is_unknown() -> None:
    traj = _trajectory([0.0, 1.0], {"a": [0.0, 1.0]})
    assert RESAMPLE_METHODS == ("linear",)
    with pytest.raises(ValueError) as err:
        resample(traj, 10.0, method="cubic")  # type: ignore[arg-type]
    assert str(err.value) == "unknown resampling method 'cubic'; methods are ['linear']"


# --------------------------------------------------------------------------------------------------
# Resampling: exact answers


def test_resample_reproduces_a_linear_signal_exactly_on_dyadic_times() -> None:
    times = [0.0, 0.25, 0.5, 1.0, 1.125, 2.0]
    traj = _trajectory(times, {"a": [4.0 * t - 1.0 for t in times], "b": [-2.0 * t for t in times]})
    out = resample(traj, 8.0).trajectory
    expected_t = np.arange(17) / 8.0
    np.testing.assert_array_equal(out.times, expected_t)
    np.testing.assert_array_equal(out.targets[:, 0], 4.0 * expected_t - 1.0)
    np.testing.assert_array_equal(out.targets[:, 1], -2.0 * expected_t)
    assert out.valid.all()


def test_resample_upsamples_and_downsamples_irregular_times() -> None:
    times = np.cumsum([0.0, 0.015, 0.016, 0.032, 0.016, 0.015, 0.016])  # 0 .. 0.11 s, GraspDB14-like
    traj = _trajectory(times, {"a": list(3.0 * times + 0.5)})
    for rate, count in ((100.0, 12), (1000.0, 111), (20.0, 3)):
        out = resample(traj, rate).trajectory
        assert out.nframes == count
        assert out.times[-1] <= times[-1]
        np.testing.assert_allclose(out.targets[:, 0], 3.0 * out.times + 0.5, rtol=0, atol=1e-14)


def test_resample_marks_output_invalid_where_a_bracketing_input_sample_is_invalid() -> None:
    valid = np.array([[True], [True], [False], [True], [True]])
    filled = np.array([[False], [False], [False], [True], [False]])
    traj = _trajectory([0.0, 1.0, 2.0, 3.0, 4.0], {"a": [0.0, 10.0, 999.0, 30.0, 40.0]}, valid, filled=filled)
    result = resample(traj, 2.0)
    out = result.trajectory
    np.testing.assert_array_equal(out.times, np.arange(9) / 2.0)
    # t = 1.0 sits on sample 1 (valid) alone; 1.5, 2.0, 2.5 touch sample 2; 3.0 sits on sample 3 alone.
    np.testing.assert_array_equal(out.valid[:, 0], [1, 1, 1, 0, 0, 0, 1, 1, 1])
    # Values come from valid samples only: across the gap from sample 1 to sample 3.
    np.testing.assert_array_equal(out.targets[:, 0], [0, 5, 10, 15, 20, 25, 30, 35, 40])
    np.testing.assert_array_equal(out.filled[:, 0], [0, 0, 0, 0, 0, 1, 1, 1, 0])
    assert result.notes[-1] == (
        "3 output samples are invalid (they touch an invalid input sample; 1 input samples were invalid)"
    )


def test_resample_treats_non_finite_targets_as_invalid_and_holds_beyond_the_valid_samples() -> None:
    valid = np.array([[False], [True], [True], [True]])
    traj = _trajectory([0.0, 1.0, 2.0, 3.0], {"a": [np.nan, 1.0, 2.0, np.inf]}, valid)
    out = resample(traj, 2.0).trajectory
    np.testing.assert_array_equal(out.valid[:, 0], [0, 0, 1, 1, 1, 0, 0])
    np.testing.assert_array_equal(out.targets[:, 0], [1.0, 1.0, 1.0, 1.5, 2.0, 2.0, 2.0])


def test_resample_keeps_a_dof_without_valid_samples_invalid() -> None:
    valid = np.array([[True, False], [True, False]])
    traj = _trajectory([0.0, 1.0], {"a": [0.0, 1.0], "b": [0.0, 0.0]}, valid)
    out = resample(traj, 2.0).trajectory
    np.testing.assert_array_equal(out.valid, [[1, 0], [1, 0], [1, 0]])
    np.testing.assert_array_equal(out.targets[:, 1], [0.0, 0.0, 0.0])


def test_slerp_midpoint_of_identity_and_quarter_turn_is_the_eighth_turn() -> None:
    expected = _quat_z(math.pi / 4)  # (cos 22.5°, 0, 0, sin 22.5°)
    np.testing.assert_allclose(slerp(_quat_z(0.0), _quat_z(math.pi / 2), 0.5), expected, atol=1e-15)
    # The same rotation written with the opposite sign takes the same (short) path.
    np.testing.assert_allclose(slerp(_quat_z(0.0), -_quat_z(math.pi / 2), 0.5), expected, atol=1e-15)
    np.testing.assert_allclose(
        slerp(_quat_z(0.0), _quat_z(math.pi / 2), 0.25), _quat_z(math.pi / 8), atol=1e-15
    )
    # The end points come back exactly as given (normalised).
    np.testing.assert_array_equal(slerp(_quat_z(0.0), -_quat_z(1.0), 1.0), -_quat_z(1.0))
    np.testing.assert_array_equal(slerp(2 * _quat_z(0.0), _quat_z(1.0), 0.0), _quat_z(0.0))


def test_resample_interpolates_root_position_linearly_and_rotation_by_slerp() -> None:
    root = np.array([[0.0, 0.0, 0.0, *_quat_z(0.0)], [0.2, -0.4, 1.0, *(-_quat_z(math.pi / 2))]])
    traj = _trajectory([0.0, 1.0], {"a": [0.0, 0.0]}, root_pose=root)
    out = resample(traj, 2.0).trajectory
    np.testing.assert_allclose(out.root_pose[1], [0.1, -0.2, 0.5, *_quat_z(math.pi / 4)], atol=1e-15)
    np.testing.assert_array_equal(out.root_pose[[0, 2]], root)


def test_resample_interpolates_object_tracks_between_valid_samples() -> None:
    pose = np.array(
        [
            [0.0, 0.0, 0.0, *_quat_z(0.0)],
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],  # not recorded: zeros
            [1.0, 2.0, 3.0, *_quat_z(math.pi / 2)],
        ]
    )
    track = ObjectTrack(
        pose=pose, articulation=np.array([0.0, 7.0, 1.0]), valid=np.array([True, False, True])
    )
    rigid = ObjectTrack(pose=np.tile([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], (3, 1)))
    traj = _trajectory([0.0, 1.0, 2.0], {"a": [0.0, 0.0, 0.0]}, objects={"box": track, "ball": rigid})
    out = resample(traj, 1.0 / 0.5).trajectory
    box = out.objects["box"]
    np.testing.assert_allclose(box.pose[2], [0.5, 1.0, 1.5, *_quat_z(math.pi / 4)], atol=1e-15)
    np.testing.assert_allclose(box.articulation, [0.0, 0.25, 0.5, 0.75, 1.0])
    np.testing.assert_array_equal(box.valid, [1, 0, 0, 0, 1])
    assert out.objects["ball"].valid is None
    np.testing.assert_array_equal(out.objects["ball"].pose, np.tile([0, 0, 0, 1.0, 0, 0, 0], (5, 1)))


def test_resample_holds_the_previous_switch_state_and_channel_value() -> None:
    traj = _trajectory(
        [0.0, 1.0, 2.0],
        {"a": [0.0, 0.0, 0.0]},
        switch=np.array([False, True, False]),
        channels={"I-AA": np.array([0.1, 0.2, 0.3])},
    )
    out = resample(traj, 4.0).trajectory
    np.testing.assert_array_equal(out.switch, [0, 0, 0, 0, 1, 1, 1, 1, 0])
    assert out.switch.dtype == bool
    np.testing.assert_array_equal(out.channels["I-AA"], [0.1] * 4 + [0.2] * 4 + [0.3])


def test_resample_maps_phases_to_the_output_frames_in_their_time_intervals() -> None:
    phases = (Phase("a", 0, 2), Phase("b", 2, 4), Phase("c", 4, 5))
    traj = _trajectory([0.0, 0.3, 0.6, 1.0, 1.2], {"x": [0.0] * 5}, phases=phases)
    out = resample(traj, 5.0).trajectory  # times 0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2
    # a: [0, 0.6) → frames 0-2; b: [0.6, 1.2) → 3-5; c: [1.2, end] → 6.
    assert out.phases == (Phase("a", 0, 3), Phase("b", 3, 6), Phase("c", 6, 7))


def test_resample_drops_a_phase_that_holds_no_output_frame_and_says_so() -> None:
    phases = (Phase("a", 0, 1), Phase("blink", 1, 2), Phase("c", 2, 4))
    traj = _trajectory([0.0, 0.3, 0.35, 1.0], {"x": [0.0] * 4}, phases=phases)
    result = resample(traj, 5.0)  # times 0, 0.2, 0.4, 0.6, 0.8, 1.0
    assert result.trajectory.phases == (Phase("a", 0, 2), Phase("c", 2, 6))
    assert result.notes[-1] == (
        "phases holding no output frame at 5 Hz were dropped: 'blink' [1, 2) (0.3000 s to 0.3500 s)"
    )


def test_resample_reports_the_largest_gap_between_input_samples() -> None:
    traj = _trajectory([0.0, 0.25, 0.5, 1.0, 1.25, 1.75], {"x": [0.0] * 6}, notes=("read",))
    result = resample(traj, 4.0)
    assert (result.largest_gap_s, result.largest_gap_at_s) == (0.5, 0.5)  # the first of two 0.5 s gaps
    assert result.notes[1] == (
        "largest gap between input samples: 500.0 ms (2.00 × the median interval, 250.0 ms), from frame 2 at "
        "0.5000 s (2.00 output periods)"
    )
    assert result.trajectory.notes == ("read", *result.notes)
    assert result.notes[0].startswith(
        "resampled 6 samples (2.86 Hz mean, intervals 250.0–500.0 ms) to 8 samples at 4 Hz"
    )


def test_resample_calls_evenly_spaced_input_regular() -> None:
    traj = _trajectory(np.arange(10) / 30.0, {"x": [0.0] * 10})
    assert resample(traj, 100.0).notes[0].startswith("resampled 10 samples (30.00 Hz mean, regular) to")


@pytest.mark.parametrize(
    ("intervals_ms", "noted"),
    [
        ([33.3] * 20, False),  # ARCTIC's regular 30 Hz clock: its period is no gap
        ([15.0, 16.0] * 10, False),  # GraspDB14's rows every 15 or 16 ms: jitter
        ([15.0, 16.0] * 10 + [23.0], False),  # 1.44 median intervals: within GAP_FACTOR
        ([15.0, 16.0] * 10 + [31.0], True),  # a dropped sample: two periods
    ],
)
def test_resample_notes_the_largest_gap_only_beyond_gap_factor_median_intervals(intervals_ms, noted) -> None:
    times = np.concatenate([[0.0], np.cumsum(intervals_ms) / 1e3])
    result = resample(_trajectory(times, {"x": [0.0] * len(times)}), 100.0)
    gap_notes = [n for n in result.notes if n.startswith("largest gap between input samples")]
    assert len(gap_notes) == noted
    assert result.largest_gap_s == pytest.approx(max(intervals_ms) / 1e3)  # reported either way


def test_resample_of_one_sample_gives_one_sample_and_no_gap() -> None:
    result = resample(_trajectory([0.5], {"x": [1.0]}), 100.0)
    assert result.trajectory.nframes == 1 and result.trajectory.times[0] == 0.5
    assert (result.largest_gap_s, result.largest_gap_at_s) == (0.0, 0.5)


def test_resample_notes_that_downsampling_does_not_filter() -> None:
    traj = _trajectory(np.arange(11) / 10.0, {"x": [0.0] * 11})
    assert resample(traj, 4.0).notes[1] == (
        "downsampled without low-pass filtering: motion faster than 2 Hz (half the new rate) aliases"
    )
    assert len(resample(traj, 100.0).notes) == 1  # a regular clock: no gap


# --------------------------------------------------------------------------------------------------
# Properties

_steps = st.lists(st.floats(1e-3, 0.1), min_size=1, max_size=40)
_rates = st.floats(1.0, 500.0)


@settings(max_examples=150, deadline=None)
@given(steps=_steps, rate=_rates, slope=st.floats(-10, 10), offset=st.floats(-10, 10))
def test_resampling_a_linear_function_is_exact(steps, rate, slope, offset) -> None:
    times = np.concatenate([[0.0], np.cumsum(steps)])
    traj = _trajectory(times, {"x": list(slope * times + offset)})
    out = resample(traj, rate).trajectory
    assert out.times[-1] <= times[-1] and out.times[-1] > times[-1] - 1.0 / rate - 1e-9
    np.testing.assert_allclose(np.diff(out.times), 1.0 / rate, rtol=1e-9)
    np.testing.assert_allclose(out.targets[:, 0], slope * out.times + offset, rtol=0, atol=1e-12)


@settings(max_examples=150, deadline=None)
@given(
    steps=_steps,
    rate=_rates,
    values=st.lists(st.floats(-10, 10), min_size=41, max_size=41),
)
def test_linear_resampling_stays_within_the_range_of_the_inputs(steps, rate, values) -> None:
    times = np.concatenate([[0.0], np.cumsum(steps)])
    x = np.array(values[: times.shape[0]])
    out = resample(_trajectory(times, {"x": list(x)}), rate).trajectory
    assert np.all(out.targets[:, 0] >= x.min()) and np.all(out.targets[:, 0] <= x.max())


# --------------------------------------------------------------------------------------------------
# Real GraspDB14 trials

TRIAL = "r_01_11_ex03-rad-004-grasp-su04.txt"


def test_limit_report_of_graspdb_trial_finds_mcp_hyperextension(graspdb_dir: Path) -> None:
    skel = read_skeleton(graspdb_dir / "default.xmlskel")
    report = limit_violations(read_trajectory(graspdb_dir / TRIAL, skel), skel)
    # Every violation of this trial is below a lower limit: MCP hyperextension (docs/conventions.md).
    assert {d.name: (d.below, d.above, d.first_frame) for d in report.violating} == {
        "th_mcp_flex": (282, 0, 0),
        "if_mcp_flex": (54, 0, 26),
        "mf_mcp_flex": (85, 0, 24),
        "rf_mcp_flex": (90, 0, 25),
        "lf_mcp_flex": (152, 0, 0),
    }
    assert (report.total, report.checked) == (663, 282 * 27)
    worst = {d.name: round(math.degrees(d.worst_below), 2) for d in report.violating}
    assert worst == {
        "th_mcp_flex": 27.62,  # -37.62° against -10°
        "if_mcp_flex": 16.67,  # I-MCPJ -16.67° against 0°
        "mf_mcp_flex": 27.67,
        "rf_mcp_flex": 30.2,
        "lf_mcp_flex": 12.39,
    }
    note = clamp_to_limits(read_trajectory(graspdb_dir / TRIAL, skel), skel).notes[-1]
    assert note.startswith(
        "clamped 663 samples of 5 DoFs to the limits of skeleton 'default': "
        "th_mcp_flex (282 below by up to 27.62°), if_mcp_flex (54 below by up to 16.67°)"
    )


@pytest.mark.parametrize(
    ("name", "dof", "below", "above", "extreme_deg"),
    [
        # The documented I-MCPJ 117° against a 90° limit: the FK-oracle recording of actor 6.
        ("fk_oracle/16_14_ex01-rad-004-grasp-su06", "if_mcp_flex", 152, 64, 116.66),
        # The documented MCP hyperextension to -42° against 0°.
        ("04_ex01-rad-045-grasp-su03.txt", "if_mcp_flex", 61, 0, -41.67),
    ],
)
def test_limit_report_finds_the_violations_documented_in_conventions(
    graspdb_dir: Path, name: str, dof: str, below: int, above: int, extreme_deg: float
) -> None:
    skel = read_skeleton(graspdb_dir / "default.xmlskel")
    traj = read_trajectory(graspdb_dir / name, skel)
    entry = limit_violations(traj, skel).dof(dof)
    assert (entry.below, entry.above) == (below, above)
    column = traj.column(dof)
    extreme = column.max() if above else column.min()
    assert round(math.degrees(extreme), 2) == extreme_deg


def test_resampling_graspdb_trial_to_100_hz_reports_its_largest_gap(graspdb_dir: Path) -> None:
    skel = read_skeleton(graspdb_dir / "default.xmlskel")
    traj = read_trajectory(graspdb_dir / TRIAL, skel)
    traj = attach_phases(traj, graspdb_dir / "01_11_ex03-rad-004-grasp-su04_annot-.txt")
    steps = np.diff(traj.times)
    # Rows every 15 or 16 ms, 19 dropped samples (31-32 ms); no repeated time stamp.
    assert np.unique(np.round(steps, 3)).tolist() == [0.015, 0.016, 0.031, 0.032]
    assert int((steps > 0.02).sum()) == 19

    result = resample(traj, 100.0)
    assert result.largest_gap_s == pytest.approx(0.032, abs=1e-12)
    assert result.largest_gap_at_s == pytest.approx(2.043, abs=1e-12)
    assert result.notes[1] == (
        "largest gap between input samples: 32.0 ms (2.00 × the median interval, 16.0 ms), from frame 123 at "
        "2.0430 s (3.20 output periods)"
    )
    out = result.trajectory
    assert out.nframes == 469 and out.times[-1] == pytest.approx(4.68)
    assert out.valid.all()
    assert [(p.name, p.start, p.stop) for p in out.phases] == [
        ("rest", 0, 41),
        ("reach", 41, 136),
        ("grasp", 136, 274),
        ("retract", 274, 389),
        ("rest", 389, 469),
    ]
    # Every output frame of a phase lies in the phase's input time interval.
    for old, new in zip(traj.phases, out.phases, strict=True):
        assert out.times[new.start] >= traj.times[old.start]
        assert out.times[new.start - 1] < traj.times[old.start] if new.start else True
    # The resampled angles stay within the recorded range of each DoF.
    assert np.all(out.targets.min(axis=0) >= traj.targets.min(axis=0))
    assert np.all(out.targets.max(axis=0) <= traj.targets.max(axis=0))


def test_uniform_times_raises_error_if_stop_is_before_start() -> None:
    with pytest.raises(ValueError, match=r"^stop time 0\.5 s is before start time 1\.0 s$"):
        uniform_times(1.0, 0.5, 10.0)
