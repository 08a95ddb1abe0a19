"""The Trajectory type: shape checks with exact messages, phases and object tracks."""

import numpy as np
import pytest

from handsim.datatypes.trajectory import ObjectTrack, Phase, Trajectory
from handsim.errors import TrajectoryError


def _trajectory(**kwargs) -> Trajectory:
    n = 5
    base = dict(
        times=np.arange(n) / 60.0,
        dof_names=("a", "b"),
        targets=np.zeros((n, 2)),
        valid=np.ones((n, 2), bool),
    )
    base.update(kwargs)
    return Trajectory(**base)


def test_phase_lookup_returns_first_phase_with_the_name() -> None:
    traj = _trajectory(phases=(Phase("rest", 0, 2), Phase("grasp", 2, 5)))
    assert traj.phase("grasp") == Phase("grasp", 2, 5)


def test_phase_lookup_raises_error_listing_phases() -> None:
    traj = _trajectory(phases=(Phase("rest", 0, 2),))
    with pytest.raises(TrajectoryError, match=r"^no phase 'grasp'; phases are \['rest'\]$"):
        traj.phase("grasp")


def test_phase_outside_the_frames_raises_error() -> None:
    with pytest.raises(TrajectoryError, match=r"^phase 'grasp' spans frames \[3, 9\), outside \[0, 5\)$"):
        _trajectory(phases=(Phase("grasp", 3, 9),))


def test_object_track_with_wrong_shape_raises_error() -> None:
    with pytest.raises(TrajectoryError, match=r"^object 'box' pose must have shape \(5, 7\), got \(4, 7\)$"):
        _trajectory(objects={"box": ObjectTrack(pose=np.zeros((4, 7)))})
    with pytest.raises(
        TrajectoryError, match=r"^object 'box' articulation must have shape \(5,\), got \(3,\)$"
    ):
        _trajectory(objects={"box": ObjectTrack(pose=np.zeros((5, 7)), articulation=np.zeros(3))})


def test_filled_mask_with_wrong_shape_raises_error() -> None:
    with pytest.raises(TrajectoryError, match=r"^filled must have shape \(5, 2\), got \(5, 3\)$"):
        _trajectory(filled=np.zeros((5, 3), bool))


def test_times_that_do_not_increase_raise_error() -> None:
    with pytest.raises(
        TrajectoryError, match=r"^times must strictly increase; sample 2 is not after sample 1$"
    ):
        _trajectory(times=np.array([0.0, 0.1, 0.1, 0.2, 0.3]))
