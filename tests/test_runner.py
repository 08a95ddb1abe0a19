"""Dataset runs: finger groups, PNG frames, records files, execution without the shared data (in-process and
pool), resume. Discovery: tests/test_dataset_discovery.py; the real sample data and the command:
tests/test_runner_real_data.py."""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import re
import struct
import zlib

import numpy as np
import pytest

from handsim.assets import TZIONAS_DIR
from handsim.datatypes.fingers import FINGER_GROUPS, TZIONAS_FINGERS, finger_groups, finger_of
from handsim.io import read_skeleton
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
from handsim.runner.worker import TrialOutcome, base_record, run_parameters, run_trial
from handsim.sim.replay import ReplayConfig
from handsim.trials import discover
from tests.runner_fixtures import CONFIG, check_renders, dataset_in, tzionas_copies, without_timing

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
    discovery = discover(tzionas_copies(tmp_path / "data", [20, 21]))
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
    discovery = discover(tzionas_copies(tmp_path / "data", [20]))
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
    discovery = discover(tzionas_copies(tmp_path / "data", [20, 21, 22]))
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
    assert without_timing(read_records(tmp_path / "out")) == without_timing(read_records(tmp_path / "ref"))
    for record in read_records(tmp_path / "out"):
        check_renders(record, tmp_path / "out", 1)


def test_a_failing_trial_records_its_error_and_the_others_run(tmp_path):
    data = tzionas_copies(tmp_path / "data", [20])
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


def test_the_same_dataset_in_two_folders_gives_byte_identical_records(tmp_path):
    config = ReplayConfig(control_rate=50.0)
    files = []
    for name in ("here", "elsewhere/deeper"):
        data = dataset_in(tmp_path / name / "data")
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
    data = tzionas_copies(tmp_path / "data", [20])
    (entry,) = discover(data).entries
    record = portable_record({"trial": entry.trial.to_dict()}, str(data))
    assert record["trial"]["skeleton_path"] == "Models/20/Model_Hand_R.SKEL"
    notes = ("hand Model_Hand_R.SKEL and objects ['cube'] from Configs/20/MODELS_INFO.txt",)  # text: relative
    assert record_trial(record, data) == dataclasses.replace(entry.trial, notes=notes)
    catalogue = portable_record({"trial": {**entry.trial.to_dict(), "objects": [{"what": "mug"}]}}, str(data))
    assert record_trial(catalogue, data).objects[0].what == "mug"  # a catalogue name, not a file in the root


def test_a_run_of_trial_entries_finds_their_dataset_root(tmp_path):
    data = tzionas_copies(tmp_path / "data", [20, 21])
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
    discovery = discover(tzionas_copies(tmp_path / "data", [20, 21, 22, 23]))
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
    check_renders(record, tmp_path, 2)
    if record["renders"]:
        frames = [r["frame"] for r in record["renders"]]
        touching = [
            sum(v[f] for v in record["curves"]["contacts_per_finger"].values())
            for f in range(record["summary"]["frames"])
        ]
        assert record["curves"]["stride"] == 1 and len(touching) == record["summary"]["frames"]
        assert frames == sorted(frames) and touching.index(max(touching)) in frames
    assert "stability tests not run" not in " ".join(record["notes"])  # no stability asked
