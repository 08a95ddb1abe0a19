"""Dataset runs: discovery, file names, finger groups, records, execution (in-process, pool, Ray), resume."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import multiprocessing
import os
import re
import secrets
import shutil
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

from handsim.assets import TZIONAS_DIR
from handsim.cli import main
from handsim.datatypes.fingers import FINGER_GROUPS, TZIONAS_FINGERS, finger_groups, finger_of
from handsim.io import read_skeleton
from handsim.io.arctic.mano import MANO_DIR_ENV
from handsim.io.graspdb.filenames import parse_graspdb_filename
from handsim.runner import execute
from handsim.runner.execute import RunnerError, run_dataset
from handsim.runner.png import encode_png
from handsim.runner.portable import dataset_root, portable_record, record_trial
from handsim.runner.records import (
    RECORDS_FILE,
    RecordsError,
    RecordWriter,
    load_records,
    read_records,
    repair_records,
)
from handsim.runner.renders import headless_glfw
from handsim.runner.worker import TrialOutcome, base_record, run_parameters, run_trial
from handsim.sim.replay import ReplayConfig
from handsim.trials import discover, select
from handsim.trials.graspdb_names import GRASP_TYPES, graspdb_meta
from tests.conftest import SHARED_DATA
from tests.mano_fixtures import (
    arctic_object_values,
    mano_hand_params,
    write_arctic_mano_npy,
    write_arctic_object_npy,
)
from tests.processes import ROOT, child_env, ray_head

CONFIG = ReplayConfig(stability_at="grasp")
FRAMES = 4
RECORD_KEYS = [
    "schema", "id", "kind", "status", "meta", "trial", "inputs", "parameters", "metric_spec_version",
    "versions", "model_sha256", "scenario", "summary", "episode", "hold", "grip", "robustness",
    "release_stability", "stability", "warnings", "diverged", "flags", "notes",
    "trajectory_quality", "curves", "renders", "error", "timing",
]  # fmt: skip
GRASPDB_IDS = [  # each trial holds one grasp episode
    "graspdb14/01_ex01-rad-002-grasp-su01.txt#1",
    "graspdb14/04_ex01-rad-045-grasp-su03.txt#1",
    "graspdb14/r_01_11_ex03-rad-004-grasp-su04.txt#1",
]
SESSION = "graspdb14/sessions/01_11_ex03-rad-004-grasp-su04.txt"  # a whole glove session: 51 grasp episodes
SESSION_IDS = [f"{SESSION}#{k}" for k in range(1, 52)]
TZIONAS_ID = "tzionas_ijcv16/Models/20"
FAST_IDS = [GRASPDB_IDS[0], TZIONAS_ID]  # the two quickest to load (no long placement search)


def _without_timing(records: list[dict]) -> dict[str, dict]:
    return {r["id"]: {k: v for k, v in r.items() if k != "timing"} for r in records}


def _files(root: Path) -> set[str]:
    return {p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()}


def _accounted(discovery) -> set[str]:
    inputs = {i.path for e in discovery.entries for i in e.inputs}
    return inputs | {c.path for c in discovery.companions} | {u.path for u in discovery.unknown}


def _renders_in_this_process() -> bool:
    """True when this test process can render offscreen (MuJoCo took EGL/OSMesa, or there is a display).

    MuJoCo picks its OpenGL backend when first imported; a test module importing ``mujoco`` before
    ``handsim`` (which selects EGL without a display) leaves the whole test process on GLFW.
    """
    return not headless_glfw()


def _check_renders(record: dict, out: Path, count: int) -> None:
    """The record has ``count`` frames whose files match their hashes, or (no OpenGL here) a note instead."""
    if not _renders_in_this_process():
        assert record["renders"] == []
        assert record["notes"][-1].startswith(
            "frames not rendered: HandsimError: MuJoCo was imported with its GLFW"
        )
        return
    assert len(record["renders"]) == count
    for render in record["renders"]:
        assert hashlib.sha256((out / render["path"]).read_bytes()).hexdigest() == render["sha256"]


def _tzionas_copies(root: Path, sequences: list[int]) -> Path:
    """A Tzionas dataset whose sequences are copies of the bundled sequence 20."""
    for n in sequences:
        shutil.copytree(TZIONAS_DIR / "Models" / "20", root / "Models" / str(n))
        shutil.copytree(TZIONAS_DIR / "Configs" / "20", root / "Configs" / str(n))
    return root


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
# Finger groups


@pytest.mark.parametrize(
    ("link", "finger"),
    [
        ("th_tmc", "thumb"), ("if_mcp", "index"), ("mf_dip", "middle"), ("rf_pip", "ring"),
        ("lf_mcp", "little"), ("root", "palm"), ("thumb1", "thumb"), ("pinky3", "little"),
        ("index0", "palm"), ("wrist", "palm"),
        ("RFing_4_Hand", "thumb"), ("RFing_3_0", "index"), ("RFing_2_2", "middle"), ("RFing_1_1", "ring"),
        ("RFing_0_2", "little"), ("Lower_Arm_R", "palm"), ("lf", "palm"),
    ],
)  # fmt: skip
def test_finger_of_a_link_name(link, finger):
    assert finger_of(link) == finger


def test_tzionas_finger_indices_follow_the_sample_hands_geometry():
    skeleton = read_skeleton(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.SKEL")
    pos = {j.name: j.position for j in skeleton.joints}
    chains = {
        i: sorted(n for n in pos if n.startswith(f"RFing.{i}_") and not n.endswith("_tip")) for i in range(5)
    }
    thumb = min(chains, key=lambda i: len(chains[i]))  # the thumb has two phalanges, the fingers three
    assert len(chains[thumb]) == 3 and all(len(c) == 4 for i, c in chains.items() if i != thumb)

    def reach(i: int) -> float:  # knuckle (first phalanx) to fingertip
        tip = next(n for n in pos if n.startswith(f"RFing.{i}_") and n.endswith("_tip"))
        return float(np.linalg.norm(pos[tip] - pos[f"RFing.{i}_0"]))

    fingers = [i for i in range(5) if i != thumb]
    index = min(fingers, key=lambda i: np.linalg.norm(pos[f"RFing.{i}_0"] - pos[f"RFing.{thumb}_0"]))
    middle, little = max(fingers, key=reach), min(fingers, key=reach)
    (ring,) = set(fingers) - {index, middle, little}
    found = {thumb: "thumb", index: "index", middle: "middle", ring: "ring", little: "little"}
    assert found == TZIONAS_FINGERS


def test_finger_groups_list_every_group_in_record_order():
    groups = finger_groups(["root", "th_mcp", "if_mcp", "if_pip", "lf_dip"])
    assert list(groups) == list(FINGER_GROUPS)
    assert groups == {"thumb": [1], "index": [2, 3], "middle": [], "ring": [], "little": [4], "palm": [0]}


# --------------------------------------------------------------------------------------------------
# PNG


def _decode_png(data: bytes) -> np.ndarray:
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks = 8, {}
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, payload = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        assert struct.unpack(">I", data[pos + 8 + length : pos + 12 + length])[0] == zlib.crc32(
            kind + payload
        )
        chunks[kind] = chunks.get(kind, b"") + payload
        pos += 12 + length
    width, height, depth, color, *_ = struct.unpack(">IIBBBBB", chunks[b"IHDR"])
    channels = {0: 1, 2: 3}[color]
    raw = np.frombuffer(zlib.decompress(chunks[b"IDAT"]), np.uint8).reshape(height, 1 + width * channels)
    assert depth == 8 and (raw[:, 0] == 1).all()  # Sub filter on every row
    rows = raw[:, 1:].astype(np.int64)
    for x in range(channels, rows.shape[1]):
        rows[:, x] = (rows[:, x] + rows[:, x - channels]) % 256
    return rows.astype(np.uint8).reshape(height, width, channels).squeeze()


@pytest.mark.parametrize("shape", [(7, 5, 3), (4, 9)])
def test_png_encoding_round_trips_and_is_reproducible(shape):
    image = np.random.default_rng(0).integers(0, 256, shape, dtype=np.uint8)
    data = encode_png(image)
    assert (_decode_png(data) == image).all()
    assert encode_png(image) == data


def test_png_encoding_raises_error_for_a_float_image():
    with pytest.raises(ValueError, match="expected uint8 pixels, got dtype float64"):
        encode_png(np.zeros((2, 2, 3)))


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


# --------------------------------------------------------------------------------------------------
# Records files


def _fake_record(trial_id: str, parameters: dict | None = None) -> dict:
    return {"schema": 1, "id": trial_id, "status": "ok", "parameters": parameters or {}}


def test_a_truncated_last_line_is_ignored_and_cut_off_before_appending(tmp_path):
    with RecordWriter(tmp_path) as writer:
        writer.append(_fake_record("a"))
        writer.append(_fake_record("b"))
    path = tmp_path / RECORDS_FILE
    whole = path.read_bytes()
    path.write_bytes(whole + b'{"schema":1,"id":"c","sta')
    assert [r["id"] for r in read_records(tmp_path)] == ["a", "b"]
    read = load_records(tmp_path)
    assert read.notes == (
        f"{path}: the last line (25 bytes, no newline) is truncated and ignored (a killed run)",
    )
    notes = repair_records(tmp_path)
    assert notes[-1] == f"{path}: removed 25 bytes of an incomplete line"
    assert path.read_bytes() == whole
    with RecordWriter(tmp_path) as writer:
        writer.append(_fake_record("c"))
    assert [r["id"] for r in read_records(tmp_path)] == ["a", "b", "c"]


def test_a_malformed_line_before_the_last_raises_error_naming_the_line(tmp_path):
    (tmp_path / RECORDS_FILE).write_text('{"schema":1,"id":"a"}\nnot json\n{"schema":1,"id":"b"}\n')
    with pytest.raises(RecordsError, match=r"records.jsonl:2: not a JSON record"):
        read_records(tmp_path)


def test_a_record_of_another_schema_raises_error(tmp_path):
    (tmp_path / RECORDS_FILE).write_text('{"schema":2,"id":"a"}\n{"schema":1,"id":"b"}\n')
    with pytest.raises(
        RecordsError, match=r"records.jsonl:1: field 'schema' is 2; this handsim reads schema 1"
    ):
        read_records(tmp_path)


def test_a_resumed_run_cuts_a_truncated_line_and_runs_nothing_already_recorded(tmp_path, monkeypatch):
    discovery = discover(_tzionas_copies(tmp_path / "data", [20, 21]))
    parameters = run_parameters(CONFIG, 0)
    with RecordWriter(tmp_path / "out") as writer:
        for entry in discovery.entries:
            writer.append(_fake_record(entry.id, parameters))
    with open(tmp_path / "out" / RECORDS_FILE, "ab") as f:
        f.write(b'{"schema":1,"id":"Mod')
    monkeypatch.setattr(execute, "trial_outcome", lambda *a: pytest.fail("a recorded trial ran again"))
    summary = run_dataset(discovery, tmp_path / "out", workers=1, frames=0, config=CONFIG, progress=False)
    assert summary.ran == () and summary.skipped == 2
    assert summary.notes[-1].endswith("removed 21 bytes of an incomplete line")
    assert (tmp_path / "out" / RECORDS_FILE).read_bytes().endswith(b"}\n")


def test_a_run_into_records_of_other_parameters_raises_error(tmp_path):
    discovery = discover(_tzionas_copies(tmp_path / "data", [20]))
    with RecordWriter(tmp_path / "out") as writer:
        writer.append(_fake_record("Models/20", run_parameters(CONFIG, 4)))
    with pytest.raises(RunnerError, match=r"render_frames: 4 there, 2 now\)\. Resume with the same options"):
        run_dataset(discovery, tmp_path / "out", workers=1, frames=2, config=CONFIG, progress=False)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"backend": "dask"}, r"unknown backend 'dask'; expected one of \['local', 'ray'\]"),
        ({"workers": 0}, "workers must be ≥ 1, got 0"),
        ({"frames": -1}, "frames must be ≥ 0, got -1"),
    ],
)
def test_run_dataset_raises_error_for_a_bad_option(tmp_path, options, message):
    with pytest.raises(RunnerError, match=message):
        run_dataset([], tmp_path, progress=False, **options)


# --------------------------------------------------------------------------------------------------
# Execution without the shared data (copies of the bundled Tzionas sequence)


@pytest.mark.slow
def test_resume_after_an_interrupt_equals_an_uninterrupted_run_and_runs_no_trial_twice(tmp_path, monkeypatch):
    discovery = discover(_tzionas_copies(tmp_path / "data", [20, 21, 22]))
    config = ReplayConfig(control_rate=50.0)
    reference = run_dataset(discovery, tmp_path / "ref", workers=1, frames=1, config=config, progress=False)
    assert reference.ok == 3

    calls: list[str] = []
    real = execute.trial_outcome

    def counted(entry, *args):
        calls.append(entry.id)
        return real(entry, *args)

    def stop_after_one(record: dict) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(execute, "trial_outcome", counted)
    with pytest.raises(KeyboardInterrupt):
        run_dataset(
            discovery, tmp_path / "out", workers=1, frames=1, config=config, progress=False,
            on_record=stop_after_one,
        )  # fmt: skip
    assert [r["id"] for r in read_records(tmp_path / "out")] == ["Models/20"]
    resumed = run_dataset(discovery, tmp_path / "out", workers=1, frames=1, config=config, progress=False)
    assert sorted(calls) == ["Models/20", "Models/21", "Models/22"]
    assert (resumed.skipped, resumed.ran) == (1, ("Models/21", "Models/22"))
    assert _without_timing(read_records(tmp_path / "out")) == _without_timing(read_records(tmp_path / "ref"))
    for record in read_records(tmp_path / "out"):
        _check_renders(record, tmp_path / "out", 1)


def test_a_failing_trial_records_its_error_and_the_others_run(tmp_path):
    data = _tzionas_copies(tmp_path / "data", [20])
    bad = data / "01_ex01-rad-002-grasp-su01.txt"
    bad.write_text("2014 09 12 08 49 21.71200 1 0.1 garbage\n")
    summary = run_dataset(discover(data), tmp_path / "out", workers=1, frames=0, progress=False)
    assert (summary.ok, summary.failed) == (1, 1)
    records = {r["id"]: r for r in read_records(tmp_path / "out")}
    error = records["01_ex01-rad-002-grasp-su01.txt"]["error"]
    assert error["type"] == "FormatError"
    assert error["message"] == (
        "01_ex01-rad-002-grasp-su01.txt:1: expected 30 blank-separated entries (6 time-stamp fields, switch, "
        "23 sensors), got 9"
    )  # the file relative to the dataset root
    assert "Traceback (most recent call last)" in error["traceback"]
    assert '  File "handsim/runner/worker.py", line ' in error["traceback"]  # not where handsim is installed
    failed = records["01_ex01-rad-002-grasp-su01.txt"]
    assert (failed["status"], failed["summary"], failed["curves"], failed["renders"]) == (
        "error",
        None,
        None,
        [],
    )
    assert records["Models/20"]["status"] == "ok"


def _dataset_in(folder: Path) -> Path:
    """A small dataset (bundled Tzionas sequence 20, a malformed glove recording) copied into ``folder``."""
    data = _tzionas_copies(folder, [20])
    (data / "01_ex01-rad-002-grasp-su01.txt").write_text("2014 09 12 08 49 21.71200 1 0.1 garbage\n")
    return data


def test_the_same_dataset_in_two_folders_gives_byte_identical_records(tmp_path):
    config = ReplayConfig(control_rate=50.0)
    files = []
    for name in ("here", "elsewhere/deeper"):
        data = _dataset_in(tmp_path / name / "data")
        summary = run_dataset(discover(data), tmp_path / name / "out", workers=1, frames=0, config=config,
                              progress=False)  # fmt: skip
        assert (summary.ok, summary.failed) == (1, 1)
        files.append((tmp_path / name / "out" / RECORDS_FILE).read_bytes())
    assert str(tmp_path).encode() not in files[0]
    without_timing = [re.sub(rb',"timing":\{[^}]*\}', b"", f) for f in files]
    assert without_timing[0] == without_timing[1] and without_timing[0].count(b"\n") == 2
    record = {r["id"]: r for r in read_records(tmp_path / "here" / "out")}["Models/20"]
    assert record["trial"]["trajectory_path"] == "Models/20/Model_Hand_R.MOTION"
    assert record["trial"]["objects"][0]["what"] == "Models/20/Model_Object_Cube.SKEL"
    assert record["notes"][0] == "hand Model_Hand_R.SKEL and objects ['cube'] from Configs/20/MODELS_INFO.txt"


def test_record_trial_joins_a_records_relative_paths_to_the_dataset_root(tmp_path):
    data = _tzionas_copies(tmp_path / "data", [20])
    (entry,) = discover(data).entries
    record = portable_record({"trial": entry.trial.to_dict()}, str(data))
    assert record["trial"]["skeleton_path"] == "Models/20/Model_Hand_R.SKEL"
    notes = ("hand Model_Hand_R.SKEL and objects ['cube'] from Configs/20/MODELS_INFO.txt",)  # text: relative
    assert record_trial(record, data) == dataclasses.replace(entry.trial, notes=notes)
    catalogue = portable_record({"trial": {**entry.trial.to_dict(), "objects": [{"what": "mug"}]}}, str(data))
    assert record_trial(catalogue, data).objects[0].what == "mug"  # a catalogue name, not a file in the root


def test_a_run_of_trial_entries_finds_their_dataset_root(tmp_path):
    data = _tzionas_copies(tmp_path / "data", [20, 21])
    discovery = discover(data)
    assert dataset_root(discovery.entries) == discovery.root == str(data)
    assert dataset_root([]) is None


def _crashing_outcome(entry, config, frames):
    """Module-level (importable by spawned workers): sequence 21 kills its worker, others finish at once."""
    if entry.id == "Models/21":
        os._exit(3)
    record = base_record(entry, config, frames)
    record.update(status="ok", timing={})
    return TrialOutcome(record)


def test_a_trial_that_kills_its_worker_is_recorded_and_the_others_finish(tmp_path, monkeypatch):
    discovery = discover(_tzionas_copies(tmp_path / "data", [20, 21, 22, 23]))
    monkeypatch.setattr(execute, "trial_outcome", _crashing_outcome)
    summary = run_dataset(discovery, tmp_path / "out", workers=2, frames=0, progress=False)
    records = {r["id"]: r for r in read_records(tmp_path / "out")}
    assert sorted(records) == ["Models/20", "Models/21", "Models/22", "Models/23"]
    assert records["Models/21"]["error"]["type"] == "WorkerCrashed"
    assert "died while running it alone" in records["Models/21"]["error"]["message"]
    assert (summary.ok, summary.failed) == (3, 1)
    assert multiprocessing.active_children() == []


def test_run_trial_writes_its_frames_and_returns_the_record(tmp_path):
    (entry,) = discover(TZIONAS_DIR).entries
    record = run_trial(entry, ReplayConfig(control_rate=50.0), tmp_path, frames=2)
    _check_renders(record, tmp_path, 2)
    if record["renders"]:
        frames = [r["frame"] for r in record["renders"]]
        touching = [
            sum(v[f] for v in record["curves"]["contacts_per_finger"].values())
            for f in range(record["summary"]["frames"])
        ]
        assert record["curves"]["stride"] == 1 and len(touching) == record["summary"]["frames"]
        assert frames == sorted(frames) and touching.index(max(touching)) in frames
    assert "stability tests not run" not in " ".join(record["notes"])  # no stability asked


# --------------------------------------------------------------------------------------------------
# The real sample data, run once in-process (GraspDB14 loading takes seconds: its placement search)


_REAL_RUN = """
import dataclasses, json, sys
from handsim.trials import discover
from handsim.runner.execute import run_dataset
from handsim.sim.replay import ReplayConfig
summary = run_dataset(
    discover(sys.argv[1]), sys.argv[2], workers=1, config=ReplayConfig(stability_at="grasp"),
    frames=int(sys.argv[3]), progress=False,
)
print(json.dumps(dataclasses.asdict(summary)))
"""


@pytest.fixture(scope="module")
def real_run(tmp_path_factory):
    """The sample data run once with workers=1, in a fresh interpreter.

    Fresh, because MuJoCo picks its OpenGL backend when first imported: a test module that imports
    ``mujoco`` before ``handsim`` leaves this process without offscreen rendering (its records would then
    carry a note instead of frames), while pool and Ray workers always start clean.
    """
    if not (SHARED_DATA / "graspdb14").exists() or not (SHARED_DATA / "tzionas_ijcv16").exists():
        pytest.skip(f"needs the real sample data in ../shared/data: {SHARED_DATA} is absent")
    out = tmp_path_factory.mktemp("real_run")
    done = subprocess.run(
        [sys.executable, "-c", _REAL_RUN, str(SHARED_DATA), str(out), str(FRAMES)],
        capture_output=True, text=True, check=False, cwd=Path(__file__).resolve().parents[1],
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    return discover(SHARED_DATA), out, summary, read_records(out)


@pytest.mark.slow
def test_the_real_data_run_records_every_trial(real_run):
    discovery, out, summary, records = real_run
    assert sorted(r["id"] for r in records) == sorted([*GRASPDB_IDS, *SESSION_IDS, TZIONAS_ID])
    assert [summary[k] for k in ("trials", "skipped", "failed", "hold_trials")] == [55, 0, 0, 29]
    assert [u.path for u in discovery.unknown] == ["mano/mano_right_mean_joints.json"]
    run = json.loads((out / "run.json").read_text())
    assert run["discovery"]["trials"] == 55 and run["parameters"] == run_parameters(CONFIG, FRAMES)
    for record in records:
        assert list(record) == RECORD_KEYS
        assert record["status"] in ("ok", "diverged") and record["error"] is None
        assert record["parameters"] == run_parameters(CONFIG, FRAMES)
        assert set(record["versions"]) == {"handsim", "mujoco", "numpy", "python", "platform"}
        assert len(record["model_sha256"]) == 64
        for item in record["inputs"]:
            assert item["sha256"] == hashlib.sha256((SHARED_DATA / item["path"]).read_bytes()).hexdigest()
        curves = record["curves"]
        n = len(curves["time_s"])
        assert n <= 600 and n == -(-record["summary"]["frames"] // curves["stride"])
        assert list(curves["contacts_per_finger"]) == list(FINGER_GROUPS)
        assert all(len(v) == n for v in curves["contacts_per_finger"].values())
        assert len(curves["penetration_mm"]) == len(curves["tracking_error_deg"]) == n
        frames = [r["frame"] for r in record["renders"]]
        assert frames[0] == 0 and frames[-1] == record["summary"]["frames"] - 1 and len(frames) <= FRAMES
        for render in record["renders"]:
            assert hashlib.sha256((out / render["path"]).read_bytes()).hexdigest() == render["sha256"]
        quality = record["trajectory_quality"]
        # the whole session has dropped samples (SOURCES.md); the single trials have none
        assert quality["limit_violations"] >= 0 and quality["gaps_filled"] == (
            (record["id"] in SESSION_IDS) * (record["trajectory_quality"]["gaps_filled"] > 0)
        )
    for record in records:  # no hold stands on a link deeper in the object than the grip's limit
        if record["summary"].get("held") is True:
            grip = record["grip"]
            assert grip["max_depth_mm"] <= grip["depth_limit_mm"] and grip["opposition"] >= 0.5
    by_id = {r["id"]: r for r in records}
    glove, recorded = by_id[GRASPDB_IDS[2]], by_id[TZIONAS_ID]
    assert glove["meta"]["grasp"] == "Power sphere" and glove["scenario"] == "glove"
    assert glove["curves"]["drift_mm"] is None and glove["stability"] is not None
    assert [i["role"] for i in glove["inputs"]] == ["trajectory", "annotation"]
    assert recorded["scenario"] == "recorded" and recorded["stability"] is None
    assert len(recorded["curves"]["drift_mm"]) == len(recorded["curves"]["time_s"])
    assert not any(n.startswith("stability tests") for n in recorded["notes"])  # no hold window by nature
    assert max(recorded["curves"]["contacts_per_finger"]["thumb"]) > 0  # the thumb pushes the cube


@pytest.mark.slow
def test_a_process_pool_gives_the_in_process_records_and_resumes_after_an_interrupt(real_run, tmp_path):
    discovery, _, _, records = real_run
    entries = tuple(e for e in discovery.entries if e.id in FAST_IDS)

    def stop(record: dict) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_dataset(
            entries, tmp_path, workers=2, config=CONFIG, frames=FRAMES, progress=False, on_record=stop
        )
    assert multiprocessing.active_children() == []  # the workers were stopped
    first = [r["id"] for r in read_records(tmp_path)]
    assert len(first) == 1
    resumed = run_dataset(entries, tmp_path, workers=2, config=CONFIG, frames=FRAMES, progress=False)
    assert sorted([*first, *resumed.ran]) == sorted(FAST_IDS)
    expected = {k: v for k, v in _without_timing(records).items() if k in FAST_IDS}
    assert _without_timing(read_records(tmp_path)) == expected


@pytest.fixture(scope="session")
def _ray_session_home(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The home of this session's Ray clusters, with the token of Ray's token authentication in it."""
    home = tmp_path_factory.mktemp("ray_home")
    token = home / ".ray" / "auth_token"
    token.parent.mkdir()
    token.write_text(secrets.token_hex(32))  # what `ray get-auth-token --generate` writes
    return home


@pytest.fixture
def ray_home(_ray_session_home: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A home of Ray's own for the test (its token in ``.ray/auth_token``), whatever ran before.

    Ray's token authentication (on by default for ``ray start`` and a local ``ray.init``) reads the token
    from ``~/.ray/auth_token`` (or ``RAY_AUTH_TOKEN_PATH``); ``ray start`` does not create one. Every Ray
    test of the session shares one home and one token (Ray caches the token it loaded once per process),
    and the user's home is never written. ``RAY_AUTH_MODE``, which a local ``ray.init`` sets in this
    process, is restored after the test.
    """
    monkeypatch.setenv("HOME", str(_ray_session_home))
    monkeypatch.setenv("RAY_AUTH_TOKEN_PATH", str(_ray_session_home / ".ray" / "auth_token"))
    monkeypatch.delenv("RAY_AUTH_TOKEN", raising=False)
    monkeypatch.delenv("RAY_AUTH_MODE", raising=False)
    return _ray_session_home


@pytest.mark.slow
def test_the_ray_backend_gives_bitwise_the_records_of_the_local_backend(real_run, tmp_path, ray_home):
    ray = pytest.importorskip("ray")
    discovery, _, _, records = real_run
    entries = tuple(e for e in discovery.entries if e.id in FAST_IDS)
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        summary = run_dataset(entries, tmp_path, backend="ray", config=CONFIG, frames=FRAMES, progress=False)
    finally:
        ray.shutdown()
    assert sorted(summary.ran) == sorted(FAST_IDS)
    expected = {k: v for k, v in _without_timing(records).items() if k in FAST_IDS}
    assert _without_timing(read_records(tmp_path)) == expected


# --------------------------------------------------------------------------------------------------
# The command


def test_handsim_report_runs_renders_and_re_renders(tmp_path, capsys):
    pytest.importorskip("handsim.report")
    data = _tzionas_copies(tmp_path / "data", [20])
    out = tmp_path / "out"
    assert main(["report", str(data), "-o", str(out), "--workers", "1", "--frames", "1", "--rate", "50"]) == 0
    printed = capsys.readouterr().out
    assert "1 trials: 1 ok, 0 diverged, 0 failed" in printed
    assert f"records     {out / 'records.jsonl'} (1 run now, 0 resumed)" in printed
    assert (out / "run.json").is_file() and len(read_records(out)) == 1
    assert main(["report", "--render-only", str(out)]) == 0
    assert "1 trials: 1 ok" in capsys.readouterr().out


@pytest.mark.slow
def test_handsim_report_runs_on_a_ray_cluster_given_its_address_and_leaves_it_running(
    tmp_path, capsys, ray_home
):
    pytest.importorskip("ray")
    data = _dataset_in(tmp_path / "data")
    options = ["--frames", "1", "--rate", "50"]
    assert main(["report", str(data), "-o", str(tmp_path / "ref"), "--workers", "1", *options]) == 0
    capsys.readouterr()
    env = {
        **child_env(),
        "RAY_AUTH_MODE": "token",
    }  # the cluster's token authentication (ray start's default)
    with ray_head(2, tmp_path / "ray.log") as (address, head):
        ray = ["--backend", "ray", "--address", address, *options]
        done = subprocess.run(
            [sys.executable, "-m", "handsim.cli", "report", str(data), "-o", str(tmp_path / "out"), *ray],
            capture_output=True, text=True, env=env, cwd=ROOT, check=False,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert head.poll() is None  # the cluster is the user's: still running
        tzionas = [e for e in discover(data).entries if e.id == "Models/20"]  # no address: a Ray of its own
        local = run_dataset(tzionas, tmp_path / "local", backend="ray", workers=1, frames=0, progress=False)
    assert "2 trials: 1 ok, 0 diverged, 1 failed" in done.stdout
    assert _without_timing(read_records(tmp_path / "out")) == _without_timing(read_records(tmp_path / "ref"))
    assert local.ran == ("Models/20",) and read_records(tmp_path / "local")[0]["status"] == "ok"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([], "give DATASET and -o OUT (or --render-only OUT)"),
        (["--only", "nothing*"], "no trial matching 'nothing*' in"),
        (["--render-only", "{tmp}/none"], "--render-only needs a run's folder with records.jsonl"),
    ],
)
def test_handsim_report_exits_2_on_a_usage_error(tmp_path, capsys, args, message):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    if args[:1] == ["--only"]:
        args = [str(TZIONAS_DIR), "-o", str(tmp_path / "out"), *args]
    assert main(["report", *args]) == 2
    assert message in capsys.readouterr().err
