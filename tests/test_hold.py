"""The hold outcome of a glove trial, judged on synthetic per-frame metrics."""

from __future__ import annotations

import numpy as np
import pytest

from handsim.sim.metrics import FrameMetrics
from handsim.sim.specs import MetricSpec
from handsim.sim.summary import hold_outcome, window_long_enough

SPEC = MetricSpec()  # slip 2 cm, contact gap 0.1 s, windows of at least 0.3 s
DT = 0.01


def _frames(n: int, slip: np.ndarray | None = None, contact: np.ndarray | None = None) -> FrameMetrics:
    """n frames 10 ms apart; the object moves ``slip`` (m) along x in the hand; contact per frame."""
    times = np.arange(n) * DT
    in_hand = np.zeros((n, 1, 3))
    if slip is not None:
        in_hand[:, 0, 0] = slip
    touching = np.ones((n, 1), bool) if contact is None else contact[:, None]
    zeros = np.zeros((n, 1, 1))
    return FrameMetrics(
        times=times, contact_count=zeros.astype(np.int32), normal_force=zeros,
        truncated_pairs=np.zeros(n, np.int32), penetration=np.zeros(n), tracking_error=np.zeros((n, 1)),
        tip_error=np.zeros((n, 1)),
        object_position_error=np.full((n, 1), np.nan), object_rotation_error=np.full((n, 1), np.nan),
        articulation_error=np.full((n, 1), np.nan), object_in_hand=in_hand, hand_contact=touching,
    )  # fmt: skip


def test_an_object_that_stays_in_hand_through_the_window_is_held():
    frames = _frames(101)
    hold = hold_outcome(frames, np.zeros(101), 0.2, (0.1, 1.0), SPEC)
    assert hold.held is True and hold.judged and hold.reason is None
    assert hold.released_at == pytest.approx(0.2) and hold.window == pytest.approx((0.2, 1.0))
    assert hold.time_held == pytest.approx(0.8)


def test_a_slip_beyond_the_limit_loses_the_object_at_its_first_frame():
    slip = np.clip((np.arange(101) * DT - 0.3) * 0.105, 0, None)  # 10.5 cm/s from 0.3 s: 1.99 cm at 0.49 s
    hold = hold_outcome(_frames(101, slip=slip), np.zeros(101), 0.2, (0.2, 1.0), SPEC)
    assert hold.held is False and hold.lost_at == pytest.approx(0.5)
    assert hold.reason == "slipped 2.1 cm relative to the hand"
    assert hold.time_held == pytest.approx(0.3) and hold.max_slip == pytest.approx(0.021)


def test_a_contact_gap_of_the_limit_loses_the_object_where_the_gap_began():
    contact = np.ones(101, bool)
    contact[40:60] = False  # 0.4–0.59 s without contact
    hold = hold_outcome(_frames(101, contact=contact), np.zeros(101), 0.2, (0.2, 1.0), SPEC)
    assert hold.held is False and hold.lost_at == pytest.approx(0.4)
    assert hold.reason == "no hand contact for 0.1 s"


def test_a_short_contact_gap_does_not_lose_the_object():
    contact = np.ones(101, bool)
    contact[40:49] = False  # 90 ms
    hold = hold_outcome(_frames(101, contact=contact), np.zeros(101), 0.2, (0.2, 1.0), SPEC)
    assert hold.held is True


@pytest.mark.parametrize(
    ("release", "window", "length"),
    [
        (0.8, (0.2, 1.0), "0.200"),  # the grasp closed near the end: 0.2 s left
        (1.0, (0.2, 1.0), "0.000"),  # released at the window's last frame
        (1.2, (0.2, 1.0), "0.000"),  # released after the window's end
        (0.5, (0.5, 0.5), "0.000"),  # an empty window
    ],
)
def test_a_window_shorter_than_the_minimum_is_not_judged(release, window, length):
    hold = hold_outcome(_frames(101), np.zeros(101), release, window, SPEC)
    assert hold.held is None and not hold.judged
    assert hold.reason.startswith(
        f"not judged: the hold window after release lasts {length} s, less than the 0.3 s"
    )
    assert hold.time_held == 0.0 and hold.lost_at is None
    assert not window_long_enough(release, window, SPEC)  # known before the run (the replay's ensemble)


def test_a_window_of_exactly_the_minimum_is_judged():
    hold = hold_outcome(_frames(101), np.zeros(101), 0.5, (0.2, 0.8), SPEC)
    assert hold.held is True and window_long_enough(0.5, (0.2, 0.8), SPEC)


def test_a_run_that_stopped_before_the_release_is_not_judged():
    hold = hold_outcome(_frames(30), np.zeros(30), 0.5, (0.2, 1.0), SPEC)
    assert hold.held is None
    assert hold.reason == "not judged: the run stopped before the release at 0.500 s"


def test_a_run_that_stopped_early_with_the_object_held_is_not_judged():
    hold = hold_outcome(_frames(80), np.zeros(80), 0.2, (0.2, 1.0), SPEC)
    assert hold.held is None
    assert hold.reason == (
        "not judged: the run stopped at 0.790 s, before the window's end at 1.000 s, "
        "with the object still held"
    )


def test_a_run_that_stopped_early_after_losing_the_object_is_not_held():
    slip = np.where(np.arange(80) * DT > 0.4, 0.05, 0.0)
    hold = hold_outcome(_frames(80, slip=slip), np.zeros(80), 0.2, (0.2, 1.0), SPEC)
    assert hold.held is False and hold.lost_at == pytest.approx(0.41)


def test_the_minimum_window_is_a_metric_spec_parameter():
    spec = MetricSpec(min_hold_window=0.1)
    assert hold_outcome(_frames(101), np.zeros(101), 0.8, (0.2, 1.0), spec).held is True
    with pytest.raises(ValueError, match="min_hold_window must be a positive finite number, got 0"):
        MetricSpec(min_hold_window=0)


def test_run_line_leaves_not_judged_holds_out_of_the_hold_rate():
    from handsim.runner.run_summary import records_line

    def record(trial_id: str, held: bool | None) -> dict:
        return {"id": trial_id, "status": "ok", "summary": {"held": held, "valid": True}}

    records = [record("a", True), record("b", False), record("c", None), record("d", None)]
    assert records_line(records) == (
        "4 trials: 4 ok, 0 diverged, 0 failed; held 1 of 2 judged glove trials (50 %); 2 glove trials not "
        "judged (left out of the hold rate)"
    )
    only_short = [record("c", None)]
    assert records_line(only_short) == (
        "1 trials: 1 ok, 0 diverged, 0 failed; 1 glove trials not judged (left out of the hold rate)"
    )
