"""Single-sample spikes of glove recordings: found, marked invalid, filled, reported; fast motion kept."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from handsim.datatypes.trajectory import Trajectory
from handsim.glove.spikes import (
    MAX_JOINT_SPEED,
    MIN_SPIKE_DOFS,
    Spike,
    find_spikes,
    remove_spikes,
)
from handsim.io.graspdb.glove import read_graspdb_glove

DT = 1.0 / 60.0
NAMES = ("a_flex", "b_flex", "c_flex", "d_abd")


def _trajectory(x: np.ndarray) -> Trajectory:
    x = np.asarray(x, dtype=float)
    return Trajectory(
        times=np.arange(x.shape[0]) * DT,
        dof_names=NAMES[: x.shape[1]],
        targets=x,
        valid=np.ones(x.shape, dtype=bool),
    )


def _ramp(n: int = 10) -> np.ndarray:
    """A slow closing: every DoF rises 0.02 rad per sample (1.2 rad/s), the last one stays."""
    x = np.zeros((n, 4))
    x[:, :3] = 0.02 * np.arange(n)[:, None]
    return x


def test_max_joint_speed_is_the_full_finger_range_crossed_in_the_fastest_pinch() -> None:
    assert MAX_JOINT_SPEED == pytest.approx(1.875 * math.radians(120.0) / 0.09)
    assert MAX_JOINT_SPEED == pytest.approx(43.63, abs=0.01)
    assert MIN_SPIKE_DOFS == 2


def test_inner_spike_on_several_dofs_that_reverts_is_found() -> None:
    x = _ramp()
    x[4, :3] += [1.5, -1.2, 1.0]
    (spike,) = find_spikes(_trajectory(x))
    assert spike.frame == 4
    assert spike.time == pytest.approx(4 * DT)
    assert spike.dofs == ("a_flex", "b_flex", "c_flex")
    assert spike.jump == pytest.approx(1.52)  # a_flex: 0.08 + 1.5 against 0.06 at frame 3
    assert spike.speed == pytest.approx(1.52 / DT)


@pytest.mark.parametrize("frame", [0, 9])
def test_spike_in_the_first_or_last_row_is_found(frame: int) -> None:
    x = _ramp()
    x[frame, :3] += 1.5
    assert [s.frame for s in find_spikes(_trajectory(x))] == [frame]


def test_fast_movement_that_does_not_revert_is_no_spike() -> None:
    x = _ramp()
    x[5:, :3] += 1.5  # 1.5 rad in one sample (90 rad/s), then the hand stays there
    assert find_spikes(_trajectory(x)) == ()


def test_real_fast_ring_finger_flexion_is_no_spike(graspdb_dir: Path) -> None:
    trajectory = read_graspdb_glove(graspdb_dir / "04_ex01-rad-045-grasp-su03.txt")
    rf_pip = trajectory.column("rf_pip_flex")
    speed = np.abs(np.diff(rf_pip)) / np.diff(trajectory.times)
    assert speed.max() == pytest.approx(22.6, abs=0.1)  # frames 66 → 68: 0.70 rad in 31 ms, no revert
    assert find_spikes(trajectory) == ()
    assert find_spikes(trajectory, max_speed=20.0) == ()


@pytest.mark.parametrize(
    "name",
    [
        "r_01_11_ex03-rad-004-grasp-su04.txt",
        "01_ex01-rad-002-grasp-su01.txt",
        "04_ex01-rad-045-grasp-su03.txt",
        "fk_oracle/01_11_ex03-rad-004-grasp-su04.txt",
        "fk_oracle/16_14_ex01-rad-004-grasp-su06",
    ],
)
def test_real_recordings_have_no_spike_on_several_sensors(graspdb_dir: Path, name: str) -> None:
    assert find_spikes(read_graspdb_glove(graspdb_dir / name)) == ()


def test_oracle_motions_first_row_jumps_on_one_sensor_only(graspdb_dir: Path) -> None:
    trajectory = read_graspdb_glove(graspdb_dir / "fk_oracle/16_14_ex01-rad-004-grasp-su06")
    (spike,) = find_spikes(trajectory, min_dofs=1)
    assert (spike.frame, spike.dofs) == (0, ("th_tmc_pron",))
    assert spike.jump == pytest.approx(0.966, abs=1e-3)


def test_spike_on_one_dof_is_not_several_sensors() -> None:
    x = _ramp()
    x[4, 0] += 1.5
    assert find_spikes(_trajectory(x)) == ()
    assert [s.frame for s in find_spikes(_trajectory(x), min_dofs=1)] == [4]


def test_oscillation_is_not_a_single_sample_spike() -> None:
    x = _ramp()
    x[3::2, :3] += 1.5  # every other sample jumps: no single odd sample
    assert find_spikes(_trajectory(x)) == ()


def test_jump_below_the_speed_bound_is_no_spike() -> None:
    x = _ramp()
    x[4, :3] += 0.6  # 36 rad/s at 60 Hz, below 43.6 rad/s
    assert find_spikes(_trajectory(x)) == ()


def test_remove_spikes_marks_them_invalid_fills_them_and_says_so() -> None:
    x = _ramp()
    x[4, :3] += [1.5, -1.2, 1.0]
    x[9, :2] += 2.0
    fixed, spikes = remove_spikes(_trajectory(x))
    assert [s.frame for s in spikes] == [4, 9]
    expected = _ramp()
    expected[9, :3] = expected[8, :3]  # the last sample takes its neighbour's value (nothing after it)
    np.testing.assert_allclose(fixed.targets, expected)  # frame 4: on the ramp between frames 3 and 5
    expected_filled = np.zeros(x.shape, bool)
    expected_filled[4, :3] = True  # the DoFs whose value differs from a neighbour's; d_abd is constant
    expected_filled[9, :3] = True  # c_flex at frame 9 differs from frame 8 too (the ramp)
    np.testing.assert_array_equal(fixed.filled, expected_filled)
    assert fixed.valid.all()
    assert fixed.notes[-3:] == (
        "2 single-sample spikes (DoFs jumping faster than 43.6 rad/s and back at the next sample, "
        "docs/cyberglove.md) marked invalid and filled: "
        "frame 4 (0.067 s): 3 DoFs jump and revert, up to 1.52 rad at 91 rad/s (a_flex, b_flex, c_flex); "
        "frame 9 (0.150 s): 2 DoFs jump and revert, up to 2.02 rad at 121 rad/s (a_flex, b_flex)",
        "filled 6 samples in 6 gaps (longest 1 frame) of a_flex, b_flex, c_flex by linear",
        "linear: 3 samples of a_flex, b_flex, c_flex hold the last valid sample (gap at the end of the "
        "recording, nothing to interpolate to)",
    )


def test_remove_spikes_leaves_a_clean_recording_unchanged() -> None:
    trajectory = _trajectory(_ramp())
    fixed, spikes = remove_spikes(trajectory)
    assert spikes == () and fixed is trajectory


def test_spike_describes_itself() -> None:
    spike = Spike(frame=0, time=0.0, dofs=("a_flex", "b_flex"), jump=1.234, speed=74.04)
    assert (
        spike.describe()
        == "frame 0 (0.000 s): 2 DoFs jump and revert, up to 1.23 rad at 74 rad/s (a_flex, b_flex)"
    )


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"max_speed": 0.0}, "max_speed must be a positive number of rad/s, got 0.0"),
        ({"max_speed": math.nan}, "max_speed must be a positive number of rad/s, got nan"),
        ({"min_dofs": 0}, "min_dofs must be at least 1, got 0"),
    ],
)
def test_find_spikes_raises_error_for_bad_parameters(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=f"^{message}$"):
        find_spikes(_trajectory(_ramp()), **kwargs)
