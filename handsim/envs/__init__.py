"""Gymnasium environments of handsim, registered when ``handsim`` is imported.

* ``handsim/Replay-v0`` (:class:`~handsim.envs.replay_env.ReplayEnv`): follow a recorded trajectory; the
  action corrects the recorded joint targets.
* ``handsim/Grasp-v0`` (:class:`~handsim.envs.grasp_env.GraspEnv`): a hand above a catalogue object; the
  action sets joint targets and moves the hand; lift the object and hold it.

Importing this package is cheap and changes no environment variable: it registers entry points by name
and imports neither ``mujoco`` nor the environment modules. ``render()`` chooses its OpenGL backend when it
first renders (:mod:`handsim.viz.headless`: EGL on Linux without a display unless ``MUJOCO_GL`` is set).
"""

from __future__ import annotations

import importlib
from typing import Any

import gymnasium

ENVS = {
    "handsim/Replay-v0": "handsim.envs.replay_env:ReplayEnv",
    "handsim/Grasp-v0": "handsim.envs.grasp_env:GraspEnv",
}
"""Registered environment ids and their entry points."""
VECTOR_ENVS = {"handsim/Replay-v0": "handsim.envs.replay_vector_env:ReplayVectorEnv"}
"""Native vector environments (``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``)."""


def register_envs() -> None:
    """Register the environments with gymnasium (again after a registry reset; never twice)."""
    for env_id, entry_point in ENVS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=entry_point, vector_entry_point=VECTOR_ENVS.get(env_id))


register_envs()

_LAZY = {
    "ReplayEnv": "handsim.envs.replay_env",
    "ReplayVectorEnv": "handsim.envs.replay_vector_env",
    "GraspEnv": "handsim.envs.grasp_env",
    "RenderError": "handsim.errors",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["ENVS", "VECTOR_ENVS", "GraspEnv", "RenderError", "ReplayEnv", "ReplayVectorEnv", "register_envs"]
