"""``handsim correct`` of glove grasps: the hold objective, its verdict, and the replay of the corrected file.

Fast by construction: the bundled scripted tennis-ball grasp (3.3 s, its ball placed into the hand, held
through its hold window) corrected with a few samples over a short horizon. What is pinned: the goal is the
ball's placed pose over the release … window's end and planning starts where the hand can act on it; the
committed simulation is the replay of the corrected recording (``correct`` checks it), and the corrected file
replays bit for bit through ``load_trial`` and ``handsim replay``; a grasp that slips out, or whose hold the
replay's grip check rejects, is reported "not corrected" with the replay's reason.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from handsim.assets import ASSETS_DIR
from handsim.cli import main
from handsim.correct import CorrectionConfig, correct, write_corrected
from handsim.correct.hold import HELD, NOT_HELD, NOT_JUDGED
from handsim.correct.score import Tracking, hold_verdict
from handsim.io.corrected import read_corrected
from handsim.sim.replay import ReplayConfig, replay
from handsim.trials import load_trial

BALL = ASSETS_DIR / "demo" / "tennis_ball.grasp.json"
FAST = CorrectionConfig(samples=4, iterations=1, horizon=15)
"""A correction small enough for a test: 4 candidates, one round, 0.15 s ahead."""


@pytest.fixture(scope="module")
def ball():
    return load_trial(BALL)


@pytest.fixture(scope="module")
def corrected(ball):
    return correct(ball, FAST, threads=1)


def test_the_goal_is_the_placed_pose_over_the_hold(corrected):
    reference = corrected.reference
    goal, switches = reference.goal, reference.switches
    schedule = reference.schedule
    assert goal is not None and reference.hands == ()  # fingers only: a glove records no wrist
    held = np.flatnonzero(goal.valid)
    assert held[0] == switches.release_frame
    assert held[-1] == schedule.frame_at(reference.scene.setup.hold_window[1]) == reference.plan_stop
    placed = reference.scene.model.qpos0[goal.qpos : goal.qpos + 7]
    assert np.array_equal(goal.placed, placed)
    assert np.array_equal(corrected.plan.qpos[0, goal.qpos : goal.qpos + 7], placed)
    # the recording's own targets where nothing is planned (after the hold window)
    assert not np.any(corrected.plan.residual[reference.plan_stop + 1 :])


def test_the_score_says_whether_the_grasp_holds(corrected):
    score = corrected.score
    assert score.objective == "hold"
    assert score.before.track == HELD and score.after.track == HELD
    assert score.status == "corrected" and "holds already in pure replay" in score.reason
    assert score.wrist_position_rms_mm is None
    assert 0 < score.finger_rms_deg <= score.finger_max_deg <= math.degrees(FAST.finger_bound) + 1e-9
    assert 0 <= score.after.within_1cm <= 1 and score.after.max_drift_mm >= score.after.mean_drift_mm


def test_the_corrected_glove_file_replays_bit_for_bit(corrected, tmp_path, capsys):
    path = write_corrected(tmp_path / "ball.corrected.npz", corrected)
    header = read_corrected(path).header
    assert header["objects"] == [] and header["hands"] == []
    assert header["score"]["objective"] == "hold"
    loaded = load_trial(path)
    assert loaded.scene.model_sha256 == corrected.loaded.scene.model_sha256
    again = replay(loaded.scene, loaded.trajectory, ReplayConfig(keep_states=True, ensemble=False))
    assert np.array_equal(again.states, corrected.plan.qpos)
    assert again.hold.held is True
    assert main(["replay", str(path)]) == 0
    printed = capsys.readouterr().out
    assert "trial       corrected" in printed and "held" in printed


def test_a_grasp_that_slips_out_is_not_corrected_with_the_replays_reason(tmp_path):
    weak = json.loads(BALL.read_text())
    weak.update(closure=0.2, description="the tennis-ball grasp closed to 0.2: the ball slips out")
    path = tmp_path / "weak.grasp.json"
    path.write_text(json.dumps(weak))
    correction = correct(load_trial(path), FAST, threads=1)
    score = correction.score
    assert score.before.track == NOT_HELD and score.after.track == NOT_HELD
    assert score.status == "not corrected"
    assert "keeps the object in the hand: lost at" in score.reason and "relative to the hand" in score.reason


def test_the_same_seed_gives_the_same_glove_file(ball, corrected):
    from handsim.correct.trial_file import corrected_bytes

    assert corrected_bytes(correct(ball, FAST, threads=2)) == corrected_bytes(corrected)


def test_the_cli_corrects_a_glove_grasp(tmp_path, capsys):
    out = tmp_path / "ball.corrected.npz"
    args = ["--samples", "3", "--iterations", "1", "--horizon", "5", "--threads", "1"]
    assert main(["correct", str(BALL), "-o", str(out), *args]) == 0
    printed = capsys.readouterr().out
    assert "wrist         not corrected" in printed
    assert any(line.startswith("before") and "held" in line for line in printed.splitlines())
    assert any(line.startswith("corrected") for line in printed.splitlines())
    assert out.is_file()


def _hold_tracking(track: str, reason: str) -> Tracking:
    return Tracking(1.0, 2.7, 7.2, 3.0, track, reason, 1.0)


def test_a_hold_the_grip_check_rejects_is_not_corrected_and_a_short_window_not_judged():
    config = CorrectionConfig()
    before = _hold_tracking(NOT_HELD, "lost at 2.94 s: slipped 2.0 cm relative to the hand")
    no_grip = _hold_tracking(NOT_JUDGED, "not judged: no grip: … in 0% of the hold window")
    status, reason = hold_verdict(before, no_grip, config, gripped=True)
    assert status == "not corrected"
    assert "grip check accepts: not judged: no grip" in reason and "mean displacement 2.7 mm" in reason
    short = _hold_tracking(NOT_JUDGED, "not judged: the hold window lasts 0.10 s after the release")
    status, reason = hold_verdict(short, short, config, gripped=False)
    assert status == "not judged" and reason.endswith("lasts 0.10 s after the release")


def test_a_link_too_deep_before_planning_starts_leaves_the_correction_not_judged(graspdb_dir):
    """GraspDB14 04_ex01: the thumb's tip is 5.1 mm in the ball at 1.140 s, the first frame planned from."""
    correction = correct(load_trial(graspdb_dir / "04_ex01-rad-045-grasp-su03.txt"), FAST, threads=1)
    score = correction.score
    start = correction.reference.schedule.times[correction.reference.plan_start]
    assert correction.after.grip.deepest_at <= start + 1e-9
    assert score.status == "not judged" and "inside the object at 1.140 s" in score.reason
