"""Hand-only sequences: a Tzionas sequence without objects replays, is measured and is a trial of a run.

The sequence is the bundled sample with the cube taken out of ``Configs/20/MODELS_INFO.txt`` (the ICCV15
in-hand-scanning sequences have this shape: a ``.SKEL`` hand and its motion, no object).
"""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from handsim.assets import TZIONAS_DIR
from handsim.cli import main
from handsim.datatypes.poses import compose
from handsim.datatypes.rotations import quat_rotate
from handsim.runner.execute import run_dataset
from handsim.runner.records import read_records
from handsim.sim.replay import replay
from handsim.sim.self_contact import SelfCollider
from handsim.sim.summary import CONTACT_KEYS, NO_OBJECT
from handsim.trials import discover, load_trial

NO_OBJECT_TEXT = "not judged: no object (a hand-only sequence: nothing to touch, hold or drift)"
SCENE_NOTE = (
    "no object: gravity along the hint [0.0, 1.0, 0.0] (nothing rests on a support to say where down is); "
    "no table; the hand's root at the first frame is the world origin"
)


@pytest.fixture(scope="module")
def hand_only(tmp_path_factory) -> Path:
    """A copy of the bundled Tzionas sample whose sequence 20 lists only its hand."""
    root = tmp_path_factory.mktemp("hand_only") / "tzionas"
    shutil.copytree(TZIONAS_DIR, root)
    (root / "Configs" / "20" / "MODELS_INFO.txt").write_text("1\nModel_Hand_R\n")
    return root


@pytest.fixture(scope="module")
def loaded(hand_only):
    return load_trial(hand_only / "Models" / "20")


@pytest.fixture(scope="module")
def result(loaded):
    return replay(loaded.scene, loaded.trajectory)


def test_a_hand_only_tzionas_sequence_loads_as_a_hand_without_objects_or_table(loaded):
    assert loaded.trial.objects == () and loaded.objects == ()
    scene = loaded.scene
    assert scene.layout.objects == () and scene.setup.scenario == "recorded"
    assert scene.setup.notes == (SCENE_NOTE,)
    names = {scene.model.geom(g).name for g in range(scene.model.ngeom)}
    assert "table" not in names and "floor" not in names


def test_the_hand_only_world_puts_the_first_root_at_the_origin_with_image_down_as_gravity(loaded):
    world = np.asarray(loaded.scene.setup.world_from_recording)
    first = compose(world, np.asarray(loaded.trajectory.root_pose[0], dtype=float))
    np.testing.assert_allclose(first[:3], 0.0, atol=1e-12)
    np.testing.assert_allclose(
        quat_rotate(world[3:], np.array([0.0, 1.0, 0.0])), [0.0, 0.0, -1.0], atol=1e-12
    )


def test_a_hand_only_replay_measures_tracking_and_says_why_hold_and_drift_are_not_judged(result):
    s = result.summary
    assert result.warnings == () and result.diverged is None and s["valid"] is True
    assert NO_OBJECT == NO_OBJECT_TEXT
    assert s["hold_reason"] == NO_OBJECT_TEXT and s["drift_reason"] == NO_OBJECT_TEXT
    assert "held" not in s and "mean_drift_mm" not in s and result.hold is None
    assert all(s[k] is None for k in CONTACT_KEYS)  # no hand–object number that reads as 0 mm / 0 contacts
    assert s["frames"] == 617
    assert 0.0 < s["mean_tracking_error_deg"] < s["max_tracking_error_deg"] < 5.0
    assert 0.0 < s["mean_tip_error_mm"] < s["max_tip_error_mm"] < 20.0
    limits = [f for f in result.flags if f.code == "joint_limits"]
    assert len(limits) == 1 and limits[0].values["samples"] == 95


def test_the_sample_hand_does_not_pass_through_itself(result):
    s = result.summary
    assert s["max_self_penetration_mm"] == 0.0 and s["max_target_self_penetration_mm"] == 0.0
    assert s["frames_self_penetrating_over_1mm"] == 0
    assert s["self_penetration_links"] is None and s["target_self_penetration_at_s"] is None


def test_fingers_driven_through_each_other_are_reported_as_self_penetration(loaded):
    scene, trajectory = loaded.scene, loaded.trajectory
    layout = scene.layout
    crossed = layout.ctrl_range[:, 0]  # every DoF at its lower limit: the ring and little fingers overlap
    column = [trajectory.dof_names.index(n) for n in layout.dof_names]
    targets = trajectory.targets.copy()
    window = slice(60, 120)
    targets[window][:, column] = crossed
    result = replay(scene, replace(trajectory, targets=targets))
    posture = scene.model.qpos0.copy()
    posture[layout.dof_qpos] = crossed
    expected = SelfCollider(scene)(posture)  # independent: the posture alone, at the model's rest root
    assert expected.depth > 0.01
    s = result.summary
    assert s["max_target_self_penetration_mm"] == pytest.approx(expected.depth * 1000.0, abs=1e-6)
    assert s["target_self_penetration_links"] == list(expected.links)
    assert trajectory.times[60] <= s["target_self_penetration_at_s"] <= trajectory.times[119]
    # the simulated fingers collide with each other: the solver keeps them from passing through
    assert 0.0 < s["max_self_penetration_mm"] < s["max_target_self_penetration_mm"]
    assert result.frames.self_penetration.shape == (617,)


def test_the_cli_replays_a_hand_only_sequence_and_writes_its_numbers_to_json(hand_only, tmp_path, capsys):
    out = tmp_path / "replay.json"
    assert main(["replay", str(hand_only / "Models" / "20"), "--json", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert f"penetration {NO_OBJECT_TEXT}" in lines
    assert f"held        {NO_OBJECT_TEXT}" in lines and f"drift       {NO_OBJECT_TEXT}" in lines
    assert "self-pen.   max 0.00 mm, p95 0.00 mm, 0 frames over 1 mm (simulated hand through itself)" in lines
    assert (
        "limits      95 target samples beyond the joint limits in 5 DoFs (flag joint_limits above)" in lines
    )
    assert not any(line.startswith("object") or line.startswith("contact ") for line in lines)
    record = json.loads(out.read_text())
    assert record["summary"]["hold_reason"] == NO_OBJECT_TEXT
    assert record["summary"]["max_self_penetration_mm"] == 0.0
    assert record["curves"]["contacts_per_link"] == {} and len(record["curves"]["self_penetration_mm"]) == 617
    assert set(record["curves"]["penetration_mm"]) == {None}


def test_a_dataset_run_lists_the_hand_only_sequence_as_a_trial_and_reports_it(hand_only, tmp_path, capsys):
    discovery = discover(hand_only)
    assert [e.id for e in discovery.entries] == ["Models/20"]
    assert discovery.entries[0].meta["objects"] == [] and discovery.entries[0].meta["object"] is None
    out = tmp_path / "out"
    summary = run_dataset(discovery, out, workers=1, frames=0, progress=False)
    assert (summary.ok, summary.failed, summary.hold_trials) == (1, 0, 0)
    (record,) = read_records(out)
    assert record["status"] == "ok" and record["kind"] == "tzionas"
    assert record["summary"]["hold_reason"] == NO_OBJECT_TEXT
    assert record["trajectory_quality"]["limit_violations"] == 95
    assert record["curves"]["penetration_mm"] is None and record["curves"]["contacts_per_finger"] == {}
    assert set(record["curves"]["self_penetration_mm"]) == {0.0}
    assert main(["report", "--render-only", str(out)]) == 0
    capsys.readouterr()
    report = json.loads((out / "summary.json").read_text())
    (row,) = report["trials"]
    assert row["outcome"] == "ran" and row["max_self_penetration_mm"] == 0.0
    assert row["reason"] == f"{NO_OBJECT_TEXT}; max self-penetration 0.00 mm"
    html = (out / "report.html").read_text()
    assert "The hand through itself (deepest, simulated)" in html
    assert f"Hand–object penetration, contacts, hold and drift: {NO_OBJECT_TEXT}." in html
    assert "Deepest hand–object penetration" not in html
    markdown = (out / "report.md").read_text()
    assert f"**ran** — {NO_OBJECT_TEXT}; max self-penetration 0.00 mm" in markdown
