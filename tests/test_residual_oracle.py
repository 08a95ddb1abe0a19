"""scripts/residual_oracle.py: its planner's look-ahead is the environment's own future, and a smoke run."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _script():
    spec = importlib.util.spec_from_file_location("residual_oracle", ROOT / "scripts" / "residual_oracle.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _planner(module, env, **overrides):
    kwargs = dict(
        samples=4,
        horizon=6,
        knot=3,
        sigma=0.3,
        joint_weight=0.25,
        joint_sigma=0.02,
        seed=0,
        iterations=2,
        **overrides,
    )
    return module.Planner(env, **kwargs)


def test_the_planners_rollout_is_the_environments_future_and_leaves_its_state_alone():
    module = _script()
    env = module.ReplayEnv(**module.PLANNER_ENV)
    env.reset(seed=0, options={"frame": 200})
    before = env.data.qpos.copy()
    planner = _planner(module, env)
    action = planner.plan(200, env.schedule.frames - 1)
    assert env.frame == 200 and np.array_equal(env.data.qpos, before)
    assert action.shape == env.action_space.shape and np.all(np.abs(action) <= 1.0)
    # the cost of a sequence, from the saved state, equals stepping a fresh environment through it
    rng = np.random.default_rng(3)
    actions = np.clip(rng.normal(0.0, 0.5, (planner.horizon, *env.action_space.shape)), -1.0, 1.0)
    predicted = planner._cost(actions, 200, env.schedule.frames - 1)
    fresh = module.ReplayEnv(**module.PLANNER_ENV)
    fresh.reset(seed=0, options={"frame": 200})
    cost = 0.0
    for h, a in enumerate(actions):
        fresh.step(a)
        k = 201 + h
        cube = fresh.data.qpos[planner.cube_qpos : planner.cube_qpos + 3] - planner.ref_position[k]
        joints = fresh.data.qpos[planner.dof_qpos] - planner.ref_ctrl[k]
        cost += cube @ cube / 0.01**2 + planner.joint_scale * (joints @ joints) / joints.size
    assert predicted == cost


@pytest.mark.slow
def test_a_smoke_run_plans_a_few_frames_and_writes_its_table(tmp_path):
    module = _script()
    assert module.main(["--frames", "4", "--samples", "3", "--horizon", "4", "--out", str(tmp_path)]) == 0
    record = json.loads((tmp_path / "oracle.json").read_text())
    assert record["planner"]["planned_frames"] == 4 and record["planner"]["frames"] == 616
    assert np.load(tmp_path / "actions.npy").shape == (4, 31)
    table = (tmp_path / "oracle.md").read_text().splitlines()
    assert table[2].startswith("| pure replay (zero residual) | ") and table[3].startswith("| planner (4 ")
