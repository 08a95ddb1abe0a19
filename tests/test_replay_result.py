"""The typed replay summary: its sections serialise to exactly the record's ``summary`` keys, in order."""

from __future__ import annotations

import pickle

import pytest

from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.sim.replay import replay
from handsim.sim.sections import (
    Closure,
    Contacts,
    FrameNumbers,
    GripNumbers,
    HandNumbers,
    HandOnly,
    HingeDrift,
    HoldNumbers,
    HoldSection,
    ObjectDrift,
    ReplaySummary,
    Robustness,
    StabilityNumbers,
    Tracking,
    TrackSection,
)
from handsim.sim.summary import CONTACT_KEYS, HAND_KEYS
from handsim.sim.track import FOLLOWED, TrackVerdict
from handsim.trials import load_trial

PER_FRAME = [
    "frames",
    "duration_s",
    "max_penetration_mm",
    "p95_penetration_mm",
    "frames_penetrating_over_1mm",
    "contact_frames",
    "max_contact_links",
    "max_total_normal_force_n",
    "truncated_contact_pairs",
    "mean_tracking_error_deg",
    "max_tracking_error_deg",
    "mean_tip_error_mm",
    "max_tip_error_mm",
]
DRIFT = [
    "mean_drift_mm",
    "max_drift_mm",
    "final_drift_mm",
    "within_tolerance",
    "mean_rotation_drift_deg",
    "max_rotation_drift_deg",
    "max_articulation_drift_deg",
]
TRACK = [
    "track",
    "track_reason",
    "track_lost_at_s",
    "track_lost_how",
    "track_manipulated_frames",
    "track_followed_fraction",
    "track_untouched_hands",
    "track_on_floor",
]
HAND_ONLY = [
    "hold_reason",
    "drift_reason",
    "max_self_penetration_mm",
    "p95_self_penetration_mm",
    "frames_self_penetrating_over_1mm",
    "self_penetration_links",
    "self_penetration_at_s",
    "max_target_self_penetration_mm",
    "target_self_penetration_links",
    "target_self_penetration_at_s",
]
HOLD = [
    "held",
    "hold_reason",
    "time_held_s",
    "max_slip_mm",
    "drop_mm",
    "grip_links",
    "grip_opposition",
    "grip_opposing_links",
    "deepest_link",
    "deepest_link_mm",
    "grip_force_n",
    "grip_force_limit_n",
    "fit_fraction",
    "grip_normal_force_n",
    "grip_servo_torque_nm",
    "grip_directions_held",
    "self_penetration_at_closure_mm",
    "hold_robustness",
    "hold_robustness_factors",
    "release_directions_held",
]
PER_HAND = [
    "max_penetration_mm",
    "frames_penetrating_over_1mm",
    "contact_frames",
    "max_contact_links",
    "max_total_normal_force_n",
    "mean_tracking_error_deg",
    "max_tracking_error_deg",
    "mean_tip_error_mm",
    "max_tip_error_mm",
]


def _numbers(hands: tuple[HandNumbers, ...] = (), drift: ObjectDrift | None = None) -> FrameNumbers:
    contacts = Contacts(1.5, 1.0, 3, 4, 2, 0.7, 0)
    return FrameNumbers(10, 0.09, contacts, Tracking(1.0, 2.0, 3.0, 4.0), hands, drift)


def _hand(name: str) -> HandNumbers:
    return HandNumbers(name, 1.0, 2, 3, 1, 0.5, 1.0, 2.0, 3.0, 4.0)


def _verdict() -> TrackVerdict:
    return TrackVerdict(FOLLOWED, "followed: the cube", 7, 1.0, untouched_hands=("left",))


def test_the_key_lists_of_summary_are_the_sections_fields():
    assert list(CONTACT_KEYS) == PER_FRAME[2:9]
    assert list(HAND_KEYS) == PER_HAND


def test_a_two_hand_recorded_summary_serialises_hands_drift_hinge_track_and_start_in_the_record_order():
    drift = ObjectDrift(1.0, 2.0, 3.0, 0.5, 4.0, 5.0, 6.0, HingeDrift(0.25, None))
    track = TrackSection(_verdict(), {"right": 1.25, "left": 0.0})
    summary = ReplaySummary(
        _numbers((_hand("right"), _hand("left")), drift), None, False, 0, track, True, None, None
    )
    record = summary.to_dict()
    assert list(record) == [
        *PER_FRAME,
        *(f"right/{key}" for key in PER_HAND),
        *(f"left/{key}" for key in PER_HAND),
        *DRIFT,
        "mean_articulation_drift_deg",
        "final_articulation_drift_deg",
        "diverged",
        "warnings",
        *TRACK,
        "right/start_penetration_mm",
        "left/start_penetration_mm",
        "valid",
    ]
    assert record["track_untouched_hands"] == ["left"] and record["track_on_floor"] == []
    assert record["final_articulation_drift_deg"] is None and record["right/start_penetration_mm"] == 1.25


def test_a_scene_s_only_hand_records_its_start_penetration_without_a_prefix():
    track = TrackSection(_verdict(), {"": 2.0})
    record = ReplaySummary(_numbers(), None, False, 0, track, True).to_dict()
    assert list(record)[-2:] == ["start_penetration_mm", "valid"]


def test_a_hand_only_summary_serialises_why_and_the_self_penetration_with_lists():
    reason = "not judged: no object"
    hand_only = HandOnly(reason, reason, 2.0, 1.0, 3, ("if_pip", "mf_pip"), 0.5, 4.0, None, None)
    summary = ReplaySummary(_numbers(), hand_only, True, 2, None, False)
    record = summary.to_dict()
    assert list(record) == [*PER_FRAME, *HAND_ONLY, "diverged", "warnings", "valid"]
    assert record["self_penetration_links"] == ["if_pip", "mf_pip"]
    assert record["diverged"] is True and record["warnings"] == 2 and record["valid"] is False
    assert summary.hold_reason == reason


def test_a_glove_summary_serialises_hold_grip_closure_robustness_and_stability_last():
    hold = HoldSection(
        HoldNumbers(True, None, 0.5, 1.0, 2.0),
        GripNumbers(("th_ip", "if_dip"), 1.0, ("th_ip", "if_dip"), "if_dip", 1.5, 3.0, 40.0),
        Closure(0.8, 10.0, 1.5, 6, None),
        Robustness(0.75, {"winner": {"held": 1, "judged": 1, "fraction": 1.0}}, 6),
    )
    summary = ReplaySummary(_numbers(), None, False, 0, None, True, hold, StabilityNumbers(True, 0.5))
    record = summary.to_dict()
    assert list(record) == [
        *PER_FRAME,
        "diverged",
        "warnings",
        "valid",
        *HOLD,
        "stable",
        "simulation_displacement_mm",
    ]
    assert record["grip_links"] == ["th_ip", "if_dip"] and record["grip_opposing_links"] == [
        "th_ip",
        "if_dip",
    ]
    assert summary.hold_reason is None


def test_a_glove_hold_without_a_grip_records_every_grip_key_as_none():
    hold = HoldSection(
        HoldNumbers(None, "not judged: short", 0.0, 0.0, 0.0),
        GripNumbers(),
        Closure(None, None, None, None, None),
        Robustness(None, None, None),
    )
    record = ReplaySummary(_numbers(), None, False, 0, None, True, hold).to_dict()
    assert all(record[key] is None for key in HOLD[5:12])
    assert record["hold_reason"] == "not judged: short"


@pytest.mark.parametrize(
    ("path", "tail"),
    [
        (
            TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION",
            [*DRIFT, "diverged", "warnings", *TRACK, "valid"],
        ),
        (ASSETS_DIR / "demo" / "tennis_ball.grasp.json", ["diverged", "warnings", "valid", *HOLD]),
    ],
    ids=["tzionas", "scripted"],
)
def test_a_replay_s_summary_is_its_typed_summary_serialised_with_the_record_s_keys(path, tail):
    loaded = load_trial(path)
    result = replay(loaded.scene, loaded.trajectory)
    assert result.summary == result.measured.to_dict()
    assert list(result.summary) == [*PER_FRAME, *tail]
    assert result.to_dict()["summary"] is result.summary
    again = pickle.loads(pickle.dumps(result))
    assert again.summary == result.summary and again.measured == result.measured
