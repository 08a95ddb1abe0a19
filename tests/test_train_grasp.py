"""scripts/train_grasp.py: its scripted demonstrator, its evaluation and a smoke run (no real training)."""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

pytest.importorskip("stable_baselines3")
pytest.importorskip("matplotlib")


@pytest.fixture(scope="module")
def script():
    sys.path.insert(0, str(ROOT / "scripts"))  # it imports train_residual's PPO plumbing
    try:
        spec = importlib.util.spec_from_file_location("train_grasp", ROOT / "scripts" / "train_grasp.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.path.remove(str(ROOT / "scripts"))


@pytest.mark.parametrize(
    ("hand_action", "hand_control"), [("joints", "position"), ("fingers", "position"), ("fingers", "rate")]
)
def test_the_scripted_grasp_passes_the_acceptance_on_every_offset(script, hand_action, hand_control):
    """The demonstrator holds the ball to the end of all 10 evaluation episodes at ≤ 5 mm (any action)."""
    env = script.GraspEnv(**{**script.ENV_KWARGS, "hand_action": hand_action, "hand_control": hand_control})
    act = script.scripted_policy(env)
    held, deepest = [], 0.0
    for episode in range(script.EVAL_EPISODES):
        env.reset(seed=script.EVAL_SEED + episode)
        for step in range(env.max_steps):
            _, _, terminated, truncated, info = env.step(act(step))
            deepest = max(deepest, info["penetration"])
            if terminated or truncated:
                break
        held.append(info["success"] and not terminated)
    assert all(held)
    assert 0.002 < deepest <= script.MAX_PENETRATION


def test_zero_action_evaluation_is_deterministic_and_holds_nothing(script):
    first = script.evaluate(script.ENV_KWARGS)
    assert first == script.evaluate(script.ENV_KWARGS)
    assert first["held"] == 0.0 and first["episodes"] == script.EVAL_EPISODES
    assert not script.passes(first)


def test_the_script_noise_evaluation_is_seeded_and_applies_the_noise(script, monkeypatch):
    monkeypatch.setattr(script, "EVAL_EPISODES", 2)
    first = script.main(["--script-noise", "0", "0.5"])["script_noise"]
    assert first == script.main(["--script-noise", "0", "0.5"])["script_noise"]  # bitwise, seeded noise
    clean, noisy = first
    assert (clean["sigma"], noisy["sigma"]) == (0.0, 0.5)
    assert clean["held"] == 1.0 and clean["return"] != noisy["return"]
    assert noisy["mean_max_penetration_mm"] != clean["mean_max_penetration_mm"]


@pytest.mark.slow
def test_a_smoke_run_from_demonstrations_writes_the_table_and_the_curves(script, tmp_path, monkeypatch):
    monkeypatch.setattr(script, "DEMO_EPISODES", 2)
    monkeypatch.setattr(script, "BC_STEPS", 20)
    monkeypatch.setattr(script, "EVAL_EPISODES", 2)
    record = script.main(
        [
            *("--timesteps", "256", "--eval-every", "128", "--seeds", "0", "--demo", "--out", str(tmp_path)),
            *("--critic-warmup", "128", "--log-std", "-2", "--env-kwargs", '{"hand_action": "fingers"}'),
        ]
    )
    assert record["env_kwargs"]["hand_action"] == "fingers" and record["policy"]["log_std_init"] == -2.0
    assert record["demo"] and record["critic_warmup"] == 128
    for name in ("learning_curve.png", "evaluation.json", "evaluation.md", "seed0/policy.zip"):
        assert (tmp_path / name).is_file()
    assert json.loads((tmp_path / "evaluation.json").read_text())["zero_action"] == record["zero_action"]
    (seed,) = record["seeds"]
    assert [c["timesteps"] for c in seed["curve"]][-1] == 256
    table = (tmp_path / "evaluation.md").read_text().splitlines()
    assert table[2].startswith("| zero action (open hand) | 0 % |")
    assert table[3].startswith("| seed 0: the clone of the script, before PPO | ")
    assert table[4].startswith("| PPO seed 0: kept (") and table[5].startswith("| seed 0: last (256 steps)")
    assert seed["policy_eval"]["timesteps"] in [c["timesteps"] for c in seed["curve"]]
    assert seed["total_minutes"] >= seed["curve"][-1]["minutes"]  # the demonstrations and cloning count too
    assert table[-1] in (
        "0 of 1 seeds pass (every episode held, ≤ 5 mm).",
        "1 of 1 seeds pass (every episode held, ≤ 5 mm).",
    )


@pytest.mark.slow
def test_the_critic_warmup_trains_the_value_function_only(script):
    import torch
    from stable_baselines3 import PPO
    from train_residual import actor_parameters  # on sys.path while the script fixture is

    venv = script.make_vec_env({"hand_action": "fingers"}, 2, 0, env_class=script.GraspEnv, gamma=0.99)
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=64, n_epochs=2, seed=0, device="cpu")
    policy = model.policy
    actor = actor_parameters(model)
    critic = [*policy.mlp_extractor.value_net.parameters(), *policy.value_net.parameters()]
    assert {id(p) for p in actor}.isdisjoint(id(p) for p in critic)
    assert len(actor) + len(critic) == len(list(policy.parameters()))  # together: every parameter
    before = [p.detach().clone() for p in actor + critic]
    args = argparse.Namespace(timesteps=256, minutes=None, eval_every=10_000)
    script.learn(model, args, lambda m: {}, critic_warmup=256)
    after = actor + critic
    assert all(torch.equal(b, a) for b, a in zip(before[: len(actor)], after[: len(actor)], strict=True))
    assert not all(torch.equal(b, a) for b, a in zip(before[len(actor) :], after[len(actor) :], strict=True))
    assert all(p.requires_grad for p in actor)  # trainable again once learn returns


def test_the_success_reward_is_paid_once_at_the_end_of_a_held_episode(script):
    """``success_weight``: the scripted grasp, held to the end, earns it on its last step only; the same
    episode without it differs by exactly that reward; the open hand never earns it."""
    kwargs = {**script.ENV_KWARGS, "max_penetration": None}
    paid = script.GraspEnv(**{**kwargs, "success_weight": 7.0})
    plain = script.GraspEnv(**{**kwargs, "success_weight": 0.0})
    act = script.scripted_policy(paid)
    paid.reset(seed=script.EVAL_SEED), plain.reset(seed=script.EVAL_SEED)
    for step in range(paid.max_steps):
        action = act(step)
        _, reward, terminated, truncated, info = paid.step(action)
        _, reward_plain, _, _, info_plain = plain.step(action)
        assert info["reward_success"] == (7.0 if truncated else 0.0) and info_plain["reward_success"] == 0.0
        assert reward == reward_plain + info["reward_success"]
    assert truncated and not terminated and info["success"]
    paid.reset(seed=0)
    zero = np.zeros(paid.action_space.shape, np.float32)
    for _ in range(paid.max_steps):
        _, _, _, truncated, info = paid.step(zero)
        assert info["reward_success"] == 0.0
    assert truncated and not info["success"]


def test_a_negative_success_weight_is_refused(script):
    with pytest.raises(ValueError, match="success_weight"):
        script.GraspEnv(success_weight=-1.0)


@pytest.mark.slow
def test_the_learning_rate_decays_to_zero_over_the_timesteps_by_steps(script):
    from stable_baselines3 import PPO

    schedule = script.linear_decay(1e-4)
    assert schedule(1.0) == 1e-4 and schedule(0.25) == pytest.approx(2.5e-5) and schedule(0.0) == 0.0
    venv = script.make_vec_env({"hand_action": "fingers"}, 2, 0, env_class=script.GraspEnv, gamma=0.99)
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=64, n_epochs=1, seed=0, device="cpu",
                learning_rate=schedule)  # fmt: skip
    rates = []
    model.learn(256, callback=lambda *_: rates.append(model.policy.optimizer.param_groups[0]["lr"]) or True)
    assert model.policy.optimizer.param_groups[0]["lr"] == 0.0  # the last update at progress 0
    assert rates[0] == pytest.approx(1e-4)
