"""Does the physics allow residual tracking to keep the cube on its track? A planner that sees everything.

    python scripts/residual_oracle.py --out docs/rl/oracle            # the run quoted in docs/rl.md
    python scripts/residual_oracle.py --frames 20 --out /tmp/oracle   # a smoke run (its test)

Issue 17 asks a residual policy on ``handsim/Replay-v0`` (the bundled Tzionas sequence 20) to keep the cube
within 1 cm of its recorded track in ≥ 90 % of frames, with mean drift ≤ 5 mm and joint tracking error at
most 2× pure replay's, "or show why the physics makes this impossible". A policy sees only its
observation; this planner sees the whole simulation: from the simulation's exact state at each frame it
tries ``--samples`` residual sequences over the next ``--horizon`` frames (predictive sampling, the
sampling planner of MuJoCo MPC: the best sequence so far and Gaussian perturbations of it, on knots every
``--knot`` frames, linearly interpolated), keeps the one whose simulated future costs least, and applies
its first frame. The cost of a future is, per frame, the cube's squared distance from its recorded
position over (1 cm)² plus ``--joint-weight`` × the mean squared joint error over
(``--joint-sigma``)²: the acceptance's own quantities. Every residual stays within the environment's
action space (``residual_scale`` 0.1 rad per joint).

The plan is then replayed open loop through ``ReplayEnv.step`` from the recording's first frame and
measured as ``scripts/train_residual.py`` measures a policy (its ``evaluate`` numbers: % of frames within
1 cm, mean and max drift, joint tracking RMS), beside pure replay. If this planner, with the exact state
and unlimited look-ahead sampling, cannot meet the acceptance, no policy on the same environment can be
expected to; if it can, the residuals exist and the open-loop sequence is one of them.

``--prefix actions.npy --plan-from K`` replays an earlier plan's first K frames open loop and plans from
there (a stronger planner on the frames that decide the outcome); ``--residual-scale`` plans with larger
corrections than the environment's 0.1 rad.

Deterministic: the sampling generator is seeded (``--seed``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from train_residual import ENV_KWARGS, WITHIN, evaluate

from handsim.envs.replay_env import ReplayEnv

_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
PLANNER_ENV = {**ENV_KWARGS, "random_start": False, "reset_noise_scale": 0.0, "max_object_drift": None}
"""The environment planned and measured on: train_residual's, from frame 0, no reset noise or drift limit."""


class Planner:
    """Predictive sampling over residual sequences on one ``ReplayEnv``'s simulation (module docstring).

    Args:
        env: The environment (reset to the plan's first frame); its simulation is stepped and restored.
        samples: Sequences tried per frame (the best so far among them).
        horizon: Frames each sequence looks ahead.
        knot: Frames between the sequences' knots.
        sigma: Standard deviation of the knots' perturbations, action units (1 = ``residual_scale``).
        joint_weight: Weight of the joint error in the cost.
        joint_sigma: Joint error scale of the cost, rad.
        seed: Seed of the perturbations.
        iterations: Rounds of sampling per frame, each around the best sequence of the round before with
            half its spread (the cross-entropy method's narrowing; 1: plain predictive sampling).
    """

    def __init__(
        self,
        env: ReplayEnv,
        *,
        samples: int,
        horizon: int,
        knot: int,
        sigma: float,
        joint_weight: float,
        joint_sigma: float,
        seed: int,
        iterations: int = 1,
    ) -> None:
        self.env, self.task = env, env.task
        self.driver = self.task.driver
        self.model, self.data = env.model, env.data
        layout = env.scene.layout
        track = env.schedule.objects[0]
        self.ref_position = np.asarray(track.pose, dtype=float)[:, :3]
        self.cube_qpos = layout.objects[0].free_qpos
        self.dof_qpos = layout.dof_qpos
        self.ref_ctrl = self.task.ref_ctrl
        self.samples, self.horizon, self.knot, self.sigma = samples, horizon, knot, sigma
        self.iterations = iterations
        self.joint_scale = joint_weight / joint_sigma**2
        self.knots = math.ceil(horizon / knot) + 1
        self.rng = np.random.default_rng(seed)
        nu = env.action_space.shape[0]
        self.nominal = np.zeros((self.knots, nu))
        # frame h of the horizon lies between knots h // knot and h // knot + 1
        h = np.arange(horizon)
        self._lo, self._w = h // knot, (h % knot) / knot
        self._state = np.empty(mujoco.mj_stateSize(self.model, _STATE))
        self._scratch = np.empty(self.model.nu)

    def _sequence(self, knots: np.ndarray) -> np.ndarray:
        """Residual actions (horizon, nu) from knots (knots, nu), clipped to the action space."""
        seq = knots[self._lo] * (1 - self._w)[:, None] + knots[self._lo + 1] * self._w[:, None]
        return np.clip(seq, -1.0, 1.0)

    def _cost(self, actions: np.ndarray, start: int, last: int) -> float:
        """The simulated future's cost from the saved state at frame ``start``, restored after."""
        model, data, driver = self.model, self.data, self.driver
        mujoco.mj_setState(model, data, self._state, _STATE)
        driver.frame = start
        cost = 0.0
        for h in range(min(self.horizon, last - start)):
            k = start + h + 1
            self.task.controls(actions[h], k, data.ctrl)
            driver.advance()
            delta = data.qpos[self.cube_qpos : self.cube_qpos + 3] - self.ref_position[k]
            error = data.qpos[self.dof_qpos] - self.ref_ctrl[k]
            cost += float(delta @ delta) / WITHIN**2 + self.joint_scale * float(error @ error) / error.size
        return cost

    def plan(self, frame: int, last: int) -> np.ndarray:
        """The residual to apply at ``frame`` (the simulation is left at ``frame``'s state)."""
        model, data = self.model, self.data
        mujoco.mj_getState(model, data, self._state, _STATE)
        best, sigma = self.nominal, self.sigma
        for _ in range(self.iterations):
            candidates = [best]
            noise = self.rng.normal(0.0, sigma, (self.samples - 1, *best.shape))
            candidates += [np.clip(best + n, -1.0, 1.0) for n in noise]
            costs = [self._cost(self._sequence(c), frame, last) for c in candidates]
            best = candidates[int(np.argmin(costs))]
            sigma /= 2
        mujoco.mj_setState(model, data, self._state, _STATE)
        self.driver.frame = frame
        action = self._sequence(best)[0]
        # next frame's nominal: the best sequence one frame on (its knots re-sampled), the tail held
        shifted = self._sequence(best)
        times = np.minimum(np.arange(self.knots) * self.knot + 1, self.horizon - 1)
        self.nominal = shifted[times]
        return action


def run_plan(args: argparse.Namespace, env_kwargs: dict) -> tuple[np.ndarray, float]:
    """Plan frame by frame through the recording (or its first ``--frames``); returns the actions and s."""
    env = ReplayEnv(**env_kwargs)
    env.reset(seed=0, options={"frame": 0})
    planner = Planner(
        env,
        samples=args.samples,
        horizon=args.horizon,
        knot=args.knot,
        sigma=args.sigma,
        joint_weight=args.joint_weight,
        joint_sigma=args.joint_sigma,
        seed=args.seed,
        iterations=args.iterations,
    )
    last = env.schedule.frames - 1 if args.frames is None else min(args.frames, env.schedule.frames - 1)
    before = np.load(args.prefix) if args.prefix is not None else np.zeros((0, env.action_space.shape[0]))
    first = min(args.plan_from, len(before), last)
    actions = []
    start = time.perf_counter()
    for frame in range(last):
        if frame < first:  # the given plan, open loop, up to --plan-from
            actions.append(before[frame])
            env.step(before[frame])
            continue
        action = planner.plan(frame, env.schedule.frames - 1)
        actions.append(action)
        env.step(action)  # float64, as planned
        if args.progress and frame % 50 == 0:
            print(f"frame {frame}/{last} ({time.perf_counter() - start:.0f} s)", flush=True)
    return np.asarray(actions), time.perf_counter() - start


class _OpenLoop:
    """The plan as a policy for ``evaluate``: its actions in order, then zero."""

    def __init__(self, actions: np.ndarray) -> None:
        self.actions, self.step = actions, 0

    def predict(self, _obs, deterministic: bool = True):
        a = self.actions[self.step] if self.step < len(self.actions) else np.zeros(self.actions.shape[1])
        self.step += 1
        return np.asarray(a, np.float64)[None], None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=32, help="sequences tried per frame")
    parser.add_argument("--horizon", type=int, default=30, help="frames each sequence looks ahead")
    parser.add_argument("--knot", type=int, default=5, help="frames between knots")
    parser.add_argument("--sigma", type=float, default=0.3, help="knot perturbation std, action units")
    parser.add_argument("--joint-weight", type=float, default=0.25, help="weight of the joint error")
    parser.add_argument("--joint-sigma", type=float, default=0.02, help="joint error scale, rad")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--iterations", type=int, default=1, help="sampling rounds per frame, spread halved")
    parser.add_argument("--frames", type=int, default=None, help="plan only the first N frames")
    parser.add_argument(
        "--prefix", type=Path, default=None, help="actions.npy of an earlier plan, applied up to --plan-from"
    )
    parser.add_argument("--plan-from", type=int, default=0, help="first frame planned (with --prefix)")
    parser.add_argument("--residual-scale", type=float, default=None, help="rad (default: the env's 0.1)")
    parser.add_argument("--progress", action="store_true")
    parser.add_argument("--out", type=Path, default=Path("docs/rl/oracle"))
    args = parser.parse_args(argv)
    env_kwargs = dict(PLANNER_ENV)
    if args.residual_scale is not None:
        env_kwargs["residual_scale"] = args.residual_scale
    actions, seconds = run_plan(args, env_kwargs)
    planned = evaluate(env_kwargs, _OpenLoop(actions))
    replay = evaluate(env_kwargs)
    if args.frames is not None:  # a smoke run: the rest of the recording runs at zero residual
        planned["planned_frames"] = len(actions)
    names = ("samples", "horizon", "knot", "sigma", "joint_weight", "seed", "iterations")
    settings = {k: getattr(args, k) for k in names}
    settings.update(
        joint_sigma=args.joint_sigma,
        prefix=None if args.prefix is None else str(args.prefix),
        plan_from=args.plan_from if args.prefix is not None else 0,
    )
    record = {
        "settings": settings,
        "env_kwargs": env_kwargs,
        "planning_minutes": seconds / 60,
        "pure_replay": replay,
        "planner": planned,
        "tracking_vs_replay": planned["tracking_rms_mrad"] / replay["tracking_rms_mrad"],
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "oracle.json").write_text(json.dumps(record, indent=2) + "\n")
    np.save(args.out / "actions.npy", actions)
    rows = [("pure replay (zero residual)", replay), (f"planner ({len(actions)} frames planned)", planned)]
    lines = [
        "| | frames within 1 cm | mean drift (mm) | max drift (mm) | joint tracking RMS (mrad) |",
        "|---|---|---|---|---|",
        *(
            f"| {name} | {r['within_1cm'] * 100:.1f} % | {r['mean_drift_mm']:.1f} | "
            f"{r['max_drift_mm']:.1f} | {r['tracking_rms_mrad']:.1f} |"
            for name, r in rows
        ),
    ]
    (args.out / "oracle.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"planning: {seconds / 60:.1f} min; joint error {record['tracking_vs_replay']:.2f}× pure replay's")
    return 0


if __name__ == "__main__":
    sys.exit(main())
