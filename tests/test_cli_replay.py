"""``handsim replay`` run as a user would: summaries, JSON, plots, videos, exit codes."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

from handsim.assets import TZIONAS_DIR
from handsim.cli import main

ROOT = Path(__file__).resolve().parents[1]
MOTION = str(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION")
GRASPDB_TRIAL = "r_01_11_ex03-rad-004-grasp-su04.txt"


def _labels(out: str) -> list[str]:
    return [line.split()[0] for line in out.splitlines() if line.strip()]


def _numbers_or_none(values: list) -> bool:
    return all(v is None or (isinstance(v, (int, float)) and math.isfinite(v)) for v in values)


def test_replay_of_the_bundled_tzionas_sequence_prints_the_summary_and_writes_json(capsys, tmp_path):
    out_json = tmp_path / "out" / "seq20.json"
    assert main(["replay", MOTION, "--json", str(out_json)]) == 0
    out = capsys.readouterr().out
    labels = _labels(out)
    for label in ("trial", "hand", "object", "scenario", "frames", "warnings", "diverged", "penetration"):
        assert label in labels
    for label in ("contact", "tracking", "tips", "drift", "rotation", "wrote"):
        assert label in labels
    assert "held" not in labels  # a recorded-object trial has no hold window
    assert "object      cube (MODELS_INFO.txt:3, follows track 'cube'), 88.7 g" in out
    assert "scenario    recorded" in out
    assert "frames      617 at 100 Hz (5 steps of 2 ms), 6.16 s" in out

    record = json.loads(out_json.read_text())
    summary = record["summary"]
    for key in (
        "mean_drift_mm",
        "max_drift_mm",
        "final_drift_mm",
        "within_tolerance",
        "max_rotation_drift_deg",
    ):
        assert isinstance(summary[key], float) and math.isfinite(summary[key])
    assert 0.0 <= summary["within_tolerance"] <= 1.0
    assert summary["diverged"] is False and record["diverged"] is None
    assert record["hold"] is None
    assert record["trial"]["kind"] == "tzionas"
    curves = record["curves"]
    n = summary["frames"]
    assert len(curves["times_s"]) == n and _numbers_or_none(curves["times_s"])
    for key in ("penetration_mm", "tracking_error_deg", "max_tip_error_mm"):
        assert len(curves[key]) == n and _numbers_or_none(curves[key])
    assert list(curves["drift_mm"]) == ["obj"] and _numbers_or_none(curves["drift_mm"]["obj"])
    assert set(curves["contacts_per_link"]) == set(record["scene"]["links"])
    assert curves["slip_mm"] is None


def test_replay_of_a_graspdb_trial_uses_the_object_of_its_file_name(capsys, tmp_path, graspdb_dir):
    out_json = tmp_path / "glove.json"
    assert main(["replay", str(graspdb_dir / GRASPDB_TRIAL), "--json", str(out_json)]) == 0
    out = capsys.readouterr().out
    assert "hand        parametric default hand, 0.19 m (27 DoFs)" in out
    assert "object      tennis_ball (object id 1 in the file name), 57.5 g" in out
    assert "scenario    glove" in out
    for label in ("placement", "release", "held", "episode"):
        assert label in _labels(out)
    assert "\ngrip check  " in out
    # its one grasp episode, from the annotation; the ball rests on the four fingertips alone in the hold
    # window: no thumb or palm opposes them, so the hold is not judged (docs/replay.md, "A hold is a grip")
    assert "episode     1: frames 24–232 of the recording, its hold from the annotated 'grasp' phase" in out
    assert "held        not judged: no grip: " in out
    record = json.loads(out_json.read_text())
    hold = record["hold"]
    assert set(hold) >= {"held", "time_held", "max_slip", "drop", "window", "released_at"}
    assert hold["held"] is None and record["grip"]["opposition"] == 0.0
    assert record["episode"]["index"] == 1 and record["episode"]["source"] == "annotation"
    assert record["scene"]["placement"]["grasp"]["source"] == "phase"
    assert _numbers_or_none(record["curves"]["slip_mm"])
    assert record["curves"]["release_s"] == hold["released_at"]


@pytest.mark.slow
def test_replay_says_along_which_grip_direction_a_turned_hand_is_judged(capsys, graspdb_dir):
    assert main(["replay", str(graspdb_dir / "04_ex01-rad-045-grasp-su03.txt")]) == 0
    out = capsys.readouterr().out
    assert "hand turned so that gravity pulls along the grip's -x" in out


def test_replay_of_a_graspdb_trial_takes_the_given_object(capsys, graspdb_dir):
    assert main(["replay", str(graspdb_dir / GRASPDB_TRIAL), "--object", "cylinder_25mm"]) == 0
    out = capsys.readouterr().out
    assert "object      cylinder_25mm (given), 69.0 g" in out
    assert "tennis_ball" not in out


def test_replay_of_an_unknown_file_type_exits_2_naming_the_kinds(capsys, tmp_path):
    path = tmp_path / "motion.csv"
    path.write_text("1,2,3\n")
    assert main(["replay", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "handsim replay: error:" in captured.err
    assert "file type '.csv' is not a trial handsim replays" in captured.err
    assert "tzionas: " in captured.err and "graspdb: " in captured.err
    assert "Traceback" not in captured.err


def test_replay_refuses_an_object_for_a_tzionas_sequence_with_exit_2(capsys):
    assert main(["replay", MOTION, "--object", "mug"]) == 2
    assert "an object does not apply to a Tzionas sequence" in capsys.readouterr().err


def test_replay_of_a_missing_file_exits_1(capsys, tmp_path):
    assert main(["replay", str(tmp_path / "missing.txt")]) == 1
    assert "missing.txt: file not found" in capsys.readouterr().err


def test_replay_writes_a_png_plot(capsys, tmp_path):
    out_png = tmp_path / "plot" / "seq20.png"
    assert main(["replay", MOTION, "--plot", str(out_png)]) == 0
    assert f"plot        {out_png}" in capsys.readouterr().out
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _run_video(path: Path) -> subprocess.CompletedProcess:
    """The command in a fresh process: it chooses headless OpenGL itself before MuJoCo is imported."""
    command = [sys.executable, "-m", "handsim.cli", "replay", MOTION, "--video", str(path)]
    command += ["--size", "160", "120", "--no-shadows"]
    done = subprocess.run(
        command, cwd=ROOT, capture_output=True, text=True, env=dict(os.environ), timeout=300
    )
    if done.returncode == 1 and "offscreen rendering is not available" in done.stderr:
        pytest.skip(f"no OpenGL for offscreen rendering here: {done.stderr.strip()}")
    assert done.returncode == 0, done.stderr
    return done


@pytest.mark.slow
def test_replay_writes_a_gif_video(tmp_path):
    pil = pytest.importorskip("PIL.Image", reason="GIF videos need Pillow")
    out_gif = tmp_path / "seq20.gif"
    done = _run_video(out_gif)
    assert "video       " in done.stdout and "gif, camera track" in done.stdout
    with pil.open(out_gif) as image:
        assert image.n_frames == 206  # 6.16 s at 100 Hz, every 3rd frame: 33.3 fps
        assert image.size == (160, 120)


def test_replay_writes_an_mp4_video(tmp_path):
    av = pytest.importorskip("av", reason='mp4 videos need PyAV: pip install "handsim[video]"')
    out_mp4 = tmp_path / "seq20.mp4"
    _run_video(out_mp4)
    with av.open(str(out_mp4)) as container:
        frames = sum(1 for _ in container.decode(video=0))
    assert frames == 206


def test_replay_with_an_unknown_video_format_exits_1_before_replaying(capsys, tmp_path):
    assert main(["replay", MOTION, "--video", str(tmp_path / "seq20.avi")]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "unknown video format '.avi'; handsim writes .mp4 (H.264 video" in captured.err


def test_check_video_names_the_video_extra_when_pyav_is_missing(monkeypatch, tmp_path):
    from handsim.errors import HandsimError
    from handsim.viz.render import check_video

    monkeypatch.setitem(sys.modules, "av", None)  # import av raises ImportError
    with pytest.raises(HandsimError, match=r'\.mp4 videos need PyAV: pip install "handsim\[video\]"'):
        check_video(tmp_path / "a.mp4")


def test_check_video_raises_error_for_an_odd_h264_size(tmp_path):
    from handsim.errors import HandsimError
    from handsim.viz.render import check_video

    with pytest.raises(HandsimError, match=r"H\.264 needs an even image size, got 161 × 120"):
        check_video(tmp_path / "a.mp4", 161, 120)


@pytest.mark.parametrize(("frame_dt", "stride"), [(0.01, 3), (1 / 30, 1), (0.002, 17), (0.5, 1)])
def test_frame_stride_plays_videos_in_real_time_near_30_fps(frame_dt, stride):
    from handsim.viz.render import frame_stride

    assert frame_stride(frame_dt) == stride


def test_render_states_raises_error_listing_the_cameras_for_an_unknown_one():
    import numpy as np

    from handsim.builders import build_scene, default_hand
    from handsim.errors import HandsimError
    from handsim.sim.scene.compiled import compile_scene
    from handsim.viz.render import render_states

    scene = compile_scene(build_scene(default_hand()))
    states = np.zeros((2, scene.model.nq))
    with pytest.raises(
        HandsimError,
        match=r"unknown camera 'top'; the scene has \['hand_cam', 'overview', 'track', 'frame'\]",
    ):
        next(render_states(scene, states, camera="top"))
    with pytest.raises(HandsimError, match=r"states must be \(frames, \d+\) qpos rows"):
        next(render_states(scene, states[:, :3]))


def test_render_states_without_multisampling_renders_the_same_scene_and_leaves_the_model_alone():
    import numpy as np

    from handsim.builders import build_scene, default_hand
    from handsim.sim.scene.compiled import compile_scene
    from handsim.viz.render import render_states

    scene = compile_scene(build_scene(default_hand()))
    samples = int(scene.model.vis.quality.offsamples)
    assert samples > 0
    states = np.tile(scene.model.qpos0, (1, 1))
    smooth = next(render_states(scene, states, camera="track", width=160, height=120))
    jagged = next(render_states(scene, states, camera="track", width=160, height=120, multisample=False))
    assert scene.model.vis.quality.offsamples == samples
    assert smooth.shape == jagged.shape == (120, 160, 3)
    differs = np.abs(smooth.astype(int) - jagged.astype(int)).max(axis=2) > 0
    # the same picture: only edge pixels differ (anti-aliasing), never the image as a whole
    assert 0 < differs.mean() < 0.2


def test_render_states_without_shadows_makes_no_shadow_map_and_renders_the_same_pixels(monkeypatch):
    import mujoco
    import numpy as np

    import handsim.viz.render as render
    from handsim.builders import build_object, build_scene, default_hand
    from handsim.builders.catalog import get
    from handsim.sim.scene.compiled import compile_scene

    scene = compile_scene(build_scene(default_hand(), build_object(get("tennis_ball"))))
    size = int(scene.model.vis.quality.shadowsize)
    states = np.tile(scene.model.qpos0, (2, 1))
    made = []  # the shadow map size each renderer's context was made with
    real = render.offscreen_renderer

    def recorded(model, width, height):
        made.append(int(model.vis.quality.shadowsize))
        return real(model, width, height)

    monkeypatch.setattr(render, "offscreen_renderer", recorded)
    fast = list(render.render_states(scene, states, camera="track", width=160, height=120, shadows=False))
    assert made == [0] and scene.model.vis.quality.shadowsize == size > 0  # the model left alone
    # the reference: a context with the model's shadow map, shadows switched off in the scene
    reference = real(scene.model, 160, 120)
    reference.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
    data = mujoco.MjData(scene.model)
    try:
        for state, image in zip(states, fast, strict=True):
            data.qpos[:] = state
            mujoco.mj_forward(scene.model, data)
            reference.update_scene(data, camera=render._camera(scene, "track"))
            np.testing.assert_array_equal(reference.render(), image)
    finally:
        reference.close()


def test_a_diverging_replay_prints_the_divergence_and_exits_3(capsys, monkeypatch):
    from dataclasses import replace

    import handsim.trials as trial_module

    real = trial_module.load_trial

    def diverging(*args, **kwargs):
        loaded = real(*args, **kwargs)
        root = loaded.trajectory.root_pose.copy()
        root[60:, 0] += 1e9  # the root's target jumps 10⁶ km away: the weld blows up
        return replace(loaded, trajectory=replace(loaded.trajectory, root_pose=root))

    monkeypatch.setattr(trial_module, "load_trial", diverging)
    assert main(["replay", MOTION]) == 3
    out = capsys.readouterr().out
    assert "DIVERGED    mjWARN_BADQACC at step " in out
    assert "diverged    no" not in out


def test_write_video_leaves_no_partial_file_when_rendering_is_interrupted(monkeypatch, tmp_path):
    pytest.importorskip("PIL.Image", reason="GIF videos need Pillow")
    import numpy as np

    from handsim.viz import render

    def interrupted(*args: object, **kwargs: object):
        yield np.zeros((8, 8, 3), dtype=np.uint8)
        raise KeyboardInterrupt

    monkeypatch.setattr(render, "render_states", interrupted)
    with pytest.raises(KeyboardInterrupt):
        render.write_video(None, np.zeros((2, 1)), 0.01, tmp_path / "v.gif", width=8, height=8)
    assert list(tmp_path.iterdir()) == []
