"""Train a residual tracking policy on handsim/Replay-v0 with Stable-Baselines3 PPO and measure it.

    python scripts/train_residual.py --minutes 25                  # writes runs/residual-<date>-<time>/
    python scripts/train_residual.py --minutes 25 --out docs/rl --overwrite   # the run docs/rl.md quotes
    python scripts/train_residual.py --timesteps 512 --out /tmp/x   # a smoke run (its test)

Needs the optional extra ``rl`` (``pip install -e .[rl]``: stable-baselines3) and ``plot`` (matplotlib).

Output: ``--out`` (default: a fresh ``runs/residual-<date>-<time>/``); a folder that exists and is not empty
is refused unless ``--overwrite`` (``docs/rl`` holds the published run). Threads: PyTorch runs
``--torch-threads`` threads (default 1). PPO's networks here are small (two layers of 256, batches of 256),
too small for PyTorch's intra-op threads to pay, and with its default (one thread per core) those threads
compete with the environment's stepping for the same cores: a 6,144-step run took 94.8 s with PyTorch's
default threads and 17.5 s with one on a shared 2-core machine.

Training: ``--n-envs`` single ``ReplayEnv`` in SB3's ``DummyVecEnv`` (``--vec dummy``, the default: one
process; on 2 shared cores the env step, 0.3 ms, is small next to PPO's update) or the native
``ReplayVectorEnv`` in same-step autoreset behind an SB3 ``VecEnv`` adapter (``--vec native``),
``VecNormalize`` on observations and rewards, PPO with a small initial action std
(``log_std_init``: the policy's own noise must not drop the cube, issue 17). Episodes start at a random
frame (reference-state initialisation) with seeded reset noise, and end at ``--drift-limit``.

Evaluation (deterministic, the whole recording from frame 0, no early termination): per step the cube's
distance from its recorded track; % of frames within 1 cm, mean drift, joint tracking RMS; the same for
pure replay (zero residual). Written: ``<out>/learning_curve.png``, ``<out>/evaluation.json`` and
``<out>/evaluation.md`` (the table docs/rl.md quotes).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from handsim.cli._common import positive_int
from handsim.envs.replay_env import ReplayEnv

ENV_KWARGS = {
    "random_start": True,
    "reset_noise_scale": 0.01,
    "reference_window": 3,
    "residual_scale": 0.1,
    "tracking_sigma": 0.02,
}
"""The training environment's keywords (the ``--drift-limit`` is added): see docs/rl.md for why."""
PPO_KWARGS = {
    "n_steps": 1024,
    "batch_size": 256,
    "n_epochs": 5,
    "learning_rate": 3e-4,
    "gamma": 0.98,
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "ent_coef": 0.0,
}
POLICY_KWARGS = {"net_arch": [256, 256], "log_std_init": -2.0}
WITHIN = 0.01
"""m: a frame counts when the cube is within this of its recorded position."""


def evaluate(env_kwargs: dict, policy=None, normalize=None) -> dict:
    """One deterministic pass over the whole recording; ``policy`` None: pure replay (zero residual).

    Returns:
        ``within_1cm`` (fraction of frames), ``mean_drift_mm``, ``max_drift_mm``, ``tracking_rms_mrad``
        (RMS over frames of the per-frame joint RMS error), ``return`` and ``frames``.
    """
    kwargs = {**env_kwargs, "random_start": False, "reset_noise_scale": 0.0, "max_object_drift": None}
    env = ReplayEnv(**kwargs)
    obs, _ = env.reset(seed=0, options={"frame": 0})
    drifts, errors, total = [], [], 0.0
    zero = np.zeros(env.action_space.shape, np.float32)
    while True:
        if policy is None:
            action = zero
        else:
            x = normalize(obs[None]) if normalize is not None else obs[None]
            action = policy.predict(x, deterministic=True)[0][0]
        obs, reward, terminated, truncated, info = env.step(action)
        total += reward
        drifts.append(info["object_drift"])
        errors.append(info["tracking_error"])
        if terminated or truncated:
            break
    d, e = np.asarray(drifts), np.asarray(errors)
    return {
        "within_1cm": float(np.mean(d < WITHIN)),
        "mean_drift_mm": float(d.mean() * 1000),
        "max_drift_mm": float(d.max() * 1000),
        "tracking_rms_mrad": float(math.sqrt(np.mean(e**2)) * 1000),
        "return": float(total),
        "frames": len(d),
    }


def make_vec_env(env_kwargs: dict, n_envs: int, seed: int, env_class=ReplayEnv, gamma: float | None = None):
    """SB3's DummyVecEnv of ``n_envs`` single ``env_class`` envs, seeded ``seed + i``, with VecNormalize."""
    from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    venv = sb3_make_vec_env(env_class, n_envs=n_envs, seed=seed, env_kwargs=env_kwargs)
    gamma = PPO_KWARGS["gamma"] if gamma is None else gamma
    return VecNormalize(venv, norm_obs=True, norm_reward=True, clip_obs=10.0, gamma=gamma)


def native_vec_env(env_kwargs: dict, n_envs: int, seed: int):
    """SB3's ``VecEnv`` over the native ``ReplayVectorEnv`` (N worlds on MuJoCo's threads), normalised.

    The native env resets an ended world in the same step when asked (``AutoresetMode.SAME_STEP``), which
    is SB3's contract: the returned observation is the reset's and ``infos[i]["terminal_observation"]`` the
    one the episode ended with. World i is seeded ``seed + i`` on the first reset, as ``make_vec_env`` does.
    """
    from gymnasium.vector import AutoresetMode
    from stable_baselines3.common.vec_env import VecEnv, VecNormalize

    from handsim.envs import ReplayVectorEnv

    class NativeVecEnv(VecEnv):
        def __init__(self) -> None:
            self.worlds = ReplayVectorEnv(n_envs, autoreset_mode=AutoresetMode.SAME_STEP, **env_kwargs)
            super().__init__(n_envs, self.worlds.single_observation_space, self.worlds.single_action_space)
            self._seeds = [seed + i for i in range(n_envs)]
            self._actions = None

        def reset(self):
            seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
            obs, _ = self.worlds.reset(seed=seeds)
            self._reset_seeds()
            return obs

        def step_async(self, actions) -> None:
            self._actions = actions

        def step_wait(self):
            obs, rewards, terminated, truncated, info = self.worlds.step(self._actions)
            dones = terminated | truncated
            infos = [{} for _ in range(self.num_envs)]
            for i in np.flatnonzero(dones):
                infos[i]["terminal_observation"] = info["final_obs"][i]
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            return obs, rewards.astype(np.float32), dones, infos

        def close(self) -> None:
            self.worlds.close()

        def get_attr(self, attr_name, indices=None):
            return [getattr(self.worlds, attr_name)] * len(self._get_indices(indices))

        def set_attr(self, attr_name, value, indices=None) -> None:
            raise NotImplementedError("the native vector env's worlds share one configuration")

        def env_method(self, method_name, *method_args, indices=None, **method_kwargs):
            raise NotImplementedError("the native vector env's worlds share one configuration")

        def env_is_wrapped(self, wrapper_class, indices=None):
            return [False] * len(self._get_indices(indices))

    return VecNormalize(
        NativeVecEnv(), norm_obs=True, norm_reward=True, clip_obs=10.0, gamma=PPO_KWARGS["gamma"]
    )


def actor_parameters(model) -> list:
    """The parameters of the policy's action distribution: SB3's ``mlp_extractor.policy_net``,
    ``action_net`` and ``log_std`` (the value function has the others)."""
    policy = model.policy
    return [*policy.mlp_extractor.policy_net.parameters(), *policy.action_net.parameters(), policy.log_std]


def set_actor_trainable(model, trainable: bool) -> None:
    """Let PPO's updates change the policy's action distribution (True) or only its value function (False).

    Frozen parameters (:func:`actor_parameters`) get no gradient, so the optimiser leaves them as they are.
    """
    for parameter in actor_parameters(model):
        parameter.requires_grad_(trainable)


def learn(model, args: argparse.Namespace, measure, critic_warmup: int = 0) -> list[dict]:
    """``model.learn`` for ``args.timesteps`` or ``args.minutes``, measuring every ``args.eval_every`` steps.

    Args:
        model: The SB3 model.
        args: ``timesteps``, ``minutes`` (None: no time limit) and ``eval_every``.
        measure: ``measure(model)`` → a record (dict) of the policy now.
        critic_warmup: Timesteps at the start during which only the value function learns (the actor is
            frozen, :func:`set_actor_trainable`): a policy that starts good (cloned) is then first judged
            by a critic that knows its returns. They count in the time and step budget.

    Returns:
        The learning curve: the records, each with ``timesteps`` and ``minutes``; the last one is taken
        after training ends.
    """
    from stable_baselines3.common.callbacks import BaseCallback

    curve: list[dict] = []
    start = time.monotonic()
    deadline = start + 60.0 * args.minutes if args.minutes else math.inf

    def record_now() -> None:
        record = measure(model)
        record.update(timesteps=model.num_timesteps, minutes=(time.monotonic() - start) / 60)
        curve.append(record)
        print(json.dumps(record), flush=True)

    class Progress(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.next_eval = 0
            self.frozen = critic_warmup > 0

        def _on_step(self) -> bool:
            if self.frozen and self.num_timesteps > critic_warmup:  # the update after step N is frozen too
                set_actor_trainable(model, True)
                self.frozen = False
            if self.num_timesteps >= self.next_eval:
                self.next_eval += args.eval_every
                record_now()
            return time.monotonic() < deadline

    if critic_warmup:
        set_actor_trainable(model, False)
    model.learn(total_timesteps=args.timesteps, callback=Progress())
    set_actor_trainable(model, True)
    record_now()
    return curve


def train(args: argparse.Namespace) -> dict:
    """Train, evaluate along the way, write the plot and the table; returns the evaluation record."""
    import torch
    from stable_baselines3 import PPO

    torch.set_num_threads(args.torch_threads)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    env_kwargs = {**ENV_KWARGS, "max_object_drift": args.drift_limit}
    if args.trajectory:
        env_kwargs["trajectory"] = args.trajectory
    vectorise = native_vec_env if args.vec == "native" else make_vec_env
    venv = vectorise(env_kwargs, args.n_envs, args.seed)
    ppo_kwargs = dict(PPO_KWARGS)
    ppo_kwargs["n_steps"] = min(ppo_kwargs["n_steps"], max(64, args.timesteps // args.n_envs))
    ppo_kwargs["batch_size"] = min(ppo_kwargs["batch_size"], ppo_kwargs["n_steps"] * args.n_envs)
    model = PPO(
        "MlpPolicy", venv, seed=args.seed, verbose=0, device="cpu", policy_kwargs=POLICY_KWARGS, **ppo_kwargs
    )
    replay = evaluate(env_kwargs)
    curve = learn(model, args, lambda m: evaluate(env_kwargs, m, venv.normalize_obs))
    final = curve[-1]
    record = {
        "env_kwargs": {k: v for k, v in env_kwargs.items() if k != "trajectory"},
        "trajectory": args.trajectory or "bundled Tzionas sequence 20",
        "ppo": PPO_KWARGS,
        "policy": POLICY_KWARGS,
        "n_envs": args.n_envs,
        "seed": args.seed,
        "replay": replay,
        "policy_eval": final,
        "curve": curve,
    }
    (out / "evaluation.json").write_text(json.dumps(record, indent=1))
    (out / "evaluation.md").write_text(table(record))
    model.save(out / "policy.zip")
    venv.save(str(out / "vecnormalize.pkl"))
    plot(curve, replay, out / "learning_curve.png")
    return record


def table(record: dict) -> str:
    """The evaluation table (markdown)."""
    r, p = record["replay"], record["policy_eval"]
    ratio = p["tracking_rms_mrad"] / r["tracking_rms_mrad"] if r["tracking_rms_mrad"] else math.nan
    rows = [
        "| | frames within 1 cm | mean drift (mm) | max drift (mm) | joint tracking RMS (mrad) | return |",
        "|---|---|---|---|---|---|",
        f"| pure replay (zero residual) | {100 * r['within_1cm']:.1f} % | {r['mean_drift_mm']:.1f} | "
        f"{r['max_drift_mm']:.1f} | {r['tracking_rms_mrad']:.1f} | {r['return']:.1f} |",
        f"| PPO residual ({p['timesteps']} steps, {p['minutes']:.1f} min) | {100 * p['within_1cm']:.1f} % | "
        f"{p['mean_drift_mm']:.1f} | {p['max_drift_mm']:.1f} | {p['tracking_rms_mrad']:.1f} "
        f"({ratio:.2f}× replay) | {p['return']:.1f} |",
    ]
    return "\n".join(rows) + "\n"


def plot(curve: list[dict], replay: dict, path: Path) -> None:
    """Learning curve: % frames within 1 cm and mean drift against timesteps, pure replay dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    steps = [c["timesteps"] for c in curve]
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.5))
    a.plot(steps, [100 * c["within_1cm"] for c in curve], "o-", label="PPO (deterministic)")
    a.axhline(100 * replay["within_1cm"], ls="--", c="k", label="pure replay")
    a.axhline(90, ls=":", c="r", label="acceptance 90 %")
    a.set(xlabel="timesteps", ylabel="% frames cube within 1 cm", ylim=(0, 100))
    a.legend(fontsize=8)
    b.plot(steps, [c["mean_drift_mm"] for c in curve], "o-")
    b.axhline(replay["mean_drift_mm"], ls="--", c="k")
    b.axhline(5, ls=":", c="r")
    b.set(xlabel="timesteps", ylabel="mean cube drift (mm)")
    save_figure(fig, path)


def save_figure(fig, path: Path) -> None:
    """Lay out, write (100 dpi) and close a matplotlib figure."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def script_parser(doc: str) -> argparse.ArgumentParser:
    """A command-line parser whose help is the script's docstring, as written."""
    return argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)


RUNS_FOLDER = Path("runs")
"""Where a training run writes by default: ``runs/<name>-<date>-<time>/`` (a fresh folder per run)."""


def add_output_options(parser: argparse.ArgumentParser, name: str) -> None:
    """Add ``--out`` (default: a fresh ``runs/<name>-<date>-<time>``) and ``--overwrite``."""
    parser.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help=f"output folder (default: a fresh {RUNS_FOLDER}/{name}-<date>-<time>); one that exists and is "
        "not empty is refused unless --overwrite",
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="write into an --out that holds files already (replacing them; docs/rl holds published runs)",
    )


def output_folder(parser: argparse.ArgumentParser, args: argparse.Namespace, name: str) -> Path:
    """The run's output folder (not created yet): ``--out``, or a fresh ``runs/<name>-<date>-<time>``.

    Exits with a usage error (status 2) when ``--out`` is a file, or a folder holding files, and
    ``--overwrite`` was not given: a run must not replace another's results (``docs/rl``) by accident.
    """
    if args.out is None:
        stamp = time.strftime("%Y%m%d-%H%M%S")
        out, n = RUNS_FOLDER / f"{name}-{stamp}", 1
        while out.exists():  # another run started in the same second
            n += 1
            out = RUNS_FOLDER / f"{name}-{stamp}-{n}"
        return out
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        parser.error(f"argument --out: {out} is a file; expected a folder")
    if out.is_dir() and any(out.iterdir()) and not args.overwrite:
        parser.error(
            f"argument --out: {out} holds files already (a run's results?): give a new folder, or add "
            "--overwrite to replace them"
        )
    return out


def main(argv: list[str] | None = None) -> dict:
    parser = script_parser(__doc__)
    parser.add_argument("--trajectory", default=None, help="recording path (default: bundled Tzionas seq 20)")
    parser.add_argument("--timesteps", type=int, default=3_000_000)
    parser.add_argument("--minutes", type=float, default=None, help="stop training after this wall time")
    parser.add_argument("--n-envs", type=int, default=2)
    parser.add_argument(
        "--vec",
        choices=("dummy", "native"),
        default="dummy",
        help="dummy: SB3's DummyVecEnv of single envs (the measured run); native: the native vector env",
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--drift-limit", type=float, default=0.05, help="max_object_drift while training, m")
    parser.add_argument("--eval-every", type=int, default=50_000, help="timesteps between evaluations")
    parser.add_argument(
        "--torch-threads",
        type=positive_int,
        default=1,
        metavar="N",
        help="PyTorch's threads (default 1: more compete with the environment for the cores; see above)",
    )
    add_output_options(parser, "residual")
    args = parser.parse_args(argv)
    args.out = str(output_folder(parser, args, "residual"))
    record = train(args)
    print(table(record))
    return record


if __name__ == "__main__":
    main()
