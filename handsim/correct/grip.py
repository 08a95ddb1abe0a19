"""The opposition term of a glove hold: a grip pressed from two sides, as the replay's grip check asks.

The hold objective (:mod:`handsim.correct.hold`) measures only where the object is; the replay's hold verdict
also asks for a grip (:mod:`handsim.sim.grip_check`): opposing contacts, the thumb against a finger or the
fingers against the palm, in force closure on enough of the hold window's frames. An object can stay put
resting on the fingers of a palm-down hand, and its hold is then "not judged". This term rewards what the
grip check counts, from what a rollout returns cheaply: the scene's link × object-part contact sensors'
normal forces (:func:`handsim.sim.metrics.contact_slot_values`), summed per side (thumb, fingers — index to
little, :data:`~handsim.sim.grip_check.FINGERS` — and palm). A frame's grip is the weaker side of the
better opposing pair, ``g = max(min(thumb, fingers), min(fingers, palm))``, and its cost::

    opposition_weight · (1 − min(1, g / (opposition_force · weight)))²

1 without an opposing pair, 0 once both sides of one press with ``opposition_force`` of the object's
weight. It counts at the hold's frames (the release to the window's end). The force closure itself (the
contacts' geometry) is left to the replay's check: a pair pressing from two sides is what the sampler can
find, and the check then judges it.
"""

from __future__ import annotations

import numpy as np

from handsim.correct.config import CorrectionConfig
from handsim.correct.reference import Reference
from handsim.datatypes.fingers import finger_of
from handsim.sim.grip_check import FINGERS
from handsim.sim.metrics import contact_slot_values

_NORMAL = 1
"""Offset of the normal force in a contact sensor's slot (:func:`contact_slot_values`)."""


class Opposition:
    """The opposition term of a glove hold's frames (module docstring).

    Args:
        reference: The recording; its ``goal`` is the hold (None: the term is 0 everywhere).
        config: ``opposition_weight`` and ``opposition_force``.
    """

    def __init__(self, reference: Reference, config: CorrectionConfig) -> None:
        self.scene = reference.scene
        self.goal = reference.goal
        self.weight = config.opposition_weight
        layout = self.scene.layout
        groups = [finger_of(name) for name in layout.link_names]
        self.sides = np.array(
            [[g == "thumb" for g in groups], [g in FINGERS for g in groups], [g == "palm" for g in groups]],
            dtype=float,
        )  # (3, links)
        obj = layout.objects[0] if layout.objects else None
        self.parts = slice(0, 0 if obj is None else len(obj.part_bodies))
        model = self.scene.model
        mass = 0.0 if obj is None else float(model.body_subtreemass[obj.root_body])
        self.force = config.opposition_force * mass * float(np.linalg.norm(model.opt.gravity))

    @property
    def active(self) -> bool:
        """Whether the term counts anywhere (a glove hold with a positive weight)."""
        return self.goal is not None and self.weight > 0 and self.force > 0

    def sides_pressing(self, sensors: np.ndarray) -> np.ndarray:
        """The thumb's, the fingers' and the palm's push on the object, N: (..., nsensordata) → (..., 3)."""
        rows = sensors.reshape(-1, sensors.shape[-1])
        normal = contact_slot_values(self.scene, rows, _NORMAL)[:, :, self.parts].sum(axis=(2, 3))
        return (normal @ self.sides.T).reshape((*sensors.shape[:-1], 3))

    def __call__(self, sensors: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """The term per frame: sensor data (..., h, nsensordata) at the control ``frames`` (h,) → (..., h)."""
        if not self.active or self.goal is None:
            return np.zeros(sensors.shape[:-1])
        side = self.sides_pressing(sensors)
        grip = np.maximum(np.minimum(side[..., 0], side[..., 1]), np.minimum(side[..., 1], side[..., 2]))
        term = self.weight * (1.0 - np.minimum(1.0, grip / self.force)) ** 2
        return np.where(self.goal.valid[frames], term, 0.0)
