"""The same recording under several names or folders is one trial: later copies are listed, not replayed.

Two trials are the same when their replays would be: the kind, every input file's bytes role by role, and
the settings (episode, hand, objects by catalogue name or by their files' bytes). A GraspDB14 recording
names its object in its file name, so the same bytes under another object's name are another trial.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.report.files import group_files
from handsim.trials import discover
from handsim.trials import discovery as discovery_module
from tests.text_samples import glove_rows
from tests.tzionas_fixtures import shifted_motion

SCRIPTED = ASSETS_DIR / "demo" / "tennis_ball.grasp.json"


def _copy_reason(first: str) -> str:
    return f"same content as {first}: replayed once"


def _scripted_copies(folder: Path, names: list[str]) -> None:
    """The bundled tennis-ball scripted grasp (one grasp episode, ``#1``) under each name."""
    for name in names:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(SCRIPTED, folder / name)


def test_the_same_recording_under_three_names_is_one_trial_and_two_copies(tmp_path):
    _scripted_copies(tmp_path, ["a.grasp.json", "b.grasp.json", "c.grasp.json"])
    discovery = discover(tmp_path)
    assert [e.id for e in discovery.entries] == ["a.grasp.json#1"]
    expected = [(f"{n}.grasp.json#1", _copy_reason("a.grasp.json#1")) for n in ("b", "c")]
    assert [(c.path, c.reason) for c in discovery.companions] == expected
    assert [(c.path, c.reason) for c in discovery.copies] == expected
    assert discovery.to_dict()["trials"] == 1
    assert [(c["path"], c["reason"]) for c in discovery.to_dict()["companion"]] == expected


def test_the_first_copy_in_id_order_is_the_trial(tmp_path):
    _scripted_copies(tmp_path, ["z.grasp.json", "m/a.grasp.json"])
    discovery = discover(tmp_path)
    assert [e.id for e in discovery.entries] == ["m/a.grasp.json#1"]
    assert [(c.path, c.reason) for c in discovery.copies] == [
        ("z.grasp.json#1", _copy_reason("m/a.grasp.json#1"))
    ]


def test_a_link_to_a_recording_under_another_name_is_the_same_trial(tmp_path):
    _scripted_copies(tmp_path, ["a.grasp.json"])
    (tmp_path / "b.grasp.json").symlink_to(tmp_path / "a.grasp.json")
    discovery = discover(tmp_path)
    assert [e.id for e in discovery.entries] == ["a.grasp.json#1"]
    assert [(c.path, c.reason) for c in discovery.companions] == [
        ("b.grasp.json#1", _copy_reason("a.grasp.json#1"))
    ]


def test_the_same_glove_bytes_named_for_another_object_are_two_trials(tmp_path):
    rows = glove_rows(6)
    names = [
        "01_ex01-rad-002-grasp-su01.txt",
        "01_ex01-rad-003-grasp-su02.txt",
        "04_ex01-rad-002-grasp-su01.txt",
    ]
    for name in names:
        (tmp_path / name).write_text(rows)
    discovery = discover(tmp_path)
    objects = {e.id: e.trial.objects[0].what for e in discovery.entries}
    assert objects == {names[0]: "tennis_ball", names[2]: "mug"}  # the tennis ball's copy is not replayed
    assert [(c.path, c.reason) for c in discovery.companions] == [(names[1], _copy_reason(names[0]))]


def test_a_copied_tzionas_sequence_is_one_trial_and_an_edited_one_two(tmp_path):
    root = tmp_path / "tzionas"
    shutil.copytree(TZIONAS_DIR, root)
    for sequence in ("21", "22"):
        shutil.copytree(root / "Models" / "20", root / "Models" / sequence)
        shutil.copytree(root / "Configs" / "20", root / "Configs" / sequence)
    motion = root / "Models" / "22" / "Model_Hand_R.MOTION"
    motion.write_text(shifted_motion(motion.read_text(), (0.0, 0.0, 1e-3)))  # the hand moved 1 µm
    discovery = discover(root)
    assert [e.id for e in discovery.entries] == ["Models/20", "Models/22"]
    assert [(c.path, c.reason) for c in discovery.copies] == [("Models/21", _copy_reason("Models/20"))]


def test_a_tzionas_copy_whose_object_differs_is_another_trial(tmp_path):
    root = tmp_path / "tzionas"
    shutil.copytree(TZIONAS_DIR, root)
    shutil.copytree(root / "Models" / "20", root / "Models" / "21")
    shutil.copytree(root / "Configs" / "20", root / "Configs" / "21")
    cube = root / "Models" / "21" / "Model_Object_Cube.MOTION"
    cube.write_text(shifted_motion(cube.read_text(), (0.0, 0.0, 1e-3)))  # same hand, the cube moved 1 µm
    discovery = discover(root)
    assert [e.id for e in discovery.entries] == ["Models/20", "Models/21"]
    assert discovery.copies == ()


def test_the_report_lists_the_copies_of_a_trial_as_one_group_naming_it(tmp_path):
    _scripted_copies(tmp_path, ["a.grasp.json", "b.grasp.json", "c.grasp.json"])
    (group,) = group_files(discover(tmp_path).to_dict()["companion"])
    assert group.what() == "./ (2 files: b.grasp.json#1, c.grasp.json#1)"
    assert group.reason == _copy_reason("a.grasp.json#1")


def test_recordings_of_other_sizes_are_never_read_for_their_hash(tmp_path, monkeypatch):
    def unread(path, digests):
        pytest.fail(f"{path} was hashed although no other trial's inputs have its sizes")

    monkeypatch.setattr(discovery_module, "_sha256", unread)
    (tmp_path / "01_ex01-rad-002-grasp-su01.txt").write_text(glove_rows(6))
    (tmp_path / "01_ex01-rad-003-grasp-su01.txt").write_text(glove_rows(7))
    assert len(discover(tmp_path).entries) == 2
