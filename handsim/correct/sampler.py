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
recording is easy or the object is lost already.

**Contact guidance** (SPIDER's virtual contact, :mod:`handsim.correct.guidance`): where ``guidance`` is
positive, the first ``guidance_rounds`` rounds of each pass simulate their candidates with a virtual force
on each object towards its goal, its gain annealed to zero; those rounds only move the MPPI mean. The plan
committed is the cheapest candidate of the **unguided** rounds (the first of which also scores the nominal
plan and the recording), so no virtual force acts in any future a committed plan was chosen by, nor in the
committed simulation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.correct.backend import CONTROLS, SWITCHED_CONTROLS, RolloutBackend, Start
from handsim.correct.config import CorrectionConfig
from handsim.correct.cost import Objective
from handsim.correct.guidance import Guidance, guidance_schedule
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
        self.guidance = Guidance(reference, config, model)
        self.gains = guidance_schedule(config)
        self.first_unguided = int(np.argmax(self.gains == 0.0))  # the schedule ends at zero

    def controls(
        self, residual: np.ndarray, frames: np.ndarray, start: Start, wrench: np.ndarray | None = None
    ) -> np.ndarray:
        """Per-step rollout controls of residual sequences.

        Args:
            residual: (N, h, D) for the frames ``frames`` (h,): frame ``f``'s targets are held during the
                step from ``f − 1`` to ``f``.
            frames: Control frames.
            start: The state planned from: mocap bodies not corrected keep its poses, equalities its flags
                (a support goes off in the steps after the release frame, as the replay core switches it).
            wrench: Guidance ``xfrc_applied`` per frame (h, 6 · nbody), the same for every sequence
                (:mod:`handsim.correct.guidance`), or None (no guidance: no such columns).

        Returns:
            (N, h · substeps, ncontrol): ``ctrl``, the wrenches where given, every equality's flag where the
            scene releases supports, then every mocap position, then every quaternion: the vector
            :meth:`spec` names.
        """
        ref = self.reference
        count, h, _ = residual.shape
        nu = self.model.nu
        ctrl = np.broadcast_to(ref.schedule.ctrl[frames], (count, h, nu)).copy()
        ctrl[..., ref.actuators] += residual[..., : ref.fingers]
        parts = [ctrl]
        if wrench is not None:
            parts.append(np.broadcast_to(wrench, (count, *wrench.shape)))
        if self.release >= 0:
            active = np.broadcast_to(start.eq_active, (h, self.model.neq)).copy()
            active[np.ix_(frames > self.release, self.supports)] = 0.0
            parts.append(np.broadcast_to(active, (count, h, self.model.neq)))
        pos = np.broadcast_to(start.mocap[:, :3], (count, h, self.nmocap, 3)).copy()
        quat = np.broadcast_to(start.mocap[:, 3:], (count, h, self.nmocap, 4)).copy()
        if ref.welded:  # the welded roots follow the recording, moved where the wrists are corrected
            roots = self.roots[frames]
            if ref.hands:
                roots = moved_roots(roots, residual[..., ref.fingers :])
            world = world_roots(self.world, np.broadcast_to(roots, (count, *roots.shape[-3:])))
            pos[..., ref.mocap, :] = world[..., :3]
            quat[..., ref.mocap, :] = world[..., 3:]
        parts += [pos.reshape(count, h, -1), quat.reshape(count, h, -1)]
        return np.repeat(np.concatenate(parts, axis=-1), self.substeps, axis=1)

    def spec(self, guided: bool) -> int:
        """The ``mjtState`` bits :meth:`controls` sets (with the guidance's wrenches or without)."""
        spec = SWITCHED_CONTROLS if self.release >= 0 else CONTROLS
        return int(spec | (mujoco.mjtState.mjSTATE_XFRC_APPLIED if guided else 0))

    def simulate(
        self, start: Start, residual: np.ndarray, frames: np.ndarray, wrench: np.ndarray | None = None
    ) -> np.ndarray:
        """``qpos`` at the end of each frame of each residual sequence (N, h, nq) from ``start``."""
        return self.futures(start, residual, frames, wrench)[0]

    def futures(
        self, start: Start, residual: np.ndarray, frames: np.ndarray, wrench: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """``qpos`` at the end of each frame (N, h, nq), and the sensor data there where the cost reads it.

        Args:
            start: The state planned from.
            residual: (N, h, D) at ``frames`` (h,).
            frames: Control frames.
            wrench: Guidance wrenches per frame (h, 6 · nbody), or None.

        Returns:
            The ``qpos``, and the sensor data of the same steps (N, h, nsensordata), or None where the cost
            does not read it.
        """
        controls = self.controls(residual, frames, start, wrench)
        sensors = self.objective.needs_sensors
        states, data = self.backend.rollout(
            self.model, start, controls, self.spec(wrench is not None), sensors
        )
        ends = slice(self.substeps - 1, None, self.substeps)
        qpos = states[:, ends, 1 : 1 + self.model.nq]  # the state's layout: time, qpos, qvel, …
        return qpos, None if data is None else data[:, ends]

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
        indices = start + np.arange(1, frames + 1)
        count = nominal.shape[0]
        ramp = np.ones(count)
        if count > 2:
            ramp[1:] = config.near_noise + (1.0 - config.near_noise) * np.arange(count - 1) / (count - 2)
        nq = self.model.nq
        on_track = self.objective.drift(begin.state[None, None, 1 : 1 + nq], indices[:1] - 1)[0] <= (
            config.position_scale
        )
        search = _Search(centre=nominal, best=nominal)
        qvel = begin.state[1 + nq : 1 + nq + self.model.nv]
        for pass_ in range(1 + config.rescue):
            if pass_ > 0 and not (on_track and search.best_drift > config.position_scale):
                break  # nothing to rescue: the plan keeps the objects on track, or they are off it already
            if pass_ > 0:
                search.centre = search.best
            for round_, gain in enumerate(self.gains):
                wrench = None
                if gain > 0:
                    wrench = self.guidance.wrenches(gain, begin.state[1 : 1 + nq], qvel, start, indices)
                first = pass_ == 0 and round_ == self.first_unguided
                self._round(
                    search,
                    nominal,
                    begin,
                    indices,
                    config.anneal**round_ * ramp[1:, None] * self.noise,
                    first,
                    wrench,
                )
        return StepPlan(
            knots=search.best,
            cost=search.best_cost,
            nominal_cost=search.nominal_cost,
            rollouts=search.rollouts,
        )

    def _round(
        self,
        search: _Search,
        nominal: np.ndarray,
        begin: Start,
        indices: np.ndarray,
        scale: np.ndarray,
        first: bool,
        wrench: np.ndarray | None,
    ) -> None:
        """One round: perturb the centre, simulate, keep the best unguided plan, move the centre (MPPI).

        Args:
            search: The planning step's state (updated).
            nominal: The plan the step started from.
            begin: The committed simulation at the start frame.
            indices: The frames planned.
            scale: The round's noise per free knot and element (K − 1, D).
            first: The step's first unguided round: the nominal plan and the recording are candidates.
            wrench: The round's guidance wrenches, or None (an unguided round: its plans may be committed).
        """
        config, centre = self.config, search.centre
        extra = [centre[None]]
        if first:  # the recording itself from the next knot on: a correction is never forced
            if self.first_unguided > 0:  # guided rounds moved the centre: the nominal plan is scored too
                extra.append(nominal[None])
            zero = np.zeros_like(centre)
            zero[0] = centre[0]
            extra.append(zero[None])
        draws = config.samples - len(extra)
        noise = self.rng.standard_normal((draws, centre.shape[0] - 1, centre.shape[1])) * scale
        free = self.reference.clip(centre[1:] + noise)
        head = np.broadcast_to(centre[:1], (draws, 1, centre.shape[1]))
        knots = np.concatenate([*extra, np.concatenate([head, free], 1)])
        offsets = indices - indices[0] + 1
        residual = self.reference.in_range(interpolate(knots, config.knot, offsets), indices)
        qpos, sensors = self.futures(begin, residual, indices, wrench)
        costs = self.objective(qpos, residual, indices, sensors)
        search.rollouts += knots.shape[0]
        i = int(np.argmin(costs))
        if wrench is None:  # a plan committed has been simulated without guidance
            if first:
                search.nominal_cost = float(costs[len(extra) - 2])
            if costs[i] < search.best_cost:
                search.best_cost, search.best = float(costs[i]), knots[i]
                search.best_drift = float(self.objective.drift(qpos[i : i + 1], indices)[0])
        spread = max(float(np.median(costs) - costs[i]), 1e-12)
        weights = np.exp(-(costs - costs[i]) / (config.temperature * spread))
        search.centre = np.tensordot(weights / weights.sum(), knots, axes=1)
        search.centre[0] = nominal[0]  # the residual already applied: exactly, not a weighted sum of copies


@dataclass
class _Search:
    """A planning step's search so far: the next round's centre and the best unguided plan simulated.

    Attributes:
        centre: The next round's mean plan (K, D).
        best: The cheapest plan simulated without guidance.
        best_cost: Its cost (inf before any).
        best_drift: Its largest object distance from the goal over the horizon, m.
        nominal_cost: The nominal plan's cost (unguided).
        rollouts: Candidates simulated.
    """

    centre: np.ndarray
    best: np.ndarray
    best_cost: float = math.inf
    best_drift: float = math.inf
    nominal_cost: float = math.nan
    rollouts: int = 0
