"""Plausibility gates (handsim.sim.plausibility): the rules on their own, with exact numbers."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from handsim.assets import TZIONAS_DIR
from handsim.datatypes.trajectory import Trajectory
from handsim.sim.plausibility import (
    check_control_rate,
    limit_violations,
    min_control_rate,
    track_jumps,
)
from handsim.sim.replay import replay
from handsim.sim.specs import MetricSpec
from handsim.trials import load_trial


def test_the_minimum_control_rate_puts_two_frames_in_the_shortest_judged_time():
    assert min_control_rate(MetricSpec()) == 20.0
    assert min_control_rate(replace(MetricSpec(), contact_gap=0.05)) == 40.0
    assert check_control_rate(20, MetricSpec()) == 20.0
    with pytest.raises(ValueError, match=r"got 19\.9$"):
        check_control_rate(19.9, MetricSpec())
    with pytest.raises(ValueError, match=r"got 'fast'$"):
        check_control_rate("fast", MetricSpec())  # type: ignore[arg-type]


def test_track_jumps_are_measured_between_valid_samples_only():
    times = np.arange(6) * 0.1
    positions = np.zeros((6, 3))
    positions[2] = (5.0, 0.0, 0.0)  # an invalid sample far away: not a jump
    positions[4] = (0.0, 2.0, 0.0)  # 2 m in 0.1 s = 20 m/s in, and out again
    valid = np.array([True, True, False, True, True, True])
    frames, fastest = track_jumps(times, positions, valid, max_speed=10.0)
    assert frames.tolist() == [4, 5] and fastest == pytest.approx(20.0)
    frames, fastest = track_jumps(times, positions, None, max_speed=10.0)
    assert frames.tolist() == [2, 3, 4, 5] and fastest == pytest.approx(50.0)
    assert track_jumps(times[:1], positions[:1], None, 10.0)[1] == 0.0


def test_limit_violations_count_valid_samples_per_dof_in_the_hands_order():
    loaded = load_trial(str(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION"))
    layout = loaded.scene.layout
    (low0, high0), (low1, high1) = layout.ctrl_range[0], layout.ctrl_range[1]
    names = (layout.dof_names[1], layout.dof_names[0])  # the trajectory's own column order
    targets = np.array(
        [[low1, high0 + 0.1], [high1, low0 - 0.3], [high1 + 1.0, low0], [high1 + 2.0, high0 + 5.0]]
    )
    valid = np.array([[True, True], [True, True], [True, True], [False, False]])  # the last: not measured
    trajectory = Trajectory(times=np.arange(4) * 0.1, dof_names=names, targets=targets, valid=valid)
    found = limit_violations(trajectory, layout)
    assert list(found) == [layout.dof_names[0], layout.dof_names[1]]
    assert found[layout.dof_names[0]] == (2, pytest.approx(0.3))
    assert found[layout.dof_names[1]] == (1, pytest.approx(1.0))


def test_the_bundled_tzionas_replay_is_valid_with_its_joint_limit_note():
    loaded = load_trial(str(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION"))
    result = replay(loaded.scene, loaded.trajectory)
    assert result.summary["valid"] is True
    assert [(f.code, f.invalid) for f in result.flags] == [("joint_limits", False)]
    assert result.to_dict()["flags"][0]["values"]["samples"] == result.flags[0].values["samples"] > 0
