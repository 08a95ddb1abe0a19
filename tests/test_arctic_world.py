"""The ARCTIC world fits its recording: a stand no larger than the object's footprint, out of the recorded
hands' way, and start states without overlap (the lid out of its base, each hand's starting depth measured).

Synthetic ARCTIC roots in the real layout (``tests/mano_fixtures.py``, ``tests/arctic_fixtures.py``): the
box template of ``tests/test_arctic_replay.py`` (a 120 × 60 × 160 mm base, its lid hinged along one edge),
standing 1 m up in ARCTIC's z-up world, and MANO hands held still where each test needs them (zero pose
relative to the mean hand, no wrist rotation). Where a test needs geometry it reads it from the compiled
model and computes depths with numpy/SciPy, not with the functions under test.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from handsim.builders.arctic_objects import arctic_object
from handsim.builders.mano_hand import build_mano_hands
from handsim.builders.objects import build_object
from handsim.io.arctic.sequence import HANDS
from handsim.sim.arctic_scene import FLOOR_DEPTH, PASS_DEPTH, arctic_scene
from handsim.sim.control import control_schedule
from handsim.sim.drive import ScheduleDriver, scenario_switches
from handsim.sim.replay import ReplayConfig, replay
from handsim.sim.scene.clearance import hand_paths
from handsim.sim.scene.settle import PART_OVERLAP_TOLERANCE
from handsim.sim.scene.support import STAND_MIN_RADIUS
from handsim.sim.stepper import Stepper
from handsim.trials import load_trial
from tests.arctic_fixtures import UPRIGHT, block, write_template
from tests.mano_fixtures import (
    mano_hand_params,
    mean_joints,
    numpy_mano_fk,
    write_arctic_mano_npy,
    write_arctic_object_npy,
)
from tests.mano_fixtures import write_synthetic_mano_pkl as write_mano

SEQ = "box_grab_01"
SHIFT = np.array([-0.010, 0.020, -0.940])
"""The scene's world from the recording: the box's origin (10, −20, 1000) mm above the origin, its lowest
point (1000 − 60 mm) on the support plane."""
AWAY = {"right": (0.5, 0.3, 0.3), "left": (-0.5, 0.3, 0.3)}
"""Wrists (scene world, m) well clear of the box, the stand and the floor."""
BOX = ((-120.0, 0.0), (-60.0, 0.0), (-80.0, 80.0))
LID = ((-120.0, 0.0), (0.0, 10.0), (-80.0, 80.0))


@pytest.fixture(scope="module")
def mano(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mano_models")
    return folder, {side: write_mano(folder / f"MANO_{side.upper()}.pkl", side=side) for side in HANDS}


def object_rows(n: int, articulation=0.3, lift_mm_per_s: float = 0.0) -> np.ndarray:
    """The box upright 1 m up, still (or rising), its lid at ``articulation`` (rad, or one per frame)."""
    t = np.arange(n) / 30.0
    art = np.broadcast_to(np.asarray(articulation, dtype=float), (n,))
    trans = np.tile([10.0, -20.0, 1000.0], (n, 1))
    trans[:, 2] += lift_mm_per_s * t
    return np.column_stack([art, np.tile(UPRIGHT, (n, 1)), trans]).astype(np.float32)


def still_hand(n: int, side: str, wrist, seed: int = 10) -> dict:
    """MANO parameters of a hand held still: mean pose, no rotation, its wrist at ``wrist`` (scene world)."""
    params = mano_hand_params(n, seed, side=side)
    params["rot"] = np.zeros((n, 3), np.float32)
    params["pose"] = np.zeros((n, 45), np.float32)
    params["shape"] = np.zeros(10, np.float32)
    recorded = np.broadcast_to(np.asarray(wrist, dtype=float) - SHIFT, (n, 3))
    params["trans"] = (recorded - mean_joints(side)[0]).astype(np.float32)
    return params


def arctic_root(tmp_path, n: int, rows: np.ndarray, wrists: dict, lid=LID):
    """An ARCTIC root with one box sequence; hands still at ``wrists`` (scene world), else away."""
    raw = tmp_path / "arctic" / "raw_seqs" / "s01"
    raw.mkdir(parents=True)
    hands = {side: still_hand(n, side, wrists.get(side, AWAY[side]), 10 + k) for k, side in enumerate(HANDS)}
    write_arctic_mano_npy(raw / f"{SEQ}.mano.npy", hands["right"], hands["left"])
    write_arctic_object_npy(raw / f"{SEQ}.object.npy", rows)
    write_template(
        tmp_path / "arctic" / "meta" / "object_vtemplates", "box", (block(*BOX), block(*lid), "parts")
    )
    return raw / f"{SEQ}.mano.npy", hands


def geom_points(model: mujoco.MjModel, data: mujoco.MjData, name: str) -> np.ndarray:
    """A mesh geom's vertices in the world (read from the compiled model)."""
    geom = model.geom(name)
    mesh = int(geom.dataid[0])
    start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    local = np.asarray(model.mesh_vert[start : start + count], dtype=float)
    return local @ data.geom_xmat[geom.id].reshape(3, 3).T + data.geom_xpos[geom.id]


def depth_in_hull(vertices: np.ndarray, points: np.ndarray) -> np.ndarray:
    """How deep points lie inside the convex hull of vertices (0 outside), by SciPy's hull planes."""
    planes = ConvexHull(vertices).equations
    return np.maximum(-(points @ planes[:, :3].T + planes[:, 3]).max(axis=1), 0.0)


def numpy_joints(arrays: dict, hands: dict) -> np.ndarray:
    """Every frame's 16 MANO joints of both hands in the scene's world, by numpy MANO kinematics."""
    out = []
    for side in HANDS:
        p = {k: np.asarray(v, dtype=float) for k, v in hands[side].items() if k != "fitting_err"}
        for k in range(p["rot"].shape[0]):
            full = p["pose"][k] + arrays[side]["hands_mean"]
            out.append(numpy_mano_fk(arrays[side], p["shape"], p["rot"][k], full, p["trans"][k])[2] + SHIFT)
    return np.vstack(out)


def static_depths(scene, points: np.ndarray) -> dict[str, float]:
    """The deepest of ``points`` inside the stand (its mesh's hull) and below the floor."""
    model = scene.model
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    floor = float(data.geom("floor").xpos[2])
    found = {"floor": float(np.maximum(floor - points[:, 2], 0.0).max())}
    if any(model.geom(g).name == "stand" for g in range(model.ngeom)):
        found["stand"] = float(depth_in_hull(geom_points(model, data, "stand"), points).max())
    return found


def frame0(scene, trajectory):
    """The scene's data at frame 0, as a replay starts it."""
    schedule = control_schedule(scene, trajectory, 100.0)
    stepper = Stepper(scene, schedule.substeps)
    ScheduleDriver(stepper, schedule, scenario_switches(scene, schedule, 0.1)).reset()
    return stepper.data


# --------------------------------------------------------------------------------------------- the stand


def test_the_support_is_a_stand_no_larger_than_the_objects_footprint_at_frame_0(mano, tmp_path):
    folder, _ = mano
    path, _ = arctic_root(tmp_path, 20, object_rows(20), {})
    loaded = load_trial(path, mano_dir=folder)
    model = loaded.scene.model
    data = frame0(loaded.scene, loaded.trajectory)
    names = [model.geom(g).name for g in range(model.ngeom) if model.body_weldid[model.geom_bodyid[g]] == 0]
    assert sorted(n for n in names if n) == ["floor", "stand"]  # no table
    stand = geom_points(model, data, "stand")
    np.testing.assert_allclose(stand[:, 2].max(), 0.0, atol=1e-6)  # its top is the support plane
    np.testing.assert_allclose(stand[:, 2].min(), -FLOOR_DEPTH, atol=1e-6)  # down to the floor
    geoms = loaded.scene.layout.objects[0].collision_geoms
    points = np.vstack([geom_points(model, data, model.geom(g).name) for g in geoms])
    footprint = points[points[:, 2] < 0.005, :2]
    # every corner of the stand's top lies within the object's footprint (its lowest 5 mm) at frame 0
    hull = ConvexHull(footprint)
    top = stand[stand[:, 2] > -1e-6, :2]
    assert (top @ hull.equations[:, :2].T + hull.equations[:, 2]).max() < 1e-6
    assert any(
        n.startswith("support: a stand under the object's footprint") for n in loaded.scene.setup.notes
    )


def test_no_recorded_hand_joint_or_fingertip_is_inside_a_static_body(mano, tmp_path):
    folder, arrays = mano
    n = 20
    path, hands = arctic_root(tmp_path, n, object_rows(n), {"right": (0.10, 0.0, -0.12)})  # fingers under
    loaded = load_trial(path, mano_dir=folder)
    joints = numpy_joints(arrays, hands)  # independent MANO kinematics: the 16 joints of every frame
    sites = hand_paths(loaded.scene, loaded.trajectory).points.reshape(-1, 3)  # joints and fingertips
    for points in (joints, sites):
        assert max(static_depths(loaded.scene, points).values()) <= PASS_DEPTH
    assert loaded.scene.setup.checks["world_fits"] is True


def test_a_hand_passing_under_the_object_shrinks_the_stand_with_a_note_naming_it(mano, tmp_path):
    folder, arrays = mano
    n = 20
    path, hands = arctic_root(tmp_path, n, object_rows(n), {"right": (0.10, 0.0, -0.12)})
    with_checks = load_trial(path, mano_dir=folder)
    joints = numpy_joints(arrays, hands)
    notes = [x for x in with_checks.scene.setup.notes if x.startswith("the stand is shrunk")]
    assert len(notes) == 1 and "into the stand" in notes[0] and "right/" in notes[0]
    support = with_checks.scene.setup.checks["support"]
    assert support["area_cm2"] < support["footprint_cm2"]
    # the same hands against the stand before it was shrunk: deep inside (what the check found)
    box = box_spec(tmp_path, object_rows(n))
    unchecked = arctic_scene(hand_specs(folder, hands), with_checks.trajectory, box, "box", checks=False)
    assert static_depths(unchecked, joints)["stand"] > 2 * PASS_DEPTH  # what the check found
    assert static_depths(with_checks.scene, joints)["stand"] <= PASS_DEPTH


def hand_specs(folder, hands: dict) -> dict:
    """Both hands built from the MANO files with the sequence's betas (as the trial builds them)."""
    return {s: h.spec for s, h in build_mano_hands(folder, {s: hands[s]["shape"] for s in HANDS}).items()}


def box_spec(tmp_path, rows: np.ndarray):
    """The box template built as the trial builds it (its hinge range from the recording)."""
    folder = tmp_path / "arctic" / "meta" / "object_vtemplates" / "box"
    return build_object(arctic_object(folder, articulation=rows[:, 0]))


def test_a_hand_under_the_objects_centre_leaves_no_stand_that_fits_and_the_replay_is_flagged(mano, tmp_path):
    folder, _ = mano
    n = 12
    path, _ = arctic_root(tmp_path, n, object_rows(n), {"right": (0.06, 0.035, -0.12)})
    loaded = load_trial(path, mano_dir=folder)
    checks = loaded.scene.setup.checks
    assert checks["world_fits"] is False and checks["blocked"]
    assert any(
        x.startswith("no stand fits the recording") and f"within {STAND_MIN_RADIUS * 1000:g} mm" in x
        for x in loaded.scene.setup.notes
    )
    result = replay(loaded.scene, loaded.trajectory)
    flag = next(f for f in result.flags if f.code == "static_body_in_path")
    assert flag.invalid and "into the stand" in flag.reason
    assert result.summary["valid"] is False


def test_a_hand_below_the_floor_moves_the_floor_down_to_it(mano, tmp_path):
    folder, arrays = mano
    n = 12
    path, hands = arctic_root(tmp_path, n, object_rows(n), {"right": (0.5, 0.3, -0.85)})
    loaded = load_trial(path, mano_dir=folder)
    floor = loaded.scene.setup.checks["floor_m"]
    lowest = hand_paths(loaded.scene, loaded.trajectory).points[..., 2].min()
    assert floor == pytest.approx(lowest) and floor < -FLOOR_DEPTH
    assert any(
        x.startswith(f"the floor is moved from {-FLOOR_DEPTH:.3f} m") for x in loaded.scene.setup.notes
    )
    assert static_depths(loaded.scene, numpy_joints(arrays, hands))["floor"] == 0.0


def test_a_recording_that_lifts_the_object_from_its_first_frame_gets_no_support(mano, tmp_path):
    folder, _ = mano
    n = 12
    path, _ = arctic_root(tmp_path, n, object_rows(n, lift_mm_per_s=300.0), {})
    loaded = load_trial(path, mano_dir=folder)
    model = loaded.scene.model
    assert "stand" not in [model.geom(g).name for g in range(model.ngeom)]
    assert loaded.scene.setup.checks["support"] == {"kind": "none"}
    assert any(
        x.startswith("no support: the recording holds the object off it") for x in loaded.scene.setup.notes
    )


# --------------------------------------------------------------------------------------------- start states


def _lid_contacts(scene, data) -> list[tuple[str, float]]:
    """The lid–base contacts at ``data`` (pair name, depth), by MuJoCo's collision detection."""
    model = scene.model
    mujoco.mj_collision(model, data)
    geoms = set(scene.layout.objects[0].collision_geoms)
    pairs = {
        tuple(sorted((int(model.pair_geom1[i]), int(model.pair_geom2[i])))): model.pair(i).name
        for i in range(model.npair)
    }
    found = []
    for c in data.contact[: data.ncon]:
        key = tuple(sorted((int(c.geom1), int(c.geom2))))
        if key in pairs and set(key) <= geoms:
            found.append((pairs[key], -float(c.dist)))
    return found


def _lid_angles(loaded, seconds: float) -> np.ndarray:
    result = replay(loaded.scene, loaded.trajectory, ReplayConfig(keep_states=True))
    hinge = loaded.scene.layout.objects[0].hinge_qpos
    return np.degrees(result.states[: int(seconds * 100) + 1, hinge])


def test_a_lid_inside_its_base_starts_at_the_nearest_angle_without_overlap_and_is_not_thrown(mano, tmp_path):
    folder, _ = mano
    n = 31
    lid = ((-120.0, -60.0), (-6.0, 4.0), (-80.0, 80.0))  # 6 mm into the base, its far half only
    path, _ = arctic_root(tmp_path, n, object_rows(n, np.linspace(0.0, 0.05, n)), {}, lid=lid)
    loaded = load_trial(path, mano_dir=folder)
    hinge = loaded.scene.setup.checks["hinge"]
    assert hinge["recorded_overlap_mm"] == pytest.approx(6.0, abs=0.01)
    assert 4.5 < hinge["start_deg"] <= 5.0 and not hinge["excluded_pairs_mm"]  # 60 mm · sin 5° = 5.2 mm
    data = frame0(loaded.scene, loaded.trajectory)
    assert math.degrees(data.qpos[loaded.scene.layout.objects[0].hinge_qpos]) == pytest.approx(
        hinge["start_deg"]
    )
    assert max(d for _, d in _lid_contacts(loaded.scene, data)) <= PART_OVERLAP_TOLERANCE
    assert any("the nearest angle at which no part is more than 1 mm" in x for x in loaded.scene.setup.notes)
    angles = _lid_angles(loaded, 0.3)
    assert np.ptp(angles) < 1.5  # the 1 mm left pushes the lid's near edge out, nothing more


def test_a_lid_overlapping_its_base_at_every_nearby_angle_has_that_pair_excluded_and_stays(mano, tmp_path):
    folder, _ = mano
    n = 31
    lid = ((-120.0, 0.0), (-3.0, 7.0), (-80.0, 80.0))  # 3 mm into the base along its whole length
    path, _ = arctic_root(tmp_path, n, object_rows(n, 0.0), {}, lid=lid)
    loaded = load_trial(path, mano_dir=folder)
    hinge = loaded.scene.setup.checks["hinge"]
    assert hinge["start_deg"] == 0.0 and hinge["residual_overlap_mm"] == 0.0
    assert hinge["excluded_pairs_mm"] == {"obj/pair_0_0": pytest.approx(3.0, abs=0.01)}
    assert loaded.scene.model.npair == 0  # the one pair (one hull per part) no longer collides
    assert _lid_contacts(loaded.scene, frame0(loaded.scene, loaded.trajectory)) == []
    assert np.abs(_lid_angles(loaded, 0.3)).max() < 0.1  # the stop at the closed pose holds it


def test_a_lid_the_checks_keep_shut_is_thrown_to_its_stop_without_them(mano, tmp_path):
    folder, _ = mano
    n = 31
    lid = ((-120.0, -20.0), (-5.0, 5.0), (-80.0, 80.0))  # 5 mm in: 20 mm · sin 5° clears 1.7 mm of it
    rows = object_rows(n, np.linspace(0.0, 0.05, n))
    path, hands = arctic_root(tmp_path, n, rows, {}, lid=lid)
    loaded = load_trial(path, mano_dir=folder)
    assert list(loaded.scene.setup.checks["hinge"]["excluded_pairs_mm"]) == ["obj/pair_0_0"]
    assert np.ptp(_lid_angles(loaded, 0.3)) < 0.1
    box = box_spec(tmp_path, rows)
    unchecked = arctic_scene(hand_specs(folder, hands), loaded.trajectory, box, "box", checks=False)
    result = replay(unchecked, loaded.trajectory, ReplayConfig(keep_states=True))
    angle = np.degrees(result.states[:31, unchecked.layout.objects[0].hinge_qpos])
    upper = math.degrees(unchecked.model.jnt_range[unchecked.model.joint("obj/hinge").id][1])
    assert angle.max() > upper - 0.5  # 5 mm of overlap throws the lid to its +10° stop in 0.3 s


def test_each_hands_starting_penetration_is_measured_and_reported(mano, tmp_path):
    folder, _ = mano
    n = 12
    path, _ = arctic_root(tmp_path, n, object_rows(n), {"right": (0.02, 0.0, 0.04)})  # the palm in the box
    loaded = load_trial(path, mano_dir=folder)
    start = loaded.scene.setup.checks["start_penetration_mm"]
    assert start["right"] > 20.0 and start["left"] == 0.0
    note = next(x for x in loaded.scene.setup.notes if x.startswith("starting penetration"))
    assert f"right {start['right']:.1f} mm" in note and "left 0.0 mm" in note
    result = replay(loaded.scene, loaded.trajectory)
    assert result.summary["right/start_penetration_mm"] == start["right"]
    assert result.summary["left/start_penetration_mm"] == 0.0
    # MuJoCo's own penetration sensor at frame 0 agrees
    assert result.frames.hand_penetration[0, 0] * 1000 == pytest.approx(start["right"], abs=1e-6)
