"""The thumb rest posture: the TMC DoFs no glove sensor drives held at a constant angle, on request only."""

from __future__ import annotations

import math

import numpy as np
import pytest

from handsim.builders import default_skeleton
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import TrajectoryError
from handsim.glove import THUMB_REST_DOFS, apply_thumb_rest, driven_dofs
from handsim.trials import Trial, find_trial


def _recording(skeleton, frames=5):
    names = tuple(d.name for d in skeleton.dofs)
    targets = np.linspace(0.0, 0.3, frames)[:, None] * np.ones((1, len(names)))
    valid = np.ones_like(targets, dtype=bool)
    valid[1, names.index("th_tmc_flex")] = False
    return Trajectory(times=np.arange(frames) * 0.01, dof_names=names, targets=targets, valid=valid)


def test_thumb_rest_dofs_are_the_undriven_tmc_dofs():
    assert set(THUMB_REST_DOFS).isdisjoint(driven_dofs())
    assert "th_tmc_pron" in driven_dofs()


def test_apply_thumb_rest_holds_both_dofs_constant_and_leaves_the_others():
    skeleton = default_skeleton(0.19)
    trajectory = _recording(skeleton)
    rested = apply_thumb_rest(trajectory, skeleton, 20.0, -10.0)
    abd, flex = (trajectory.dof_names.index(n) for n in THUMB_REST_DOFS)
    np.testing.assert_array_equal(rested.targets[:, abd], math.radians(20.0))
    np.testing.assert_array_equal(rested.targets[:, flex], math.radians(-10.0))
    assert rested.valid[:, flex].all()
    others = [k for k in range(len(trajectory.dof_names)) if k not in (abd, flex)]
    np.testing.assert_array_equal(rested.targets[:, others], trajectory.targets[:, others])
    np.testing.assert_array_equal(rested.valid[:, others], trajectory.valid[:, others])


@pytest.mark.parametrize(
    ("abd", "flex", "message"),
    [
        (90.0, 0.0, "thumb rest th_tmc_abd = 90 deg is outside the joint's limits -30..60 deg"),
        (0.0, -40.0, "thumb rest th_tmc_flex = -40 deg is outside the joint's limits -25..35 deg"),
        (math.nan, 0.0, "thumb rest th_tmc_abd: expected a finite angle in degrees, got nan"),
    ],
)
def test_apply_thumb_rest_raises_error_outside_the_joint_limits(abd, flex, message):
    skeleton = default_skeleton(0.19)
    with pytest.raises(TrajectoryError, match=f"^{message}$"):
        apply_thumb_rest(_recording(skeleton), skeleton, abd, flex)


def test_apply_thumb_rest_raises_error_for_a_hand_without_the_dofs():
    skeleton = default_skeleton(0.19)
    trajectory = _recording(skeleton)
    keep = [k for k, n in enumerate(trajectory.dof_names) if n != "th_tmc_abd"]
    without = Trajectory(
        times=trajectory.times,
        dof_names=tuple(trajectory.dof_names[k] for k in keep),
        targets=trajectory.targets[:, keep],
        valid=trajectory.valid[:, keep],
    )
    with pytest.raises(TrajectoryError, match="the hand has no DoF 'th_tmc_abd'"):
        apply_thumb_rest(without, skeleton, 0.0, 0.0)


def test_find_trial_carries_the_thumb_rest_through_to_dict_and_back(tmp_path):
    path = tmp_path / "01_ex01-rad-002-grasp-su01.txt"
    path.write_text("")
    trial = find_trial(path, thumb_rest=(20, 10))
    assert trial.thumb_rest == (20.0, 10.0)
    assert find_trial(path).thumb_rest is None
    assert Trial.from_dict(trial.to_dict()) == trial


@pytest.mark.slow
def test_graspdb_recording_with_a_thumb_rest_drives_the_thumb_there(graspdb_dir):
    from handsim.trials import load_trial

    loaded = load_trial(graspdb_dir / "01_ex01-rad-002-grasp-su01.txt", thumb_rest=(20.0, 10.0))
    columns = [loaded.trajectory.dof_names.index(n) for n in THUMB_REST_DOFS]
    np.testing.assert_allclose(
        loaded.trajectory.targets[:, columns],
        np.radians([[20.0, 10.0]]).repeat(loaded.trajectory.nframes, axis=0),
    )
    assert any(
        n.startswith("thumb rest posture: th_tmc_abd 20 deg, th_tmc_flex 10 deg") for n in loaded.notes
    )
