"""A glove hold counts only where the grip is one: opposing contacts, no link inside, servo forces."""

from __future__ import annotations

import json
import re
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh

from handsim.assets import ASSETS_DIR
from handsim.sim.grip_check import GripCheck, check_grip
from handsim.sim.replay import ReplayConfig, replay
from handsim.sim.specs import GripSpec, MetricSpec
from handsim.trials import TrialError
from handsim.trials.registry import load_trial

DEMO = ASSETS_DIR / "demo"
LIMITS = GripSpec()
GRIP_REASONS = (
    "not judged: link ",
    "not judged: wedged: ",
    "not judged: no grip: ",
    "not judged: the object could not be placed",
)


def _check(**fields) -> GripCheck:
    values = {
        "window": (1.0, 2.0), "frames": 40, "links": ("th_ip", "if_dip"), "opposition": 1.0,
        "opposing_links": ("th_ip", "if_dip"), "deepest_link": "if_dip", "max_depth": 0.002,
        "deepest_at": 1.5, "depth_limit": 0.005, "wall": 0.02, "grip_force": 8.0, "force_limit": 60.0,
        "torque_limit": 3.0, "weight": 0.5,
    }  # fmt: skip
    values.update(fields)
    return GripCheck(**values)


def test_a_grip_within_every_limit_stands():
    check = _check()
    assert check.depth_failure(LIMITS) is None and check.grip_failure(LIMITS) is None


def test_a_link_deeper_than_the_pad_and_the_tolerance_is_not_judged():
    check = _check(deepest_link="th_ip", max_depth=0.0091, deepest_at=1.234)
    assert check.depth_failure(LIMITS) == (
        "not judged: link th_ip is 9.1 mm inside the object at 1.234 s (at most 5 mm: the pad's compliance "
        "and the placement's tolerance): a tunnelled or wedged grip"
    )


def test_a_link_deeper_than_a_thin_wall_may_have_passed_through_it():
    check = _check(deepest_link="rf_dip", max_depth=0.0042, deepest_at=1.21, depth_limit=0.003, wall=0.003)
    assert check.depth_failure(LIMITS) == (
        "not judged: link rf_dip is 4.2 mm inside the object at 1.210 s (at most 3 mm: the object's wall "
        "there is 3.0 mm thick: it may have passed through): a tunnelled or wedged grip"
    )


def test_a_grip_force_beyond_what_the_servos_can_press_with_is_a_wedge():
    check = _check(grip_force=344.0, force_limit=14.2, torque_limit=0.71, weight=0.56)
    assert check.grip_failure(LIMITS) == (
        "not judged: wedged: 344.0 N of grip force from servos of at most 0.71 N·m, which press with at most "
        "14.2 N at these contacts (+ the object's weight, 0.56 N)"
    )


def test_a_hold_without_opposing_contacts_is_no_grip():
    check = _check(links=("th_ip", "root"), opposition=0.25, opposing_links=None)
    assert check.grip_failure(LIMITS) == (
        "not judged: no grip: the thumb and a finger, or fingers and the palm, press on the object from "
        "opposing sides in 25% of the hold window (at least 50% needed); touching: th_ip, root"
    )
    assert (
        _check(opposition=None, links=())
        .grip_failure(LIMITS)
        .endswith("(at least 50% needed); touching: nothing")
    )


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("max_depth", 0.0, "grip max_depth must be a positive finite number, got 0.0"),
        ("min_opposition", 1.5, "grip min_opposition must be a fraction in [0, 1], got 1.5"),
        ("frames", 0, "grip frames must be ≥ 1, got 0"),
    ],
)
def test_grip_limits_out_of_range_raise_error(field, value, message):
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        GripSpec(**{field: value})


def test_grip_limits_round_trip_through_the_metric_spec():
    spec = MetricSpec(grip=GripSpec(max_depth=0.004, min_opposition=0.6, frames=12))
    assert MetricSpec.from_dict(spec.to_dict()) == spec


@pytest.fixture(scope="module")
def ball():
    loaded = load_trial(DEMO / "tennis_ball.grasp.json")
    return loaded, replay(loaded.scene, loaded.trajectory, ReplayConfig(ensemble=False, keep_states=True))


@pytest.mark.slow
def test_the_demo_ball_is_held_by_opposing_contacts_within_every_limit(ball):
    _, result = ball
    grip = result.grip
    assert result.hold.held is True
    assert grip.opposition >= LIMITS.min_opposition and grip.opposing_links is not None
    assert grip.max_depth <= LIMITS.max_depth and grip.grip_force <= grip.force_limit
    assert grip.window == pytest.approx(result.hold.window, abs=result.frame_dt)
    assert result.summary["grip_opposition"] == grip.opposition
    assert result.summary["deepest_link_mm"] == grip.max_depth * 1000.0


@pytest.mark.slow
def test_a_ball_moved_into_a_finger_is_a_tunnelled_grip(ball):
    loaded, result = ball
    scene = loaded.scene
    obj = scene.layout.objects[0]
    qpos = np.repeat(_held_state(result)[None], 3, axis=0)
    data = mujoco.MjData(scene.model)
    data.qpos[:] = qpos[0]
    mujoco.mj_kinematics(scene.model, data)
    link = scene.layout.link_bodies[list(scene.layout.link_names).index(result.grip.deepest_link)]
    towards = data.xpos[link] - qpos[0, obj.free_qpos : obj.free_qpos + 3]
    qpos[:, obj.free_qpos : obj.free_qpos + 3] += 0.012 * towards / np.linalg.norm(towards)
    sensors = np.empty((3, scene.model.nsensordata))
    for k in range(3):
        data.qpos[:] = qpos[k]
        mujoco.mj_forward(scene.model, data)
        sensors[k] = data.sensordata
    check = check_grip(scene, qpos, sensors, np.array([0.0, 0.01, 0.02]), (0.0, 0.02), LIMITS)
    assert check.max_depth > LIMITS.max_depth
    assert check.depth_failure(LIMITS).startswith(f"not judged: link {check.deepest_link} is ")


def _held_state(result) -> np.ndarray:
    """The ball replay's state in the middle of its hold window."""
    times = result.frames.times
    return result.states[int(np.searchsorted(times, sum(result.hold.window) / 2))]


def test_the_demo_cylinder_closing_through_its_object_is_not_judged():
    loaded = load_trial(DEMO / "cylinder_25mm.grasp.json")
    result = replay(loaded.scene, loaded.trajectory, ReplayConfig(ensemble=False))
    assert result.hold.held is None and result.summary["held"] is None
    assert result.hold.reason.startswith("not judged: link lf_dip is 7.7 mm inside the object at ")
    assert result.summary["deepest_link"] == "lf_dip"


def _wall(tmp_path: Path) -> Path:
    """A 3 mm plywood divider, 60 × 60 mm, as an OBJ in millimetres."""
    path = tmp_path / "divider.obj"
    trimesh.creation.box(extents=(3.0, 60.0, 60.0)).export(path)
    return path


@pytest.mark.slow
def test_a_hand_closing_on_a_thin_wall_is_never_held(tmp_path):
    loaded = load_trial(DEMO / "cube.grasp.json", obj=_wall(tmp_path), units="mm", density=600.0)
    result = replay(loaded.scene, loaded.trajectory, ReplayConfig(ensemble=False))
    assert result.hold.held is not True
    if result.hold.held is None:
        assert result.hold.reason.startswith(GRIP_REASONS)


def _cut_off(tmp_path: Path) -> Path:
    """The demo ball's scripted grasp ending while the hand still holds: its one episode is truncated."""
    fields = json.loads((DEMO / "tennis_ball.grasp.json").read_text(encoding="utf-8"))
    fields["open_s"] = 0.0
    path = tmp_path / "cut.grasp.json"
    path.write_text(json.dumps(fields), encoding="utf-8")
    return path


def test_a_truncated_episode_is_never_judged(tmp_path):
    path = _cut_off(tmp_path)
    with pytest.raises(
        TrialError, match=r"grasp episode 1 is truncated \(the annotated grasp ends at the last"
    ):
        load_trial(path, grasp=1)
    loaded = load_trial(path)  # the whole recording: the hand is measured, its hold not judged
    result = replay(loaded.scene, loaded.trajectory, ReplayConfig(ensemble=False))
    assert result.hold.held is None and result.summary["held"] is None
    assert result.summary["hold_reason"] == (
        "not judged: the recording holds no complete grasp episode (episode 1: the annotated grasp ends at "
        "the last frame)"
    )
    assert result.grip is None and result.summary["grip_opposition"] is None


def test_the_closure_tests_cross_products_are_numpys_bitwise():
    from handsim.sim.grip_check import _cross

    rng = np.random.default_rng(7)
    for left, right in (((6, 3), (6, 3)), ((6, 3), (1, 3)), ((6, 1, 3), (6, 8, 3))):
        a, b = rng.normal(size=left), rng.normal(size=right)
        assert np.array_equal(_cross(a, b), np.cross(a, b))
