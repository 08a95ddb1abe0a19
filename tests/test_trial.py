"""Trials from files: which kind, hand and objects a recording makes, and the scene it loads into."""

from __future__ import annotations

import pickle
import shutil

import pytest

from handsim.assets import TZIONAS_DIR
from handsim.builders.graspdb_objects import UnknownObjectError
from handsim.errors import InputFileError
from handsim.sim.replay import replay
from handsim.trials import (
    TRIAL_KINDS,
    Trial,
    TrialError,
    TrialObject,
    UnsupportedTrialError,
    find_trial,
    load_trial,
    trial_kind,
)

SEQ20 = TZIONAS_DIR / "Models" / "20"
MOTION = SEQ20 / "Model_Hand_R.MOTION"
GRASPDB_TRIAL = "r_01_11_ex03-rad-004-grasp-su04.txt"


def test_find_trial_of_a_tzionas_motion_names_its_skeleton_and_the_sequence_objects():
    trial = find_trial(MOTION)
    assert trial.kind == "tzionas"
    assert trial.trajectory_path == str(MOTION)
    assert trial.skeleton_path == str(SEQ20 / "Model_Hand_R.SKEL")
    assert trial.objects == (TrialObject(str(SEQ20 / "Model_Object_Cube.SKEL"), "cube", "MODELS_INFO.txt:3"),)


def test_find_trial_of_a_tzionas_models_folder_picks_the_listed_hand():
    assert find_trial(SEQ20).trajectory_path == str(MOTION)


def test_find_trial_accepts_the_tzionas_motions_own_skeleton():
    assert find_trial(MOTION, skeleton=SEQ20 / "Model_Hand_R.SKEL").skeleton_path == str(
        SEQ20 / "Model_Hand_R.SKEL"
    )


@pytest.mark.parametrize(
    ("option", "value", "what"),
    [
        ("obj", "mug", "an object"),
        ("calibration", "c.json", "a calibration"),
        ("hand_length", 0.18, "a hand length"),
        ("thumb_rest", (20.0, 10.0), "a thumb rest posture"),
    ],
)
def test_find_trial_raises_error_if_a_glove_option_is_given_for_a_tzionas_motion(option, value, what):
    with pytest.raises(
        TrialError, match=f"{what} does not apply to a Tzionas sequence; it brings its own hand and objects"
    ):
        find_trial(MOTION, **{option: value})


def test_find_trial_raises_error_if_a_tzionas_motion_gets_another_skeleton(tmp_path):
    other = tmp_path / "other.SKEL"
    other.write_text("")
    with pytest.raises(TrialError, match=r"drives its own skeleton Model_Hand_R\.SKEL"):
        find_trial(MOTION, skeleton=other)


def test_find_trial_raises_error_if_a_tzionas_sequence_has_no_models_info(tmp_path):
    models = tmp_path / "Models" / "20"
    models.mkdir(parents=True)
    motion = models / "Model_Hand_R.MOTION"
    motion.write_text("")
    with pytest.raises(TrialError, match=r"no .*Configs/20/MODELS_INFO.txt"):
        find_trial(motion)


def test_find_trial_raises_error_for_an_object_motion():
    with pytest.raises(TrialError, match="not a hand motion"):
        find_trial(SEQ20 / "Model_Object_Cube.MOTION")


def test_find_trial_raises_error_listing_the_kinds_for_an_unknown_file_type(tmp_path):
    path = tmp_path / "motion.csv"
    path.write_text("1,2,3\n")
    with pytest.raises(UnsupportedTrialError) as exc:
        find_trial(path)
    message = str(exc.value)
    assert "file type '.csv' is not a trial handsim replays" in message
    for kind in TRIAL_KINDS:
        assert f"{kind}: " in message
    assert isinstance(exc.value, InputFileError)


def test_trial_kind_raises_error_for_a_graspdb_annotation_file(tmp_path):
    path = tmp_path / "01_11_ex03-rad-004-grasp-su04_annot-.txt"
    path.write_text("")
    with pytest.raises(UnsupportedTrialError, match="a GraspDB14 phase annotation file, not a recording"):
        trial_kind(path)


def test_trial_kind_raises_error_for_a_folder_without_a_hand_motion(tmp_path):
    with pytest.raises(UnsupportedTrialError, match="a folder without Model_Hand_"):
        trial_kind(tmp_path)


def test_find_trial_raises_error_if_the_file_is_missing(tmp_path):
    with pytest.raises(InputFileError, match=r"missing\.txt: file not found"):
        find_trial(tmp_path / "missing.txt")


def test_find_trial_takes_the_graspdb_object_from_the_file_name(tmp_path):
    path = tmp_path / "13_ex01-rad-002-grasp-su01.txt"
    path.write_text("")
    trial = find_trial(path)
    assert trial.kind == "graspdb"
    assert trial.objects == (TrialObject("cylinder_25mm", "", "object id 13 in the file name"),)
    assert trial.skeleton_path is None and trial.hand_length == 0.19
    assert trial.annotation_path is None
    assert trial.notes[-1] == (
        "no phase annotation (13_ex01-rad-002-grasp-su01_annot-.txt) beside 13_ex01-rad-002-grasp-su01.txt: "
        "the grasp phase is found from the finger flexion"
    )


def test_find_trial_prefers_the_given_object_to_the_file_name(tmp_path):
    path = tmp_path / "13_ex01-rad-002-grasp-su01.txt"
    path.write_text("")
    assert find_trial(path, obj="mug").objects == (TrialObject("mug", "", "given"),)


def test_find_trial_raises_error_if_a_graspdb_file_name_carries_no_object_id(tmp_path):
    path = tmp_path / "glove.txt"
    path.write_text("")
    with pytest.raises(TrialError, match="carries no GraspDB14 object id"):
        find_trial(path)


def test_find_trial_raises_error_listing_the_ids_for_an_unknown_object_id(tmp_path):
    path = tmp_path / "99_ex01-rad-002-grasp-su01.txt"
    path.write_text("")
    with pytest.raises(
        UnknownObjectError, match=r"unknown GraspDB object id 99; catalogue ids are: 1 \(tennis_ball\)"
    ):
        find_trial(path)


def test_find_trial_raises_error_if_a_hand_length_comes_with_a_skeleton(tmp_path):
    path = tmp_path / "01_ex01-rad-002-grasp-su01.txt"
    path.write_text("")
    with pytest.raises(TrialError, match="hand length is for the parametric default hand"):
        find_trial(path, skeleton="default.xmlskel", hand_length=0.2)


def test_find_trial_raises_error_for_both_density_and_mass():
    with pytest.raises(TrialError, match="density or a mass, not both"):
        find_trial(MOTION, density=500.0, mass=0.1)


def test_find_trial_raises_error_for_an_unknown_hand_collision():
    with pytest.raises(
        TrialError, match=r"unknown hand collision 'hulls'; expected one of \['capsules', 'mesh'\]"
    ):
        find_trial(MOTION, collision="hulls")


def test_find_trial_finds_the_graspdb_annotation_beside_the_recording(graspdb_dir, tmp_path):
    for name in (GRASPDB_TRIAL, "01_11_ex03-rad-004-grasp-su04_annot-.txt"):
        shutil.copy(graspdb_dir / name, tmp_path / name)
    trial = find_trial(tmp_path / GRASPDB_TRIAL)
    assert trial.annotation_path == str(tmp_path / "01_11_ex03-rad-004-grasp-su04_annot-.txt")
    assert trial.objects[0].what == "tennis_ball"


def test_load_trial_of_a_tzionas_motion_builds_the_recorded_scene_and_pickles():
    loaded = load_trial(MOTION)
    assert loaded.scene.setup.scenario == "recorded"
    assert loaded.scene.setup.object_tracks == ("cube",)
    assert set(loaded.trajectory.objects) == {"cube"}
    assert [o.name for o in loaded.objects] == ["cube"]
    assert loaded.objects[0].mass == pytest.approx(0.0887, abs=5e-4)  # 53 mm cube at 600 kg/m³
    assert loaded.hand == "Model_Hand_R.SKEL (31 DoFs, capsules)"
    again = pickle.loads(pickle.dumps(loaded))
    assert again.trial == loaded.trial
    assert again.scene.model_sha256 == loaded.scene.model_sha256
    assert again.scene.model.nq == loaded.scene.model.nq


def test_load_trial_raises_error_if_options_come_with_a_trial():
    with pytest.raises(TypeError, match="options \\['obj'\\] are for a path"):
        load_trial(find_trial(MOTION), obj="mug")


def test_load_trial_raises_error_for_an_unknown_kind():
    trial = Trial(kind="vicon", trajectory_path="x", skeleton_path=None, objects=())
    with pytest.raises(
        TrialError,
        match=r"unknown trial kind 'vicon'; expected one of "
        r"\['tzionas', 'arctic', 'scripted', 'graspdb', 'corrected'\]",
    ):
        load_trial(trial)


def test_load_trial_of_a_graspdb_recording_places_its_object_for_the_annotated_grasp(graspdb_dir):
    loaded = load_trial(graspdb_dir / GRASPDB_TRIAL)
    assert loaded.scene.setup.scenario == "glove"
    assert loaded.hand == "parametric default hand, 0.19 m (27 DoFs)"
    assert [(o.name, o.origin) for o in loaded.objects] == [("tennis_ball", "object id 1 in the file name")]
    assert [p.name for p in loaded.trajectory.phases] == ["rest", "reach", "grasp", "retract", "rest"]
    assert loaded.scene.setup.placement["grasp"]["source"] == "phase"
    result = replay(loaded.scene, loaded.trajectory)
    assert result.hold is not None
