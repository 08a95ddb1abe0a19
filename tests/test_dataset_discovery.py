"""Dataset discovery of the samples and of made-up layouts (GraspDB14, Tzionas, ARCTIC), GraspDB14 file
names and the grasp taxonomy. Every reason of every file kind: tests/test_discovery_reasons.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from handsim.assets import TZIONAS_DIR
from handsim.io.arctic.mano import MANO_DIR_ENV
from handsim.io.graspdb.filenames import parse_graspdb_filename
from handsim.runner.execute import run_dataset
from handsim.runner.records import read_records
from handsim.trials import discover, select
from handsim.trials.graspdb_names import GRASP_TYPES, graspdb_meta
from tests.mano_fixtures import (
    arctic_object_values,
    mano_hand_params,
    write_arctic_mano_npy,
    write_arctic_object_npy,
)
from tests.runner_fixtures import GRASPDB_IDS, SESSION_IDS


def _files(root: Path) -> set[str]:
    return {p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()}


def _accounted(discovery) -> set[str]:
    inputs = {i.path for e in discovery.entries for i in e.inputs}
    return inputs | {c.path for c in discovery.companions} | {u.path for u in discovery.unknown}


# --------------------------------------------------------------------------------------------------
# GraspDB14 file names (spec 003 §4.1.2) and the grasp taxonomy (Table 3.3)


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        (  # Example 4.2
            "01_ex01-raw-002-grasp-su01.txt",
            {"object": "tennis_ball", "grasp": None, "grasp_id": None, "action": None, "actor": "su01",
             "scenario": "uncontrolled object transport", "scenario_id": "01", "trial_counter": 2,
             "datatype": "raw"},
        ),
        (  # Example 4.3
            "01_i_r_ex02-raw-025-grasp-su01.txt",
            {"object": "tennis_ball", "grasp": None, "action": "interact (right hand)", "action_id": "i_r",
             "scenario": "object use and interaction", "scenario_id": "02", "trial_counter": 25,
             "actor": "su01"},
        ),
        (  # Example 4.4
            "01_11_ex03-1-rad-001-grasp-su04.txt",
            {"object": "tennis_ball", "grasp": "Power sphere", "grasp_id": 11,
             "grasp_class": "power, palm opposition", "action": None,
             "scenario": "controlled object transport", "scenario_id": "03-1", "trial_counter": 1,
             "actor": "su04", "datatype": "rad"},
        ),
    ],
)  # fmt: skip
def test_graspdb_meta_decodes_the_specs_file_name_examples(name, expected):
    meta = graspdb_meta(parse_graspdb_filename(name), "tennis_ball")
    assert {k: meta[k] for k in expected} == expected
    assert meta["sequence"] is None


def test_grasp_types_are_the_25_of_table_3_3_and_cover_every_grasp_id_of_table_4_1():
    table_4_1 = {11, 13, 26, 27, 28, 33, 20, 1, 31, 9, 16, 10, 3, 15, 18, 22, 30, 6, 7, 8, 2, 4, 17, 32, 14}
    assert set(GRASP_TYPES) == table_4_1
    assert GRASP_TYPES[20].name == "Writing tripod"
    assert GRASP_TYPES[20].grasp_class == "precision, side opposition"
    assert sum(g.grasp_class.startswith("power") for g in GRASP_TYPES.values()) == 13


def test_graspdb_meta_of_a_grasp_id_outside_table_3_3_keeps_the_id_without_a_name():
    meta = graspdb_meta(parse_graspdb_filename("01_05_ex03-rad-001-grasp-su04.txt"), "tennis_ball")
    assert (meta["grasp"], meta["grasp_id"], meta["grasp_class"]) == (None, 5, None)


# --------------------------------------------------------------------------------------------------
# Discovery


def test_discovery_of_the_graspdb_sample_accounts_for_every_file(graspdb_dir):
    discovery = discover(graspdb_dir)
    assert [e.id for e in discovery.entries] == [
        i.removeprefix("graspdb14/") for i in [*GRASPDB_IDS, *SESSION_IDS]
    ]
    assert discovery.unknown == ()
    assert _accounted(discovery) == _files(graspdb_dir)
    companions = {c.path: c.reason for c in discovery.companions}
    assert set(companions) == {
        "default.xmlskel",
        *(f"fk_oracle/{p.name}" for p in (graspdb_dir / "fk_oracle").iterdir()),
    }
    assert "forward-kinematics oracle" in companions["fk_oracle/16_14_ex01-rad-004-grasp-su06"]
    annotated = discovery.entries[2]
    assert [(i.role, i.path) for i in annotated.inputs] == [
        ("trajectory", "r_01_11_ex03-rad-004-grasp-su04.txt"),
        ("annotation", "01_11_ex03-rad-004-grasp-su04_annot-.txt"),
    ]
    assert annotated.meta["object"] == "tennis_ball" and annotated.meta["grasp"] == "Power sphere"
    assert discovery.entries[1].meta["object"] == "mug"


def test_discovery_of_the_tzionas_sample_accounts_for_every_file(tzionas_dir):
    discovery = discover(tzionas_dir)
    assert [e.id for e in discovery.entries] == ["Models/20"]
    assert discovery.unknown == ()
    assert _accounted(discovery) == _files(tzionas_dir)
    (entry,) = discovery.entries
    assert entry.meta == {
        "object": "cube", "grasp": None, "grasp_id": None, "action": None, "scenario": None, "actor": None,
        "sequence": "20", "objects": ["cube"],
    }  # fmt: skip
    roles = {}
    for i in entry.inputs:
        roles.setdefault(i.role, []).append(Path(i.path).name)
    assert roles == {
        "trajectory": ["Model_Hand_R.MOTION", "INDEX_BOUNDS.txt"],
        "skeleton": [f"Model_Hand_R.{e}" for e in ("SKEL", "LIMITS", "OFF", "SKIN", "VOI")],
        "object": [f"Model_Object_Cube.{e}" for e in ("SKEL", "LIMITS", "MOTION", "OFF", "SKIN")],
        "models_info": ["MODELS_INFO.txt"],
    }
    companions = {c.path: c.reason for c in discovery.companions}
    assert "no hand motion here" in companions["Models/17/Model_Object_Pipe_Gray.SKEL"]
    assert "camera calibration" in companions["Calibration/Cameras.txt"]
    assert "vertex-of-interest" in companions["VOIs/VOIs_Model_0.txt"]


def test_discovery_of_one_recording_or_one_sequence_folder_gives_one_trial():
    (entry,) = discover(TZIONAS_DIR / "Models" / "20").entries
    assert entry.id == "20"
    assert "../Configs/20/MODELS_INFO.txt" in [i.path for i in entry.inputs]
    single = discover(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION")
    assert [e.id for e in single.entries] == ["Model_Hand_R.MOTION"]
    assert single.companions == () and single.unknown == ()


def test_discovery_lists_unknown_and_companion_files_with_their_reasons(tmp_path):
    (tmp_path / "01_ex01-raw-002-grasp-su01.txt").write_text("raw twin\n")
    (tmp_path / "01_ex01-rad-002-grasp-su01.txt").write_text("rad\n")
    (tmp_path / "99_ex01-rad-001-grasp-su01.txt").write_text("object 99\n")
    (tmp_path / "02_ex01-rad-001-grasp-su02_annot-.txt").write_text("orphan\n")
    (tmp_path / "notes.txt").write_text("x\n")
    (tmp_path / "table.csv").write_text("x\n")
    (tmp_path / "README.md").write_text("x\n")
    (tmp_path / ".DS_Store").write_text("x\n")
    (tmp_path / ".git").mkdir()
    (tmp_path / ".git" / "HEAD").write_text("x\n")
    (tmp_path / "again").symlink_to(tmp_path, target_is_directory=True)
    discovery = discover(tmp_path)
    assert [e.id for e in discovery.entries] == ["01_ex01-rad-002-grasp-su01.txt"]
    unknown = {u.path: u.reason for u in discovery.unknown}
    assert set(unknown) == {
        "99_ex01-rad-001-grasp-su01.txt", "02_ex01-rad-001-grasp-su02_annot-.txt", "notes.txt", "table.csv",
    }  # fmt: skip
    assert unknown["99_ex01-rad-001-grasp-su01.txt"].startswith(
        "a GraspDB14 recording name, but not a trial: unknown GraspDB object id 99; catalogue ids are: "
        "1 (tennis_ball)"
    )
    assert unknown["02_ex01-rad-001-grasp-su02_annot-.txt"] == (
        "a GraspDB14 phase annotation file, not a recording; no recording of the dataset uses it (the one it "
        "annotates is not in the dataset, or covers another number of frames: that trial's notes say so)"
    )
    assert "not a GraspDB14 motion file name" in unknown["notes.txt"]
    assert "file type '.csv'" in unknown["table.csv"]
    companions = {c.path: c.reason for c in discovery.companions}
    assert companions == {
        "01_ex01-raw-002-grasp-su01.txt": (
            "raw sensor counts of 01_ex01-rad-002-grasp-su01.txt, which is replayed"
        ),
        "README.md": "documentation (not read)",
        ".DS_Store": "hidden file (not read)",
        ".git/": "hidden folder (not searched)",
        "again/": f"link to a folder searched already ({tmp_path.resolve()})",
    }


def test_select_matches_ids_by_glob_and_keeps_the_first_n():
    discovery = discover(TZIONAS_DIR)
    assert [e.id for e in select(discovery.entries, "Models/*")] == ["Models/20"]
    assert select(discovery.entries, "nothing*") == ()
    assert select(discovery.entries, None, 0) == ()
    with pytest.raises(ValueError, match="limit must be ≥ 0, got -1"):
        select(discovery.entries, None, -1)


def _arctic_dataset(root: Path) -> Path:
    raw = root / "raw_seqs" / "s01"
    raw.mkdir(parents=True)
    n = 5
    write_arctic_mano_npy(
        raw / "box_grab_01.mano.npy", mano_hand_params(n, 1), mano_hand_params(n, 2, side="left")
    )
    values = arctic_object_values(n)
    write_arctic_object_npy(raw / "box_grab_01.object.npy", values)
    np.save(raw / "box_grab_01.egocam.dist.npy", np.zeros(3))
    np.save(raw / "box_grab_01.smplx.npy", np.zeros(3))
    write_arctic_object_npy(raw / "ketchup_use_02.object.npy", values)  # no .mano.npy beside it
    template = root / "meta" / "object_vtemplates" / "box"
    template.mkdir(parents=True)
    for name in ("mesh.obj", "parts.json", "mesh_tex.obj", "object_params.json"):
        (template / name).write_text("x\n")
    (root / "meta" / "misc.json").write_text("{}\n")
    (root / "images" / "s01").mkdir(parents=True)
    (root / "images" / "s01" / "00001.jpg").write_bytes(b"x")
    return root


def test_discovery_of_an_arctic_layout_lists_its_sequences_and_companions(tmp_path):
    discovery = discover(_arctic_dataset(tmp_path))
    (entry,) = discovery.entries
    assert entry.id == "raw_seqs/s01/box_grab_01.mano.npy"
    assert entry.kind == "arctic"
    assert {k: entry.meta[k] for k in ("object", "action", "actor", "sequence")} == {
        "object": "box", "action": "grab", "actor": "s01", "sequence": "box_grab_01",
    }  # fmt: skip
    assert [(i.role, i.path) for i in entry.inputs] == [
        ("trajectory", "raw_seqs/s01/box_grab_01.mano.npy"),
        ("trajectory", "raw_seqs/s01/box_grab_01.object.npy"),
        ("object", "meta/object_vtemplates/box/mesh.obj"),
        ("object", "meta/object_vtemplates/box/parts.json"),
    ]
    companions = {c.path: c.reason for c in discovery.companions}
    assert set(companions) == {
        "images/", "meta/misc.json", "meta/object_vtemplates/box/mesh_tex.obj",
        "meta/object_vtemplates/box/object_params.json", "raw_seqs/s01/box_grab_01.egocam.dist.npy",
        "raw_seqs/s01/box_grab_01.smplx.npy",
    }  # fmt: skip
    assert [u.path for u in discovery.unknown] == ["raw_seqs/s01/ketchup_use_02.object.npy"]


def test_an_arctic_trial_without_mano_files_records_which_files_it_needs(tmp_path, monkeypatch):
    monkeypatch.delenv(MANO_DIR_ENV, raising=False)
    discovery = discover(_arctic_dataset(tmp_path / "arctic"))
    summary = run_dataset(discovery, tmp_path / "out", workers=1, progress=False)
    assert (summary.failed, summary.ok) == (1, 0) and summary.all_failed
    (record,) = read_records(tmp_path / "out")
    assert record["status"] == "error" and record["error"]["type"] == "InputFileError"
    message = record["error"]["message"]
    assert message.startswith(f"no MANO folder given and {MANO_DIR_ENV} is not set")
    assert "MANO_RIGHT.pkl and MANO_LEFT.pkl" in message and "--mano-dir DIR" in message
