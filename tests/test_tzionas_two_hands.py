"""Two-hand Tzionas sequences (issue 13, deliverable 4): one trial, both hands in one scene.

The sequence is the bundled sample's sequence 20 with a left hand added (``tests/tzionas_fixtures.py``): a
copy of the right hand whose recorded global pose is moved 25 cm along the camera's x. The left hand is then
the right hand's motion away from the cube, so the replay has an independent reference: the right hand must
replay exactly as it does alone (the hands never touch, and each is driven by its own motion), and the left
hand exactly as the right one until the right hand first touches the cube (frame 105, 1.05 s); after that
only the cube's contacts on the right hand tell them apart.
"""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest

from handsim.assets import TZIONAS_DIR
from handsim.cli import main
from handsim.datatypes.poses import compose
from handsim.datatypes.rotations import quat_rotate
from handsim.errors import TrajectoryError
from handsim.runner.execute import run_dataset
from handsim.runner.records import read_records
from handsim.sim.control import control_schedule
from handsim.sim.drive import ScenarioSwitches, ScheduleDriver
from handsim.sim.replay import replay
from handsim.sim.stepper import Stepper
from handsim.sim.summary import HAND_KEYS
from handsim.trials import TrialError, discover, find_trial, load_trial
from tests.tzionas_fixtures import LEFT_SHIFT_MM, truncated_motion, two_hand_sample

RIGHT_CONTACT_FRAME = 104  # measured; 105 before the pads rested 1.5 mm outside the fitted mesh
"""The first replay frame (100 Hz) in which the right hand of sequence 20 touches the cube."""


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> Path:
    return two_hand_sample(tmp_path_factory.mktemp("two_hands") / "tzionas")


@pytest.fixture(scope="module")
def loaded(models):
    return load_trial(models)


@pytest.fixture(scope="module")
def result(loaded):
    return replay(loaded.scene, loaded.trajectory)


@pytest.fixture(scope="module")
def alone():
    """The bundled sequence 20 as it is: the right hand alone."""
    one = load_trial(TZIONAS_DIR / "Models" / "20")
    return replay(one.scene, one.trajectory)


def test_a_sequence_listing_two_hands_is_one_trial_of_its_models_folder(models):
    trial = find_trial(models)
    assert trial.kind == "tzionas" and trial.trajectory_path == str(models) and trial.skeleton_path is None
    assert [(o.track, o.origin) for o in trial.objects] == [("cube", "MODELS_INFO.txt:4")]
    info = models.parent.parent / "Configs" / "20" / "MODELS_INFO.txt"
    assert trial.notes == (
        f"hands right Model_Hand_R.SKEL, left Model_Hand_L.SKEL and objects ['cube'] from {info}",
    )


@pytest.mark.parametrize("hand", ["Model_Hand_R", "Model_Hand_L"])
def test_either_hands_motion_given_finds_the_whole_sequence_and_says_so(models, hand):
    trial = find_trial(models / f"{hand}.MOTION")
    assert trial.trajectory_path == str(models)
    assert trial.notes[1] == (
        f"{hand}.MOTION given: MODELS_INFO.txt lists two hands, so the trial is the whole sequence {models} "
        "with both"
    )


def test_both_hands_are_in_one_scene_each_driven_by_its_own_motion(loaded):
    layout = loaded.scene.layout
    assert [h.name for h in layout.hands] == ["right", "left"]
    assert all(h.mocap >= 0 and h.root_free_qpos >= 0 for h in layout.hands)
    assert len(layout.dof_names) == 62
    assert all(n.startswith("right/") for n in layout.dof_names[:31])
    assert all(n.startswith("left/") for n in layout.dof_names[31:])
    trajectory = loaded.trajectory
    assert trajectory.dof_names == layout.dof_names and set(trajectory.hand_roots) == {"right", "left"}
    assert trajectory.root_pose is None and list(trajectory.objects) == ["cube"]
    # the left motion is the right one moved: the same angles, the root 250 mm away in the recording frame
    np.testing.assert_array_equal(trajectory.targets[:, 31:], trajectory.targets[:, :31])
    shift = trajectory.hand_roots["left"][:, :3] - trajectory.hand_roots["right"][:, :3]
    # (the file prints 6 significant digits: origins up to ~600 mm are rounded to 0.5 µm)
    np.testing.assert_allclose(shift, np.tile(np.array(LEFT_SHIFT_MM) / 1000.0, (len(shift), 1)), atol=1e-6)
    assert loaded.hand == "right Model_Hand_R.SKEL (31 DoFs), left Model_Hand_L.SKEL (31 DoFs); capsules"


def test_each_hand_root_starts_at_its_own_recorded_pose_in_the_scene(loaded):
    scene, trajectory = loaded.scene, loaded.trajectory
    stepper = Stepper(scene, 1)
    ScheduleDriver(stepper, control_schedule(scene, trajectory, 100.0), ScenarioSwitches()).reset()
    mujoco.mj_kinematics(scene.model, stepper.data)
    right, left = (stepper.data.xpos[h.root_body] for h in scene.layout.hands)
    world = np.asarray(scene.setup.world_from_recording)
    expected = quat_rotate(world[3:], np.array(LEFT_SHIFT_MM) / 1000.0)  # independent: the shift turned
    np.testing.assert_allclose(left - right, expected, atol=1e-6)  # the files' 6 digits


def test_the_two_hands_collide_with_each_other(loaded):
    scene = loaded.scene
    model = scene.model
    stepper = Stepper(scene, 1)
    ScheduleDriver(stepper, control_schedule(scene, loaded.trajectory, 100.0), ScenarioSwitches()).reset()
    data = stepper.data
    right, left = scene.layout.hands
    data.qpos[left.root_free_qpos : left.root_free_qpos + 7] = data.qpos[
        right.root_free_qpos : right.root_free_qpos + 7
    ]  # the left hand put onto the right one
    mujoco.mj_forward(model, data)

    def hand(geom: int) -> str:
        name = model.body(model.geom_bodyid[geom]).name
        return name.split("/")[1] if name.startswith("hand/") else name

    between = [c for c in data.contact[: data.ncon] if {hand(c.geom1), hand(c.geom2)} == {"right", "left"}]
    assert len(between) > 10


def test_the_two_hand_replay_tracks_both_hands_with_zero_warnings(result, alone):
    s = result.summary
    assert result.warnings == () and result.diverged is None and s["valid"] is True
    # the right hand replays as it does alone: same contacts, penetration, tracking (solver round-off only)
    for key in HAND_KEYS:
        assert s[f"right/{key}"] == pytest.approx(alone.summary[key], rel=1e-9, abs=1e-9), key
    assert s["max_drift_mm"] == pytest.approx(alone.summary["max_drift_mm"], rel=1e-9)
    # the left hand touches no object, and tracks like the right one until the right hand's first cube
    # contact: to 0.02° (measured 0.008°; each hand's fingers touch each other from the first frame — the
    # fitted skin's rest offset — and both hands' contacts are solved as one system), after which its mean
    # joint error stays within 0.15° (measured 0.106°: the cube's contacts load the right fingers, the left
    # ones follow their targets freely)
    assert s["left/contact_frames"] == 0 and s["left/max_penetration_mm"] == 0.0
    frames = result.frames
    right_links = frames.link_hand == 0
    touching = frames.contact_count[:, right_links].sum(axis=(1, 2)) > 0
    assert int(np.argmax(touching)) == RIGHT_CONTACT_FRAME
    before = slice(0, RIGHT_CONTACT_FRAME)
    error = np.abs(frames.tracking_error[before])
    np.testing.assert_allclose(
        error[:, frames.dof_hand == 1], error[:, frames.dof_hand == 0], rtol=0, atol=np.radians(0.02)
    )
    tips = frames.tip_error[before]
    np.testing.assert_allclose(
        tips[:, frames.tip_hand == 1],
        tips[:, frames.tip_hand == 0],
        rtol=0,
        atol=1e-4,  # 0.1 mm; 25 µm
    )
    assert abs(s["left/mean_tracking_error_deg"] - alone.summary["mean_tracking_error_deg"]) < 0.15
    assert s["left/max_tracking_error_deg"] < alone.summary["max_tracking_error_deg"] < 5.0
    assert s["left/mean_tip_error_mm"] < 10.0


def test_the_cli_replay_prints_a_line_per_hand(models, capsys):
    assert main(["replay", str(models / "Model_Hand_R.MOTION")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert f"trial       tzionas  {models}" in lines
    assert "warnings    none" in lines
    (right,) = [line for line in lines if line.startswith("right ")]
    (left,) = [line for line in lines if line.startswith("left ")]
    assert right.startswith("right       contact 372 frames (up to 3 links, 2.19 N); penetration max 0.31 mm")
    assert left.startswith("left        contact 0 frames (up to 0 links, 0.00 N); penetration max 0.00 mm")


def test_a_dataset_run_lists_the_sequence_as_one_trial_with_per_hand_records(models, tmp_path, capsys):
    root = models.parent.parent
    discovery = discover(root)
    assert [e.id for e in discovery.entries] == ["Models/20"]
    assert discovery.unknown == ()
    (entry,) = discovery.entries
    paths = [(i.role, i.path) for i in entry.inputs]
    assert paths[:3] == [
        ("trajectory", "Models/20/Model_Hand_R.MOTION"),
        ("trajectory", "Models/20/Model_Hand_L.MOTION"),
        ("trajectory", "Configs/20/INDEX_BOUNDS.txt"),
    ]
    for ext in ("SKEL", "LIMITS", "OFF", "SKIN"):
        assert ("skeleton", f"Models/20/Model_Hand_L.{ext}") in paths
    out = tmp_path / "out"
    summary = run_dataset(discovery, out, workers=1, frames=0, progress=False)
    assert (summary.ok, summary.failed) == (1, 0)
    (record,) = read_records(out)
    assert record["status"] == "ok" and record["kind"] == "tzionas"
    for side in ("right", "left"):
        assert all(f"{side}/{key}" in record["summary"] for key in HAND_KEYS)
    assert record["summary"]["right/contact_frames"] == 372 and record["summary"]["left/contact_frames"] == 0
    assert main(["report", "--render-only", str(out)]) == 0
    capsys.readouterr()
    markdown = (out / "report.md").read_text()
    assert "## Two-hand trials" in markdown
    assert "| [Models/20](report.html#trial-models-20) | 372 | 0.31 | 0.39 | 0 | 0.00 | 0.29 |" in markdown
    report = json.loads((out / "summary.json").read_text())
    (row,) = report["trials"]
    assert row["right/contact_frames"] == 372 and row["left/contact_frames"] == 0


def test_hands_whose_motions_have_different_frame_counts_are_refused_naming_both(tmp_path, capsys):
    models = two_hand_sample(tmp_path / "tzionas")
    skel, motion = models / "Model_Hand_L.SKEL", models / "Model_Hand_L.MOTION"
    lines = skel.read_text().splitlines()
    skel.write_text("\n".join(["150", *lines[1:]]) + "\n")
    motion.write_text(truncated_motion(motion.read_text(), 150))
    message = (
        f"the two hands of sequence 20 must share their frames: {models}/Model_Hand_R.MOTION has 187 frames "
        f"(Model_Hand_R.SKEL's count) and {models}/Model_Hand_L.MOTION has 150 frames (Model_Hand_L.SKEL's "
        "count)"
    )
    with pytest.raises(TrajectoryError) as caught:
        load_trial(models)
    assert str(caught.value) == message
    assert main(["replay", str(models)]) == 1
    assert capsys.readouterr().err.strip() == f"handsim: error: {message}"


def test_a_sequence_listing_two_hands_of_the_same_side_is_refused_naming_its_lines(tmp_path):
    models = two_hand_sample(tmp_path / "tzionas")
    info = models.parent.parent / "Configs" / "20" / "MODELS_INFO.txt"
    info.write_text("3\nModel_Hand_R\nModel_Hand_R2\nModel_Object_Cube\n")
    with pytest.raises(TrajectoryError) as caught:
        find_trial(models)
    assert str(caught.value) == (
        f"{info}: lists the hands 'Model_Hand_R' (line 2), 'Model_Hand_R2' (line 3); a two-hand sequence "
        "lists exactly Model_Hand_R and Model_Hand_L, one each"
    )


def test_a_listed_hand_without_its_motion_is_no_trial_and_discovery_says_why(tmp_path):
    models = two_hand_sample(tmp_path / "tzionas")
    (models / "Model_Hand_L.MOTION").unlink()
    reason = (
        f"{models}: MODELS_INFO.txt:3 lists the left hand 'Model_Hand_L', but Model_Hand_L.MOTION is not in "
        "the folder"
    )
    with pytest.raises(TrialError) as caught:
        find_trial(models)
    assert str(caught.value) == reason
    discovery = discover(models.parent.parent)
    assert discovery.entries == ()
    unknown = {u.path: u.reason for u in discovery.unknown}
    assert unknown["Models/20/Model_Hand_R.MOTION"] == f"a Tzionas hand motion, but not a trial: {reason}"


def test_a_two_hand_sequence_without_objects_replays_both_hands_hand_only(tmp_path):
    models = two_hand_sample(tmp_path / "tzionas")
    (models.parent.parent / "Configs" / "20" / "MODELS_INFO.txt").write_text(
        "2\nModel_Hand_R\nModel_Hand_L\n"
    )
    loaded = load_trial(models)
    scene = loaded.scene
    assert [h.name for h in scene.layout.hands] == ["right", "left"] and scene.layout.objects == ()
    world = np.asarray(scene.setup.world_from_recording)
    first = compose(world, loaded.trajectory.hand_roots["right"][0])
    np.testing.assert_allclose(first[:3], 0.0, atol=1e-12)  # the first hand's first root is the origin
    result = replay(scene, loaded.trajectory)
    s = result.summary
    assert result.warnings == () and result.diverged is None
    assert s["contact_frames"] is None and s["right/contact_frames"] is None  # nothing to touch
    assert s["max_self_penetration_mm"] == 0.0  # the hands, 25 cm apart, never meet
    assert 0.0 < s["left/mean_tracking_error_deg"] < 5.0 and 0.0 < s["right/mean_tracking_error_deg"] < 5.0
