"""Grasp stability tests: a tennis ball enclosed by the default hand holds in all six directions of gravity,
the same ball with the hand open does not; the spec travels with the result; bad inputs raise."""

from __future__ import annotations

import copy
import dataclasses
import json
import pickle

import mujoco
import numpy as np
import pytest

from handsim.builders import default_hand
from handsim.builders.catalog import get
from handsim.builders.hand import build_hand
from handsim.builders.objects import build_object
from handsim.builders.scene import build_scene
from handsim.errors import SimulationError
from handsim.io.graspdb.default_skeleton import DEFAULT_BREADTH_RATIO, DEFAULT_HAND_LENGTH_M, default_skeleton
from handsim.sim.scene.compiled import SimScene, compile_scene
from handsim.sim.specs import STABILITY_SPEC_VERSION, StabilitySpec
from handsim.sim.stability.gravity import DIRECTIONS, stability_test

BALL_CENTRE = (0.0, -0.075, 0.0739)
"""Under the palm of the default hand at the scene's default hand position (wrist at z = 0.12 m, palm
facing −z): between the palm's centre and the knuckles, the 32 mm ball touching the palm's lower face
(z = 0.1059 m)."""
FINGER_CLOSURE = 0.6
"""Flexion targets of the four fingers as a fraction of their range: curled around the ball."""
THUMB = {"th_tmc_abd": 0.5, "th_tmc_pron": 2.0, "th_tmc_flex": 0.3, "th_mcp_flex": 0.8, "th_ip_flex": 0.6}
"""Thumb targets (rad): opposed, wrapping the ball from the thumb side."""


def _ball_scene(hand: mujoco.MjSpec, hand_root: str = "fixed") -> SimScene:
    ball = build_object(get("tennis_ball"))
    spec = build_scene(
        hand,
        [ball],
        object_poses=[[*BALL_CENTRE, 1.0, 0.0, 0.0, 0.0]],
        object_support=True,
        hand_root=hand_root,
    )
    return compile_scene(spec)


def _closed_ctrl(scene: SimScene) -> np.ndarray:
    layout = scene.layout
    ctrl = np.zeros(scene.model.nu)
    for i, name in enumerate(layout.dof_names):
        low, high = layout.ctrl_range[i]
        if name.endswith("_flex") and not name.startswith(("root", "th")):
            ctrl[i] = low + FINGER_CLOSURE * (high - low)
        elif name in THUMB:
            ctrl[i] = THUMB[name]
    return ctrl


def _grasp_state(scene: SimScene, ctrl: np.ndarray) -> np.ndarray:
    """Close the hand on the supported ball, then release it without gravity so that it settles where the
    grip alone holds it: the synthetic perfect grasp."""
    model = scene.model
    data = mujoco.MjData(model)
    steps = round(0.6 / model.opt.timestep)
    for k in range(steps):  # ramp the targets over 0.36 s, hold 0.24 s
        data.ctrl[:] = ctrl * min(1.0, (k + 1) / (0.6 * steps))
        mujoco.mj_step(model, data)
    weightless = copy.deepcopy(model)
    weightless.opt.gravity[:] = 0.0
    data.eq_active[scene.layout.objects[0].support_eq] = 0
    mujoco.mj_step(weightless, data, nstep=round(0.3 / model.opt.timestep))
    return data.qpos.copy()


@pytest.fixture(scope="module")
def grasp() -> tuple[SimScene, np.ndarray, np.ndarray]:
    """The default hand (root fixed) enclosing a tennis ball: scene, qpos, ctrl."""
    scene = _ball_scene(default_hand())
    ctrl = _closed_ctrl(scene)
    return scene, _grasp_state(scene, ctrl), ctrl


@pytest.fixture(scope="module")
def open_hand(grasp) -> tuple[SimScene, np.ndarray, np.ndarray]:
    """The same ball and place, the hand flat (every DoF at 0) and targeting flat."""
    scene, qpos, _ = grasp
    opened = qpos.copy()
    opened[scene.layout.dof_qpos] = 0.0
    return scene, opened, np.zeros(scene.model.nu)


def test_enclosed_ball_is_stable_in_all_six_directions(grasp) -> None:
    result = stability_test(*grasp)
    assert result.success
    assert [d.direction for d in result.directions] == list(DIRECTIONS)
    assert result.in_contact_at_start
    assert result.initial_penetration < 0.002
    for d in result.directions:
        assert d.success, d.failure
        assert d.failure == ""
        assert d.in_contact_at_end
        assert {"root", "th_ip"} <= set(d.links_in_contact)  # palm and thumb …
        assert len({link[:2] for link in d.links_in_contact} & {"if", "mf", "rf", "lf"}) >= 2  # … and fingers
        assert d.displacement < 0.005
        assert d.simulated_time == pytest.approx(1.0)
        assert d.warnings == ()
    assert result.simulation_displacement < 0.001


def test_open_hand_drops_the_ball(open_hand) -> None:
    result = stability_test(*open_hand)
    assert not result.success
    down = result.direction("-z")
    assert not down.success
    assert not down.in_contact_at_end
    assert down.displacement > 1.0
    assert "lost contact with the hand" in down.failure
    assert sum(d.success for d in result.directions) <= 1  # at most +z: gravity pressing it into the palm


def test_obman_displacement_of_a_dropped_ball_is_its_free_fall(open_hand) -> None:
    scene, _, _ = open_hand
    result = stability_test(*open_hand)
    h, n = scene.timestep, round((35 / 240) / scene.timestep)
    free_fall = 9.81 * h * h * n * (n + 1) / 2  # semi-implicit Euler from rest
    assert result.obman.simulated_time == pytest.approx(n * h)
    assert result.simulation_displacement == pytest.approx(free_fall, rel=1e-6)


def test_stability_test_is_deterministic(grasp) -> None:
    first = stability_test(*grasp).to_dict()
    second = stability_test(*grasp).to_dict()
    assert first == second  # floats compared exactly


def test_result_carries_the_spec_with_its_version_and_is_json_ready(grasp) -> None:
    spec = StabilitySpec(duration=0.2, max_displacement=0.01, max_rotation_deg=30.0)
    result = stability_test(*grasp, spec=spec)
    record = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert record["spec"] == spec.to_dict()
    assert record["spec"]["version"] == STABILITY_SPEC_VERSION == "1"
    assert record["spec"]["max_displacement"] == 0.01
    assert record["model_sha256"] == grasp[0].model_sha256
    assert record["mujoco_version"] == mujoco.__version__
    assert [d["direction"] for d in record["directions"]] == list(DIRECTIONS)
    assert record["directions"][0]["simulated_time"] == pytest.approx(0.2)


def test_supports_are_switched_off_during_the_test(open_hand) -> None:
    scene = open_hand[0]
    support = scene.layout.objects[0].support_eq
    assert support >= 0 and scene.model.eq_active0[support] == 1  # the scene holds the ball up
    assert stability_test(*open_hand).direction("-z").displacement > 1.0


def test_callers_model_is_unchanged(grasp) -> None:
    scene = grasp[0]
    before = pickle.dumps(scene.model)
    stability_test(*grasp)
    assert pickle.dumps(scene.model) == before


def test_environment_contacts_let_the_table_catch_the_ball(open_hand) -> None:
    spec = StabilitySpec(environment_contacts=True)
    down = stability_test(*open_hand, spec=spec).direction("-z")
    gap = BALL_CENTRE[2] - 0.032  # ball's lowest point above the table top
    assert down.displacement == pytest.approx(gap, abs=0.003)


def test_rotation_threshold_is_judged_when_given(grasp) -> None:
    result = stability_test(*grasp, spec=StabilitySpec(duration=0.2, max_rotation_deg=0.01))
    assert not result.success
    assert all("turned" in d.failure for d in result.directions)


def test_divergence_fails_every_direction_with_the_warning(grasp) -> None:
    scene, _, ctrl = grasp
    model = copy.deepcopy(scene.model)
    model.actuator_gainprm[:, 0] *= 1e9  # absurdly stiff servos: the first step blows up
    model.actuator_biasprm[:, 1] *= 1e9
    model.actuator_forcelimited[:] = 0
    unstable = dataclasses.replace(scene, model=model)
    result = stability_test(unstable, scene.model.qpos0, ctrl)
    assert not result.success
    assert result.simulation_displacement is None
    for d in (*result.directions, result.obman):
        assert not d.success
        assert d.displacement is None and d.rotation_deg is None
        assert any("mjWARN_BADQACC" in w for w in d.warnings)
        assert d.failure.startswith("diverged: mjWARN_BADQACC")
        assert d.simulated_time < 1.0


def test_non_finite_ctrl_raises_before_stepping(grasp) -> None:
    scene, qpos, ctrl = grasp
    bad = ctrl.copy()
    bad[3] = np.nan
    with pytest.raises(SimulationError, match="stability test ctrl: non-finite value at index 3"):
        stability_test(scene, qpos, bad)


def test_non_finite_qpos_raises(grasp) -> None:
    scene, qpos, ctrl = grasp
    bad = qpos.copy()
    bad[-1] = np.inf
    with pytest.raises(
        SimulationError, match=f"stability test qpos: non-finite value at index {qpos.size - 1}"
    ):
        stability_test(scene, bad, ctrl)


def test_wrong_shapes_and_indices_raise_value_error(grasp) -> None:
    scene, qpos, ctrl = grasp
    with pytest.raises(ValueError, match=r"qpos must have shape \(34,\), got \(33,\)"):
        stability_test(scene, qpos[:-1], ctrl)
    with pytest.raises(ValueError, match=r"ctrl must have shape \(27,\), got \(2, 27\)"):
        stability_test(scene, qpos, np.stack([ctrl, ctrl]))
    with pytest.raises(ValueError, match="object_index 1 names no object; the scene has 1"):
        stability_test(scene, qpos, ctrl, object_index=1)
    with pytest.raises(ValueError, match="the scene's hand has no mocap target"):
        stability_test(scene, qpos, ctrl, mocap_pos=[0.0, 0.0, 0.12])


def test_direction_lookup_raises_key_error_listing_the_labels(grasp) -> None:
    result = stability_test(*grasp, spec=StabilitySpec(duration=0.01, obman_duration=0.01))
    with pytest.raises(KeyError, match=r"no direction 'up'; expected one of \['\+x', '-x'"):
        result.direction("up")


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"version": "2"}, "unknown stability spec version '2'; this handsim knows '1'"),
        ({"duration": 0.0}, "duration must be a positive finite number, got 0.0"),
        ({"gravity": float("nan")}, "gravity must be a positive finite number, got nan"),
        ({"max_displacement": -0.01}, "max_displacement must be a positive finite number"),
        ({"max_rotation_deg": 0.0}, "max_rotation_deg must be positive or None, got 0.0"),
        ({"obman_direction": (0.0, 0.0, 0.0)}, "obman_direction must be 3 finite numbers, not all zero"),
    ],
)
def test_spec_rejects_invalid_parameters(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        StabilitySpec(**kwargs)


@pytest.fixture(scope="module")
def welded_grasp() -> tuple[SimScene, np.ndarray, np.ndarray]:
    """The perfect grasp with the hand's root free and welded to its mocap target (no wrist DoFs)."""
    skeleton = default_skeleton()
    skeleton = dataclasses.replace(skeleton, dofs=tuple(d for d in skeleton.dofs if d.joint != "root"))
    hand = build_hand(skeleton, breadth=DEFAULT_BREADTH_RATIO * DEFAULT_HAND_LENGTH_M)
    scene = _ball_scene(hand, hand_root="weld")
    ctrl = _closed_ctrl(scene)
    return scene, _grasp_state(scene, ctrl), ctrl


def test_welded_hand_is_held_where_qpos_puts_it_by_default(welded_grasp) -> None:
    scene, qpos, ctrl = welded_grasp
    assert scene.layout.mocap >= 0
    assert stability_test(scene, qpos, ctrl).success


def test_mocap_target_moves_a_welded_hand(welded_grasp) -> None:
    scene, qpos, ctrl = welded_grasp
    root = qpos[scene.layout.root_free_qpos : scene.layout.root_free_qpos + 3]
    result = stability_test(scene, qpos, ctrl, mocap_pos=root + np.array([0.05, 0.0, 0.0]))
    assert not result.success
    assert all(d.displacement > 0.03 for d in result.directions)  # the hand carried the ball towards +x


def test_zero_mocap_quaternion_raises_value_error(welded_grasp) -> None:
    with pytest.raises(ValueError, match=r"mocap_quat must be a non-zero quaternion \(w, x, y, z\)"):
        stability_test(*welded_grasp, mocap_quat=[0.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize("case", ["grasp", "open_hand"])
def test_directions_on_threads_give_the_results_of_one_thread(case, request, monkeypatch) -> None:
    """The seven runs go to threads (handsim.sim.parallel): bit for bit what one thread computes."""
    args = request.getfixturevalue(case)
    monkeypatch.setenv("HANDSIM_THREADS", "1")
    alone = stability_test(*args, stop_at_failure=True).to_dict()
    monkeypatch.setenv("HANDSIM_THREADS", "4")
    assert stability_test(*args, stop_at_failure=True).to_dict() == alone


@pytest.mark.parametrize("needed", [2, 3, 6])
def test_a_test_that_cannot_reach_the_directions_needed_stops_there(open_hand, needed) -> None:
    """The open hand holds at most one direction: the test ends once fewer than ``needed`` could still
    succeed; the runs made are those of the whole test, bit for bit, and the others (ObMan's too) say they
    were not run."""
    whole = stability_test(*open_hand, stop_at_failure=True)
    cut = stability_test(*open_hand, stop_at_failure=True, needed=needed)
    runs, failed = 0, 0
    for d in whole.directions:  # the rule, on the whole test's outcomes
        if len(DIRECTIONS) - failed < needed:
            break
        runs, failed = runs + 1, failed + (not d.success)
    assert runs == 1 if needed == len(DIRECTIONS) else runs >= 1  # six needed: the first failure ends it
    assert [d.to_dict() for d in cut.directions[:runs]] == [d.to_dict() for d in whole.directions[:runs]]
    for skipped in (*cut.directions[runs:], cut.obman):
        assert not skipped.success and skipped.displacement is None and skipped.simulated_time == 0.0
        assert skipped.failure == f"not run: fewer than {needed} directions could still be resisted"
    assert cut.simulation_displacement is None and not cut.success
    assert [d.direction for d in cut.directions] == list(DIRECTIONS)


def test_a_grip_that_can_still_reach_the_directions_needed_runs_the_whole_test(grasp) -> None:
    assert (
        stability_test(*grasp, stop_at_failure=True, needed=6).to_dict()
        == stability_test(*grasp, stop_at_failure=True).to_dict()
    )


def test_the_directions_needed_may_rise_while_the_test_runs(open_hand) -> None:
    """A function gives the count before each run until the test stops (a search's best so far, raised by
    other threads)."""
    asked = []

    def needed() -> int:
        asked.append(len(asked))
        return 0 if len(asked) <= 2 else 6 + len(asked)  # rising: asked once it has stopped, it would say so

    whole = stability_test(*open_hand, stop_at_failure=True)
    cut = stability_test(*open_hand, stop_at_failure=True, needed=needed)
    assert [d.to_dict() for d in cut.directions[:2]] == [d.to_dict() for d in whole.directions[:2]]
    assert all(d.failure.startswith("not run: fewer than 9 ") for d in (*cut.directions[2:], cut.obman))
    assert len(asked) == 3  # before the two runs made and the first not made: not once it has stopped


def test_the_directions_named_first_run_first_and_change_no_result(grasp, open_hand) -> None:
    whole = stability_test(*grasp, stop_at_failure=True).to_dict()
    assert stability_test(*grasp, stop_at_failure=True, needed=6, first=("-z", "+y")).to_dict() == whole
    dropped = stability_test(*open_hand, stop_at_failure=True)
    cut = stability_test(*open_hand, stop_at_failure=True, needed=6, first=("-z",))
    assert cut.direction("-z").to_dict() == dropped.direction("-z").to_dict()  # the one run made
    assert all(d.failure.startswith("not run") for d in cut.directions if d.direction != "-z")
    with pytest.raises(ValueError, match=r"first: unknown directions \['down'\]"):
        stability_test(*grasp, needed=6, first=("down",))
    with pytest.raises(ValueError, match="first orders the runs of a test with needed"):
        stability_test(*grasp, first=("-z",))
