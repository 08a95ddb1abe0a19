"""Builders: plain data in, :class:`mujoco.MjSpec` out. Builders never compile or write files.

* :func:`build_hand`, :func:`default_hand` — hands from skeletons, or the parametric default.
* :func:`build_mano_hand` — the MANO hand from a user's ``MANO_RIGHT.pkl`` or the bundled mean shape;
  :func:`handsim.builders.mano_hand.build_mano_hands` — both hands from a MANO folder, each with its betas.
* :func:`build_object` — objects (:class:`handsim.object_model.ObjectModel`), with cached CoACD hulls.
* :func:`build_scene` — a hand and objects on a table.
* :mod:`handsim.builders.catalog` — GraspDB14 objects, bundled Tzionas objects, ARCTIC templates
  (:func:`handsim.builders.arctic_objects.arctic_object`: hinge range, colliding parts, per-object mass).
"""

from handsim.builders.default_hand import default_hand, default_skeleton
from handsim.builders.hand import build_hand
from handsim.builders.mano_hand import build_mano_hand, mano_hand_skeleton
from handsim.builders.objects import build_object, prepare_object
from handsim.builders.scene import build_scene

__all__ = [
    "build_hand",
    "build_mano_hand",
    "build_object",
    "build_scene",
    "default_hand",
    "default_skeleton",
    "mano_hand_skeleton",
    "prepare_object",
]
