"""The parts the environments are made of: Grasp-v0's action, task, observation and reward, the base's
explicit pickling, and the vector environment's info helpers."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from handsim.envs._base import HandEnv
from handsim.envs.grasp_action import HandConfig, RootConfig
from handsim.envs.grasp_env import GraspEnv
from handsim.envs.grasp_reward import GraspRewardWeights, contact_sides, held_from_two_sides
from handsim.envs.grasp_scene import grasp_scene
from handsim.envs.grasp_task import EpisodeConfig
from handsim.envs.replay_vector_info import final_info, put_reset_numbers


@pytest.fixture(scope="module")
def grasp() -> GraspEnv:
    return GraspEnv()


def test_a_hand_env_that_does_not_describe_its_action_cannot_be_made():
    class Silent(HandEnv):
        pass

    with pytest.raises(TypeError, match="_action_description"):
        Silent()


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: HandConfig("open", "joints", "rate", 0.0), "hand_rate must be a finite number > 0, got 0.0"),
        (lambda: HandConfig("open", "toes", "rate", 1.0), "unknown hand_action 'toes'"),
        (lambda: RootConfig("velocity", -0.1, (0.1, 0.1, 0.1)), "root_speed must be a finite number ≥ 0"),
        (lambda: RootConfig("velocity", 0.1, (0.1, -0.1, 0.1)), r"root_range must be 3 finite numbers ≥ 0"),
        (
            lambda: EpisodeConfig(3.0, 0.02, 0.01, 0.05, -0.5, False, None),
            "hold_time must be a finite number",
        ),
        (lambda: EpisodeConfig(3.0, 0.02, 0.01, 0.05, 0.5, False, 0.0), "max_penetration must be a finite"),
        (lambda: GraspRewardWeights(0.1, 0.1, 1.0, 1.0, 0.0, -0.2), "penetration_weight must be a finite"),
    ],
)
def test_grasp_configs_raise_value_error_naming_the_keyword(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_configs_hold_checked_floats():
    root = RootConfig("velocity", 1, [0, 0, 1])
    assert root.root_range == (0.0, 0.0, 1.0) and isinstance(root.root_speed, float)
    episode = EpisodeConfig(3, 0, 0, 1, 0, 1, 2)
    assert episode.terminate_on_success is True and episode.max_penetration == 2.0


@pytest.mark.parametrize(
    ("kwargs", "description"),
    [
        ({"hand_action": "fingers", "hand_control": "rate"}, "6 finger target rates then 3 root velocities"),
        ({"root_control": "scripted"}, "24 joint targets"),
    ],
)
def test_a_wrong_action_shape_is_refused_naming_what_an_action_holds(kwargs, description):
    with pytest.raises(ValueError, match=rf"\({description} in \[-1, 1\]\), got shape \(2,\)"):
        GraspEnv(**kwargs).step(np.zeros(2))


def test_the_velocity_root_stays_in_its_range_and_above_the_table(grasp):
    root = grasp.task.root
    for sign, steps in ((1.0, 100), (-1.0, 60)):
        grasp.reset(seed=0)
        velocity = np.zeros(grasp.action_space.shape)
        velocity[-3:] = sign
        for _ in range(steps):  # 2 mm per step at most along each axis
            grasp.step(velocity)
        if sign > 0:
            np.testing.assert_allclose(root.target, root.start + np.array([0.1, 0.1, 0.15]))
        else:
            np.testing.assert_allclose(root.target[:2], root.start[:2] - 0.1)
            assert root.target[2] == grasp_scene("tennis_ball", 0.02).root_floor  # the palm on the table
        np.testing.assert_array_equal(grasp.data.mocap_pos[0], root.target)


def test_object_to_grasp_is_the_object_minus_root_minus_grasp_offset(grasp):
    obs, _ = grasp.reset(seed=3)
    s = grasp.observation_slices
    expected = obs[s["obj/pose"]][:3] - obs[s["root_pose"]][:3] - grasp.task.grasp_offset
    np.testing.assert_array_equal(obs[s["object_to_grasp"]], expected)
    np.testing.assert_array_equal(obs[s["root_target"]], grasp.task.root.start)


def test_the_task_counts_held_steps_and_ends_on_success_when_told():
    env = GraspEnv(hold_time=0.02, terminate_on_success=True)
    env.reset(seed=0)
    task = env.task
    assert task.hold_steps == 2
    first = task.judge(lift=0.06, touching=1, penetration=0.0, events=())
    assert first.lifted and not first.success and not first.terminated
    second = task.judge(lift=0.06, touching=1, penetration=0.0, events=())
    assert second.success and second.terminated and second.held_at_end and task.hold_fraction == 1.0
    dropped = task.judge(lift=0.06, touching=0, penetration=0.0, events=())
    assert not dropped.lifted and not dropped.success and task.held == 0


def test_held_from_two_sides_needs_two_sides_not_two_links(grasp):
    links = grasp.scene.layout.link_names
    sides = contact_sides(links)
    assert [[links[i] for i in side] for side in sides[::2]] == [["th_tmc", "th_mcp", "th_ip"], ["root"]]
    forces = np.zeros(len(links))
    forces[[links.index("if_dip"), links.index("mf_dip")]] = 1.0
    assert not held_from_two_sides(forces, sides)
    forces[links.index("th_ip")] = 1.0
    assert held_from_two_sides(forces, sides)


def test_a_pickled_env_keeps_its_changed_model_and_views_its_own_data():
    env = GraspEnv()
    env.reset(seed=1)
    env.model.geom_friction[:, 0] *= 0.5  # domain randomisation of this env only
    copy = pickle.loads(pickle.dumps(env))
    np.testing.assert_array_equal(copy.model.geom_friction, env.model.geom_friction)
    action = np.full(env.action_space.shape, 0.3)
    for _ in range(5):
        original, clone = env.step(action), copy.step(action)
        np.testing.assert_array_equal(original[0], clone[0])
        assert original[1:] == clone[1:]
    assert not np.shares_memory(copy.data.qpos, env.data.qpos)


def test_final_info_keeps_only_the_ended_worlds_values():
    infos = {
        "frame": np.array([3, 7, 9]),
        "_frame": np.ones(3, bool),
        "warnings": np.array([None, ("w",), None], dtype=object),
        "_warnings": np.array([False, True, False]),
        "diverged": np.array([False, True, True]),
        "_diverged": np.array([True, True, False]),
    }
    final = final_info(infos, np.array([False, True, True]))
    assert final["frame"].tolist() == [0, 7, 9] and final["_frame"].tolist() == [False, True, True]
    assert final["warnings"].tolist() == [None, ("w",), None]
    assert final["_diverged"].tolist() == [False, True, False]


def test_put_reset_numbers_adds_and_masks_the_reset_worlds():
    infos: dict = {}
    numbers = tuple(float(i) for i in range(11))
    put_reset_numbers(infos, {1: numbers}, 3)
    assert infos["reward_tracking"].tolist() == [0.0, 0.0, 0.0]
    assert infos["reward_object"].tolist() == [0.0, 1.0, 0.0]
    assert infos["_penetration"].tolist() == [False, True, False]
