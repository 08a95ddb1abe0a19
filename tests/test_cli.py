"""The handsim command line, run as a user would (through main())."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from handsim.cli import main


def test_help_explains_the_commands(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "handsim demo" in out and "build" in out


@pytest.mark.slow
def test_demo_checks_the_default_hand_and_reports_on_the_bundled_tzionas_sample(capsys, tmp_path):
    out_dir = tmp_path / "demo"
    assert main(["demo", "-o", str(out_dir), "--workers", "1", "--frames", "0"]) == 0
    out = capsys.readouterr().out
    assert "27 actuated DoFs" in out and "0 MuJoCo warnings" in out
    assert "synthetic scripted grasps" in out and "not recordings" in out
    assert not [line for line in out.splitlines() if line.startswith("note")]  # records it reads cleanly
    records = [json.loads(line) for line in (out_dir / "records.jsonl").read_text().splitlines()]
    assert sorted((r["id"], r["kind"], r["status"]) for r in records) == [
        ("demo/cube.grasp.json#1", "scripted", "ok"),  # each scripted grasp: one grasp episode
        ("demo/cylinder_25mm.grasp.json#1", "scripted", "ok"),
        ("demo/tennis_ball.grasp.json#1", "scripted", "ok"),
        ("tzionas_ijcv16/Models/20", "tzionas", "ok"),
    ]
    assert all(r["summary"]["warnings"] == 0 for r in records)
    for record in (r for r in records if r["kind"] == "scripted"):  # a verdict, or why there is none
        summary = record["summary"]
        assert isinstance(summary["held"], bool) or summary["hold_reason"].startswith("not judged: ")
        if summary["held"] is True:  # never on a link deeper than the grip's limit, always in force closure
            grip = record["grip"]
            assert grip["max_depth_mm"] <= grip["depth_limit_mm"] and grip["opposition"] >= 0.5
    for name in ("report.html", "report.md", "summary.json"):
        assert (out_dir / name).is_file() and str(out_dir / name) in out


def test_build_hand_from_graspdb_skeleton_writes_mjcf(capsys, tmp_path, graspdb_dir):
    out_file = tmp_path / "sub" / "hand.xml"
    assert main(["build", "hand", str(graspdb_dir / "default.xmlskel"), "-o", str(out_file)]) == 0
    out = capsys.readouterr().out
    for word in ("bodies", "DoFs       27", "actuators  27", "mass", "bbox", "note"):
        assert word in out
    model = mujoco.MjModel.from_xml_path(str(out_file))
    assert model.njnt == 27


def test_build_hand_default_accepts_a_hand_length(capsys):
    assert main(["build", "hand", "--default", "--hand-length", "0.17"]) == 0
    assert "mass       0.322 kg" in capsys.readouterr().out  # 0.45 kg × (0.17 / 0.19)³


def test_build_hand_reports_a_missing_file_and_exits_1(capsys, tmp_path):
    assert main(["build", "hand", str(tmp_path / "missing.xmlskel")]) == 1
    assert "missing.xmlskel: file not found" in capsys.readouterr().err


def test_build_hand_refuses_both_a_file_and_default(tmp_path, capsys):
    assert main(["build", "hand", str(tmp_path / "a.xmlskel"), "--default"]) == 2
    err = capsys.readouterr().err
    assert err == "handsim build hand: error: give a SKELETON file or --default, not both\n"


def test_catalog_lists_every_object_with_size_and_mass(capsys):
    from handsim.builders import catalog

    assert main(["catalog"]) == 0
    out = capsys.readouterr().out
    for name in catalog.names():
        assert name in out
    assert "tennis_ball      1   graspdb14  58 g" in out


def test_build_object_from_catalogue_writes_mjcf_that_compiles(capsys, tmp_path):
    out_file = tmp_path / "mug.xml"
    assert main(["build", "object", "mug", "-o", str(out_file)]) == 0
    out = capsys.readouterr().out
    assert "collision 16 hulls (cached" in out and "mass       340.0 g" in out
    model = mujoco.MjModel.from_xml_path(str(out_file))
    assert model.body("body").mass[0] == pytest.approx(0.340)


def test_build_object_from_mesh_file_needs_units(capsys, tmp_path):
    import trimesh

    path = tmp_path / "block.stl"
    trimesh.creation.box((40.0, 30.0, 20.0)).export(path)
    assert main(["build", "object", str(path)]) == 1
    assert "give the mesh's units (--units m or --units mm)" in capsys.readouterr().err
    assert main(["build", "object", str(path), "--units", "m"]) == 1
    assert "are the coordinates in mm? (give --units mm)" in capsys.readouterr().err
    assert main(["build", "object", str(path), "--units", "mm", "--density", "500"]) == 0
    assert "mass       12.0 g" in capsys.readouterr().out


def test_build_object_with_unknown_name_lists_the_catalogue(capsys):
    assert main(["build", "object", "teapot"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("handsim: error: unknown object 'teapot'; catalogue objects are: bottle, ")


def test_build_scene_with_hand_and_object_writes_mjcf_that_compiles(capsys, tmp_path):
    out_file = tmp_path / "scene.xml"
    assert main(["build", "scene", "--object", "tennis_ball", "-o", str(out_file)]) == 0
    model = mujoco.MjModel.from_xml_path(str(out_file))
    assert model.body("obj/body") is not None and model.body("hand/root") is not None
    assert model.nu == 27


def test_inspect_prints_timing_phases_and_limit_violations_and_writes_a_plot(capsys, tmp_path, graspdb_dir):
    motion = graspdb_dir / "r_01_11_ex03-rad-004-grasp-su04.txt"
    plot = tmp_path / "plot.png"
    args = ["inspect", str(motion), "--skeleton", str(graspdb_dir / "default.xmlskel"), "--plot", str(plot)]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "frames     282 over 4.680 s (60.0 Hz mean; largest interval 32.0 ms at 2.043 s)" in out
    assert "phase      grasp      frames 81–163 (1.36–2.71 s)" in out
    assert "663 of 7614 valid samples outside the limits (663 below, 0 above) in 5 of 27 DoFs" in out
    assert plot.stat().st_size > 10_000 and plot.read_bytes()[:4] == b"\x89PNG"


def test_calibrate_fits_a_calibration_sequence_and_writes_json(capsys, tmp_path):
    from handsim.io.graspdb.calibration import load_calibration
    from tests.test_glove_calibration import _synthetic_sequence, _write_raw

    raw, switch, gains, _ = _synthetic_sequence()
    recording = _write_raw(tmp_path / "01_calib-raw-001-su01.txt", raw, switch)
    assert main(["calibrate", str(recording), "-o", str(tmp_path / "glove.json")]) == 0
    assert "wrote" in capsys.readouterr().out
    calibration = load_calibration(tmp_path / "glove.json")
    i = calibration.sensor_names.index("I-MCPJ")
    assert abs(calibration.gains[i]) == pytest.approx(abs(gains[i]), rel=0.01)


def test_inspect_raw_file_without_calibration_explains_what_to_do(capsys, tmp_path):
    from tests.test_glove_calibration import _synthetic_sequence, _write_raw

    raw, switch, _, _ = _synthetic_sequence()
    recording = _write_raw(tmp_path / "01_ex01-raw-002-grasp-su01.txt", raw, switch)
    assert main(["inspect", str(recording)]) == 1
    assert "estimate_calibration" in capsys.readouterr().err


def test_inspect_bundled_tzionas_motion_reports_root_and_cube_tracks(capsys):
    from handsim.assets import TZIONAS_DIR

    assert main(["inspect", str(TZIONAS_DIR / "Models/20/Model_Hand_R.MOTION")]) == 0
    out = capsys.readouterr().out
    assert "frames     186 over 6.167 s (30.0 Hz mean" in out
    assert "root pose  recorded" in out and "object     cube: pose track" in out
    assert "95 of 5766 valid samples outside the limits" in out


def _arctic_sequence(tmp_path, n=40):
    from tests.arctic_fixtures import recording
    from tests.mano_fixtures import mano_hand_params, write_arctic_mano_npy, write_arctic_object_npy

    raw = tmp_path / "raw_seqs" / "s02"
    raw.mkdir(parents=True)
    right, left = mano_hand_params(n, 1), mano_hand_params(n, 2, side="left")
    write_arctic_mano_npy(raw / "laptop_use_01.mano.npy", right, left)
    values = recording("laptop", n)
    write_arctic_object_npy(raw / "laptop_use_01.object.npy", values)
    return raw / "laptop_use_01.mano.npy", right, left, values


def test_inspect_arctic_sequence_shows_frames_both_hands_the_object_and_its_articulation(capsys, tmp_path):
    path, right, left, values = _arctic_sequence(tmp_path)
    assert main(["inspect", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == f"file       {path} (ARCTIC sequence laptop_use_01, subject s02)"
    assert lines[2] == "frames     40 over 1.300 s (30 fps)"
    assert lines[3].startswith("right hand wrist travels ") and lines[5].startswith(
        "left hand  wrist travels "
    )
    for line, hand in ((lines[4], right), (lines[6], left)):
        err = np.asarray(hand["fitting_err"])
        k = int(np.argmax(err))
        assert line == (
            f"           fitting error (as stored, ARCTIC gives no unit): mean {err.mean():.4g}, median "
            f"{np.median(err):.4g}, max {err[k]:.4g} at frame {k}"
        )
    assert lines[7].startswith("object     laptop (laptop_use_01.object.npy): travels ")
    assert lines[7].endswith(f"at frame 0 its origin is {values[0, 6] / 1000:.3f} m up (z-up world)")
    lo, hi = float(values[:, 0].min()), float(values[:, 0].max())
    assert lines[8] == (
        f"articul.   {np.degrees(lo):.1f}°..{np.degrees(hi):.1f}° ({lo:.3f}..{hi:.3f} rad) about the "
        "object's (0, 0, −1) axis"
    )


def test_inspect_arctic_sequence_refuses_options_for_one_hand_recordings(capsys, tmp_path):
    path, *_ = _arctic_sequence(tmp_path)
    with pytest.raises(SystemExit) as exc:
        main(["inspect", str(path), "--plot", str(tmp_path / "p.png")])
    assert str(exc.value) == (
        "handsim inspect: --plot does not apply to an ARCTIC sequence (its hands are MANO's: their joint "
        "angles need the MANO models)"
    )


def test_inspect_arctic_sequence_with_a_corrupted_frame_names_it(capsys, tmp_path):
    from tests.mano_fixtures import write_arctic_object_npy

    path, _, _, values = _arctic_sequence(tmp_path)
    values[12, 4:] *= 1000.0
    write_arctic_object_npy(path.with_name("laptop_use_01.object.npy"), values)
    assert main(["inspect", str(path)]) == 1
    assert "[translation]: frame 12: the object is " in capsys.readouterr().err


def test_one_hand_trajectory_reader_names_an_arctic_sequence(tmp_path):
    from handsim.errors import InputFileError
    from handsim.io import read_trajectory

    path, *_ = _arctic_sequence(tmp_path)
    with pytest.raises(InputFileError) as err:
        read_trajectory(path)
    assert str(err.value) == (
        f"{path}: an ARCTIC sequence (two MANO hands in <seq>.mano.npy, the object in <seq>.object.npy), not "
        "a one-hand trajectory: read it with handsim.io.arctic.sequence.read_arctic_sequence "
        "(`handsim inspect <seq>.mano.npy` summarises it)"
    )


def test_build_hand_mass_and_scene_object_mass_are_separate_options(capsys):
    assert main(["build", "hand", "--default", "--mass", "0.5"]) == 0
    assert "mass       0.500 kg" in capsys.readouterr().out
    args = ["build", "scene", "--object", "cube", "--mass", "0.2", "--hand-mass", "0.4"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "mass       200.0 g" in out  # the object
    assert "mass       0.600 kg" in out  # the scene: hand 0.4 + cube 0.2


@pytest.mark.parametrize(
    "command",
    [
        ["replay", "{tzionas}/Models/20"],
        ["report", "{tzionas}", "-o", "{out}"],
        ["demo", "-o", "{out}"],
        ["export", "minari", "{out}", "--dataset-id", "handsim/test-v0"],
    ],
)
def test_a_bad_thread_setting_is_a_usage_error_before_any_work(command, monkeypatch, capsys, tmp_path):
    from handsim.assets import TZIONAS_DIR

    monkeypatch.setenv("HANDSIM_THREADS", "0")
    out = tmp_path / "out"
    args = [a.format(tzionas=TZIONAS_DIR, out=out) for a in command]
    with pytest.raises(SystemExit) as exited:
        main(args)
    assert exited.value.code == 2
    name = " ".join(args[:2]) if args[0] == "export" else args[0]
    first = capsys.readouterr().err.splitlines()[0]
    assert first == f"handsim {name}: error: $HANDSIM_THREADS must be a positive integer (threads), got '0'"
    assert not out.exists()


def test_a_command_that_does_not_simulate_ignores_the_thread_setting(monkeypatch, capsys):
    monkeypatch.setenv("HANDSIM_THREADS", "many")
    assert main(["catalog"]) == 0
    assert "tennis_ball" in capsys.readouterr().out
