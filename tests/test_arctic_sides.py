"""Swapped ARCTIC hands are a flag in every output, and two-hand contacts are counted per hand and finger.

The sequence: each hand closes around a ball of its own (``tests/test_arctic_hands.py::ball_grasp``), stored
with the left hand's data under ``right`` and the right hand's under ``left``, in an ARCTIC root whose object
template (``meta/object_vtemplates/balls/``, not one of ARCTIC's objects) is the two balls in millimetres.
``handsim inspect``, ``handsim replay`` (exit code, printed flags, ``--json``), the records and the
Markdown/HTML report must all carry the ``hands_swapped`` flag; the same sequence stored correctly none.
"""

from __future__ import annotations

import json
import re
from dataclasses import replace

import numpy as np
import pytest
import trimesh

from handsim.cli import main
from handsim.datatypes.fingers import FINGER_GROUPS, finger_groups, finger_of, hand_of
from handsim.datatypes.flags import Flag
from handsim.datatypes.trajectory import Trajectory
from handsim.datatypes.trajectory_ops import join_hands
from handsim.io.arctic.mano import MANO_DIR_ENV, MANO_JOINT_NAMES
from handsim.io.arctic.sequence import HANDS
from handsim.runner.records import read_records
from handsim.runner.trial_record import curves
from handsim.sim.replay import replay
from handsim.trials import load_trial
from tests.arctic_fixtures import write_obj
from tests.mano_fixtures import write_synthetic_mano_pkl
from tests.test_arctic_hands import ball_grasp

SEQUENCE = "raw_seqs/s01/balls_grab_00.mano.npy"
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def mano(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mano_models")
    arrays = {
        side: write_synthetic_mano_pkl(folder / f"MANO_{side.upper()}.pkl", side=side) for side in HANDS
    }
    return folder, arrays


def _root(folder, arrays, *, swap):
    """An ARCTIC root holding the ball grasp (seed 0) as ``s01/balls_grab_00`` and its two-ball template."""
    raw = folder / "raw_seqs" / "s01"
    raw.mkdir(parents=True)
    _, obj = ball_grasp(raw, arrays, 0, swap=swap)
    template = folder / "meta" / "object_vtemplates" / "balls"
    template.mkdir(parents=True)
    for part in obj.parts:  # ARCTIC's templates are in millimetres
        write_obj(
            template / f"{part.name}.obj", trimesh.Trimesh(part.mesh.vertices * 1000.0, part.mesh.faces)
        )
    return folder


@pytest.fixture(scope="module")
def swapped(mano, tmp_path_factory):
    return _root(tmp_path_factory.mktemp("swapped"), mano[1], swap=True)


@pytest.fixture(scope="module")
def stored(mano, tmp_path_factory):
    return _root(tmp_path_factory.mktemp("stored"), mano[1], swap=False)


@pytest.fixture(scope="module")
def report(mano, swapped, tmp_path_factory):
    """``handsim report`` of the swapped root: its exit code and output folder."""
    out = tmp_path_factory.mktemp("report") / "out"
    args = [
        "report",
        str(swapped),
        "-o",
        str(out),
        "--mano-dir",
        str(mano[0]),
        "--workers",
        "1",
        "--frames",
        "0",
    ]
    return main(args), out


SWAPPED = re.compile(
    r"^flag       hands_swapped: (?P<path>\S+): 'right' and 'left' look swapped \(heuristic\): each hand "
    r"touches the balls only when driving the other hand's model: .*; "
    r"check the file's 'right'/'left' entries$"
)


# --------------------------------------------------------------------------------------------------
# handsim inspect


def test_inspect_shows_swapped_hands_as_the_replays_flag(mano, swapped, capsys):
    path = swapped / SEQUENCE
    assert main(["inspect", str(path), "--mano-dir", str(mano[0])]) == 0
    lines = capsys.readouterr().out.splitlines()
    (flag,) = [line for line in lines if line.startswith("flag ")]
    assert SWAPPED.match(flag)["path"] == str(path)
    assert not any(line.startswith("sides ") for line in lines)


def test_inspect_shows_hands_as_stored_without_a_flag(mano, stored, capsys):
    path = stored / SEQUENCE
    assert main(["inspect", str(path), "--mano-dir", str(mano[0])]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1].startswith(
        f"sides      {path}: the hands are as stored (heuristic): 'right' driving the "
    )
    assert not any(line.startswith("flag ") for line in lines)


def test_inspect_without_the_mano_files_says_the_sides_were_not_checked(
    swapped, capsys, monkeypatch, tmp_path
):
    monkeypatch.delenv(MANO_DIR_ENV, raising=False)
    path = swapped / SEQUENCE
    assert main(["inspect", str(path)]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == (
        "sides      not checked: the side check drives both MANO models (--mano-dir DIR with your "
        "MANO_RIGHT.pkl and MANO_LEFT.pkl, or HANDSIM_MANO_DIR)"
    )
    assert main(["inspect", str(path), "--mano-dir", str(tmp_path)]) == 0
    last = capsys.readouterr().out.splitlines()[-1]
    assert last.startswith(
        f"sides      not checked: {tmp_path}: MANO_RIGHT.pkl and MANO_LEFT.pkl not found there"
    )


def test_inspect_refuses_the_arctic_options_for_other_recordings(tmp_path):
    with pytest.raises(SystemExit) as exc:
        main(["inspect", str(tmp_path / "trial.txt"), "--mano-dir", str(tmp_path)])
    assert str(exc.value) == "handsim inspect: --mano-dir apply to ARCTIC sequences (<seq>.mano.npy) only"


# --------------------------------------------------------------------------------------------------
# handsim replay and the trial


def test_replay_of_swapped_hands_is_flagged_not_valid_and_exits_4(mano, swapped, capsys, tmp_path):
    path = swapped / SEQUENCE
    out = tmp_path / "result.json"
    assert main(["replay", str(path), "--mano-dir", str(mano[0]), "--json", str(out)]) == 4
    lines = capsys.readouterr().out.splitlines()
    assert "valid       no (hands_swapped): the numbers below judge nothing" in lines
    (flag,) = [line for line in lines if line.startswith("flag        hands_swapped")]
    assert SWAPPED.match(flag.replace("flag        ", "flag       ", 1))
    record = json.loads(out.read_text())
    (swap,) = [f for f in record["flags"] if f["code"] == "hands_swapped"]
    assert swap["invalid"] is True and swap["values"]["verdict"] == "swapped"
    assert swap["values"]["right"]["own_fraction"] == 0.0 and swap["values"]["right"]["other_fraction"] > 0.05
    assert record["summary"]["valid"] is False


def test_trial_of_hands_as_stored_has_no_flag_and_notes_the_verdict(mano, stored):
    loaded = load_trial(stored / SEQUENCE, mano_dir=mano[0])
    assert loaded.trajectory.flags == ()
    assert any(": the hands are as stored (heuristic): " in note for note in loaded.notes)


def test_trial_of_swapped_hands_carries_the_flag_in_its_trajectory(mano, swapped):
    loaded = load_trial(swapped / SEQUENCE, mano_dir=mano[0])
    assert [f.code for f in loaded.trajectory.flags] == ["hands_swapped"]
    assert not any("look swapped" in note for note in loaded.notes)  # a flag, not a note beside it


def test_joined_hands_keep_each_hands_flags_once():
    flag = Flag("hands_swapped", True, "swapped", {"verdict": "swapped"})
    note = Flag("other", False, "a note")
    hand = Trajectory(
        np.arange(3) / 30.0,
        ("a",),
        np.zeros((3, 1)),
        np.ones((3, 1), bool),
        root_pose=np.tile(IDENTITY, (3, 1)),
    )
    joined = join_hands({"right": replace(hand, flags=(flag,)), "left": replace(hand, flags=(flag, note))})
    assert joined.flags == (flag, note)


# --------------------------------------------------------------------------------------------------
# Records and report


def test_report_records_and_shows_the_swapped_flag(report):
    code, out = report
    assert code == 0
    (record,) = read_records(out)
    assert record["status"] == "ok", record.get("error")
    assert [f["code"] for f in record["flags"] if f["invalid"]] == ["hands_swapped"]
    assert record["summary"]["valid"] is False
    markdown = (out / "report.md").read_text()
    assert "1 flagged not valid" in markdown
    worst = next(line for line in markdown.splitlines() if line.startswith("1. [raw_seqs/s01/balls_grab_00"))
    assert "**flagged** — not valid: " in worst and "'right' and 'left' look swapped (heuristic)" in worst
    html = (out / "report.html").read_text()
    assert "<li><strong>hands_swapped</strong> (not valid): " in html


def test_two_hand_contacts_are_counted_per_hand_and_finger_in_the_records(mano, stored, report):
    result = replay(*(lambda t: (t.scene, t.trajectory))(load_trial(stored / SEQUENCE, mano_dir=mano[0])))
    per_finger = curves(result)["contacts_per_finger"]  # the record's curve: fingers touch
    assert list(per_finger) == [f"{hand}/{g}" for hand in HANDS for g in FINGER_GROUPS]
    assert sum(max(values) for key, values in per_finger.items() if not key.endswith("/palm")) > 0
    _, out = report
    (record,) = read_records(out)
    assert list(record["curves"]["contacts_per_finger"]) == list(per_finger)
    html = (out / "report.html").read_text()
    assert "Contacts per finger (stacked), right hand" in html
    assert "Contacts per finger (stacked), left hand" in html


def test_every_mano_finger_link_of_a_two_hand_scene_is_in_its_hand_and_finger(mano, stored):
    loaded = load_trial(stored / SEQUENCE, mano_dir=mano[0])
    links = loaded.scene.layout.link_names
    groups = finger_groups(links)
    fingers = {"thumb": "thumb", "index": "index", "middle": "middle", "ring": "ring", "pinky": "little"}
    checked = 0
    for i, link in enumerate(links):
        hand, bare = hand_of(link), link.partition("/")[2]
        assert hand in HANDS
        if bare in MANO_JOINT_NAMES[1:]:  # a phalanx: <finger><1-3>
            finger = fingers[bare.rstrip("123")]
            assert finger_of(link) == finger and i in groups[f"{hand}/{finger}"]
            checked += 1
    assert checked == 2 * 15
