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
        f"handsim: error: {path}: give the mesh's units ('m' or 'mm'); a wrong guess scales it 1000×",
    )


def test_earlier_row_a_mesh_in_mm_read_as_metres_suggests_mm(capsys, tmp_path):
    path = write(tmp_path / "box.obj", box_text("obj"))
    result = run(capsys, "build", "object", path, "--units", "m")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: the object is 50 m across in units='m', outside the plausible 5 mm – "
        "0.6 m; are the coordinates in mm? (pass units='mm')",
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
