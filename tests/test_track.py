"""The verdict on a recorded object's track (followed, lost at t, not judged) and its flags, end to end.

Synthetic ARCTIC sequences of ``tests/test_arctic_world.py`` (the box 1 m up, MANO hands held still) whose
object tracks are simple physics the simulation must reproduce or visibly fails to: a free fall (followed),
an object the recording lifts with no hand near it (it falls: lost, dropped, on the floor), an object the
recording never moves (not judged), a hand inside the object (deep penetration); and an ARCTIC-shaped carry
by the bundled mean-shape MANO hands, followed when the palms press enough and lost when they do not. Then
the verdict in ``handsim replay``'s lines and JSON, and in the report (counted and ranked like the glove
hold).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from handsim.builders.arctic_objects import arctic_object
from handsim.builders.mano_hand import build_mano_hand, mano_hand_skeleton
from handsim.builders.objects import build_object
from handsim.cli import main
from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.io.arctic.sequence import HANDS
from handsim.report import read_run, render_report
from handsim.report.aggregate import group_stats, outcome, rank
from handsim.sim.arctic_scene import arctic_scene
from handsim.sim.replay import replay
from handsim.sim.specs import TrackSpec
from handsim.sim.track import manipulated
from handsim.trials import load_trial
from tests.arctic_fixtures import block, write_template
from tests.mano_fixtures import write_synthetic_mano_pkl as write_mano
from tests.test_arctic_world import arctic_root, object_rows
from tests.test_report import _make_run

G = 9.81


@pytest.fixture(scope="module")
def mano(tmp_path_factory):
    """A folder with synthetic MANO_RIGHT.pkl and MANO_LEFT.pkl."""
    folder = tmp_path_factory.mktemp("mano_models")
    for side in HANDS:
        write_mano(folder / f"MANO_{side.upper()}.pkl", side=side)
    return folder, None


def _replayed(folder, tmp_path, n: int, rows: np.ndarray, wrists: dict | None = None):
    path, _ = arctic_root(tmp_path, n, rows, wrists or {})
    loaded = load_trial(path, mano_dir=folder)
    return path, replay(loaded.scene, loaded.trajectory)


def test_a_recorded_free_fall_is_followed_and_the_hands_that_never_touch_it_are_named(mano, tmp_path):
    folder, _ = mano
    n = 11  # 0.33 s: the box falls 54 cm, above the floor 75 cm down
    rows = object_rows(n)
    rows[:, 6] -= 0.5 * G * (np.arange(n) / 30.0) ** 2 * 1000.0
    _, result = _replayed(folder, tmp_path, n, rows)
    s = result.summary
    assert s["track"] == "followed" and s["track_followed_fraction"] == 1.0
    assert s["track_manipulated_frames"] == 27  # from 64 ms on the box is 2 cm below its start
    assert s["track_reason"].startswith("followed: the box within 2 cm, 30°, hinge 30° of its recording")
    assert s["track_untouched_hands"] == ["right", "left"]
    assert "the right hand and the left hand never touch it" in s["track_reason"]
    flags = {f.code: f for f in result.flags}
    assert set(flags) == {"hand_never_touches"} and not flags["hand_never_touches"].invalid
    assert s["valid"] is True  # valid, with a note


def test_an_object_the_recording_lifts_with_no_hand_near_is_lost_dropped_and_flagged_on_the_floor(
    mano, tmp_path
):
    folder, _ = mano
    n = 31
    _, result = _replayed(folder, tmp_path, n, object_rows(n, lift_mm_per_s=300.0))
    s = result.summary
    assert s["track"] == "lost" and s["track_lost_how"] == "dropped"
    # the recording lifts it while it falls: 2 cm apart after √(2·0.02 / (g + 2·0.3·…)) ≈ 50 ms
    assert s["track_lost_at_s"] == pytest.approx(0.05, abs=0.011)
    assert s["track_reason"].startswith(f"lost at {s['track_lost_at_s']:.2f} s: the box was dropped")
    assert "no hand touching it" in s["track_reason"] and "it ends on the floor" in s["track_reason"]
    assert s["track_on_floor"] == ["box"]
    codes = [f.code for f in result.flags]
    assert codes == ["object_on_floor", "hand_never_touches"]
    assert all(not f.invalid for f in result.flags)


def test_an_object_the_recording_never_moves_is_not_judged_and_says_why(mano, tmp_path):
    folder, _ = mano
    n = 12
    _, result = _replayed(folder, tmp_path, n, object_rows(n))
    s = result.summary
    assert s["track"] == "not judged" and s["track_manipulated_frames"] == 0
    assert s["track_reason"] == (
        "not judged: the recording never moves the box beyond 2 cm, 30°, hinge 30° from its start; the right "
        "hand and the left hand never touch it"
    )
    assert s["track_followed_fraction"] is None and s["track_lost_at_s"] is None


def test_a_hand_deep_inside_the_object_is_flagged_and_the_replay_not_valid(mano, tmp_path):
    folder, _ = mano
    n = 12
    _, result = _replayed(folder, tmp_path, n, object_rows(n), {"right": (0.02, 0.0, 0.04)})
    flag = next(f for f in result.flags if f.code == "deep_penetration")
    assert flag.invalid and flag.values["threshold_mm"] == 10.0
    assert set(flag.values["hands"]) == {"right"} and flag.values["hands"]["right"]["depth_mm"] > 10.0
    assert flag.reason.startswith("a hand passes through an object, deeper than 10 mm")
    assert result.summary["valid"] is False
    assert [f.code for f in result.flags if f.code == "hand_never_touches"] == ["hand_never_touches"]
    assert "the left hand never touches" in result.summary["track_reason"]


def test_manipulated_frames_are_those_the_recording_moves_beyond_the_tolerance_from_its_start():
    n = 10
    pose = np.tile([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], (n, 1))
    pose[3, 0] = 0.021  # 2.1 cm aside
    half = math.radians(31.0) / 2
    pose[5, 3:] = [math.cos(half), 0.0, 0.0, math.sin(half)]  # turned 31°
    articulation = np.zeros(n)
    articulation[7] = math.radians(31.0)
    valid = np.ones(n, bool)
    valid[8] = False
    pose[8, 0] = 1.0  # far away, but not a valid sample
    found = manipulated(ObjectTrack(pose, articulation, valid), TrackSpec())
    assert np.flatnonzero(found).tolist() == [3, 5, 7]


def test_track_spec_refuses_a_non_positive_tolerance_by_name():
    with pytest.raises(ValueError, match=r"position must be a positive finite number, got 0\.0"):
        TrackSpec(position=0.0)


def test_handsim_replay_prints_the_verdict_and_writes_it_to_json(mano, tmp_path, capsys):
    folder, _ = mano
    n = 11
    rows = object_rows(n)
    rows[:, 6] -= 0.5 * G * (np.arange(n) / 30.0) ** 2 * 1000.0
    path, _ = arctic_root(tmp_path, n, rows, {})
    out = tmp_path / "result.json"
    assert main(["replay", str(path), "--mano-dir", str(folder), "--json", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    track = [line for line in lines if line.startswith("track ")]
    assert len(track) == 1 and "followed: the box within 2 cm" in track[0]
    assert track[0].endswith("[within tolerance in 100.0% of 27 manipulated frames]")
    assert any(line.startswith("right ") and "starts 0.0 mm inside the object" in line for line in lines)
    assert any(line.startswith("flag ") and "hand_never_touches (a note)" in line for line in lines)
    summary = json.loads(out.read_text())["summary"]
    assert summary["track"] == "followed" and summary["right/start_penetration_mm"] == 0.0


# --------------------------------------------------------------------------------------------- report


def _with_verdicts(out):
    """The report fixture run with the recorded trial lost and an ARCTIC trial followed."""
    records = _make_run(out)
    tz = next(r for r in records if r["id"] == "Models/20")
    tz["summary"].update(
        track="lost",
        track_reason="lost at 4.78 s: the cube was dropped (2.3 cm from its recording)",
        track_lost_at_s=4.78,
        track_lost_how="dropped",
        track_manipulated_frames=393,
        track_followed_fraction=0.646,
        track_untouched_hands=[],
        track_on_floor=[],
    )
    arctic = json.loads(json.dumps(tz))
    arctic.update(id="s01/box_grab_01", kind="arctic")
    arctic["summary"].update(
        track="followed",
        track_reason="followed: the box within 2 cm, 30°, hinge 30° of its recording over its 27 frames",
        track_lost_at_s=None,
        track_lost_how=None,
        track_followed_fraction=1.0,
    )
    records.append(arctic)
    (out / "records.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
    return records


def test_the_report_counts_and_ranks_the_track_verdict_like_the_glove_hold(tmp_path):
    records = _with_verdicts(tmp_path)
    run = read_run(tmp_path)
    outcomes = {r["id"]: outcome(r) for r in run.records}
    assert outcomes["Models/20"] == "lost" and outcomes["s01/box_grab_01"] == "followed"
    stats = group_stats(run.records)
    assert (stats["followed"], stats["track_judged"], stats["follow_rate"]) == (1, 2, 0.5)
    assert (stats["held"], stats["hold_judged"]) == (2, 3)  # the glove numbers are untouched
    tiers = {r["id"]: (r["tier"], r["reason"]) for r in rank(run.records)}
    assert tiers["Models/20"][0] == "not held"  # the lost tier
    assert tiers["Models/20"][1].startswith("object lost at 4.78 s: the cube was dropped")
    assert tiers["s01/box_grab_01"][0] == "ok"
    files = render_report(tmp_path)
    markdown = files.markdown.read_text()
    assert "follow rate" in markdown and "**lost**" in markdown and "**followed**" in markdown
    html = files.html.read_text()
    assert "<h4>Object track</h4>" in html and "object lost" in html
    assert len(records) == 7


# --------------------------------------------------------------------------------------------- carrying


def _carry(squeeze_y: float):
    """Two mean-shape MANO hands (bundled) press a 0.75 kg box's sides flat-handed, lift it 10 cm and set
    it down: in 0.6 s, lift over 1–2 s, hold, lower over 3–4 s, out from 4.3 s (5 s at 30 fps).

    ``squeeze_y``: the wrists' distance from the box's mid-plane while they press (the box's sides are at
    ±80 mm; a flat hand touches at about ±108 mm).
    """
    n = 150
    t = np.arange(n) / 30.0
    up = np.clip(t - 1.0, 0, 1) - np.clip(t - 3.0, 0, 1)
    height = 0.10 * 0.5 * (1 - np.cos(np.pi * up))
    upright = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
    pose = np.tile([0.0, 0.0, 0.06, *upright], (n, 1))
    pose[:, 2] += height
    track = ObjectTrack(pose=pose, articulation=np.zeros(n))
    reach = 0.02 * (1 - np.clip(t / 0.6, 0, 1)) + 0.02 * np.clip((t - 4.3) / 0.6, 0, 1)
    columns, targets, roots, hands = [], [], {}, {}
    for side, x, sign, quat in (("right", 0.04, 1.0, (1, 0, 0, 0)), ("left", -0.16, -1.0, (0, 1, 0, 0))):
        skeleton = mano_hand_skeleton(side=side)  # flat hands: every DoF at 0
        hands[side] = build_mano_hand(side=side, root="fixed")
        columns += [f"{side}/{d}" for d in skeleton.dof_names]
        targets.append(np.zeros((n, len(skeleton.dof_names))))
        position = np.column_stack([np.full(n, x), sign * (squeeze_y + reach), 0.04 + height])
        roots[side] = np.column_stack([position, np.tile(quat, (n, 1))])
    trajectory = Trajectory(
        t, tuple(columns), np.hstack(targets), np.ones((n, len(columns)), bool), objects={"box": track},
        hand_roots=roots,
    )  # fmt: skip
    return trajectory, hands, track


@pytest.mark.parametrize(
    ("squeeze_y", "verdict", "fraction"), [(0.099, "followed", 1.0), (0.101, "lost", 0.6887966804979253)]
)
def test_two_mean_shape_mano_hands_carrying_the_box_are_followed_only_when_they_press_enough(
    tmp_path, squeeze_y, verdict, fraction
):
    trajectory, hands, track = _carry(squeeze_y)
    bottom = block((-120.0, 0.0), (-60.0, 0.0), (-80.0, 80.0))
    top = block((-120.0, 0.0), (0.0, 10.0), (-80.0, 80.0))
    write_template(tmp_path, "box", (bottom, top, "parts"))
    box = build_object(arctic_object(tmp_path / "box", articulation=track.articulation))
    scene = arctic_scene(hands, trajectory, box, "box")
    result = replay(scene, trajectory)
    s = result.summary
    assert s["warnings"] == 0 and s["track"] == verdict
    assert s["track_manipulated_frames"] == 241  # the box more than 2 cm up
    assert s["track_followed_fraction"] == pytest.approx(fraction, rel=1e-9)
    assert s["right/start_penetration_mm"] == 0.0 and s["max_penetration_mm"] < 5.0
    assert result.flags == () and s["valid"] is True  # no flag: a clean carry, judged on its track
    if verdict == "lost":  # 2 mm less squeeze: the box slides down the palms as it is lifted
        assert s["track_lost_how"] == "dropped" and s["track_lost_at_s"] == pytest.approx(2.96, abs=0.011)
