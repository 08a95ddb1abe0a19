"""Builders: plain data in, :class:`mujoco.MjSpec` out. Builders never compile or write files.

* :func:`build_hand`, :func:`default_hand` — hands from skeletons, or the parametric default.
* :func:`build_mano_hand` — the MANO hand from a user's ``MANO_RIGHT.pkl`` or the bundled mean shape;
  :func:`handsim.builders.mano_hand.build_mano_hands` — both hands from a MANO folder, each with its betas.
* :func:`build_object` — objects (:class:`handsim.datatypes.object_model.ObjectModel`), with cached CoACD
  hulls.
* :func:`build_scene` — a hand and objects on a table.
* :mod:`handsim.builders.catalog` — GraspDB14 objects, bundled Tzionas objects, ARCTIC templates
  (:func:`handsim.builders.arctic_objects.arctic_object`: hinge range, colliding parts, per-object mass).

The builders are imported from their modules on first use, so that importing one submodule (the
catalogue for ``handsim catalog``, the object builder for ``handsim build object``) does not import the
others (the hand builder needs SciPy's optimiser; the catalogue needs neither MuJoCo nor trimesh).
:func:`default_hand` and :func:`default_skeleton` are bound at once (cheap): ``default_hand`` is also the
name of its module, which the import system would otherwise bind here when it is first imported;
``default_skeleton`` is plain data from :mod:`handsim.io.graspdb.default_skeleton`, exported here beside the
hand.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from handsim.builders.default_hand import default_hand
from handsim.io.graspdb.default_skeleton import default_skeleton

if TYPE_CHECKING:
    from handsim.builders.hand import build_hand
    from handsim.builders.mano_hand import build_mano_hand, mano_hand_skeleton
    from handsim.builders.objects import build_object, prepare_object
    from handsim.builders.scene import build_scene

_EXPORTS = {
    "build_hand": "handsim.builders.hand",
    "build_mano_hand": "handsim.builders.mano_hand",
    "build_object": "handsim.builders.objects",
    "build_scene": "handsim.builders.scene",
    "mano_hand_skeleton": "handsim.builders.mano_hand",
    "prepare_object": "handsim.builders.objects",
}


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:  # lazy: start-up time, see the module docstring
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
