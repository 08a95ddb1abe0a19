"""The replay core: recorded-object and glove scenarios on real data, divergence, determinism, pickling."""

from __future__ import annotations

import copy
import pickle
from dataclasses import fields, replace
from functools import cache

import numpy as np
import pytest

import handsim.sim.replay as replay_module
from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.builders import build_hand, build_scene, default_hand
from handsim.builders.catalog import get, get_graspdb
from handsim.builders.objects import build_object
from handsim.datatypes.trajectory import Phase, Trajectory
from handsim.errors import SimulationError, TrajectoryError
from handsim.io import read_skeleton, read_trajectory
from handsim.io.graspdb.annotations import attach_phases, find_annotation_file
from handsim.io.tzionas.objects import read_tzionas_object
from handsim.io.tzionas.sequence import read_tzionas_sequence
from handsim.sim.control import control_schedule
from handsim.sim.drive import ScenarioSwitches, ScheduleDriver
from handsim.sim.placement.robustness import ensemble_scenes
from handsim.sim.replay import ReplayConfig, member_verdict, replay
from handsim.sim.scenarios import glove_scene, recorded_scene
from handsim.sim.scene.compiled import compile_scene
from handsim.sim.stepper import Stepper
from handsim.sim.warnings import WARNING_NAMES
from handsim.trials import load_trial

SEQ20 = TZIONAS_DIR / "Models" / "20"


@cache
def _tzionas() -> tuple:
    trajectory = read_tzionas_sequence(SEQ20)
    hand = build_hand(read_skeleton(SEQ20 / "Model_Hand_R.SKEL"))
    cube = build_object(read_tzionas_object(SEQ20 / "Model_Object_Cube.SKEL"))
    return recorded_scene(hand, trajectory, {"cube": cube}), trajectory


@cache
def _tzionas_result():
    scene, trajectory = _tzionas()
    return replay(scene, trajectory)


def _assert_results_equal(a, b) -> None:
    for f in fields(a.frames):
        x, y = getattr(a.frames, f.name), getattr(b.frames, f.name)
        floats = np.asarray(x).dtype.kind == "f"
        assert np.array_equal(x, y, equal_nan=floats), f.name
    assert a.to_dict() == b.to_dict()


def test_tzionas_seq20_replays_end_to_end_with_zero_warnings_and_reports_cube_drift_per_frame():
    result = _tzionas_result()
    scene, trajectory = _tzionas()
    assert result.warnings == () and result.diverged is None
    n = result.frames.times.shape[0]
    assert n == control_schedule(scene, trajectory, 100.0).frames == 617
    drift = result.frames.object_position_error[:, 0]
    assert drift.shape == (n,) and np.all(np.isfinite(drift))
    assert drift[0] == pytest.approx(0.0, abs=1e-9)  # the cube starts at its recorded pose
    assert 0.0 <= result.summary["within_tolerance"] <= 1.0
    assert result.summary["within_tolerance"] == pytest.approx(float(np.mean(drift <= 0.01)))
    assert result.summary["max_drift_mm"] == pytest.approx(drift.max() * 1000)
    assert result.summary["contact_frames"] > 0  # the hand touches the cube it moves


def test_tzionas_hand_root_follows_the_recorded_root_pose_through_the_weld():
    result = _tzionas_result()
    # fingertips follow their kinematic targets (recorded root pose + fitted joint angles) within ~1 cm
    assert result.summary["mean_tip_error_mm"] < 10.0
    assert result.summary["max_tracking_error_deg"] < 10.0


def test_recorded_scene_puts_the_support_plane_under_the_cube_at_z0_and_gravity_near_image_down():
    scene, trajectory = _tzionas()
    assert scene.setup.scenario == "recorded" and scene.setup.object_tracks == ("cube",)
    assert "+y axis" in scene.setup.notes[0] and "22.6°" in scene.setup.notes[0]
    stepper = Stepper(scene, 1)
    ScheduleDriver(stepper, control_schedule(scene, trajectory, 100.0), ScenarioSwitches()).reset()
    data, model = stepper.data, scene.model
    cube = [g for g in range(model.ngeom) if model.geom_bodyid[g] == scene.layout.objects[0].root_body]
    lowest = min(
        (model.mesh_vert[model.mesh_vertadr[m] : model.mesh_vertadr[m] + model.mesh_vertnum[m]]
         @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g])[:, 2].min()
        for g in cube if (m := model.geom_dataid[g]) >= 0 and model.geom_contype[g]
    )  # fmt: skip
    assert lowest == pytest.approx(0.0, abs=1e-6)  # MuJoCo stores mesh vertices as float32


def test_replaying_twice_gives_bitwise_identical_results():
    scene, trajectory = _tzionas()
    _assert_results_equal(replay(scene, trajectory), _tzionas_result())


def test_scene_pickles_and_an_unpickled_scene_replays_identically():
    scene, trajectory = _tzionas()
    clone = pickle.loads(pickle.dumps(scene))
    assert clone.model_sha256 == scene.model_sha256
    _assert_results_equal(replay(clone, trajectory), _tzionas_result())


def test_a_diverging_replay_is_reported_as_diverged_at_the_step_it_happened():
    scene, trajectory = _tzionas()
    root = trajectory.root_pose.copy()
    root[60:, 0] += 1e9  # the root's target jumps 10⁶ km away: the weld blows up
    bad = replace(trajectory, root_pose=root)
    result = replay(scene, bad)
    assert result.diverged is not None and result.diverged.name == "mjWARN_BADQACC"
    assert result.summary["diverged"] is True

    # independent check: one step at a time, the first step whose warning counters move
    schedule = control_schedule(scene, bad, 100.0)
    stepper = Stepper(scene, 1)
    ScheduleDriver(stepper, schedule, ScenarioSwitches()).reset()
    data, step, first = stepper.data, 0, None
    for k in range(schedule.frames - 1):
        data.mocap_pos[0], data.mocap_quat[0] = schedule.root_pose[k + 1, :3], schedule.root_pose[k + 1, 3:]
        for _ in range(schedule.substeps):
            if stepper.step(schedule.ctrl[k + 1]):
                first = step
                break
            step += 1
        if first is not None:
            break
    assert result.diverged.step == first
    assert result.diverged.frame == first // schedule.substeps
    assert result.frames.times.shape[0] == result.diverged.frame + 1  # frames up to the divergence only
    assert "QACC" in result.diverged.message


@pytest.mark.parametrize("where", ["another thread", "this thread, before the run"])
def test_a_warning_message_goes_to_its_own_run(where: str):
    """MuJoCo's warning hook is process-wide; a run's events carry its own messages only. A warning left
    unread (a bad ``qpos`` at DOF 5) by another thread (the stability directions, grip tests and ensemble
    members run on threads) or by earlier work in this one (a collision query, a forward pass) is not
    attached to this run's event (a bad ``qpos`` at DOF 3): on one thread and on several alike."""
    import threading

    import mujoco

    scene, _ = _tzionas()

    def leave_one_unread() -> None:
        Stepper(scene, 1)  # installs the hook
        data = mujoco.MjData(scene.model)
        data.qpos[5] = np.nan
        mujoco.mj_step(scene.model, data)  # a warning whose message no stepper reads

    if where == "another thread":
        other = threading.Thread(target=leave_one_unread)
        other.start()
        other.join()
    stepper = Stepper(scene, 1)
    if where != "another thread":
        leave_one_unread()
    stepper.reset()
    stepper.data.qpos[3] = np.nan
    (event,) = stepper.step()
    assert event.name == "mjWARN_BADQPOS" and event.info == 3
    assert "DOF 3" in event.message and "DOF 5" not in event.message


def test_non_finite_targets_are_refused_before_stepping():
    scene, trajectory = _tzionas()
    targets = trajectory.targets.copy()
    targets[:, 3] = np.inf
    with pytest.raises(SimulationError, match="non-finite value at frame 0, column"):
        replay(scene, replace(trajectory, targets=targets))


def test_a_trajectory_dof_the_hand_lacks_is_an_error_listing_the_hand_dofs():
    scene, trajectory = _tzionas()
    names = ("wrong_dof", *trajectory.dof_names[1:])
    with pytest.raises(TrajectoryError, match=r"DoFs \['wrong_dof'\] are not DoFs of the hand"):
        replay(scene, replace(trajectory, dof_names=names))


def test_a_welded_hand_needs_a_root_pose():
    scene, trajectory = _tzionas()
    with pytest.raises(TrajectoryError, match="has none"):
        replay(scene, replace(trajectory, root_pose=None, objects={}))


def test_keep_states_returns_qpos_per_frame():
    scene, trajectory = _tzionas()
    result = replay(scene, trajectory, ReplayConfig(keep_states=True))
    assert result.states.shape == (result.frames.times.shape[0], scene.model.nq)


def _ball_trajectory(layout, frames: int = 120) -> Trajectory:
    t = np.arange(frames) / 60.0
    closing = np.clip(t / 1.0, 0, 1)[:, None]
    flex = np.array(["flex" in n and not n.startswith("root") for n in layout.dof_names])
    targets = closing * np.where(flex, 0.6 * layout.ctrl_range[:, 1], 0.0)
    return Trajectory(times=t, dof_names=layout.dof_names, targets=targets, valid=np.ones_like(targets, bool))


def test_glove_scene_places_the_object_supports_it_and_releases_it_after_the_grasp_frame():
    hand, ball = default_hand(), build_object(get("tennis_ball"))
    probe = compile_scene(build_scene(hand, ball))
    trajectory = _ball_trajectory(probe.layout)
    scene = glove_scene(hand, trajectory, ball)
    setup = scene.setup
    assert setup.scenario == "glove" and setup.placement["grasp"]["source"] == "peak flexion"
    assert setup.placement["links"], setup.notes
    assert setup.placement["penetration_m"] <= 0.002
    result = replay(scene, trajectory)
    assert result.hold is not None
    assert result.hold.released_at == pytest.approx(setup.release_time + 0.1, abs=0.011)
    assert result.summary["held"] == result.hold.held
    # before release the support holds the object still
    release = int(np.searchsorted(result.frames.times, result.hold.released_at - 1e-9))
    inside = result.frames.object_in_hand[:release, 0]
    assert np.abs(inside - inside[0]).max() < 2e-3  # the stiff weld gives ~1 mm under finger forces


def test_graspdb_power_sphere_trial_places_the_ball_and_reports_the_hold_through_the_grasp_phase(graspdb_dir):
    path = graspdb_dir / "r_01_11_ex03-rad-004-grasp-su04.txt"
    skeleton = read_skeleton(graspdb_dir / "default.xmlskel")
    trajectory = attach_phases(read_trajectory(path, skeleton=skeleton), find_annotation_file(path))
    ball = build_object(get_graspdb(1))
    scene = glove_scene(build_hand(skeleton), trajectory, ball)
    placement = scene.setup.placement
    grasp = placement["grasp"]
    assert grasp == {"frame": 81, "open": 45, "closed": 126, "window": [81, 163], "source": "phase"}
    # closed: the first frame of the phase with 98 % of the flexion rise within it (independent sum)
    flex = trajectory.targets[:, ["flex" in n and not n.startswith("root") for n in trajectory.dof_names]]
    total = flex.sum(axis=1)
    rise = total[81:164]
    level = rise[0] + 0.98 * (rise.max() - rise[0])
    assert rise[126 - 81] >= level > rise[125 - 81]
    # open: the least flexed frame of the 2 s before the closed frame
    first = int(np.searchsorted(trajectory.times, trajectory.times[126] - 2.0 - 1e-9))
    assert first + int(np.argmin(total[first:127])) == 45
    # the ball fits (≤ 2 mm) where the closing has come fit_fraction of the way, and the recorded closing
    # presses on it after: it is gripped in all six gravity directions at the release
    fit = placement["fit_frame"]
    assert 45 <= fit <= 126 and placement["penetration_m"] <= 0.002 and placement["feasible"]
    assert placement["fit_fraction"] == pytest.approx((total[fit] - total[45]) / (total[126] - total[45]))
    assert placement["grip"]["directions_held"] == 6 and placement["grip_tests"] >= 2
    # contacts act from the start of the run of fitting frames, at most from the open frame
    contact = placement["contact_trajectory_frame"]
    assert 45 <= contact <= fit and scene.setup.contact_time == trajectory.times[contact]
    result = replay(scene, trajectory)
    assert result.diverged is None and result.warnings == ()
    first_touch = int(np.flatnonzero(result.frames.hand_contact[:, 0])[0])
    assert first_touch >= result.scene["contact_frame"]
    hold = result.hold
    assert hold.window[1] == pytest.approx(trajectory.times[163])
    assert hold.released_at == pytest.approx(trajectory.times[126] + 0.1, abs=0.011)
    assert hold.held is True and hold.time_held == pytest.approx(hold.window[1] - hold.released_at, abs=0.011)
    placements = [m for m in result.robustness.members if m.factor == "placement"]
    assert len(placements) == len(placement["ensemble"]) + 1  # and the hand members: thumb, undriven, sensors
    assert {m.factor for m in result.robustness.members} == {"placement", "thumb", "undriven", "sensor"}
    assert result.summary["release_directions_held"] == 6


def test_a_pickled_driver_continues_exactly_like_the_original():
    scene, trajectory = _tzionas()
    schedule = control_schedule(scene, trajectory, 100.0)
    driver = ScheduleDriver(Stepper(scene, schedule.substeps), schedule, ScenarioSwitches())
    driver.reset()
    for k in range(50):
        driver.advance(schedule.ctrl[k + 1])
    clone = pickle.loads(pickle.dumps(driver))
    assert clone.stepper.data is not driver.stepper.data and clone.frame == 50
    for k in range(50, 120):
        assert driver.advance(schedule.ctrl[k + 1]) == clone.advance(schedule.ctrl[k + 1]) == ()
    assert np.array_equal(driver.stepper.data.qpos, clone.stepper.data.qpos)
    # the clone's warning counters are live views of its own data
    clone.stepper.data.warning.number[WARNING_NAMES.index("mjWARN_BADQACC")] += 1
    assert clone.stepper.step(schedule.ctrl[120])[0].name == "mjWARN_BADQACC"


def test_glove_replay_switches_contacts_on_its_own_model_copy_and_leaves_the_scene_alone():
    hand, ball = default_hand(), build_object(get("tennis_ball"))
    probe = compile_scene(build_scene(hand, ball))
    t = np.arange(100) / 64.0
    flex = np.array(["flex" in n and not n.startswith("root") for n in probe.layout.dof_names])
    # a fist first (through where the ball will be), then open, then close on it
    closing = np.where(t < 0.2, 0.95, np.clip((t - 0.4) / 0.6, 0, 0.6 / 0.95) * 0.95)
    targets = closing[:, None] * np.where(flex, probe.layout.ctrl_range[:, 1], 0.0)
    phases = (Phase("grasp", int(np.searchsorted(t, 0.8)), 100),)
    trajectory = Trajectory(t, probe.layout.dof_names, targets, np.ones_like(targets, bool), phases=phases)
    scene = glove_scene(hand, trajectory, ball)
    before = scene.model.geom_contype.copy()
    result = replay(scene, trajectory)
    assert np.array_equal(scene.model.geom_contype, before)
    contact = result.scene["contact_frame"]
    assert contact > 0
    # before contacts act, the fist passes through the ball's place without touching it
    assert not result.frames.hand_contact[: contact + 1, 0].any()
    assert result.frames.penetration[: contact + 1].max() == 0.0  # the sensors follow the contact switch


def test_a_run_stopped_by_until_has_the_whole_runs_first_rows():
    scene, trajectory = _tzionas()
    schedule = control_schedule(scene, trajectory, 100.0)

    def driver() -> ScheduleDriver:
        d = ScheduleDriver(Stepper(scene, schedule.substeps), schedule, ScenarioSwitches())
        d.reset()
        return d

    whole, whole_sensors, _, _ = replay_module.run_schedule(driver(), frames=40)
    asked = []

    def until(qpos, sensors) -> bool:
        asked.append(qpos.shape[0])
        np.testing.assert_array_equal(qpos, whole[: qpos.shape[0]])
        np.testing.assert_array_equal(sensors, whole_sensors[: qpos.shape[0]])
        return qpos.shape[0] == 21  # stop at frame 20

    # any order, repeats and frames outside the run are fine: asked at 10 and 20 only, once each
    qpos, sensors, _, diverged = replay_module.run_schedule(
        driver(), frames=40, until=until, checks=(20, 0, 10, 20, 99)
    )
    assert asked == [11, 21] and diverged is None
    np.testing.assert_array_equal(qpos, whole[:21])
    np.testing.assert_array_equal(sensors, whole_sensors[:21])
    never = replay_module.run_schedule(driver(), frames=40, until=lambda q, s: False, checks=())
    assert never[0].shape[0] == 40


def _member_holds_match_their_whole_replays(scene, trajectory, monkeypatch) -> int:
    """Every ensemble member's verdict equals its whole replay's; a lost member stops soon after the loss."""
    config = ReplayConfig(ensemble=False)
    schedule = control_schedule(scene, trajectory, config.control_rate)
    members = ensemble_scenes(scene)
    simulated = []  # rows each member's run returned
    whole_run = replay_module.run_schedule

    def recorded(*args, **kwargs):
        result = whole_run(*args, **kwargs)
        simulated.append(result[0].shape[0])
        return result

    lost = 0
    for label, variant in members:
        whole = replay(variant, trajectory, config).hold
        with monkeypatch.context() as patch:
            patch.setattr(replay_module, "run_schedule", recorded)
            assert member_verdict(variant, schedule, config.metrics) == (whole.held, whole.reason), label
        window_end = int(np.searchsorted(schedule.times, whole.window[1] + 1e-9))
        if whole.held is False:  # stopped at the first look after the loss is seen (looks 0.1 s, 0.2 s … in)
            lost += 1
            looked = schedule.times[simulated[-1] - 1] - whole.released_at
            seen = whole.lost_at - whole.released_at  # a slip is seen where it is lost, a contact gap later
            seen += config.metrics.contact_gap if whole.reason.startswith("no hand contact") else 0.0
            assert simulated[-1] < window_end and looked < 2 * max(seen, 0.1)
        elif whole.held is True:  # simulated to the window's end and no further
            assert simulated[-1] == window_end
        else:  # not judged by the grip check: up to its loss, or to the window's end
            assert simulated[-1] <= window_end
    assert members
    return lost


@pytest.mark.slow
def test_an_ensemble_member_judged_up_to_the_window_end_is_its_whole_replay_bitwise(monkeypatch):
    loaded = load_trial(ASSETS_DIR / "demo" / "tennis_ball.grasp.json")
    _member_holds_match_their_whole_replays(loaded.scene, loaded.trajectory, monkeypatch)


@pytest.mark.slow
def test_ensemble_members_lost_and_held_are_judged_as_by_their_whole_replays(graspdb_dir, monkeypatch):
    # the fk_oracle motion's one complete grasp episode: its members lose the ball (tests/test_verdicts.py)
    loaded = load_trial(graspdb_dir / "fk_oracle" / "16_14_ex01-rad-004-grasp-su06", grasp=1)
    assert _member_holds_match_their_whole_replays(loaded.scene, loaded.trajectory, monkeypatch) > 0


@pytest.mark.slow
def test_the_ensemble_on_threads_judges_as_on_one_thread(monkeypatch):
    # the demo ball's grasp episode: held by all but one member (the sensors offset -3°)
    loaded = load_trial(ASSETS_DIR / "demo" / "tennis_ball.grasp.json", grasp=1)
    results, ahead = {}, []
    members_ahead = replay_module._members_ahead

    def watched(*args):
        ahead.append(members_ahead(*args))
        return ahead[-1]

    monkeypatch.setattr(replay_module, "_members_ahead", watched)
    for threads in ("1", "2"):
        monkeypatch.setenv("HANDSIM_THREADS", threads)
        results[threads] = replay(loaded.scene, loaded.trajectory)
    assert ahead[0] is None and ahead[1] is not None  # on threads, the members ran beside the winner
    one, two = results["1"], results["2"]
    assert one.robustness == two.robustness and 0 < one.robustness.held < one.robustness.judged
    assert one.release_stability == two.release_stability and one.summary == two.summary


def test_members_judged_ahead_of_a_run_that_diverges_are_dropped_and_waited_for(monkeypatch):
    """The members start beside the winner's run when its hold will be judged; if the run then diverges
    before the release, the hold is not judged, and the members' answers are dropped once they are in."""
    loaded = load_trial(ASSETS_DIR / "demo" / "tennis_ball.grasp.json")
    whole_run, members_ahead, ahead = replay_module.run_schedule, replay_module._members_ahead, []

    def diverging(driver, *args, **kwargs):
        qpos, sensors, _, _ = whole_run(driver, frames=5)
        event = replay_module.WarningEvent("mjWARN_BADQACC", 19, 3, 1, 0, diverged=True)
        return qpos[:4], sensors[:4], [event], event

    def watched(*args):
        ahead.append(members_ahead(*args))
        return ahead[-1]

    monkeypatch.setenv("HANDSIM_THREADS", "2")
    monkeypatch.setattr(replay_module, "run_schedule", diverging)
    monkeypatch.setattr(replay_module, "_members_ahead", watched)
    result = replay(loaded.scene, loaded.trajectory)
    assert result.diverged is not None and not result.hold.judged and result.robustness is None
    assert ahead[0] is not None and ahead[0].done()  # they ran, and the replay waited for them


@pytest.mark.parametrize("threads", ["1", "2"])
def test_a_members_error_comes_first_with_the_members_ahead_or_not(monkeypatch, threads):
    """Whether the members ran ahead or not, an error of theirs is raised before one of the release test
    (the order of the one-thread replay: members, then the release test)."""
    loaded = load_trial(ASSETS_DIR / "demo" / "tennis_ball.grasp.json")

    def member_fails(*args, **kwargs):
        raise KeyError("member")

    def release_fails(*args, **kwargs):
        raise IndexError("release")

    monkeypatch.setenv("HANDSIM_THREADS", threads)
    monkeypatch.setattr(replay_module, "member_verdict", member_fails)
    monkeypatch.setattr(replay_module, "_release_stability", release_fails)
    with pytest.raises(KeyError, match="member"):
        replay(loaded.scene, loaded.trajectory)


def test_a_replay_without_a_hold_does_not_ask_for_threads(monkeypatch):
    """The thread setting is read where runs go on threads, not by every replay (a bad one is an error
    there: tests/test_parallel.py)."""
    monkeypatch.setenv("HANDSIM_THREADS", "none")
    scene, trajectory = _tzionas()
    assert replay(scene, trajectory).hold is None


def test_the_model_hash_is_the_compiled_models_same_spec_same_hash_any_change_another():
    from handsim.sim.scene.compiled import model_digest

    spec = build_scene(default_hand(), build_object(get("tennis_ball")))
    first, again = compile_scene(spec), compile_scene(spec)
    assert first.model_sha256 == again.model_sha256 == model_digest(again.model)
    assert len(first.model_sha256) == 64
    changed = copy.deepcopy(again.model)
    changed.geom_friction[0, 0] += 1e-9  # one number the simulation reads
    assert model_digest(changed) != first.model_sha256
