"""Scripted grasps: the synthetic ``.grasp.json`` format, its trial kind, discovery and a replay."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from handsim.assets import ASSETS_DIR
from handsim.builders import default_skeleton
from handsim.builders.graspdb_objects import UnknownObjectError
from handsim.errors import FormatError
from handsim.io import read_trajectory
from handsim.io.scripted import SYNTHETIC_NOTE, read_scripted_grasp
from handsim.trials import TRIAL_KINDS, Trial, TrialError, discover, find_trial, load_trial, trial_kind

DEMO_DIR = ASSETS_DIR / "demo"
GRASP = {
    "format": "handsim-scripted-grasp",
    "version": 1,
    "object": "tennis_ball",
    "hand_length": 0.19,
    "rate_hz": 60,
    "rest_s": 0.3,
    "close_s": 1.0,
    "hold_s": 1.5,
    "open_s": 0.5,
    "closure": 0.6,
}


def _write(tmp_path: Path, **changes: object) -> Path:
    fields = {k: v for k, v in {**GRASP, **changes}.items() if v is not None}
    path = tmp_path / "ball.grasp.json"
    path.write_text(json.dumps(fields))
    return path


def test_targets_at_hold_are_closure_times_upper_limit_for_flexion_dofs(tmp_path):
    trajectory = read_scripted_grasp(_write(tmp_path))
    skeleton = default_skeleton(0.19)
    assert trajectory.dof_names == skeleton.dof_names
    hold = trajectory.targets[78:168]  # after rest (18) and the whole closing (60), the hold (90 frames)
    for i, name in enumerate(trajectory.dof_names):
        low, high = skeleton.limits[i]
        if "flex" in name and not name.startswith("root"):
            expected = 0.6 * high
        else:
            expected = float(np.clip(0.0, low, high))
        np.testing.assert_allclose(hold[:, i], expected, err_msg=name)
        np.testing.assert_allclose(trajectory.targets[0, i], np.clip(0.0, low, high), err_msg=name)
    np.testing.assert_allclose(trajectory.targets[-1], trajectory.targets[0])
    assert trajectory.valid.all()


def test_phases_follow_the_durations_at_the_sample_rate(tmp_path):
    trajectory = read_scripted_grasp(_write(tmp_path))
    assert [(p.name, p.start, p.stop) for p in trajectory.phases] == [
        ("rest", 0, 18),
        ("close", 18, 60),
        ("grasp", 60, 168),
        ("release", 168, 198),
    ]
    # first contact: the cosine ramp (1 − cos πu)/2 reaches 0.8 at u = acos(−0.6)/π = 0.7048, i.e. the
    # 43rd of the 60 closing samples (u = 43/60), frame 18 + 42
    assert 42 / 60 < math.acos(-0.6) / math.pi <= 43 / 60
    assert trajectory.nframes == 198
    assert trajectory.mean_rate == pytest.approx(60.0)


def test_phases_of_no_samples_are_left_out(tmp_path):
    trajectory = read_scripted_grasp(_write(tmp_path, rest_s=0, open_s=0))
    assert [p.name for p in trajectory.phases] == ["close", "grasp"]


def test_trajectory_is_labelled_synthetic_with_the_file_hash(tmp_path):
    import hashlib

    path = _write(tmp_path)
    trajectory = read_trajectory(path)
    assert trajectory.notes[0] == SYNTHETIC_NOTE == "synthetic scripted grasp (not a recording)"
    assert trajectory.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert trajectory.source == str(path)


@pytest.mark.parametrize(
    ("changes", "field", "message"),
    [
        ({"grip": 1}, "grip", "unknown field(s) ['grip']"),
        ({"closure": None}, "closure", "missing field(s) ['closure']"),
        ({"format": "other"}, "format", "expected 'handsim-scripted-grasp', got 'other'"),
        ({"version": 2}, "version", "expected version 1, got 2"),
        ({"object": ""}, "object", "expected a catalogue object name, got ''"),
        ({"closure": 0}, "closure", "expected a number > 0 and ≤ 1, got 0"),
        ({"closure": 1.5}, "closure", "expected a number > 0 and ≤ 1, got 1.5"),
        ({"rate_hz": "60"}, "rate_hz", "expected a finite number, got '60'"),
        ({"rest_s": True}, "rest_s", "expected a finite number, got True"),
        ({"hold_s": -1}, "hold_s", "expected a number ≥ 0 and ≤ 60, got -1"),
        ({"close_s": 0.001}, "close_s", "expected at least one sample"),
        ({"hand_length": 190}, "hand_length", "expected a number ≥ 0.08 and ≤ 0.3, got 190"),
    ],
)
def test_reader_raises_error_naming_file_and_field(tmp_path, changes, field, message):
    path = _write(tmp_path, **changes)
    with pytest.raises(FormatError, match=r"\[" + field + r"\]") as info:
        read_scripted_grasp(path)
    assert str(info.value).startswith(str(path))
    assert message in str(info.value)


def test_reader_raises_error_if_not_json(tmp_path):
    path = tmp_path / "bad.grasp.json"
    path.write_text("{not json")
    with pytest.raises(FormatError, match="not a JSON document"):
        read_scripted_grasp(path)


def test_trial_kind_finds_and_loads_a_scripted_grasp(tmp_path):
    path = _write(tmp_path, hand_length=0.18)
    assert "scripted" in TRIAL_KINDS
    assert trial_kind(path) == "scripted"
    trial = find_trial(path)
    assert (trial.kind, trial.skeleton_path, trial.hand_length) == ("scripted", None, 0.18)
    assert [(o.what, o.origin) for o in trial.objects] == [("tennis_ball", "the scripted grasp's object")]
    assert "synthetic scripted grasp (not a recording)" in trial.notes[0]
    assert Trial.from_dict(json.loads(json.dumps(trial.to_dict()))) == trial
    loaded = load_trial(trial)
    assert loaded.scene.setup.scenario == "glove"
    assert loaded.hand == "parametric default hand, 0.18 m (27 DoFs)"
    assert loaded.trajectory.notes[0] == SYNTHETIC_NOTE


def test_find_trial_takes_an_object_override_and_refuses_a_skeleton(tmp_path):
    path = _write(tmp_path)
    assert find_trial(path, obj="cube").objects[0].what == "cube"
    with pytest.raises(TrialError, match="a skeleton does not apply to a scripted grasp"):
        find_trial(path, skeleton=tmp_path / "hand.xmlskel")


def test_find_trial_raises_error_if_object_is_not_in_the_catalogue(tmp_path):
    with pytest.raises(UnknownObjectError, match=r"\[object\]: unknown object 'teapot'"):
        find_trial(_write(tmp_path, object="teapot"))


def test_discovery_lists_the_bundled_scripted_grasps_as_scripted_trials():
    found = discover(DEMO_DIR)
    assert [(e.id, e.kind, e.meta["object"], e.meta["grasp"]) for e in found.entries] == [
        ("cube.grasp.json#1", "scripted", "cube", "scripted"),  # each holds one grasp episode
        ("cylinder_25mm.grasp.json#1", "scripted", "cylinder_25mm", "scripted"),
        ("tennis_ball.grasp.json#1", "scripted", "tennis_ball", "scripted"),
    ]
    assert [e.trial.grasp for e in found.entries] == [1, 1, 1]
    assert all(e.meta["synthetic"] and e.meta["actor"] is None for e in found.entries)
    assert [c.path for c in found.companions] == ["README.md"] and not found.unknown


def test_discovery_lists_an_invalid_scripted_grasp_as_unknown(tmp_path):
    _write(tmp_path, closure=2)
    found = discover(tmp_path)
    assert not found.entries
    assert found.unknown[0].reason.startswith("a scripted grasp (.grasp.json), but not a trial:")


def test_replay_of_a_bundled_scripted_grasp_has_no_warnings_and_a_hold_outcome():
    from handsim.sim.replay import ReplayConfig, replay

    loaded = load_trial(DEMO_DIR / "tennis_ball.grasp.json")
    result = replay(loaded.scene, loaded.trajectory, ReplayConfig(stability_at="grasp"))
    assert result.summary["warnings"] == 0 and not result.summary["diverged"]
    assert result.hold is not None
    assert isinstance(result.summary["held"], bool)
    assert loaded.scene.setup.grasp_time == pytest.approx(loaded.trajectory.times[60])  # first contact
    assert result.hold.window[0] >= loaded.scene.setup.grasp_time
    assert result.hold.held == (result.hold.reason is None)
