"""Contact guidance: a virtual force on each free object towards its goal in the first, guided rounds.

SPIDER (Pan et al. 2025, "SPIDER: Scalable Physics-Informed Dexterous Retargeting") guides its sampler with
virtual contact: in the first annealing iterations a soft constraint pulls the object to its reference (an
equality whose stiffness is annealed), so that candidates which would drop the object are still told apart
by how well the hand carries it, and the mean moves towards contact-rich plans the unguided sampler misses;
by the last iterations the constraint is gone. Here the virtual force acts through MuJoCo's
``xfrc_applied`` on each object's root body, set with every rollout step's controls
(``mjSTATE_XFRC_APPLIED``); like SPIDER's point constraint it is a force, no torque.

``mujoco.rollout`` runs open-loop, so the force is a function of time, fixed per planning round: the force
that would carry the object along its goal, and pull it back from where it starts, were nothing else acting
on it. At frame ``f`` of a plan from frame ``k`` (``t`` the time since ``k``)::

    F(f) = γ · m · (a_goal(f) − g + ω² e(t) + 2ω ė(t)),   e(t) = p_goal(f) − (p_k + v_k t)

``m`` the object's mass (its subtree's), ``g`` gravity, ``a_goal`` the goal's acceleration (a central
difference over one knot, so the resampled recording's corners do not become spikes), ``p_k, v_k`` the
object's position and velocity at the start, ``ω`` :data:`GUIDANCE_RATE` and ``γ`` the round's gain. The
goal is the recorded track, or a glove scene's placement (:mod:`handsim.correct.hold`); frames where the
goal is not valid (a glove object on its support before the release) get no force.

The gain falls linearly from ``guidance`` in a pass's first round to zero after ``guidance_rounds`` rounds,
at most all rounds but the last (:func:`guidance_schedule`); the rounds after are unguided and the plan
committed is chosen among them only (:mod:`handsim.correct.sampler`), so the committed simulation, and the
corrected file's replay, carry no virtual force.
"""

from __future__ import annotations

import mujoco
import numpy as np

from handsim.correct.config import CorrectionConfig
from handsim.correct.reference import Reference

GUIDANCE_RATE = 10.0
"""ω of the guidance's pull back to the goal, rad/s: a critically damped error closes in about 0.2 s, under
half the 0.5 s horizon, so a guided future ends on its goal, while the pull stays below gravity for the
centimetre errors a slip makes (ω² · 1 cm = 1 m/s²)."""


def guidance_schedule(config: CorrectionConfig) -> np.ndarray:
    """The guidance gain of each round of a planning pass (iterations,): annealed linearly to exactly zero.

    With ``n = min(guidance_rounds, iterations − 1)`` guided rounds (the last round is always unguided: the
    plan committed is chosen there), round ``r < n`` gets ``guidance · (1 − r / n)``, the others 0.
    """
    rounds = np.arange(config.iterations)
    guided = min(config.guidance_rounds, config.iterations - 1)
    if config.guidance <= 0 or guided == 0:
        return np.zeros(config.iterations)
    return np.where(rounds < guided, config.guidance * (1.0 - rounds / guided), 0.0)


class Guidance:
    """The guidance wrenches of a planning round (module docstring).

    Args:
        reference: The recording (its objects' goals).
        config: ``knot`` (the acceleration's difference step).
        model: The rollouts' model.
    """

    def __init__(self, reference: Reference, config: CorrectionConfig, model: mujoco.MjModel) -> None:
        self.model = model
        self.dt = float(reference.schedule.frame_dt)
        self.objects = reference.objects
        joints = [_free_joint(model, o.qpos) for o in self.objects]
        self.bodies = [int(model.jnt_bodyid[j]) for j in joints]
        self.dofs = [int(model.jnt_dofadr[j]) for j in joints]
        self.mass = [float(model.body_subtreemass[b]) for b in self.bodies]
        self.gravity = np.array(model.opt.gravity, dtype=float)
        step = config.knot
        self.accel = []
        for obj in self.objects:
            p = np.asarray(obj.pose[:, :3], dtype=float)
            padded = np.concatenate([np.repeat(p[:1], step, 0), p, np.repeat(p[-1:], step, 0)])
            self.accel.append((padded[2 * step :] - 2 * p + padded[: -2 * step]) / (step * self.dt) ** 2)

    def wrenches(
        self, gain: float, qpos: np.ndarray, qvel: np.ndarray, start: int, frames: np.ndarray
    ) -> np.ndarray:
        """``xfrc_applied`` of every body per frame (h, nbody · 6): the guidance force on the objects.

        Args:
            gain: The round's gain γ (0: all zero).
            qpos: The start state's ``qpos`` (nq,).
            qvel: Its ``qvel`` (nv,).
            start: The frame the plan starts from.
            frames: The frames planned (h,), after ``start``.
        """
        out = np.zeros((frames.shape[0], self.model.nbody, 6))
        if gain == 0.0:
            return out.reshape(frames.shape[0], -1)
        t = (frames - start)[:, None] * self.dt
        omega = GUIDANCE_RATE
        for obj, body, dof, mass, accel in zip(
            self.objects, self.bodies, self.dofs, self.mass, self.accel, strict=True
        ):
            p0, v0 = qpos[obj.qpos : obj.qpos + 3], qvel[dof : dof + 3]
            goal = obj.pose[frames, :3]
            goal_v = (obj.pose[np.minimum(frames + 1, obj.pose.shape[0] - 1), :3] - goal) / self.dt
            error, rate = goal - (p0 + v0 * t), goal_v - v0
            force = mass * (accel[frames] - self.gravity + omega**2 * error + 2.0 * omega * rate)
            out[:, body, :3] = np.where(obj.valid[frames, None], gain * force, 0.0)
        return out.reshape(frames.shape[0], -1)


def _free_joint(model: mujoco.MjModel, qpos: int) -> int:
    """The free joint whose ``qpos`` starts at ``qpos``."""
    return int(np.flatnonzero(model.jnt_qposadr == qpos)[0])
