"""Discovery's reasons for every Tzionas and GraspDB14 file kind that is not a trial (exact strings).

Tzionas (spec 000): ``.SKEL .LIMITS .OFF .SKIN .VOI .MOTION`` (and the sample's ``.ZONES``) of hands and
objects, ``Configs/NN/MODELS_INFO.txt`` and ``INDEX_BOUNDS.txt``, the ``Calibration/`` and ``VOIs/`` folders.
GraspDB14 (spec 003 §4): rad and raw recordings, ``_annot-`` phase files, ``_calib-`` glove calibration
sequences, ``.xmlskel`` skeletons, the camera calibration files and hand images, and ``fk_oracle/``.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from handsim.assets import TZIONAS_DIR
from handsim.trials import discover
from tests.tzionas_fixtures import shifted_motion

_NOT_A_TRIAL_17 = (
    "Tzionas/Ballan model of sequence 17, which has no hand motion here (no Model_Hand_*.MOTION): not a trial"
)
_ZONES = "Tzionas skinning zones (.ZONES; not read by handsim)"


def _tzionas(root: Path) -> Path:
    """The bundled sample plus: 21 hand-only (the cube's files left unlisted), 22 without its
    MODELS_INFO.txt, 23 with a .VOI of its listed object and a stray file in its Configs folder (its hand
    moved 1 µm: a recording of its own, as a byte-identical copy of 20 is replayed once)."""
    shutil.copytree(TZIONAS_DIR, root)
    models, configs = root / "Models", root / "Configs"
    for sequence in ("21", "22", "23"):
        shutil.copytree(models / "20", models / sequence)
    (configs / "21").mkdir()
    (configs / "21" / "MODELS_INFO.txt").write_text("1\nModel_Hand_R\n")
    shutil.copytree(configs / "20", configs / "23")
    (models / "22" / "Model_Object_Cube.SKEL").unlink()
    (models / "23" / "Model_Object_Cube.VOI").write_text("1\n0\n")
    (configs / "23" / "notes.txt").write_text("x\n")
    motion = models / "23" / "Model_Hand_R.MOTION"
    motion.write_text(shifted_motion(motion.read_text(), (0.0, 0.0, 1e-3)))
    return root


def test_every_tzionas_file_kind_is_a_trial_input_or_has_its_exact_reason(tmp_path):
    root = _tzionas(tmp_path / "tzionas")
    discovery = discover(root)
    assert [e.id for e in discovery.entries] == ["Models/20", "Models/21", "Models/23"]
    assert discovery.entries[1].trial.objects == ()
    companions = {c.path: c.reason for c in discovery.companions}
    unknown = {u.path: u.reason for u in discovery.unknown}
    no_config = root / "Configs" / "22" / "MODELS_INFO.txt"
    failed = "hand motion Models/22/Model_Hand_R.MOTION is not a trial (its entry says why)"
    unlisted = "Tzionas model Model_Object_Cube beside the hand motion of sequence 21, not listed in its " + (
        "Configs/21/MODELS_INFO.txt: not part of the trial"
    )
    assert unknown == {
        "Configs/23/notes.txt": "a file of Tzionas sequence 23's configuration folder other than "
        "MODELS_INFO.txt and INDEX_BOUNDS.txt (the files handsim reads there): not read",
        "Models/22/Model_Hand_R.MOTION": "a Tzionas hand motion, but not a trial: "
        f"{root / 'Models' / '22' / 'Model_Hand_R.MOTION'}: no {no_config} beside the sequence's Models "
        "folder; it lists the sequence's hand and objects",
        **{
            f"Models/22/Model_{model}.{ext}": f"Tzionas model Model_{model} of sequence 22, whose {failed}"
            for model, exts in (
                ("Hand_R", ("SKEL", "LIMITS", "OFF", "SKIN", "VOI")),
                ("Object_Cube", ("LIMITS", "MOTION", "OFF", "SKIN")),
            )
            for ext in exts
        },
        **{
            f"Models/21/Model_Object_Cube.{ext}": unlisted
            for ext in ("SKEL", "LIMITS", "MOTION", "OFF", "SKIN")
        },
    }
    assert companions == {
        "Calibration/Cameras.txt": (
            "Tzionas camera calibration (not read: motion times use the sensor's 30 Hz, docs/conventions.md)"
        ),
        "Configs/17/INDEX_BOUNDS.txt": "Tzionas configuration of sequence 17, which has no hand motion here: "
        "not a trial",
        "Configs/17/MODELS_INFO.txt": "Tzionas configuration of sequence 17, which has no hand motion here: "
        "not a trial",
        "LICENSE": "documentation (not read)",
        "README.md": "documentation (not read)",
        **{
            f"Models/17/Model_Object_Pipe_Gray.{ext}": _NOT_A_TRIAL_17
            for ext in ("SKEL", "LIMITS", "MOTION", "OFF", "SKIN", "ZONES")
        },
        **{f"Models/{s}/Model_Hand_R.ZONES": _ZONES for s in ("20", "21", "22", "23")},
        **{f"Models/{s}/Model_Object_Cube.ZONES": _ZONES for s in ("20", "21", "22", "23")},
        "Models/23/Model_Object_Cube.VOI": (
            "Tzionas .VOI of Model_Object_Cube, which sequence 23 replays: not read (handsim reads a hand's "
            ".SKEL, .LIMITS, .MOTION, .OFF, .SKIN, .VOI and an object's .SKEL, .LIMITS, .MOTION, .OFF, .SKIN)"
        ),
        **{
            f"VOIs/VOIs_Model_{i}.txt": (
                "Tzionas vertex-of-interest list of the dataset's models (not read; a hand's own .VOI is)"
            )
            for i in (0, 1)
        },
    }


def test_the_configuration_of_a_sequence_whose_hand_motion_is_not_a_trial_says_so(tmp_path):
    root = _tzionas(tmp_path / "tzionas")
    (root / "Configs" / "22").mkdir()
    (root / "Configs" / "22" / "MODELS_INFO.txt").write_text("2\nModel_Hand_R\n")  # one name of two
    discovery = discover(root)
    assert "Models/22" not in [e.id for e in discovery.entries]
    companions = {c.path: c.reason for c in discovery.companions}
    unknown = {u.path: u.reason for u in discovery.unknown}
    assert companions["Configs/22/MODELS_INFO.txt"] == (
        "Tzionas configuration of sequence 22, whose hand motion is not a trial (the entry of its "
        "Models/22/Model_Hand_*.MOTION says why)"
    )
    assert unknown["Models/22/Model_Hand_R.SKEL"] == (
        "Tzionas model Model_Hand_R of sequence 22, whose hand motion Models/22/Model_Hand_R.MOTION is not a "
        "trial (its entry says why)"
    )


GRASPDB_FILES = (
    "01_ex01-rad-002-grasp-su01.txt",  # a trial
    "01_ex01-raw-002-grasp-su01.txt",  # its raw twin
    "01_ex01-rad-002-grasp-su01_annot-.txt",  # its phases: an input of the trial
    "02_ex01-raw-003-grasp-su01.txt",  # raw counts alone
    "02_ex01-raw-003-grasp-su01_annot-.txt",  # the phases of that raw recording
    "03_ex01-rad-004-grasp-su01_annot-.txt",  # phases of a recording that is not here
    "99_ex01-rad-001-grasp-su01.txt",  # an object id GraspDB14 does not have
    "su04_calib-raw-1.txt",
    "su04_calib-rad-1.txt",
    "su04_calib-.txt",
    "img123.jpg",
    "img123-rect.jpg",
    "img123-rect.xml",
    "default.xmlskel",
    "fk_oracle/16_14_ex01-rad-004-grasp-su06",
    "fk_oracle/16_14_ex01-rad-004-grasp-su06_w_traj.mat",
)


def test_every_graspdb_file_kind_is_a_trial_input_or_has_its_exact_reason(tmp_path):
    for name in GRASPDB_FILES:
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("x\n")
    # the trial's own annotation must cover its frames (one row here) to be one of its inputs
    (tmp_path / "01_ex01-rad-002-grasp-su01_annot-.txt").write_text("1 1 .grasp\n")
    discovery = discover(tmp_path)
    (entry,) = discovery.entries
    assert entry.id == "01_ex01-rad-002-grasp-su01.txt"
    assert [i.path for i in entry.inputs] == [entry.id, "01_ex01-rad-002-grasp-su01_annot-.txt"]
    companions = {c.path: c.reason for c in discovery.companions}
    unknown = {u.path: u.reason for u in discovery.unknown}
    oracle = (
        "GraspDB14 tools' forward-kinematics oracle (calcJointTrajectories output and its input motions): "
        "test data for the skeleton, not trials"
    )
    assert companions == {
        "01_ex01-raw-002-grasp-su01.txt": "raw sensor counts of 01_ex01-rad-002-grasp-su01.txt, which is "
        "replayed",
        "02_ex01-raw-003-grasp-su01.txt": "raw sensor counts without their -rad- twin: a dataset run has no "
        "glove calibration to turn them into angles; replay it alone with handsim replay FILE "
        "--calibration CAL.json",
        "02_ex01-raw-003-grasp-su01_annot-.txt": "GraspDB14 phase annotation of "
        "02_ex01-raw-003-grasp-su01.txt, which is not replayed (its entry says why)",
        "su04_calib-raw-1.txt": (
            "calibration sequence (use `handsim calibrate`): CyberGlove raw counts; the calibration "
            "estimated from it replays -raw- recordings"
        ),
        "su04_calib-rad-1.txt": "calibration sequence, in radians (already calibrated): not read; `handsim "
        "calibrate` takes the raw-count sequence, and -rad- recordings need none",
        "su04_calib-.txt": (
            "calibration sequence (use `handsim calibrate` if it holds raw counts; its name says neither "
            "-rad- nor -raw-, and reading it refuses angles)"
        ),
        "img123.jpg": "GraspDB14 image of an actor's hand, rectified as img123-rect.jpg (spec 003 §4.1.1): "
        "not read",
        "img123-rect.jpg": "GraspDB14 rectified image of an actor's hand (spec 003 §4.1.1): not read",
        "img123-rect.xml": "GraspDB14 camera calibration and hand measurements of a rectified hand image "
        "(spec 003 §4.1.1, §4.2.1): not read",
        "default.xmlskel": "GraspDB14 hand skeleton (.xmlskel); trials replay the parametric default hand "
        "(handsim replay --skeleton uses this one)",
        "fk_oracle/16_14_ex01-rad-004-grasp-su06": oracle,
        "fk_oracle/16_14_ex01-rad-004-grasp-su06_w_traj.mat": oracle,
    }
    assert set(unknown) == {"03_ex01-rad-004-grasp-su01_annot-.txt", "99_ex01-rad-001-grasp-su01.txt"}
    assert unknown["03_ex01-rad-004-grasp-su01_annot-.txt"] == (
        "a GraspDB14 phase annotation file, not a recording; no recording of the dataset uses it (the one it "
        "annotates is not in the dataset, or covers another number of frames: that trial's notes say so)"
    )
    assert unknown["99_ex01-rad-001-grasp-su01.txt"].startswith(
        "a GraspDB14 recording name, but not a trial: unknown GraspDB object id 99; catalogue ids are: "
    )
