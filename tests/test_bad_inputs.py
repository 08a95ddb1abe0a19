"""The bad-input catalogue of issue 14 as tests: one case per row, each asserting the exit code and the
exact first line of stderr (or, for a flagged result, the flag; for an input that must now be accepted,
exit 0 and the first line of stdout), as a new user would meet them.

Every case runs ``handsim.cli.main`` in-process (or the command in a subprocess where a signal or a killed
process is the point). A usage error (exit 2) prints the error line first, then the usage. Inputs are made
here or copied from the bundled data, so only rows that need the GraspDB14 skeleton (``../shared/data``)
can skip.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import trimesh

from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.cli import main
from tests.processes import child_env, descendants, linux_only, reaped, wait_for
from tests.text_samples import glove_rows

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
    assert "frames      36 at 20 Hz (25 steps of 2 ms)" in out  # its one grasp episode
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
        "handsim replay: error: --stability 99 s is after the grasp episode 1's end (1.783 s)",
    )


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["build", "hand", "--default", "--mass", "nan"],
            "handsim build hand: error: argument --mass: hand mass nan kg: expected a positive number",
        ),
        (
            ["build", "object", "mug", "--density", "-1"],
            "handsim build object: error: argument --density: density -1 kg/m³: expected a positive number",
        ),
        (
            ["replay", str(SCRIPTED), "--mass", "inf"],
            "handsim replay: error: argument --mass: mass inf kg: expected a positive number",
        ),
        (
            ["demo", "--hand-length", "0"],
            "handsim demo: error: argument --hand-length: expected a finite number > 0, got 0",
        ),
    ],
)
def test_a_mass_density_or_length_that_is_no_positive_number_is_a_usage_error(capsys, argv, message):
    code, first, out = cli(argv, capsys)
    assert (code, first, out) == (2, message, "")


def test_an_os_error_writing_an_output_is_one_line_and_exit_1(capsys, tmp_path):
    target = tmp_path / ("x" * 300 + ".xml")  # longer than a file name may be
    code, first, _ = cli(["build", "hand", "--default", "-o", str(target)], capsys)
    assert (code, first) == (1, f"handsim: error: {target}: File name too long")
    assert list(tmp_path.iterdir()) == []  # no temporary file left


def test_write_atomic_leaves_no_partial_file_when_interrupted(tmp_path, monkeypatch):
    from handsim import files

    def interrupted(*args: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(files.os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        files.write_atomic(tmp_path / "out.json", b"{}")
    assert list(tmp_path.iterdir()) == []


def test_write_atomic_from_threads_at_once_leaves_one_whole_file(tmp_path):
    # two threads of one process writing the same cache entry must not share a temporary file (they did:
    # its name held only the process id, and every such race left a mixed or missing file)
    import threading

    from handsim import files

    errors: list[OSError] = []
    for trial in range(5):
        target = tmp_path / f"entry{trial}.bin"
        payloads = [bytes([i]) * (4 << 20) for i in range(8)]
        barrier = threading.Barrier(len(payloads))

        def write(payload: bytes, target=target, barrier=barrier) -> None:
            barrier.wait()
            try:
                files.write_atomic(target, payload)
            except OSError as exc:  # another writer's rename took the shared temporary file
                errors.append(exc)

        threads = [threading.Thread(target=write, args=(p,)) for p in payloads]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert target.read_bytes() in payloads
    assert errors == []
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"entry{i}.bin" for i in range(5)]


def test_every_trial_failing_exits_1_with_the_errors_counted(capsys, tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    for name in ("01_ex01-rad-002-grasp-su01.txt", "04_ex01-rad-045-grasp-su03.txt"):
        (data / name).write_text("not a recording\n")
    code, first, out = cli(["report", str(data), "-o", str(tmp_path / "out"), "--workers", "1"], capsys)
    assert (code, first) == (1, "handsim report: error: every trial failed (2 of 2): 2 FormatError")
    assert "2 trials: 0 ok, 0 diverged, 2 failed" in out
    assert (tmp_path / "out" / "report.html").is_file()  # the report still shows the errors
    code, first, out = cli(["report", "--render-only", str(tmp_path / "out")], capsys)
    assert (code, first) == (1, "handsim report: error: every trial failed (2 of 2): 2 FormatError")
    assert "2 trials: 0 ok, 0 diverged, 2 failed" in out


def test_a_report_into_a_folder_another_run_writes_exits_1_naming_that_run(capsys, tmp_path):
    from handsim.runner.output_lock import LOCK_FILE, OutputLock

    out = tmp_path / "out"
    other = ["handsim", "report", "other", "-o", str(out)]
    with OutputLock(out / LOCK_FILE, what="held", command=other):
        holder = (out / LOCK_FILE).read_text()
        code, first, _ = cli(["report", str(SCRIPTED), "-o", str(out), "--workers", "1"], capsys)
        assert (out / LOCK_FILE).read_text() == holder  # the holder's lock is untouched
    started = json.loads(holder)["started"]
    assert (code, first) == (
        1,
        f"handsim: error: output folder {out} is in use by another run (pid {os.getpid()} on "
        f"{socket.gethostname()}, started {started}: handsim report other -o {out}; lock file "
        f"{out / LOCK_FILE}): wait for it to end, or write to another place",
    )
    assert not (out / "records.jsonl").exists()


def test_an_export_of_a_dataset_id_another_export_writes_exits_1_naming_that_export(
    capsys, tmp_path, monkeypatch
):
    pytest.importorskip("minari", reason="the Minari export needs: pip install 'handsim[minari]'")
    from handsim.runner.output_lock import OutputLock

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "records.jsonl").write_text('{"schema": 1, "id": "a", "status": "ok"}\n')
    lock_file = tmp_path / "minari" / ".handsim-export" / "handsim" / "busy-v0.lock"
    with OutputLock(lock_file, what="held", command=["handsim", "export", "minari", "other"]):
        started = json.loads(lock_file.read_text())["started"]
        code, first, _ = cli(
            ["export", "minari", str(tmp_path / "run"), "--dataset-id", "handsim/busy-v0"], capsys
        )
    assert (code, first) == (
        1,
        f"handsim: error: Minari dataset 'handsim/busy-v0' is in use by another run (pid {os.getpid()} on "
        f"{socket.gethostname()}, started {started}: handsim export minari other; lock file {lock_file}): "
        "wait for it to end, or write to another place",
    )
    assert not (tmp_path / "minari" / "handsim").exists()


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
        # the CoACD worker itself: MuJoCo's import may start a short-lived child first (GLFW's version check)
        wait_for(
            lambda: children.add(_descendants_running(process.pid, b"_coacd_worker.py")),
            120,
            "no CoACD worker",
        )
        os.killpg(process.pid, signal.SIGINT)  # Ctrl-C: the terminal signals the whole group
        _, err = process.communicate(timeout=60)
        assert process.returncode == 130
        assert err.decode().splitlines()[-1] == "handsim: interrupted"
        assert "Traceback" not in err.decode()
        wait_for(lambda: not children.alive(), 60, "the CoACD worker stayed alive")
    assert [p for p in cache.rglob("*") if p.is_file()] == []


def _descendants_running(pid: int, marker: bytes) -> set[int]:
    """The processes below ``pid`` whose command line contains ``marker``."""
    found = set()
    for child in descendants(pid):
        try:
            cmdline = Path(f"/proc/{child}/cmdline").read_bytes()
        except OSError:
            continue
        if marker in cmdline:
            found.add(child)
    return found


def _spawn_workers(pid: int) -> set[int]:
    """The pool workers below ``pid`` (processes started by multiprocessing's spawn)."""
    return _descendants_running(pid, b"multiprocessing.spawn")


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
        wait_for(
            lambda: children.add(_descendants_running(process.pid, b"_coacd_worker.py")),
            120,
            "no CoACD worker",
        )
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
    # the start's depth also passes the object track's penetration limit (a recorded-object trial)
    assert "valid       no (initial_penetration, deep_penetration): the numbers below judge nothing" in out
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
        ("deep_penetration", True),
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
        # no placement cache: every trial runs its search (seconds), so the Ctrl-C lands mid-run; with the
        # placements cached by an earlier test the whole run can end before the signal
        env={**child_env(), "HANDSIM_CACHE_DIR": str(tmp_path / "cache")},
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


# --------------------------------------------------------------------------------------------------------
# readers and inputs: helpers

REC = "01_ex01-rad-001-grasp-su01.txt"  # object id 1 (tennis ball) in the name, as replay needs


@dataclass(frozen=True)
class Outcome:
    """What a user sees: the exit code, stderr's lines and stdout's lines."""

    code: int
    err: list[str]
    out: list[str]

    @property
    def first(self) -> str:
        return self.err[0] if self.err else ""


def run(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> Outcome:
    """``handsim ARGV`` in-process (a usage error's SystemExit becomes its code)."""
    capsys.readouterr()
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exit_:
        code = exit_.code if isinstance(exit_.code, int) else 1
    captured = capsys.readouterr()
    return Outcome(code, captured.err.splitlines(), captured.out.splitlines())


def write(path: Path, data: str | bytes) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(data, bytes):
        path.write_bytes(data)
    else:
        path.write_text(data)
    return path


def tzionas_sample(tmp_path: Path) -> Path:
    """A copy of the bundled Tzionas sample (Models/NN, Configs/NN) to edit."""
    root = tmp_path / "tzionas_ijcv16"
    shutil.copytree(TZIONAS_DIR, root)
    return root


def box_text(file_type: str, size: tuple[float, float, float] = (50.0, 40.0, 30.0)) -> str:
    text = trimesh.creation.box(size).export(file_type=file_type)
    return "".join(line + "\n" for line in text.splitlines() if not line.startswith("#"))


# readers and inputs
# --------------------------------------------------------------------------------------------------
# Rows of issue 14's catalogue: silent meaningless results, now refused or noted


def test_row_targets_beyond_the_joint_limits_on_the_glove_path_get_a_per_dof_note(
    capsys, tmp_path, graspdb_dir
):
    rows = [line.split() for line in glove_rows(4).splitlines()]
    for row in rows:
        row[7:] = ["0.0"] * 23
        row[7 + 4] = "-3.0"  # I-MCPJ: if_mcp_flex = 172°, the skeleton allows 0..90°
    path = write(tmp_path / REC, "".join(" ".join(r) + " \n" for r in rows))
    result = run(capsys, "inspect", path, "--skeleton", graspdb_dir / "default.xmlskel")
    assert (result.code, result.err) == (0, [])
    notes = [line for line in result.out if "outside the DoF limits" in line]
    assert notes == [
        "note       targets outside the DoF limits of 'default' in 4 samples (position actuators clamp them "
        "to the joint range): if_mcp_flex 4/4 (up to 81.9° beyond)"
    ]


@pytest.mark.parametrize("rows", [1, 2])
def test_row_recording_of_one_or_two_rows_is_refused(capsys, tmp_path, rows):
    path = write(tmp_path / REC, glove_rows(rows))
    result = run(capsys, "replay", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: {rows} row{'s' if rows == 2 else ''}: a recording needs at least 3 (two "
        "sample intervals) to describe a motion",
    )


def test_row_samples_10_microseconds_apart_are_refused(capsys, tmp_path):
    lines = glove_rows(5).splitlines()
    for i, line in enumerate(lines):
        tokens = line.split()
        tokens[5] = f"{9.024 + 1e-5 * i:08.5f}"
        lines[i] = " ".join(tokens)
    path = write(tmp_path / REC, "\n".join(lines) + "\n")
    result = run(capsys, "replay", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:2 [timestamp]: time stamp '2014 09 15 08 02 09.02401' is 1e-05 s after the "
        "previous row's (line 1): closer than 6.67 ms, a sampling rate above 150 Hz, faster than any "
        "CyberGlove records (at most 120 records/s); are the time stamps right?",
    )


def test_row_a_one_hour_jump_is_refused_before_any_resampling(capsys, tmp_path):
    lines = glove_rows(6).splitlines()
    lines[3:] = [line.replace(" 08 02 ", " 09 02 ", 1) for line in lines[3:]]
    path = write(tmp_path / REC, "\n".join(lines) + "\n")
    result = run(capsys, "replay", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:4 [timestamp]: time stamp '2014 09 15 09 02 09.07200' is 3600.02 s after "
        "the previous row's (line 3): more than the 1 s a recording may skip (the replay would invent the "
        "hand's motion over the hole); cut the recording there into two files",
    )


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        (
            "--mass",
            "1e-9",
            "mass 1e-09 kg is outside the plausible 0.001 to 23 kg (household objects a hand grasps)",
        ),
        (
            "--mass",
            "1e9",
            "mass 1e+09 kg is outside the plausible 0.001 to 23 kg (household objects a hand grasps)",
        ),
        (
            "--density",
            "1e-6",
            "density 1e-06 kg/m³ is outside the plausible 10 to 11400 kg/m³ (expanded polystyrene foam to "
            "lead)",
        ),
        (
            "--density",
            "1e9",
            "density 1e+09 kg/m³ is outside the plausible 10 to 11400 kg/m³ (expanded polystyrene foam to "
            "lead)",
        ),
    ],
)
@pytest.mark.parametrize("command", [("build", "object", "mug"), ("build", "scene", "--object", "mug")])
def test_row_implausible_mass_or_density_is_a_usage_error(capsys, command, option, value, message):
    result = run(capsys, *command, option, value)
    assert result.code == 2
    assert result.err[1].startswith(f"usage: handsim {command[0]} {command[1]} ")
    assert result.first == (
        f"handsim {command[0]} {command[1]}: error: argument {option}: {message}, see docs/objects.md; give "
        "--force to use it anyway"
    )


def test_row_a_3_micrometre_thick_mesh_is_refused_not_built_at_0_grams(capsys, tmp_path):
    path = write(tmp_path / "foil.obj", box_text("obj", (50.0, 50.0, 0.003)))
    result = run(capsys, "build", "object", path, "--units", "mm")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: the object is 0.003 mm thick (its smallest extent along its principal "
        "axes), thinner than the 0.1 mm handsim accepts (a sheet of paper); a surface this thin has no "
        "usable volume, mass or contact",
    )


def test_row_off_header_promising_more_faces_than_present_is_refused(capsys, tmp_path):
    path = write(tmp_path / "box.off", box_text("off").replace("8 12 0", "8 13 0", 1))
    result = run(capsys, "build", "object", path, "--units", "mm")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:2 [counts]: the header promises 8 vertices and 13 faces, but the file ends "
        "after 8 vertex and 12 face lines (line 22)",
    )


# --------------------------------------------------------------------------------------------------
# Rows of issue 14's catalogue: vague or wrong messages, now naming the real cause


def test_row_degree_values_are_called_degrees_not_a_raw_count_file(capsys, tmp_path):
    rows = [line.split() for line in glove_rows(4).splitlines()]
    for row in rows:
        row[7:] = [f"{-30.0 + 4.5 * k:.4f}" for k in range(23)]
    path = write(tmp_path / REC, "".join(" ".join(r) + " \n" for r in rows))
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:1 [sensor T-TMCJ]: value -30.0000 exceeds 7 in magnitude: the sensor values "
        "reach 69 and 87% of them exceed 7, so they look like angles in degrees; GraspDB14 'rad' files hold "
        "radians (|x| <= 2*pi): convert the file's sensor values to radians",
    )


def test_row_motion_row_whose_first_token_is_not_a_number_names_that_token(capsys, tmp_path):
    motion = tzionas_sample(tmp_path) / "Models" / "20" / "Model_Hand_R.MOTION"
    lines = motion.read_text().splitlines()
    assert len(lines[2].split()) == 12  # the first bone's row 1
    lines[2] = "x" + lines[2].lstrip()  # a stray letter glued to R[0][0]
    bad = lines[2].split()[0]
    motion.write_text("\n".join(lines) + "\n")
    result = run(capsys, "inspect", motion)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {motion}:3 [R[0][0]]: expected a number, got {bad!r}",
    )


def test_row_obj_without_faces_says_no_faces_not_0_vertices(capsys, tmp_path):
    path = write(
        tmp_path / "cloud.obj",
        "".join(line + "\n" for line in box_text("obj").splitlines() if line[:2] == "v "),
    )
    result = run(capsys, "build", "object", path, "--units", "mm")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: the file holds 8 vertices but no faces; a mesh needs triangles or polygons "
        "(OBJ 'f' lines) that close its surface, not a point cloud",
    )


def test_row_unsupported_mesh_extension_is_not_looked_up_in_the_catalogue(capsys):
    result = run(capsys, "build", "object", "foo.xyz")
    assert (result.code, result.first) == (
        1,
        "handsim: error: foo.xyz: unsupported mesh extension '.xyz'; handsim reads meshes .obj, .off, .stl, "
        ".ply (give their units), Tzionas object .SKEL files, ARCTIC template folders and catalogue names "
        "(see `handsim catalog`)",
    )


def test_row_a_directory_named_like_a_motion_is_called_a_directory(capsys, tmp_path):
    folder = tmp_path / "x.MOTION"
    folder.mkdir()
    result = run(capsys, "inspect", folder)
    assert (result.code, result.first) == (1, f"handsim: error: {folder}: is a directory, expected a file")


# --------------------------------------------------------------------------------------------------
# Rows of issue 14's catalogue: wrong rejections, now read


def test_row_a_byte_order_mark_before_a_graspdb14_recording_is_read(capsys, tmp_path):
    path = write(tmp_path / REC, b"\xef\xbb\xbf" + glove_rows(4).replace("\n", "\r\n").encode())
    result = run(capsys, "inspect", path)
    assert (result.code, result.err, result.out[0]) == (0, [], f"file       {path}")


def test_row_a_byte_order_mark_before_every_tzionas_file_is_read(capsys, tmp_path):
    root = tzionas_sample(tmp_path)
    for path in (root / "Models" / "20").iterdir():
        path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    for path in (root / "Configs" / "20").iterdir():
        path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    motion = root / "Models" / "20" / "Model_Hand_R.MOTION"
    result = run(capsys, "inspect", motion)
    assert (result.code, result.err, result.out[0]) == (0, [], f"file       {motion}")


# --------------------------------------------------------------------------------------------------
# Earlier rows (readers and inputs) that already gave a clear error, kept as they are


def test_earlier_row_a_missing_recording_is_file_not_found(capsys, tmp_path):
    result = run(capsys, "inspect", tmp_path / REC)
    assert (result.code, result.first) == (1, f"handsim: error: {tmp_path / REC}: file not found")


def test_earlier_row_an_empty_recording_says_what_a_row_holds(capsys, tmp_path):
    path = write(tmp_path / REC, "\n")
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: empty file: expected rows of 30 blank-separated entries (YYYY MM DD HH mm "
        "ss.sssss switch, then 23 sensor values in radians)",
    )


def test_earlier_row_a_raw_file_without_calibration_says_how_to_calibrate(capsys, tmp_path):
    path = write(tmp_path / REC.replace("-rad-", "-raw-"), glove_rows(4, counts=True))
    result = run(capsys, "inspect", path)
    assert result.code == 1
    assert result.first.startswith(
        f"handsim: error: {path}: this is a raw-count file ('-raw-' in its name); "
    )


def test_earlier_row_nan_in_a_recording_names_line_and_sensor(capsys, tmp_path):
    rows = glove_rows(4).splitlines()
    rows[1] = rows[1].replace("0.01000", "nan", 1)
    path = write(tmp_path / REC, "\n".join(rows) + "\n")
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:2 [sensor T-TMCJ]: expected a finite number, got 'nan'",
    )


def test_earlier_row_time_stamps_that_go_back_name_both_lines(capsys, tmp_path):
    rows = glove_rows(4).splitlines()
    rows[1], rows[2] = rows[2], rows[1]
    path = write(tmp_path / REC, "\n".join(rows) + "\n")
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:3 [timestamp]: time stamp '2014 09 15 08 02 09.04000' is not after the "
        "previous row's '2014 09 15 08 02 09.05600' (line 2); time stamps must strictly increase",
    )


def test_earlier_row_a_mesh_without_units_asks_for_them(capsys, tmp_path):
    path = write(tmp_path / "box.obj", box_text("obj"))
    result = run(capsys, "build", "object", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: give the mesh's units (--units m or --units mm); a wrong guess scales it "
        "1000×",
    )


def test_earlier_row_a_mesh_in_mm_read_as_metres_suggests_mm(capsys, tmp_path):
    path = write(tmp_path / "box.obj", box_text("obj"))
    result = run(capsys, "build", "object", path, "--units", "m")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: the object is 50 m across with --units m, outside the plausible 5 mm – "
        "0.6 m; are the coordinates in mm? (give --units mm)",
    )


def test_earlier_row_an_unknown_catalogue_name_lists_the_catalogue(capsys):
    result = run(capsys, "build", "object", "teapot")
    assert result.code == 1
    assert result.first.startswith("handsim: error: unknown object 'teapot'; catalogue objects are: bottle, ")


def test_earlier_row_a_skel_without_its_limits_names_the_missing_file(capsys, tmp_path):
    models = tmp_path / "Models" / "20"
    models.mkdir(parents=True)
    shutil.copy(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.SKEL", models)
    result = run(capsys, "build", "hand", models / "Model_Hand_R.SKEL")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {models / 'Model_Hand_R.LIMITS'}: file not found; a .SKEL needs its .LIMITS beside "
        "it (same stem)",
    )


# --------------------------------------------------------------------------------------------------
# The same missing file gives the same exit code and the same first line from every command: a missing input
# is a handsim error (exit 1, docs/cli.md), never a usage error


def arctic_sequence(tmp_path: Path) -> tuple[Path, Path]:
    """An ARCTIC sequence with its object motion and template, and a folder of synthetic MANO models.

    The sequence is ``raw_seqs/s01/phone_grab_01.mano.npy`` of a root in ARCTIC's layout.
    """
    from tests.arctic_fixtures import recording, write_template
    from tests.mano_fixtures import (
        mano_hand_params,
        write_arctic_mano_npy,
        write_arctic_object_npy,
        write_synthetic_mano_pkl,
    )

    mano = tmp_path / "mano"
    mano.mkdir()
    for side in ("right", "left"):
        write_synthetic_mano_pkl(mano / f"MANO_{side.upper()}.pkl", side=side)
    raw = tmp_path / "arctic" / "raw_seqs" / "s01"
    raw.mkdir(parents=True)
    path = raw / "phone_grab_01.mano.npy"
    write_arctic_mano_npy(path, mano_hand_params(12, 1), mano_hand_params(12, 2, side="left"))
    write_arctic_object_npy(raw / "phone_grab_01.object.npy", recording("phone", 12))
    write_template(tmp_path / "arctic" / "meta" / "object_vtemplates", "phone")
    return path, mano


def every_command(path: Path, mano: Path, tmp_path: Path) -> dict[str, list[str | Path]]:
    """Each command that reads an ARCTIC sequence, with its arguments."""
    return {
        "replay": ["replay", path, "--mano-dir", mano],
        "inspect": ["inspect", path, "--mano-dir", mano],
        "correct": ["correct", path, "--mano-dir", mano, "-o", tmp_path / "phone.corrected.npz"],
        "report": ["report", path, "--mano-dir", mano, "-o", tmp_path / "out"],
    }


def test_row_a_missing_arctic_object_motion_is_the_same_handsim_error_from_every_command(capsys, tmp_path):
    path, mano = arctic_sequence(tmp_path)
    motion = path.with_name("phone_grab_01.object.npy")
    motion.unlink()
    line = (
        f"handsim: error: {motion}: file not found; the ARCTIC sequence phone_grab_01.mano.npy needs its "
        "object motion phone_grab_01.object.npy (from the same raw_seqs folder)"
    )
    for command, argv in every_command(path, mano, tmp_path).items():
        result = run(capsys, *argv)
        assert (result.code, result.first) == (1, line), command
    assert not (tmp_path / "out").exists()  # refused before any run


def test_row_a_missing_arctic_template_is_the_same_handsim_error_from_every_command_that_reads_it(
    capsys, tmp_path
):
    path, mano = arctic_sequence(tmp_path)
    template = tmp_path / "arctic" / "meta" / "object_vtemplates" / "phone"
    shutil.rmtree(template)
    commands = every_command(path, mano, tmp_path)
    for command in ("replay", "correct", "report"):
        result = run(capsys, *commands[command])
        assert (result.code, result.first) == (
            1,
            f"handsim: error: {template}: ARCTIC template folder not found",
        )
    # inspect needs the template only for its side check, which then says why it was not run
    result = run(capsys, *commands["inspect"])
    assert result.code == 0
    assert f"sides      not checked: {template}: ARCTIC template folder not found" in result.out


# --------------------------------------------------------------------------------------------------
# Bounded reads: a pipe, a device or a socket is never opened, a file's size and a .npy header are checked
# before anything is read or allocated. A command that reads without bound would block or fill the memory,
# so these rows run it in a child process with a time limit.


def bounded(*argv: str | Path, timeout: float = 120) -> Outcome:
    """``handsim ARGV`` in a child process that must end within ``timeout`` seconds."""
    done = subprocess.run(
        [sys.executable, "-m", "handsim.cli", *map(str, argv)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=child_env(),
        check=False,
    )
    return Outcome(done.returncode, done.stderr.splitlines(), done.stdout.splitlines())


NOT_REGULAR = (
    "not a regular file; handsim reads regular files only (a pipe or a device may block or never end)"
)


@linux_only
def test_row_a_named_pipe_named_like_a_recording_is_refused_not_waited_on(tmp_path):
    fifo = tmp_path / REC
    os.mkfifo(fifo)
    result = bounded("inspect", fifo, timeout=60)
    assert (result.code, result.first) == (1, f"handsim: error: {fifo}: a named pipe (FIFO), {NOT_REGULAR}")


@linux_only
def test_row_dev_zero_linked_as_a_recording_is_refused_not_read_without_end(tmp_path):
    link = tmp_path / REC
    link.symlink_to("/dev/zero")
    result = bounded("inspect", link, timeout=60)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {link}: a character device (/dev/zero), {NOT_REGULAR}",
    )


@linux_only
def test_row_a_dataset_with_a_pipe_and_a_device_lists_them_unknown_without_opening_them(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    os.mkfifo(data / REC)
    (data / "04_ex01-rad-045-grasp-su03.txt").symlink_to("/dev/urandom")
    result = bounded("report", data, "-o", tmp_path / "out", timeout=120)
    assert (result.code, result.first) == (2, f"handsim report: error: no trial in {data}")
    unknown = [line for line in result.out if line.startswith("unknown")]
    assert len(unknown) == 2
    assert unknown[0].endswith(
        f"{REC}: a named pipe (FIFO), not a regular file (not read: it could block or never end)"
    )
    assert unknown[1].endswith(
        "04_ex01-rad-045-grasp-su03.txt: a character device, not a regular file (not read: it could block or "
        "never end)"
    )


@pytest.mark.skipif(not hasattr(socket, "AF_UNIX"), reason="needs Unix domain sockets")
def test_row_a_socket_named_like_a_recording_is_refused(capsys):
    folder = Path(tempfile.mkdtemp(prefix="hs"))  # short: a socket's path has at most 107 bytes
    path = folder / REC
    server = socket.socket(socket.AF_UNIX)
    try:
        server.bind(str(path))
        result = run(capsys, "inspect", path)
    finally:
        server.close()
        shutil.rmtree(folder)
    assert (result.code, result.first) == (1, f"handsim: error: {path}: a socket, {NOT_REGULAR}")


def test_row_a_recording_over_the_size_limit_is_refused_before_it_is_read(capsys, tmp_path):
    from handsim.io.text_files import MAX_RECORDING_BYTES

    path = tmp_path / REC
    with path.open("wb") as f:
        f.truncate(MAX_RECORDING_BYTES + 1)  # sparse: nothing is written
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: 67108865 bytes, more than the 64 MiB (67108864 bytes) handsim reads from a "
        "glove recording (about 80 minutes at 60 Hz; reading and replaying it takes memory in proportion): "
        "cut it into shorter recordings",
    )


def test_row_a_mesh_over_the_size_limit_is_refused_before_it_is_read(capsys, tmp_path):
    from handsim.io.text_files import MAX_FILE_BYTES

    path = tmp_path / "huge.obj"
    with path.open("wb") as f:
        f.truncate(MAX_FILE_BYTES + 1)
    result = run(capsys, "build", "object", path, "--units", "mm")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: 268435457 bytes, more than the 256 MiB (268435456 bytes) handsim reads "
        "from an input file",
    )


def arctic_files(folder: Path, right_shape: np.ndarray | None = None) -> tuple[Path, Path, Path]:
    """An ARCTIC root in ``folder``: ``raw_seqs/s01/phone_grab_01.mano.npy`` (12 frames of both hands, the
    right hand's betas ``right_shape`` when given), its ``.object.npy`` and the phone's template; and a folder
    of synthetic MANO models.

    Returns:
        The ``.mano.npy``, the ``.object.npy`` and the MANO folder.
    """
    from tests.arctic_fixtures import recording, write_template
    from tests.mano_fixtures import (
        mano_hand_params,
        write_arctic_mano_npy,
        write_arctic_object_npy,
        write_synthetic_mano_pkl,
    )

    raw = folder / "arctic" / "raw_seqs" / "s01"
    raw.mkdir(parents=True)
    right = mano_hand_params(12, 1)
    if right_shape is not None:
        right["shape"] = right_shape.astype(np.float32)
    mano = raw / "phone_grab_01.mano.npy"
    write_arctic_mano_npy(mano, right, mano_hand_params(12, 2, side="left"))
    write_arctic_object_npy(raw / "phone_grab_01.object.npy", recording("phone", 12))
    write_template(folder / "arctic" / "meta" / "object_vtemplates", "phone")
    models = folder / "mano"
    models.mkdir()
    for side in ("right", "left"):
        write_synthetic_mano_pkl(models / f"MANO_{side.upper()}.pkl", side=side)
    return mano, raw / "phone_grab_01.object.npy", models


def test_row_an_npy_header_claiming_a_trillion_rows_is_refused_naming_shape_and_size(capsys, tmp_path):
    import io

    mano, motion, models = arctic_files(tmp_path)
    data = np.load(motion)
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": data.dtype.str, "fortran_order": False, "shape": (10**12, 7)}
    )
    motion.write_bytes(header.getvalue() + data.tobytes())
    for command in ("inspect", "replay"):
        result = run(capsys, command, mano, "--mano-dir", models)
        assert (result.code, result.first) == (
            1,
            f"handsim: error: {motion}: the header declares an array of shape (1000000000000, 7) and dtype "
            "float32 (28000000000000 bytes of data), but the file holds 336 bytes after its header: a "
            "truncated or corrupted file",
        ), command


# --------------------------------------------------------------------------------------------------
# Silent results, now refused, flagged or noted


def test_row_an_empty_limits_beside_a_skel_is_refused_not_built_as_a_rigid_hand(capsys, tmp_path):
    models = tzionas_sample(tmp_path) / "Models" / "20"
    limits = write(models / "Model_Hand_R.LIMITS", "\n")
    result = run(capsys, "build", "hand", models / "Model_Hand_R.SKEL")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {limits}: no bone entries (the file is empty or blank): expected 8 lines per bone "
        "(name, flags 't rx ry rz', 3 axis lines, 3 'min max' lines), at least one for the root bone "
        "'Lower Arm R'; without them the model would have no degree of freedom",
    )


def test_row_a_motionless_recording_is_flagged_and_its_hold_says_no_grasp(capsys, tmp_path):
    path = glove_recording(tmp_path, np.tile(0.5 * FLEXED, (60, 1)), np.arange(60) / 60)
    code, first, out = cli(["replay", str(path)], capsys)
    assert (code, first) == (0, "")
    assert (
        "flag        no_motion (a note): the hand does not move: all 60 rows hold the same joint angles, so "
        "the recording holds no grasp (a glove lying still, or a frozen data stream?)"
    ) in out.splitlines()
    (held,) = [line for line in out.splitlines() if line.startswith("held ")]
    assert held.startswith(
        "held        not judged: no grasp in the recording (the summed finger flexion spans "
    )


def test_row_a_switch_off_in_every_row_is_flagged(capsys, tmp_path):
    ramp = np.clip(np.linspace(-0.3, 1.3, 60), 0.0, 1.0)[:, None] * FLEXED
    path = glove_recording(tmp_path, ramp, np.arange(60) / 60)
    path.write_text(path.read_text().replace(" 1 ", " 0 "))  # the switch, the first lone 1 of each row
    result = run(capsys, "inspect", path)
    assert (result.code, result.err) == (0, [])
    assert result.out[-1] == (
        "flag       switch_off (a note): the glove's switch is off in all 60 rows; GraspDB14 actors switch "
        "it on for the task (spec §3.5–3.7): is this the recording of a task?"
    )


def _cube_report(tmp_path, capsys) -> tuple[Path, Path, dict]:
    """A report of one short scripted cube grasp: its folder, its records file and the one record."""
    from tests.helpers import write_short_grasp

    out = tmp_path / "out"
    grasp = write_short_grasp(tmp_path / "data", "cube")
    assert cli(["report", str(grasp), "-o", str(out), "--workers", "1", "--frames", "0"], capsys)[0] == 0
    records = out / "records.jsonl"
    return out, records, json.loads(records.read_text())


def test_row_a_corrupted_value_in_the_records_is_noted_naming_record_and_key(capsys, tmp_path):
    out, records, record = _cube_report(tmp_path, capsys)
    record["summary"]["max_penetration_mm"] = "lots"
    record["summary"]["valid"] = "yes"
    records.write_text(json.dumps(record) + "\n")
    code, first, stdout = cli(["report", "--render-only", str(out)], capsys)
    assert (code, first) == (0, "")
    assert stdout.splitlines()[:2] == [
        f"note        {records}: record 1 ('cube.grasp.json#1'): summary 'max_penetration_mm' is 'lots', "
        "expected a finite number: shown as missing and left out of every statistic",
        f"note        {records}: record 1 ('cube.grasp.json#1'): summary 'valid' is 'yes', expected true or "
        "false: shown as missing and left out of every statistic",
    ]
    assert "'max_penetration_mm' is 'lots'" in (out / "report.md").read_text()  # the report says it too


def test_row_per_frame_lists_in_the_records_are_read_as_lists_of_numbers(capsys, tmp_path):
    out, records, record = _cube_report(tmp_path, capsys)
    record.setdefault("trajectory_quality", {})["spike_frames"] = [3, 17]  # a glove recording's spikes
    record["summary"]["grip_links"] = ["th_tmc", "if_dip"]  # names, not numbers
    records.write_text(json.dumps(record) + "\n")
    code, first, stdout = cli(["report", "--render-only", str(out)], capsys)
    assert (code, first) == (0, "")
    assert not [line for line in stdout.splitlines() if line.startswith("note")]
    record["trajectory_quality"]["spike_frames"] = [3, "x"]
    records.write_text(json.dumps(record) + "\n")
    code, first, stdout = cli(["report", "--render-only", str(out)], capsys)
    assert stdout.splitlines()[0] == (
        f"note        {records}: record 1 ('cube.grasp.json#1'): trajectory_quality 'spike_frames' is "
        "[3, 'x'], expected a list of finite numbers: shown as missing and left out of every statistic"
    )


WHOLE = "options['{}'] must be a whole number (int), got"


@pytest.mark.parametrize(
    ("env_id", "options", "error", "message"),
    [
        (
            "handsim/Replay-v0",
            {"fram": 2},
            ValueError,
            "ReplayEnv.reset: unknown option 'fram'; its options are 'frame' (the start frame, a whole "
            "number before the last frame); 'recording' (which recording, a whole number from 0)",
        ),
        (
            "handsim/Replay-v0",
            [2],
            TypeError,
            "ReplayEnv.reset: options must be a dict or None, got list [2]",
        ),
        ("handsim/Replay-v0", {"frame": 2.7}, TypeError, f"{WHOLE.format('frame')} float 2.7"),
        ("handsim/Replay-v0", {"frame": True}, TypeError, f"{WHOLE.format('frame')} bool True"),
        ("handsim/Replay-v0", {"frame": "abc"}, TypeError, f"{WHOLE.format('frame')} str 'abc'"),
        ("handsim/Replay-v0", {"recording": 0.0}, TypeError, f"{WHOLE.format('recording')} float 0.0"),
        ("handsim/Grasp-v0", {"frame": 2}, ValueError, "GraspEnv.reset takes no options, got 'frame'"),
        (
            "handsim/Grasp-v0",
            "f=2",
            TypeError,
            "GraspEnv.reset: options must be a dict or None, got str 'f=2'",
        ),
    ],
)
def test_row_env_reset_options_are_checked_gymnasium_style(env_id, options, error, message):
    import re

    import gymnasium as gym

    import handsim  # noqa: F401  (registers the environments)

    env = gym.make(env_id).unwrapped
    with pytest.raises(error, match=f"^{re.escape(message)}$"):
        env.reset(seed=0, options=options)
    env.reset(seed=0, options={})  # no options, as None: accepted
    if env_id == "handsim/Replay-v0":
        assert env.reset(seed=0, options={"frame": np.int64(3)})[1]["frame"] == 3  # a NumPy integer is one


def test_row_an_unwritable_cache_is_reported_once_for_mesh_and_placement_writes(
    capsys, caplog, tmp_path, monkeypatch
):
    from tests.helpers import write_short_grasp

    blocker = write(tmp_path / "cache", "a file where the cache folder should be")
    monkeypatch.setenv("HANDSIM_CACHE_DIR", str(blocker))
    grasp = write_short_grasp(tmp_path / "data", "cube")
    with caplog.at_level("WARNING", logger="handsim"):
        code, _, out = cli(["replay", str(grasp)], capsys)
        assert code == 0
        cli(["replay", str(grasp)], capsys)  # again: the folder was reported already
    reported = [r.getMessage() for r in caplog.records if "cannot be written" in r.getMessage()]
    assert len(reported) == 1
    assert reported[0].endswith(
        f"; the cache folder {blocker} cannot be written, so cached results are computed again on every run "
        "(make it writable, or set HANDSIM_CACHE_DIR to a writable folder)"
    )
    assert f"could not write placement cache entry {blocker / 'placement'}" in out


def test_row_an_unwritable_hull_cache_is_reported(capsys, caplog, tmp_path):
    blocker = write(tmp_path / "cache", "a file where the cache folder should be")
    argv = build_ring(tmp_path)[3:]  # build object ring.stl --units m
    with caplog.at_level("WARNING", logger="handsim"):
        code, first, _ = cli([*argv, "--cache-dir", str(blocker)], capsys)
    assert (code, first.startswith("CoACD") or first == "") == (0, True)
    (message,) = [r.getMessage() for r in caplog.records if "cannot be written" in r.getMessage()]
    assert message.startswith(f"could not write hull cache entry {blocker / 'coacd'}")


def test_row_a_hand_position_a_thousand_km_away_is_a_usage_error(capsys):
    result = run(capsys, "build", "scene", "--hand-pos", "1e6", "0", "0.1")
    assert result.code == 2
    assert result.first == (
        "handsim build scene: error: argument --hand-pos: expected a coordinate within ±1 m of the table "
        "top's centre (the table is 1 m × 0.7 m, its top at z = 0), got 1e6"
    )
    assert result.err[1].startswith("usage: handsim build scene ")


def test_row_calibrated_targets_beyond_7_rad_are_refused_naming_gain_and_line(capsys, tmp_path):
    from handsim.glove.calibration import GloveCalibration

    gains = [-0.015] * 23
    gains[4] = -1000.0  # I-MCPJ: a typing error for -0.01
    calibration = GloveCalibration(gains=tuple(gains), offsets=(100.0,) * 23, provenance="typo")
    cal = write(tmp_path / "cal.json", json.dumps(calibration.to_dict()))
    path = write(tmp_path / REC.replace("-rad-", "-raw-"), glove_rows(4, counts=True))
    result = run(capsys, "inspect", path, "--calibration", cal)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:1 [sensor I-MCPJ]: count 104 becomes -4000 rad with the calibration 'typo' "
        "(gain -1000 rad/count, offset 100), beyond the 7 rad no joint angle exceeds (|angle| ≤ 2π; 4 "
        "calibrated values are): is the calibration this glove's?",
    )


def test_row_two_cubes_half_a_metre_apart_in_one_obj_are_noted(capsys, tmp_path):
    near, far = trimesh.creation.box((0.05, 0.05, 0.05)), trimesh.creation.box((0.05, 0.05, 0.05))
    far.apply_translation((0.5, 0.0, 0.0))
    path = write(tmp_path / "two.obj", trimesh.util.concatenate([near, far]).export(file_type="obj"))
    result = run(capsys, "build", "object", path, "--units", "m", "--no-cache")
    assert result.code == 0
    assert (
        "note       the mesh has 2 disconnected parts, apart from one another (no edge joins them and their "
        "bounding boxes do not meet); they are simulated as one rigid object: split the file to get separate "
        "objects"
    ) in result.out


def test_a_mug_whose_handle_is_its_own_shell_is_one_part():
    from handsim.builders.catalog import get

    assert "disconnected parts" not in str(get("mug"))  # two closed shells that meet: one object


# --------------------------------------------------------------------------------------------------
# Vague messages, now naming the file, line, field and what was expected


@linux_only
def test_row_a_file_size_limit_while_recording_names_the_records_file_and_leaves_no_partial_line(
    capsys, tmp_path, monkeypatch
):
    import resource

    from tests.helpers import write_short_grasp

    monkeypatch.setenv("HANDSIM_CACHE_DIR", str(tmp_path / "cache"))
    grasp = write_short_grasp(tmp_path / "data", "cube")
    assert cli(["replay", str(grasp)], capsys)[0] == 0  # mesh and placement cached: the child writes neither
    out = tmp_path / "out"

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (8192, 8192))  # `ulimit -f 8`: run.json fits, a record not

    argv = ["report", str(grasp), "-o", str(out), "--workers", "1", "--frames", "0"]
    done = subprocess.run(
        [sys.executable, "-m", "handsim.cli", *argv],
        capture_output=True, text=True, timeout=300, env=child_env(), preexec_fn=small_files, check=False,
    )  # fmt: skip
    assert (done.returncode, done.stderr.splitlines()[0]) == (
        1,
        f"handsim: error: {out / 'records.jsonl'}: File too large",
    )
    assert (out / "records.jsonl").read_bytes() == b""  # the failed line was cut back


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("v 0.1 abc 0.2", "2 [vertex]: expected a number, got 'abc'"),
        ("v 0.1 0.2", "2 [vertex]: expected 3 to 7 numbers after 'v', got 2"),
        (
            "f 1 2 100",
            "10 [face index]: vertex index 100 out of range; expected 1..8 or -8..-1 (counting back from the "
            "last vertex read): the file has 8 vertices and OBJ indices are 1-based",
        ),
        (
            "f 1 2 0",
            "10 [face index]: vertex index 0 out of range; expected 1..8 or -8..-1 (counting back from the "
            "last vertex read): the file has 8 vertices and OBJ indices are 1-based",
        ),
        ("f 1 2", "10 [face]: a face needs at least 3 vertex indices, got 2"),
        (
            "f 1 2 x",
            "10 [face index]: expected a vertex index (a whole number, optionally followed by "
            "/texture/normal indices), got 'x'",
        ),
    ],
)
def test_row_an_obj_with_a_bad_line_names_the_file_the_line_and_what_was_expected(
    capsys, tmp_path, line, message
):
    lines = box_text("obj").splitlines()
    index = 1 if line.startswith("v") else 9
    assert lines[index].split()[0] == line.split()[0]
    lines[index] = line
    path = write(tmp_path / "box.obj", "\n".join(lines) + "\n")
    result = run(capsys, "build", "object", path, "--units", "mm")
    assert (result.code, result.first) == (1, f"handsim: error: {path}:{message}")


@pytest.mark.parametrize("value", ["-1", "0", "two"])
def test_row_workers_that_are_no_whole_number_of_at_least_1_say_what_is_accepted(capsys, value):
    result = run(capsys, "report", str(SCRIPTED), "--workers", value)
    shown = repr(value) if value == "two" else value
    assert (result.code, result.first) == (
        2,
        f"handsim report: error: argument --workers: expected a whole number ≥ 1, got {shown}",
    )


def test_row_a_non_finite_beta_is_called_a_beta_not_a_frame(capsys, tmp_path):
    betas = np.zeros(10)
    betas[3] = np.nan
    mano, _, _ = arctic_files(tmp_path, right_shape=betas)
    result = run(capsys, "inspect", mano)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {mano} [right.shape]: non-finite value at beta 3",
    )


@pytest.mark.parametrize(
    ("data", "after_path"),
    [
        (
            glove_rows(4).encode("utf-16"),
            ": not a UTF-8 text file: it starts with a UTF-16 byte-order mark; save it as UTF-8 text",
        ),
        (
            glove_rows(4).replace("\n", "\x00\n", 2).encode(),
            ":1: not a UTF-8 text file: a NUL byte at byte 212 (binary data, or UTF-16/32 text); save it as "
            "UTF-8 text",
        ),
    ],
    ids=["utf-16", "nul"],
)
def test_row_utf16_or_nul_bytes_in_a_recording_say_not_a_utf8_text_file(capsys, tmp_path, data, after_path):
    path = write(tmp_path / REC, data)
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (1, f"handsim: error: {path}{after_path}")


def test_row_mano_betas_scaled_a_millionfold_are_refused_naming_the_side_the_beta_and_its_value(
    capsys, tmp_path
):
    betas = np.linspace(-1.0, 1.0, 10) * 1e6
    mano, _, models = arctic_files(tmp_path, right_shape=betas)
    result = run(capsys, "replay", mano, "--mano-dir", models)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {mano} [right.shape]: beta 0 is -1e+06 (10 beyond the limit); MANO betas are in "
        "standard deviations of its shape space and fitted hands lie within a few units of 0, expected "
        "|beta| ≤ 10: a corrupted or mis-scaled shape",
    )
    assert result.out == []  # refused before any model is built or replayed


def test_row_a_rot_cut_to_10_frames_names_rot_not_pose(capsys, tmp_path):
    from tests.mano_fixtures import mano_hand_params, write_arctic_mano_npy

    mano, _, models = arctic_files(tmp_path)
    right = mano_hand_params(12, 1)
    right["rot"] = right["rot"][:10]
    write_arctic_mano_npy(mano, right, mano_hand_params(12, 2, side="left"))
    result = run(capsys, "inspect", mano, "--mano-dir", models)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {mano} [right.rot]: 10 frames, but right.pose and right.trans have 12; expected "
        "one row per frame in every field (a truncated or misaligned field)",
    )


def test_row_a_mesh_over_the_face_limit_is_announced_before_coacd_starts(capsys, tmp_path, monkeypatch):
    import handsim.builders.decompose as decompose
    from handsim.builders.decomposition_types import DecompositionError

    mesh = tmp_path / "ring.stl"
    ring = trimesh.creation.annulus(r_min=0.03, r_max=0.05, height=0.02, sections=16)
    ring.export(mesh)
    started = []

    def no_coacd(mesh, params, name, progress):  # the warning must come first; CoACD never runs here
        started.append(name)
        raise DecompositionError(f"{name}: CoACD not run in this test")

    monkeypatch.setattr(decompose, "COACD_FACE_WARNING", len(ring.faces) - 1)
    monkeypatch.setattr(decompose, "run_worker", no_coacd)
    monkeypatch.setenv("HANDSIM_CACHE_DIR", str(tmp_path / "cache"))
    result = run(capsys, "build", "object", mesh, "--units", "m")
    assert (result.code, result.first) == (
        1,
        f"handsim: warning: {mesh}: {len(ring.faces)} faces, more than the {len(ring.faces) - 1} beyond "
        "which CoACD may run until its 600 s timeout; decimate the mesh first to decompose it in seconds",
    )
    assert started == [str(mesh)]


def test_row_a_mass_out_of_range_on_the_command_line_suggests_force_not_force_true(capsys, tmp_path):
    path = tmp_path / "crate.obj"
    trimesh.creation.box(extents=(0.5, 0.5, 0.5)).export(path)
    result = run(capsys, "build", "object", path, "--units", "m")
    assert (result.code, result.first) == (
        1,
        "handsim: error: object 'crate' mass 125 kg (1.25e+05 cm³ at 1000 kg/m³) is outside the plausible "
        "0.001 to 23 kg (household objects a hand grasps), see docs/objects.md; give --force to use it "
        "anyway",
    )
