"""One planning step: annealed sampling of residual sequences over a horizon, scored on batched rollouts.

The method follows three published samplers:

* **Predictive sampling** (Howell et al. 2022, "Predictive Sampling: Real-time Behaviour Synthesis with
  MuJoCo", the sampling planner of MuJoCo MPC): a plan is a spline of knots; candidates are the nominal plan
  and Gaussian perturbations of its knots; each is simulated from the current state and scored by its cost;
  the nominal plan is among the candidates, so the chosen plan never costs more than keeping it.
* **MPPI** (Williams et al. 2017, "Information Theoretic MPC for Model-Based Reinforcement Learning"):
  between rounds the knots are averaged with weights ``exp(−(c − c_min) / λ)``, so near-best candidates
  all pull the next round's centre; here λ is ``temperature`` times the round's cost spread (median minus
  best), which makes the weights independent of the cost's units.
* **Annealing** (Xue et al. 2024, DIAL-MPC, "Full-Order Sampling-Based MPC for Torque-Level Locomotion
  Control via Diffusion-Style Annealing"; Pan et al. 2025, SPIDER, "Scalable Physics-Informed Dexterous
  Retargeting", which anneals the same way to retarget human motion): the noise shrinks by ``anneal`` from
  one round to the next, and grows along the horizon from ``near_noise`` times its scale on the first free
  knot to its full scale on the last.

The plan returned is the cheapest candidate simulated in any round (the rounds' MPPI means are candidates of
the round after them), so what is committed is a plan whose simulated future was seen. Where that plan still
lets an object leave its track (farther than ``position_scale`` from its recording at some frame of the
horizon) while it is on its track now, up to ``rescue`` more passes of annealed rounds start again from it
at the full noise: the search spends its effort where a loss may still be prevented, and none where the
recording is easy or the object is lost already. SPIDER's virtual contact guidance is not used: no force but
the hand's acts on the object in any rollout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.correct.backend import RolloutBackend, Start
from handsim.correct.config import CorrectionConfig
from handsim.correct.cost import Objective
from handsim.correct.reference import Reference, moved_roots, world_roots


@dataclass(frozen=True)
class StepPlan:
    """The result of one planning step.

    Attributes:
        knots: The chosen plan's knots (K, D); knot 0 is the residual at the start frame.
        cost: Its simulated cost.
        nominal_cost: The cost of the plan the step started from (the previous plan, shifted).
        rollouts: Candidates simulated.
    """

    knots: np.ndarray
    cost: float
    nominal_cost: float
    rollouts: int


def knot_count(frames: int, knot: int) -> int:
    """Knots of a plan over ``frames`` frames, ``knot`` frames apart (the first at the start frame)."""
    return math.ceil(frames / knot) + 1


def interpolate(knots: np.ndarray, knot: int, offsets: np.ndarray) -> np.ndarray:
    """Residuals at frame ``offsets`` after the start, linear between knots ``knot`` frames apart.

    Args:
        knots: (..., K, D), knot ``j`` at offset ``j · knot``.
        knot: Frames between knots.
        offsets: Frame offsets (h,), ≥ 0; past the last knot the last knot holds.

    Returns:
        (..., h, D).
    """
    last = knots.shape[-2] - 1
    position = np.minimum(np.asarray(offsets, dtype=float) / knot, last)
    lo = np.minimum(np.floor(position).astype(np.int64), max(last - 1, 0))
    hi = np.minimum(lo + 1, last)
    w = (position - lo)[:, None]
    return knots[..., lo, :] * (1.0 - w) + knots[..., hi, :] * w


class AnnealedSampler:
    """Plans residuals from a state by annealed MPPI over batched rollouts (module docstring).

    Args:
        reference: The recording and the residual layout.
        config: The parameters.
        backend: The rollout backend.
        model: The model the rollouts simulate (the replay's).
        rng: The seeded generator of the perturbations (drawn in a fixed order: deterministic).
    """

    def __init__(
        self,
        reference: Reference,
        config: CorrectionConfig,
        backend: RolloutBackend,
        model: mujoco.MjModel,
        rng: np.random.Generator,
    ) -> None:
        self.reference, self.config, self.backend = reference, config, backend
        self.model, self.rng = model, rng
        self.objective = Objective(reference, config)
        nf, hands = reference.fingers, len(reference.hands)
        wrist = [config.wrist_position_noise] * 3 + [config.wrist_rotation_noise] * 3
        self.noise = np.concatenate([np.full(nf, config.finger_noise), np.tile(wrist, hands)]).astype(float)
        schedule = reference.schedule
        self.substeps = schedule.substeps
        self.world = np.asarray(reference.scene.setup.world_from_recording, dtype=float)
        self.roots = reference.recorded_roots()
        self.nmocap = model.nmocap
        # a scene that releases supports sets every equality's flag at every step (the release on its frame)
        self.release = reference.switches.release_frame
        layout = reference.scene.layout
        self.supports = np.array([o.support_eq for o in layout.objects if o.support_eq >= 0], dtype=np.int64)

    def controls(self, residual: np.ndarray, frames: np.ndarray, start: Start) -> np.ndarray:
        """Per-step rollout controls of residual sequences.

        Args:
            residual: (N, h, D) for the frames ``frames`` (h,): frame ``f``'s targets are held during the
                step from ``f − 1`` to ``f``.
            frames: Control frames.
            start: The state planned from: mocap bodies not corrected keep its poses, equalities its flags
                (a support goes off in the steps after the release frame, as the replay core switches it).

        Returns:
            (N, h · substeps, nu [+ neq] + 7 · nmocap): ``ctrl``, every equality's flag where the scene
            releases supports (:data:`~handsim.correct.backend.SWITCHED_CONTROLS`), then every mocap
            position, then every quaternion.
        """
        ref = self.reference
        count, h, _ = residual.shape
        nu = self.model.nu
        neq = self.model.neq if self.release >= 0 else 0
        mocap = start.mocap
        out = np.empty((count, h, nu + neq + 7 * self.nmocap))
        ctrl = np.broadcast_to(ref.schedule.ctrl[frames], (count, h, nu)).copy()
        ctrl[..., ref.actuators] += residual[..., : ref.fingers]
        out[..., :nu] = ctrl
        if neq:
            active = np.broadcast_to(start.eq_active, (h, neq)).copy()
            active[np.ix_(frames > self.release, self.supports)] = 0.0
            out[..., nu : nu + neq] = active
        nu += neq  # the mocap columns follow
        pos = np.broadcast_to(mocap[:, :3], (count, h, self.nmocap, 3)).copy()
        quat = np.broadcast_to(mocap[:, 3:], (count, h, self.nmocap, 4)).copy()
        if ref.welded:  # the welded roots follow the recording, moved where the wrists are corrected
            roots = self.roots[frames]
            if ref.hands:
                roots = moved_roots(roots, residual[..., ref.fingers :])
            world = world_roots(self.world, np.broadcast_to(roots, (count, *roots.shape[-3:])))
            pos[..., ref.mocap, :] = world[..., :3]
            quat[..., ref.mocap, :] = world[..., 3:]
        out[..., nu : nu + 3 * self.nmocap] = pos.reshape(count, h, -1)
        out[..., nu + 3 * self.nmocap :] = quat.reshape(count, h, -1)
        return np.repeat(out, self.substeps, axis=1)

    def simulate(self, start: Start, residual: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """``qpos`` at the end of each frame of each residual sequence (N, h, nq) from ``start``."""
        controls = self.controls(residual, frames, start)
        states = self.backend.rollout(self.model, start.state, start.warmstart, controls)
        ends = states[:, self.substeps - 1 :: self.substeps]
        return ends[..., 1 : 1 + self.model.nq]  # the state's layout: time, qpos, qvel, …

    def plan(
        self,
        start: int,
        frames: int,
        nominal: np.ndarray,
        begin: Start,
    ) -> StepPlan:
        """Plan the residuals of frames ``start + 1 … start + frames`` from the state at ``start``.

        Args:
            start: The frame the state is at.
            frames: Frames ahead (≥ 1).
            nominal: The plan to improve (K, D), ``K = knot_count(frames, knot)``; knot 0 (the residual
                already applied at ``start``) is kept as it is.
            begin: The committed simulation at ``start``.
        """
        config = self.config
        knot = config.knot
        offsets = np.arange(1, frames + 1)
        indices = start + offsets
        count = nominal.shape[0]
        ramp = np.ones(count)
        if count > 2:
            ramp[1:] = config.near_noise + (1.0 - config.near_noise) * np.arange(count - 1) / (count - 2)
        on_track = self.objective.drift(begin.state[None, None, 1 : 1 + self.model.nq], indices[:1] - 1)[
            0
        ] <= (config.position_scale)
        centre = nominal
        best_cost, best, best_drift = math.inf, nominal, math.inf
        nominal_cost = math.nan
        rollouts = 0
        for pass_ in range(1 + config.rescue):
            if pass_ > 0 and not (on_track and best_drift > config.position_scale):
                break  # nothing to rescue: the plan keeps the objects on track, or they are off it already
            centre = best if pass_ > 0 else centre
            for round_ in range(config.iterations):
                first = pass_ == 0 and round_ == 0
                scale = config.anneal**round_ * ramp[1:, None] * self.noise
                draws = config.samples - 1 - (1 if first else 0)
                noise = self.rng.standard_normal((draws, count - 1, nominal.shape[1])) * scale
                candidates = [centre[None]]
                if first:  # the recording itself from the next knot on: a correction is never forced
                    zero = np.zeros_like(centre)
                    zero[0] = centre[0]
                    candidates.append(zero[None])
                free = self.reference.clip(centre[1:] + noise)
                candidates.append(
                    np.concatenate([np.broadcast_to(centre[:1], (draws, 1, centre.shape[1])), free], 1)
                )
                knots = np.concatenate(candidates)
                residual = self.reference.in_range(interpolate(knots, knot, offsets), indices)
                qpos = self.simulate(begin, residual, indices)
                costs = self.objective(qpos, residual, indices)
                rollouts += knots.shape[0]
                if first:
                    nominal_cost = float(costs[0])
                i = int(np.argmin(costs))
                if costs[i] < best_cost:
                    best_cost, best = float(costs[i]), knots[i]
                    best_drift = float(self.objective.drift(qpos[i : i + 1], indices)[0])
                spread = max(float(np.median(costs) - costs[i]), 1e-12)
                weights = np.exp(-(costs - costs[i]) / (config.temperature * spread))
                centre = np.tensordot(weights / weights.sum(), knots, axes=1)
                centre[0] = nominal[0]  # the residual already applied: exactly, not a weighted sum of copies
        return StepPlan(knots=best, cost=best_cost, nominal_cost=nominal_cost, rollouts=rollouts)
