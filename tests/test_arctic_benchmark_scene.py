"""The ARCTIC-shaped benchmark scene (``benchmarks/arctic_recording.py``): a manipulation the physics follows.

Two bundled mean-shape MANO hands carry the benchmark's box between their palms and set it down, then the
right hand lifts the lid by its lip with its fingertips. The recording is consistent (its object moves as the
hands holding it do, nothing starts inside anything, no recorded hand passes through the stand or the
floor), and the normal replay path follows it: the track verdict is *followed*.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.arctic_recording import (
    CARRIED,
    FPS,
    LID_LIFT,
    OPENING,
    TRACK,
    UNDER_LID,
    about_hinge,
    arctic_case_scene,
)
from handsim.datatypes.poses import compose, inverse
from handsim.datatypes.rotations import quat_angle
from handsim.sim.arctic_scene import PASS_DEPTH
from handsim.sim.replay import replay


@pytest.fixture(scope="module")
def case():
    return arctic_case_scene()


def test_the_benchmark_scene_is_followed_over_all_its_manipulated_frames_with_no_flag(case):
    result = replay(case.scene, case.trajectory)
    s = result.summary
    assert s["warnings"] == 0 and not s["diverged"]
    assert s["track"] == "followed", s["track_reason"]
    assert s["track_followed_fraction"] == 1.0
    assert s["track_manipulated_frames"] == 404  # lifted more than 2 cm, or the lid more than 30° open
    assert s["track_untouched_hands"] == []  # both hands carry it
    assert s["max_articulation_drift_deg"] < 10.0  # the lid rises on the fingertips, as recorded
    assert s["max_penetration_mm"] < 5.0
    assert result.flags == () and s["valid"] is True


def test_no_recorded_hand_passes_through_the_stand_or_the_floor(case):
    checks = case.scene.setup.checks
    assert checks["support"]["kind"] == "stand" and checks["world_fits"] is True
    assert checks["blocked"] == [] and checks["floor_m"] == -0.75  # neither moved nor shrunk
    assert {p["body"] for p in checks["passages"]} <= {"stand", "floor"}
    assert all(p["depth_mm"] <= PASS_DEPTH * 1000.0 for p in checks["passages"])
    assert checks["support"]["area_cm2"] == pytest.approx(checks["support"]["footprint_cm2"])
    assert checks["support"]["footprint_cm2"] == pytest.approx(192.0)  # the base's 12 × 16 cm


def test_nothing_starts_inside_anything(case):
    checks = case.scene.setup.checks
    assert checks["hinge"]["excluded_pairs_mm"] == {} and checks["hinge"]["overlap_mm"] <= 1.0
    assert case.scene.setup.start_articulation == (0.0,)
    assert checks["start_penetration_mm"] == {"right": 0.0, "left": 0.0}


def test_the_recorded_box_moves_as_the_hands_holding_it_do(case):
    traj = case.trajectory
    pose, hinge = traj.objects[TRACK].pose, traj.objects[TRACK].articulation
    held = (traj.times >= CARRIED[0][0]) & (traj.times <= CARRIED[-1][0])
    for side in ("right", "left"):
        grip = compose(inverse(traj.hand_roots[side][held]), pose[held])  # the box in the wrist's frame
        assert np.ptp(grip, axis=0).max() < 1e-12
    lifting = traj.times >= LID_LIFT[0]
    unturned = about_hinge(traj.hand_roots["right"][lifting], -hinge[lifting])
    assert np.abs(unturned[:, :3] - UNDER_LID).max() < 1e-12  # the fingertips stay where they touch the lid
    assert hinge.max() == pytest.approx(OPENING) and np.all(hinge[~lifting] == 0.0)


def test_the_targets_move_smoothly_with_no_jump(case):
    traj = case.trajectory
    assert np.all(traj.targets == 0.0) and traj.valid.all()  # flat hands: no joint target moves
    step = 1.0 / FPS
    for side in ("right", "left"):
        roots = traj.hand_roots[side]
        speed = np.linalg.norm(np.diff(roots[:, :3], axis=0), axis=1) / step
        assert speed.max() < 1.5  # m/s: a reaching hand's peak
        turned = quat_angle(roots[1:, 3:], roots[:-1, 3:])
        assert turned.max() < math.radians(300.0) * step  # < 300°/s
    pose = traj.objects[TRACK].pose
    assert np.linalg.norm(np.diff(pose[:, :3], axis=0), axis=1).max() < 0.3 * step
    assert np.abs(np.diff(traj.objects[TRACK].articulation)).max() < math.radians(90.0) * step
