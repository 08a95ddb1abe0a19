"""ARCTIC end to end (issue 13): two MANO hands and an articulated object replayed from ARCTIC's files.

A synthetic MANO pair (the real ``MANO_*.pkl`` structure) and a synthetic ARCTIC root in exactly the real
layout: ``raw_seqs/s01/<seq>.mano.npy`` (``fitting_err`` a plain list) + ``.object.npy`` (mm, z-up), and
``meta/object_vtemplates/<object>/`` in mm, one template as ``top.obj`` + ``bottom.obj``, one as ``mesh.obj``
+ ``parts.json`` (0 = top). The templates' parts are convex blocks (no convex decomposition: fast).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handsim.cli import main
from handsim.datatypes.skeleton import mj_name
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import InputFileError, TrajectoryError
from handsim.io.arctic.mano import MANO_DIR_ENV, MANO_JOINT_NAMES
from handsim.io.arctic.sequence import HANDS
from handsim.runner.records import read_records
from handsim.sim.control import control_schedule
from handsim.sim.drive import ScenarioSwitches, ScheduleDriver
from handsim.sim.replay import replay
from handsim.sim.stepper import Stepper
from handsim.sim.summary import HAND_KEYS
from handsim.trials import load_trial
from tests.arctic_fixtures import UPRIGHT, block, template_vertices_mm, write_template
from tests.mano_fixtures import (
    mano_hand_params,
    numpy_mano_fk,
    write_arctic_mano_npy,
    write_arctic_object_npy,
)
from tests.mano_fixtures import write_synthetic_mano_pkl as write_mano

FRAMES = 12
SEQUENCES = {"box": "box_grab_01", "notebook": "notebook_use_01"}
"""Object → sequence: the box as top.obj + bottom.obj, the notebook as mesh.obj + parts.json."""


@pytest.fixture(scope="module")
def mano(tmp_path_factory):
    """A folder with synthetic MANO_RIGHT.pkl and MANO_LEFT.pkl, and their arrays."""
    folder = tmp_path_factory.mktemp("mano_models")
    arrays = {side: write_mano(folder / f"MANO_{side.upper()}.pkl", side=side) for side in HANDS}
    return folder, arrays


def _template(folder, name: str) -> None:
    """A closed lid on a base, hinged on the canonical z axis (mm, canonical +y up, lid along −x)."""
    bottom = block((-120.0, 0.0), (-60.0, 0.0), (-80.0, 80.0))
    top = block((-120.0, 0.0), (0.0, 10.0), (-80.0, 80.0))
    write_template(folder, name, (bottom, top, "parts" if name == "box" else "mesh"))


def _object_rows(n: int) -> np.ndarray:
    """Upright, 1 m up, slightly turning and drifting, the lid opening from 0.3 to 0.5 rad (float32)."""
    t = np.arange(n) / 30.0
    art = 0.3 + 0.2 * t / t[-1]
    rotvec = np.tile(UPRIGHT, (n, 1)) + 0.1 * t[:, None] * [0.0, 0.2, 1.0]
    trans = np.array([10.0, -20.0, 1000.0]) + np.column_stack([30.0 * t, 10.0 * t, 0.0 * t])
    return np.column_stack([art, rotvec, trans]).astype(np.float32)


@pytest.fixture
def arctic_root(tmp_path):
    """An ARCTIC root with two sequences of subject s01 and their templates."""
    root = tmp_path / "arctic"
    raw = root / "raw_seqs" / "s01"
    raw.mkdir(parents=True)
    params = {}
    for k, (name, seq) in enumerate(SEQUENCES.items()):
        right, left = mano_hand_params(FRAMES, 10 + k), mano_hand_params(FRAMES, 20 + k, side="left")
        write_arctic_mano_npy(raw / f"{seq}.mano.npy", right, left)
        write_arctic_object_npy(raw / f"{seq}.object.npy", _object_rows(FRAMES))
        _template(root / "meta" / "object_vtemplates", name)
        params[seq] = {"right": right, "left": left}
    return root, params


def _frame0(loaded):
    """The scene's data at frame 0, as the replay starts it."""
    scene = loaded.scene
    schedule = control_schedule(scene, loaded.trajectory, 100.0)
    stepper = Stepper(scene, schedule.substeps)
    ScheduleDriver(stepper, schedule, ScenarioSwitches()).reset()
    return scene.model, stepper.data


# --------------------------------------------------------------------------------------------------
# Conventions against an independent numpy computation


@pytest.mark.parametrize("name", list(SEQUENCES))
def test_arctic_scene_at_frame_0_equals_numpy_arctic_object_and_mano_hands(mano, arctic_root, name):
    folder, arrays = mano
    root, params = arctic_root
    seq = SEQUENCES[name]
    raw = root / "raw_seqs" / "s01"
    loaded = load_trial(raw / f"{seq}.mano.npy", mano_dir=folder)
    model, data = _frame0(loaded)
    shift = np.asarray(loaded.scene.setup.world_from_recording)
    np.testing.assert_array_equal(shift[3:], [1.0, 0.0, 0.0, 0.0])  # no axis snapping: a shift only
    np.testing.assert_array_equal(model.opt.gravity, [0.0, 0.0, -9.81])

    # The object: ARCTIC's formula on the template (mm → m), read independently of handsim.
    row = np.load(raw / f"{seq}.object.npy").astype(float)[0]
    theta, rotation, translation = row[0], Rotation.from_rotvec(row[1:4]).as_matrix(), row[4:] / 1000.0
    lid = Rotation.from_rotvec([0.0, 0.0, -theta]).as_matrix()
    lowest = math.inf
    for part, vertices in template_vertices_mm(root / "meta" / "object_vtemplates" / name).items():
        v = vertices / 1000.0
        turn = rotation @ (lid if part == "top" else np.eye(3))
        expected = v @ turn.T + translation + shift[:3]
        body = data.body(f"obj/{part}")
        simulated = body.xpos + v @ body.xmat.reshape(3, 3).T
        np.testing.assert_allclose(simulated, expected, rtol=0, atol=1e-9)
        geom = model.geom(f"obj/{part}_visual")  # MuJoCo's own (float32, recentred) mesh sits there too
        mesh = model.mesh_vert[model.mesh_vertadr[geom.dataid[0]] :][: model.mesh_vertnum[geom.dataid[0]]]
        placed = data.geom(geom.id).xpos + mesh @ data.geom(geom.id).xmat.reshape(3, 3).T
        assert np.abs(np.sort(placed, axis=0) - np.sort(expected, axis=0)).max() < 1e-6
        lowest = min(lowest, float(expected[:, 2].min()))
    assert lowest == pytest.approx(0.0, abs=1e-6)  # the support plane is under the lowest point at frame 0

    # The hands: numpy MANO (betas, flat_hand_mean=False) of the same file, both sides.
    for side in HANDS:
        p = {k: np.asarray(v, dtype=float) for k, v in params[seq][side].items()}
        full = p["pose"][0] + arrays[side]["hands_mean"]
        _, _, joints = numpy_mano_fk(arrays[side], p["shape"], p["rot"][0], full, p["trans"][0])
        sites = np.array([data.site(f"hand/{side}/{mj_name(j)}").xpos for j in MANO_JOINT_NAMES])
        np.testing.assert_allclose(sites, joints + shift[:3], rtol=0, atol=1e-9)


def test_recording_that_starts_below_the_closed_lid_starts_at_the_stop_and_says_so(mano, arctic_root):
    folder, _ = mano
    root, _ = arctic_root
    raw = root / "raw_seqs" / "s01"
    rows = _object_rows(FRAMES)
    rows[:, 0] = np.linspace(-0.1, 0.4, FRAMES)
    write_arctic_object_npy(raw / "box_grab_01.object.npy", rows)
    loaded = load_trial(raw / "box_grab_01.mano.npy", mano_dir=folder)
    _, data = _frame0(loaded)
    assert data.joint("obj/hinge").qpos[0] == 0.0  # the closed pose: the hinge's stop
    assert (
        "the recorded articulation at frame 0 (-5.7°) is outside the hinge's range: the object starts "
        "at 0.0°, its stop (drift is still measured against the recording)"
    ) in loaded.scene.setup.notes


# --------------------------------------------------------------------------------------------------
# Replay and report end to end


def test_arctic_replay_runs_both_hands_with_zero_warnings_and_reports_per_hand_and_drift(mano, arctic_root):
    folder, _ = mano
    root, _ = arctic_root
    loaded = load_trial(root / "raw_seqs" / "s01" / "box_grab_01.mano.npy", mano_dir=folder)
    assert [h.name for h in loaded.scene.layout.hands] == ["right", "left"]
    assert all(h.mocap >= 0 and h.dofs.size == 45 for h in loaded.scene.layout.hands)
    result = replay(loaded.scene, loaded.trajectory)
    assert result.warnings == () and result.diverged is None
    s = result.summary
    for side in HANDS:
        assert all(f"{side}/{key}" in s for key in HAND_KEYS)
    assert s["contact_frames"] >= max(s["right/contact_frames"], s["left/contact_frames"])
    assert s["max_penetration_mm"] == max(s["right/max_penetration_mm"], s["left/max_penetration_mm"])
    for key in ("mean_drift_mm", "max_rotation_drift_deg", "max_articulation_drift_deg"):
        assert s[key] is not None and s[key] >= 0.0
    assert s["mean_articulation_drift_deg"] <= s["max_articulation_drift_deg"]
    assert result.frames.object_position_error[0, 0] == pytest.approx(0.0, abs=1e-9)


def test_arctic_replay_cli_prints_both_hands_and_writes_them_to_json(mano, arctic_root, capsys, tmp_path):
    folder, _ = mano
    root, _ = arctic_root
    out = tmp_path / "result.json"
    path = root / "raw_seqs" / "s01" / "notebook_use_01.mano.npy"
    assert main(["replay", str(path), "--mano-dir", str(folder), "--json", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "warnings    none" in lines
    assert sum(line.startswith(("right   ", "left    ")) for line in lines) == 2
    record = json.loads(out.read_text())
    assert record["trial"]["kind"] == "arctic" and record["trial"]["mano_dir"] == str(folder.resolve())
    summary = record["summary"]
    assert summary["left/contact_frames"] >= 0 and "final_articulation_drift_deg" in summary


def test_arctic_replay_without_mano_files_says_which_files_and_where_before_any_work(
    arctic_root, capsys, monkeypatch, tmp_path
):
    monkeypatch.delenv(MANO_DIR_ENV, raising=False)
    root, _ = arctic_root
    path = root / "raw_seqs" / "s01" / "box_grab_01.mano.npy"
    assert main(["replay", str(path)]) == 1
    err = capsys.readouterr().err
    assert f"no MANO folder given and {MANO_DIR_ENV} is not set" in err
    assert "MANO_RIGHT.pkl and MANO_LEFT.pkl" in err and "--mano-dir DIR" in err
    assert main(["replay", str(path), "--mano-dir", str(tmp_path)]) == 1
    assert f"{tmp_path}: MANO_RIGHT.pkl and MANO_LEFT.pkl not found there" in capsys.readouterr().err


def test_mano_folder_from_the_environment_is_used(mano, arctic_root, monkeypatch):
    folder, _ = mano
    root, _ = arctic_root
    monkeypatch.setenv(MANO_DIR_ENV, str(folder))
    loaded = load_trial(root / "raw_seqs" / "s01" / "box_grab_01.mano.npy")
    assert loaded.trial.mano_dir == str(folder.resolve())


def test_arctic_report_runs_every_sequence_with_per_hand_numbers_and_drift(mano, arctic_root, tmp_path):
    folder, _ = mano
    root, _ = arctic_root
    out = tmp_path / "out"
    args = ["report", str(root), "-o", str(out), "--mano-dir", str(folder), "--workers", "1", "--frames", "0"]
    assert main(args) == 0
    records = read_records(out)
    ids = [f"raw_seqs/s01/{s}.mano.npy" for s in sorted(SEQUENCES.values())]
    assert sorted(r["id"] for r in records) == ids
    for record in records:
        assert record["status"] == "ok", record.get("error")
        assert record["warnings"] == [] and record["trial"]["kind"] == "arctic"
        summary = record["summary"]
        assert all(f"{side}/{key}" in summary for side in HANDS for key in HAND_KEYS)
        assert summary["max_articulation_drift_deg"] is not None
    markdown = (out / "report.md").read_text()
    table = markdown[markdown.index("## Two-hand trials") : markdown.index("## Reproducibility")]
    assert "| trial | right contact frames | right pen. max mm |" in table
    assert sum(line.startswith("| [raw_seqs/s01/") for line in table.splitlines()) == 2
    html = (out / "report.html").read_text()
    assert "<h3>Two-hand trials</h3>" in html and "left: frames in contact" in html
    assert "mean hinge drift °" in html


def test_templates_folder_given_replaces_the_roots_object_templates(mano, arctic_root, tmp_path):
    folder, _ = mano
    root, _ = arctic_root
    elsewhere = tmp_path / "templates"
    (root / "meta" / "object_vtemplates").rename(elsewhere)
    path = root / "raw_seqs" / "s01" / "box_grab_01.mano.npy"
    with pytest.raises(
        InputFileError, match=r"meta/object_vtemplates/box: ARCTIC template folder not found$"
    ):
        load_trial(path, mano_dir=folder)
    loaded = load_trial(path, mano_dir=folder, templates=elsewhere)
    assert loaded.trial.objects[0].what == str(elsewhere / "box")
    assert loaded.objects[0].mass == pytest.approx(0.75)  # the box's default mass (docs/objects.md)


def test_arctic_replay_refuses_the_one_hand_stability_tests(mano, arctic_root, capsys):
    folder, _ = mano
    root, _ = arctic_root
    path = root / "raw_seqs" / "s01" / "box_grab_01.mano.npy"
    assert main(["replay", str(path), "--mano-dir", str(folder), "--stability", "0.1"]) == 2
    assert "--stability tests hold one hand; this trial has two (ARCTIC)" in capsys.readouterr().err


def test_trajectory_hand_roots_of_the_wrong_shape_or_beside_a_root_pose_raise_error():
    times, names = np.arange(3) / 30.0, ("right/a",)
    targets, valid = np.zeros((3, 1)), np.ones((3, 1), bool)
    with pytest.raises(
        TrajectoryError, match=r"hand 'right' root pose must have shape \(3, 7\), got \(2, 7\)"
    ):
        Trajectory(times, names, targets, valid, hand_roots={"right": np.zeros((2, 7))})
    with pytest.raises(
        TrajectoryError, match="give one hand's root_pose or several hands' hand_roots, not both"
    ):
        Trajectory(
            times, names, targets, valid, root_pose=np.zeros((3, 7)), hand_roots={"right": np.zeros((3, 7))}
        )
