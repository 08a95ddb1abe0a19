"""The cost a correction minimises: the object off its recorded track, plus the correction's own size.

Per control frame ``f`` of a simulated future, summed over the frames (every term dimensionless, 1 at its
scale; the scales and weights are :class:`~handsim.correct.config.CorrectionConfig`'s):

* ``|p − p_rec|² / position_scale²`` per recorded object (its origin against its recording);
* ``rotation_weight · θ² / rotation_scale²``, θ the angle between its orientation and the recorded one;
* ``articulation_weight · (a − a_rec)² / articulation_scale²`` for an articulated object;
* ``finger_weight · mean(δ²) / finger_scale²`` over the corrected finger targets;
* ``wrist_weight · (|Δp|² / wrist_position_scale² + |Δr|² / wrist_rotation_scale²)``, averaged over the
  corrected wrists.

Object terms count only at frames whose recorded pose is valid. A glove hold adds the opposition term
(:mod:`handsim.correct.grip`) over the hold's frames: the grip the replay's grip check asks for. A plan is
judged by what the committed simulation will measure; a guided round's costs (:mod:`handsim.correct.guidance`)
only steer the next round's mean.
"""

from __future__ import annotations

import numpy as np

from handsim.correct.config import CorrectionConfig
from handsim.correct.grip import Opposition
from handsim.correct.reference import Reference
from handsim.datatypes.rotations import quat_angle


class Objective:
    """The cost of simulated futures (module docstring).

    Args:
        reference: The recording and the residual layout.
        config: Scales and weights.
    """

    def __init__(self, reference: Reference, config: CorrectionConfig) -> None:
        self.reference, self.config = reference, config
        nf = reference.fingers
        hands = len(reference.hands)
        self._finger_scale = config.finger_weight / (config.finger_scale**2 * max(nf, 1))
        wrist = np.tile(
            [1.0 / config.wrist_position_scale**2] * 3 + [1.0 / config.wrist_rotation_scale**2] * 3, hands
        )
        self._wrist_scale = config.wrist_weight * wrist / max(hands, 1)
        self.opposition = Opposition(reference, config)

    @property
    def needs_sensors(self) -> bool:
        """Whether the cost reads the rollouts' sensor data (the opposition term of a glove hold)."""
        return self.opposition.active

    def control(self, residual: np.ndarray) -> np.ndarray:
        """The correction's size term per frame, residuals (..., D) → (...)."""
        nf = self.reference.fingers
        finger = np.sum(residual[..., :nf] ** 2, axis=-1) * self._finger_scale
        wrist = residual[..., nf:] ** 2 @ self._wrist_scale if self.reference.hands else 0.0
        return finger + wrist

    def tracking(self, qpos: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """The objects' term per frame: simulated ``qpos`` (..., nq) at the control ``frames`` (matching)."""
        config = self.config
        total = np.zeros(qpos.shape[:-1])
        for obj in self.reference.objects:
            ref = obj.pose[frames]
            pos = qpos[..., obj.qpos : obj.qpos + 3] - ref[:, :3]
            term = np.sum(pos**2, axis=-1) / config.position_scale**2
            angle = quat_angle(qpos[..., obj.qpos + 3 : obj.qpos + 7], ref[:, 3:])
            term += config.rotation_weight * angle**2 / config.rotation_scale**2
            if obj.hinge >= 0 and obj.articulation is not None:
                hinge = qpos[..., obj.hinge] - obj.articulation[frames]
                term += config.articulation_weight * hinge**2 / config.articulation_scale**2
            total += np.where(obj.valid[frames], term, 0.0)
        return total

    def drift(self, qpos: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """The largest distance of an object from its recording over valid frames, m: (N, h, nq) → (N,)."""
        largest = np.zeros(qpos.shape[0])
        for obj in self.reference.objects:
            distance = np.linalg.norm(qpos[..., obj.qpos : obj.qpos + 3] - obj.pose[frames, :3], axis=-1)
            largest = np.maximum(largest, np.max(np.where(obj.valid[frames], distance, 0.0), axis=-1))
        return largest

    def __call__(
        self, qpos: np.ndarray, residual: np.ndarray, frames: np.ndarray, sensors: np.ndarray | None = None
    ) -> np.ndarray:
        """Total cost per future: ``qpos`` (N, h, nq) and ``residual`` (N, h, D) at ``frames`` (h,) → (N,).

        ``sensors`` (N, h, nsensordata), the sensor data at the same frames, adds the opposition term where
        :attr:`needs_sensors`.
        """
        total = self.tracking(qpos, frames) + self.control(residual)
        if sensors is not None and self.needs_sensors:
            total = total + self.opposition(sensors, frames)
        return np.sum(total, axis=-1)
