"""The bad-input catalogue of issue 14 as tests: one case per row, each asserting the exit code and the
exact first line of stderr (or, for a flagged result, the flag), as a new user would meet them."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.cli import main
from tests.processes import child_env, descendants, linux_only, reaped, wait_for

ROOT = Path(__file__).resolve().parents[1]
MOTION = TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION"
SCRIPTED = ASSETS_DIR / "demo" / "tennis_ball.grasp.json"
RATE_LINE = (
    "argument --rate: expected a control rate of at least 20 Hz (two control frames within the 0.1 s "
    "contact gap and release delay the metrics judge), got {}"
)


def cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """Run ``handsim ARGV`` in this process: the exit code, the first line of stderr, and stdout."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's usage errors
        code = exc.code
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    return code, lines[0] if lines else "", captured.out


def stalling_coacd(tmp_path: Path) -> Path:
    """A folder with a ``coacd`` module whose decomposition never ends (the CoACD worker imports it)."""
    folder = tmp_path / "stalling"
    folder.mkdir()
    (folder / "coacd.py").write_text(
        "import time\n\n"
        "def set_log_level(level):\n    pass\n\n"
        "def Mesh(vertices, faces):\n    return vertices, faces\n\n"
        "def run_coacd(mesh, **kwargs):\n    time.sleep(3600)\n"
    )
    return folder


def build_ring(tmp_path: Path) -> list[str]:
    """The command line building a concave ring mesh (CoACD runs for it)."""
    import trimesh

    mesh = tmp_path / "ring.stl"
    trimesh.creation.annulus(r_min=0.03, r_max=0.05, height=0.02, sections=16).export(mesh)
    return [sys.executable, "-m", "handsim.cli", "build", "object", str(mesh), "--units", "m"]


# --------------------------------------------------------------------------------------------------------
# runs and CLI


@pytest.mark.parametrize("rate", ["0", "-5", "nan", "1"])
def test_replay_refuses_a_control_rate_below_20_hz_before_any_work(capsys, rate):
    code, first, out = cli(["replay", str(SCRIPTED), f"--rate={rate}"], capsys)
    assert code == 2
    assert first == "handsim replay: error: " + RATE_LINE.format(rate)
    assert out == ""  # nothing loaded, nothing replayed


def test_replay_refuses_a_rate_that_is_not_a_number(capsys):
    code, first, _ = cli(["replay", str(SCRIPTED), "--rate", "fast"], capsys)
    assert (code, first) == (2, "handsim replay: error: argument --rate: expected a number of Hz, got 'fast'")


def test_report_refuses_a_control_rate_of_0_instead_of_failing_every_trial(capsys, tmp_path):
    code, first, _ = cli(["report", str(TZIONAS_DIR), "-o", str(tmp_path / "out"), "--rate", "0"], capsys)
    assert (code, first) == (2, "handsim report: error: " + RATE_LINE.format("0"))
    assert not (tmp_path / "out").exists()


def test_replay_config_refuses_a_control_rate_below_the_minimum():
    from handsim.sim.replay import ReplayConfig

    with pytest.raises(ValueError, match=r"^expected a control rate of at least 20 Hz .*got 1$"):
        ReplayConfig(control_rate=1.0)
    with pytest.raises(ValueError, match=r"got nan$"):
        ReplayConfig(control_rate=float("nan"))


def test_a_glove_replay_at_the_minimum_control_rate_judges_the_hold(capsys):
    code, first, out = cli(["replay", str(SCRIPTED), "--rate", "20"], capsys)
    assert (code, first) == (0, "")
    assert "frames      66 at 20 Hz (25 steps of 2 ms)" in out
    assert "held        yes" in out


def test_replay_refuses_a_folder_as_json_output(capsys, tmp_path):
    code, first, _ = cli(["replay", str(MOTION), "--json", str(tmp_path)], capsys)
    assert (code, first) == (
        2,
        f"handsim replay: error: argument --json: {tmp_path} is a folder; expected a file name to write",
    )


def test_replay_refuses_an_output_below_a_file(capsys, tmp_path):
    (tmp_path / "a").write_text("")
    target = tmp_path / "a" / "plot.png"
    code, first, _ = cli(["replay", str(MOTION), "--plot", str(target)], capsys)
    assert (code, first) == (
        2,
        f"handsim replay: error: argument --plot: cannot create {target}: {tmp_path / 'a'} is a file, "
        "not a folder",
    )


def test_build_refuses_a_folder_as_model_output(capsys, tmp_path):
    code, first, _ = cli(["build", "hand", "--default", "-o", str(tmp_path)], capsys)
    assert (code, first) == (
        2,
        f"handsim build hand: error: argument -o/--output: {tmp_path} is a folder; expected a file name to "
        "write",
    )


@pytest.mark.parametrize("command", ["report", "demo"])
def test_a_dataset_run_refuses_an_existing_file_as_output_folder(capsys, tmp_path, command):
    out = tmp_path / "out.txt"
    out.write_text("keep me")
    argv = ["report", str(TZIONAS_DIR)] if command == "report" else ["demo"]
    code, first, _ = cli([*argv, "-o", str(out)], capsys)
    assert (code, first) == (
        2,
        f"handsim {command}: error: argument -o/--output: {out} exists and is not a folder; expected an "
        "output folder",
    )
    assert out.read_text() == "keep me"


def test_run_dataset_refuses_an_existing_file_as_output_folder(tmp_path):
    from handsim.runner.execute import RunnerError, run_dataset
    from handsim.trials import discover

    out = tmp_path / "out.txt"
    out.write_text("")
    with pytest.raises(RunnerError, match=r"out\.txt exists and is not a folder; expected an output folder$"):
        run_dataset(discover(TZIONAS_DIR), out, workers=1)


def test_build_hand_without_a_skeleton_is_a_usage_error(capsys):
    code, first, _ = cli(["build", "hand"], capsys)
    assert (code, first) == (
        2,
        "handsim build hand: error: give a SKELETON file, or --default for the parametric hand",
    )


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--threshold", "5", "argument --threshold: threshold must be in [0.01, 1], got 5.0"),
        ("--timeout", "-1", "argument --timeout: timeout_s must be positive, got -1.0"),
        (
            "--max-hulls",
            "0",
            "argument --max-hulls: max_convex_hull must be -1 (no limit) or at least 1, got 0",
        ),
        ("--max-hulls", "x", "argument --max-hulls: expected a whole number, got 'x'"),
    ],
)
def test_build_object_refuses_bad_decomposition_settings_before_any_work(capsys, option, value, message):
    code, first, out = cli(["build", "object", "mug", option, value], capsys)
    assert (code, first, out) == (2, f"handsim build object: error: {message}", "")


@pytest.mark.parametrize("value", ["nan", "-3"])
def test_replay_refuses_a_stability_time_that_is_no_time(capsys, value):
    code, first, out = cli(["replay", str(SCRIPTED), "--stability", value], capsys)
    assert (code, first, out) == (
        2,
        f"handsim replay: error: argument --stability: expected 'grasp' or a time ≥ 0 s, got {value}",
        "",
    )


def test_replay_refuses_a_stability_time_after_the_recording(capsys):
    code, first, _ = cli(["replay", str(SCRIPTED), "--stability", "99"], capsys)
    assert (code, first) == (
        2,
        "handsim replay: error: --stability 99 s is after the recording's end (3.283 s)",
    )


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["build", "hand", "--default", "--mass", "nan"], "handsim build hand: error: argument --mass: "),
        (["build", "object", "mug", "--density", "-1"], "handsim build object: error: argument --density: "),
        (["replay", str(SCRIPTED), "--mass", "inf"], "handsim replay: error: argument --mass: "),
        (["demo", "--hand-length", "0"], "handsim demo: error: argument --hand-length: "),
    ],
)
def test_a_mass_density_or_length_that_is_no_positive_number_is_a_usage_error(capsys, argv, message):
    code, first, out = cli(argv, capsys)
    assert (code, first, out) == (2, f"{message}expected a finite number > 0, got {argv[-1]}", "")


def test_an_os_error_writing_an_output_is_one_line_and_exit_1(capsys, tmp_path):
    target = tmp_path / ("x" * 300 + ".xml")  # longer than a file name may be
    code, first, _ = cli(["build", "hand", "--default", "-o", str(target)], capsys)
    assert (code, first) == (1, f"handsim: error: {target}: File name too long")
    assert list(tmp_path.iterdir()) == []  # no temporary file left


def test_write_atomic_leaves_no_partial_file_when_interrupted(tmp_path, monkeypatch):
    from handsim.runner import records

    def interrupted(*args: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(records.os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        records.write_atomic(tmp_path / "out.json", b"{}")
    assert list(tmp_path.iterdir()) == []


def test_every_trial_failing_exits_1_with_the_errors_counted(capsys, tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    for name in ("01_ex01-rad-002-grasp-su01.txt", "04_ex01-rad-045-grasp-su03.txt"):
        (data / name).write_text("not a recording\n")
    code, first, out = cli(["report", str(data), "-o", str(tmp_path / "out"), "--workers", "1"], capsys)
    assert (code, first) == (1, "handsim report: error: every trial failed (2 of 2): 2 FormatError")
    assert "2 trials: 0 ok, 0 diverged, 2 failed" in out
    assert (tmp_path / "out" / "report.html").is_file()  # the report still shows the errors


@linux_only
def test_ctrl_c_during_a_coacd_decomposition_exits_130_leaving_no_cache_entry_or_process(tmp_path):
    cache = tmp_path / "cache"
    process = subprocess.Popen(
        [*build_ring(tmp_path), "--cache-dir", str(cache)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=child_env(stalling_coacd(tmp_path)),
        start_new_session=True,  # its own process group, as a terminal's foreground job
    )
    with reaped(process) as children:
        wait_for(lambda: children.add(descendants(process.pid)), 120, "no CoACD worker")
        os.killpg(process.pid, signal.SIGINT)  # Ctrl-C: the terminal signals the whole group
        _, err = process.communicate(timeout=60)
        assert process.returncode == 130
        assert err.decode().splitlines()[-1] == "handsim: interrupted"
        assert "Traceback" not in err.decode()
        wait_for(lambda: not children.alive(), 60, "the CoACD worker stayed alive")
    assert [p for p in cache.rglob("*") if p.is_file()] == []


def _spawn_workers(pid: int) -> set[int]:
    """The pool workers below ``pid`` (processes started by multiprocessing's spawn)."""
    found = set()
    for child in descendants(pid):
        try:
            cmdline = Path(f"/proc/{child}/cmdline").read_bytes()
        except OSError:
            continue
        if b"multiprocessing.spawn" in cmdline:
            found.add(child)
    return found


@linux_only
def test_kill_9_of_a_dataset_run_leaves_no_worker_process(tmp_path):
    argv = [
        sys.executable,
        "-m",
        "handsim.cli",
        "report",
        str(ASSETS_DIR / "demo"),
        "-o",
        str(tmp_path / "o"),
    ]
    process = subprocess.Popen(
        [*argv, "--workers", "2", "--frames", "0"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=child_env(),
    )
    with reaped(process) as children:
        wait_for(lambda: len(_spawn_workers(process.pid)) >= 2, 120, "the pool's workers did not start")
        children.add(descendants(process.pid))  # the workers and multiprocessing's resource tracker
        process.kill()  # SIGKILL: the run cannot stop its workers itself
        process.wait(timeout=30)
        wait_for(lambda: not children.alive(), 60, "orphaned processes stayed alive")


@linux_only
def test_kill_9_during_a_coacd_decomposition_leaves_no_worker_process(tmp_path):
    process = subprocess.Popen(
        [*build_ring(tmp_path), "--no-cache"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=child_env(stalling_coacd(tmp_path)),
    )
    with reaped(process) as children:
        wait_for(lambda: children.add(descendants(process.pid)), 120, "no CoACD worker")
        process.kill()
        process.wait(timeout=30)
        wait_for(lambda: not children.alive(), 60, "the CoACD worker stayed alive")


def glove_recording(folder: Path, rows: np.ndarray, times: np.ndarray) -> Path:
    """A GraspDB14 radian recording of the tennis ball (object id 1 in its name) with these rows."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "r_01_11_ex03-rad-004-grasp-su04.txt"
    lines = [
        f"2014 09 15 08 02 {9.024 + t:08.5f} 1 " + " ".join(f"{x:.5f}" for x in row) + " "
        for t, row in zip(times, rows, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


def tzionas_copy(folder: Path, edit_cube) -> Path:
    """The bundled Tzionas sequence 20 with its cube's MOTION rows (after the rigging row) edited.

    ``edit_cube(k, values)`` gets the sample index and the row's 12 numbers (R row-major, T in mm).
    """
    shutil.copytree(TZIONAS_DIR / "Models" / "20", folder / "Models" / "20")
    shutil.copytree(TZIONAS_DIR / "Configs" / "20", folder / "Configs" / "20")
    motion = folder / "Models" / "20" / "Model_Object_Cube.MOTION"
    lines = motion.read_text().splitlines()
    for k in range(2, len(lines)):
        values = np.array(lines[k].split(), dtype=float)
        edit_cube(k - 2, values)
        lines[k] = " ".join(f"{v:.9g}" for v in values) + " "
    motion.write_text("\n".join(lines) + "\n")
    return folder / "Models" / "20" / "Model_Hand_R.MOTION"


FLEXED = np.array(
    [-1.85, 0.6, -0.6, 0.07, -0.73, -1.27, -0.3, -0.15, -0.47, -1.37, -0.37, -0.05, -0.12, -1.47, -0.44, 0.26,
     -0.45, -1.47, -0.44, 0.33, -0.85, -0.32, 0.18]
)  # fmt: skip
"""A power grasp in GraspDB14's 23 channels (radians)."""


def test_a_two_row_recording_is_not_judged_held(capsys, tmp_path):
    path = glove_recording(tmp_path, np.zeros((2, 23)), np.array([0.0, 1 / 60]))
    code, first, out = cli(["replay", str(path)], capsys)
    assert (code, first) == (0, "")
    assert "\nheld        not judged: the hold window after release lasts 0.007 s" in out  # was "held yes"


def test_samples_10_us_apart_are_flagged_too_few_frames(capsys, tmp_path):
    path = glove_recording(tmp_path, np.zeros((2, 23)), np.array([0.0, 1e-5]))
    code, first, out = cli(["replay", str(path)], capsys)
    assert (code, first) == (
        4,
        "handsim replay: not valid: 1 control frame from 2 samples over 0.01 ms: nothing was simulated (a "
        "replay needs 2 frames, 10 ms apart at this rate)",
    )
    assert "valid       no (too_few_frames): the numbers below judge nothing" in out


def test_targets_beyond_the_joint_limits_are_noted_on_the_glove_path(capsys, tmp_path):
    ramp = np.clip(np.linspace(-0.3, 1.3, 180), 0.0, 1.0)[:, None] * FLEXED
    ramp[:, 4] = 3.0  # I-MCPJ, far beyond the index MCP's range
    path = glove_recording(tmp_path, ramp, np.arange(180) / 60)
    code, first, out = cli(["replay", str(path)], capsys)
    assert (code, first) == (0, "")
    assert "valid       yes" in out
    assert (
        "flag        joint_limits (a note): 293 target samples beyond the joint limits in 2 of 27 DoFs (the "
        "actuators clamp them to the limits): if_mcp_flex 180 (up to 171.9°), th_mcp_flex 113 (up to 24.4°)"
    ) in out


def test_a_hand_starting_inside_the_object_is_flagged_with_its_depth(capsys, tmp_path):
    def into_the_index_finger(k: int, values: np.ndarray) -> None:
        values[9:12] += (-47.4, -54.4, -26.0)  # mm: the cube's centre onto the index fingertip at frame 0

    motion = tzionas_copy(tmp_path / "data", into_the_index_finger)
    code, first, out = cli(["replay", str(motion)], capsys)
    assert (code, first) == (
        4,
        "handsim replay: not valid: the hand is 37.7 mm inside the object at the start, more than 5 mm: the "
        "solver pushes them apart, and what follows is not the recording's",
    )
    assert "valid       no (initial_penetration): the numbers below judge nothing" in out
    assert "warnings    none" in out  # MuJoCo itself sees nothing wrong


def test_an_object_track_jumping_10_km_in_one_frame_is_flagged_with_its_samples(capsys, tmp_path):
    def jump(k: int, values: np.ndarray) -> None:
        if k == 50:
            values[9] += 1e7  # 10 km, in mm

    motion = tzionas_copy(tmp_path / "data", jump)
    code, first, out = cli(["replay", str(motion)], capsys)
    assert "valid       no (track_jump): the numbers below judge nothing" in out
    assert (code, first) == (
        4,
        "handsim replay: not valid: the recorded object 'cube' track jumps faster than 10 m/s into 2 of 186 "
        "samples (up to 3e+05 m/s; samples 50, 51)",
    )


def test_a_dataset_record_of_a_flagged_trial_says_not_valid_and_the_report_leaves_it_out(capsys, tmp_path):
    from handsim.runner.records import read_records

    def into_the_index_finger(k: int, values: np.ndarray) -> None:
        values[9:12] += (-47.4, -54.4, -26.0)

    tzionas_copy(tmp_path / "data", into_the_index_finger)
    out_dir = tmp_path / "out"
    code, first, out = cli(["report", str(tmp_path / "data"), "-o", str(out_dir), "--workers", "1"], capsys)
    assert (code, first) == (0, "")
    assert "1 trials: 1 ok, 0 diverged, 0 failed (1 flagged not valid, left out of the rates)" in out
    (record,) = read_records(out_dir)
    assert (record["status"], record["summary"]["valid"]) == ("ok", False)
    assert [(f["code"], f["invalid"]) for f in record["flags"]] == [
        ("initial_penetration", True),
        ("joint_limits", False),
    ]
    assert record["flags"][0]["values"]["depth_mm"] == pytest.approx(37.7, abs=0.05)
    assert "flagged" in (out_dir / "report.md").read_text()


@pytest.mark.parametrize("env_id", ["handsim/Replay-v0", "handsim/Grasp-v0"])
def test_an_absurd_action_is_clipped_to_the_action_space_and_noted(env_id):
    import gymnasium as gym

    import handsim  # noqa: F401  (registers the environments)

    env, same = gym.make(env_id).unwrapped, gym.make(env_id).unwrapped
    env.reset(seed=0)
    same.reset(seed=0)
    huge = np.full(env.action_space.shape, 1e30)
    huge[0] = 0.5
    obs, reward, _, _, info = env.step(huge)
    clipped = np.ones(env.action_space.shape)
    clipped[0] = 0.5
    obs_same, reward_same, _, _, info_same = same.step(clipped)
    assert info["action_clipped"] == env.action_space.shape[0] - 1 and info_same["action_clipped"] == 0
    assert reward == reward_same and np.array_equal(obs, obs_same)  # exactly the action at its bound
    assert huge[1] == 1e30  # the caller's array is left alone


@pytest.mark.parametrize("env_id", ["handsim/Replay-v0", "handsim/Grasp-v0"])
def test_a_non_finite_action_raises_a_clear_value_error(env_id):
    import gymnasium as gym

    import handsim  # noqa: F401

    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape)
    action[2] = np.nan
    name = type(env).__name__
    with pytest.raises(ValueError, match=rf"^{name}: action has NaN or infinite values: \[0\.0, 0\.0, nan, "):
        env.step(action)


@linux_only
def test_ctrl_c_during_a_dataset_run_exits_130_with_complete_records_and_no_worker_left(tmp_path):
    from handsim.runner.records import load_records

    out_dir = tmp_path / "out"
    argv = [sys.executable, "-m", "handsim.cli", "report", str(ASSETS_DIR / "demo"), "-o", str(out_dir)]
    process = subprocess.Popen(
        [*argv, "--workers", "2", "--frames", "0"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=child_env(),
        start_new_session=True,
    )
    with reaped(process) as children:
        wait_for(lambda: len(_spawn_workers(process.pid)) >= 2, 120, "the pool's workers did not start")
        children.add(descendants(process.pid))
        os.killpg(process.pid, signal.SIGINT)
        _, err = process.communicate(timeout=120)
        assert process.returncode == 130
        assert err.decode().splitlines()[0] == (
            f"handsim report: interrupted; the finished trials are recorded in {out_dir / 'records.jsonl'}: "
            "run the same command to resume"
        )
        wait_for(lambda: not children.alive(), 60, "a worker outlived the interrupted run")
    read = load_records(out_dir)
    assert read.valid_bytes == read.size and read.notes == ()  # complete lines only
