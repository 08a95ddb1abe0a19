"""Stretches in which a recording holds its object in the air: nothing touching it, nothing under it.

Pinned on the bundled Tzionas sequence 20, whose recording ends with the cube 27–29 mm above the table and
the hand moving away from it: one stretch, from about 5.3 s to the last frame, checked against MuJoCo's own
geom distances computed here independently (no collision margins); the cube resting on the table at the
start is supported; a recorded object lifted off its support by hand in a copy of the reference makes a
stretch only when it stays up for :data:`~handsim.correct.support.MIN_STRETCH`; a glove scene has none. On the
ARCTIC-shaped benchmark scene, whose hands perform its recording, nothing is said, until its lid is turned
by hand in a copy of the reference while no hand is near it, beyond the track verdict's 30° hinge tolerance.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.correct.config import CorrectionConfig
from handsim.correct.reference import build_reference
from handsim.correct.score import EXPLAINS_WITHIN, unfollowable_clause
from handsim.correct.support import (
    MIN_STRETCH,
    TOUCH_DISTANCE,
    Unreachable,
    UntouchedTurn,
    unsupported_stretches,
)
from handsim.trials import load_trial

SEQ20 = TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION"


@pytest.fixture(scope="module")
def reference():
    loaded = load_trial(SEQ20)
    return build_reference(loaded.scene, loaded.trajectory, CorrectionConfig())


def _pose(reference, frame: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The recorded pose of a frame, set by hand: root, joints clipped to their ranges, the cube."""
    scene, schedule = reference.scene, reference.schedule
    model, data = scene.model, mujoco.MjData(scene.model)
    layout = scene.layout
    data.qpos[:] = model.qpos0
    low, high = np.asarray(layout.ctrl_range).T
    data.qpos[np.asarray(layout.dof_qpos)] = np.clip(schedule.ctrl[frame], low, high)
    root = layout.hands[0].root_free_qpos
    data.qpos[root : root + 7] = schedule.root_pose[frame]
    cube = reference.objects[0]
    data.qpos[cube.qpos : cube.qpos + 7] = cube.pose[frame]
    mujoco.mj_forward(model, data)
    return model, data


def _gaps(reference, frame: int) -> tuple[float, float]:
    """The cube's least distance to a hand geom and to the table at a frame (mj_geomDistance, up to 0.1 m)."""
    model, data = _pose(reference, frame)
    layout = reference.scene.layout
    cube = layout.objects[0].collision_geoms
    hand_bodies = set(np.asarray(layout.link_bodies).tolist())
    hand = [g for g in range(model.ngeom) if model.geom_bodyid[g] in hand_bodies and model.geom_contype[g]]
    table = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "table")
    to_hand = min(mujoco.mj_geomDistance(model, data, h, c, 0.1, None) for h in hand for c in cube)
    to_table = min(mujoco.mj_geomDistance(model, data, table, c, 0.1, None) for c in cube)
    return to_hand, to_table


def test_sequence_20_ends_with_the_cube_held_by_nothing(reference):
    (stretch,) = unsupported_stretches(reference)
    times = reference.schedule.times
    assert stretch.object == "cube"
    assert 5.1 < stretch.start_s < 5.4 and stretch.stop_s == pytest.approx(times[-1])
    assert 0.1 < stretch.share < 0.2 and stretch.frames == round((stretch.stop_s - stretch.start_s) * 100) + 1
    assert 25.0 < stretch.height_mm < 30.0 and abs(stretch.fall_mm) < 2.0  # it hangs still, 27 mm up
    assert TOUCH_DISTANCE * 1000 < stretch.hand_mm[0] < stretch.hand_mm[1] <= 30.0
    text = stretch.describe()
    assert text.startswith("the recording holds the cube in the air from 5.") and "free fall: " in text
    # independently: MuJoCo's distances without the margins the analysis uses
    for frame in np.flatnonzero((times >= stretch.start_s) & (times <= stretch.stop_s))[::10]:
        to_hand, to_table = _gaps(reference, frame)
        assert to_hand > TOUCH_DISTANCE and to_table > TOUCH_DISTANCE, frame
    before = int(np.searchsorted(times, stretch.start_s)) - 1
    assert min(_gaps(reference, before)) <= TOUCH_DISTANCE + 1e-6  # what ends the support ends the stretch


def test_the_cube_on_the_table_is_supported(reference):
    assert _gaps(reference, 100)[1] <= TOUCH_DISTANCE
    assert all(s.start_s > reference.schedule.times[100] for s in unsupported_stretches(reference))


@pytest.mark.parametrize("seconds, found", [(MIN_STRETCH - 0.03, False), (MIN_STRETCH + 0.1, True)])
def test_an_object_lifted_into_the_air_makes_a_stretch_if_it_stays_there(reference, seconds, found):
    cube = reference.objects[0]
    pose = np.array(cube.pose)
    frames = slice(50, 50 + round(seconds * 100))
    pose[frames, :3] += [0.2, -0.2, 0.1]  # 10 cm up, off the table, and 28 cm aside, away from the hand
    lifted = dataclasses.replace(reference, objects=(dataclasses.replace(cube, pose=pose),))
    starts = [s.start_s for s in unsupported_stretches(lifted)]
    assert (reference.schedule.times[50] in starts) is found


def test_a_glove_scene_has_no_recorded_track_to_judge():
    loaded = load_trial(ASSETS_DIR / "demo" / "tennis_ball.grasp.json")
    reference = build_reference(loaded.scene, loaded.trajectory, CorrectionConfig())
    assert unsupported_stretches(reference) == ()


@pytest.fixture(scope="module")
def arctic_reference():
    from benchmarks.arctic_recording import arctic_case_scene

    case = arctic_case_scene()
    return build_reference(case.scene, case.trajectory, CorrectionConfig())


def test_the_arctic_benchmark_recording_is_performed_by_its_hands(arctic_reference):
    assert unsupported_stretches(arctic_reference) == ()


@pytest.mark.parametrize("degrees, found", [(25.0, False), (40.0, True)])
def test_a_lid_the_recording_turns_with_no_hand_on_it_is_said_beyond_the_hinge_tolerance(
    arctic_reference, degrees, found
):
    box = arctic_reference.objects[0]
    angle = np.array(box.articulation)
    angle[550:600] += np.radians(np.linspace(0.0, degrees, 50))  # 5.5–6.0 s: both hands away from the lid
    angle[600:700] += np.radians(degrees)
    turned = dataclasses.replace(arctic_reference, objects=(dataclasses.replace(box, articulation=angle),))
    turns = [s for s in unsupported_stretches(turned) if isinstance(s, UntouchedTurn)]
    assert bool(turns) is found  # the track verdict's hinge tolerance is 30°
    if found:
        (turn,) = turns
        assert (turn.object, turn.part) == ("box", "top") and turn.turn_deg == pytest.approx(degrees)
        assert (turn.start_s, turn.stop_s) == pytest.approx((5.50, 5.99))
        assert turn.hand_mm[0] > TOUCH_DISTANCE * 1000
        assert turn.describe().startswith("the recording turns the box's top by 40° from 5.50 s to 5.99 s")


def test_a_lost_tracks_reason_names_the_stretch_the_loss_runs_into(reference):
    (stretch,) = unsupported_stretches(reference)
    clause = f"; {stretch.brief()}"
    assert clause.endswith("nothing within 5 mm of it: no motion near the recording carries it there")
    assert unfollowable_clause((stretch,), stretch.start_s + 0.2) == clause  # lost within it
    assert unfollowable_clause((stretch,), stretch.start_s - EXPLAINS_WITHIN + 0.01) == clause  # just before
    assert unfollowable_clause((stretch,), stretch.start_s - EXPLAINS_WITHIN - 0.1) == ""  # long before it
    assert unfollowable_clause((stretch,), stretch.stop_s + 0.1) == ""  # after it
    assert unfollowable_clause((stretch,), None) == ""  # not lost


def test_an_object_no_hand_comes_near_is_unreachable(reference):
    cube = reference.objects[0]
    pose = np.array(cube.pose)
    pose[:, :3] += [0.5, 0.5, 0.0]  # half a metre aside on the table, all through the recording
    far = dataclasses.replace(reference, objects=(dataclasses.replace(cube, pose=pose),))
    (finding,) = unsupported_stretches(far)  # the stretch in the air goes: it is untouched all through
    assert isinstance(finding, Unreachable) and finding.object == "cube"
    assert (finding.start_s, finding.stop_s) == (reference.schedule.times[0], reference.schedule.times[-1])
    assert finding.describe().startswith("no contact possible: no recorded hand link comes within 30 mm")
    assert finding.to_dict()["text"] == finding.brief() == finding.describe()


def test_frames_without_a_recorded_pose_are_neither_simulated_nor_judged(reference):
    cube = reference.objects[0]
    pose, valid = np.array(cube.pose), np.array(cube.valid)
    pose[550:600], valid[550:600] = np.nan, False  # a capture gap inside the stretch in the air
    gapped = dataclasses.replace(reference, objects=(dataclasses.replace(cube, pose=pose, valid=valid),))
    first, second = unsupported_stretches(gapped)
    times = reference.schedule.times
    assert (first.start_s, first.stop_s) == pytest.approx((5.26, times[549]))
    assert (second.start_s, second.stop_s) == pytest.approx((times[600], times[-1]))
