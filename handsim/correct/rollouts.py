"""The rollout backends by name: ``handsim correct --rollouts cpu|warp``.

``cpu`` is :class:`~handsim.correct.backend.CpuRollout` (``mujoco.rollout`` on CPU threads, bitwise
deterministic); ``warp`` is :class:`~handsim.correct.warp_backend.WarpRollout` (MuJoCo Warp, an optional
dependency: ``handsim[warp]``), imported only when asked for.
"""

from __future__ import annotations

from handsim.correct.backend import CpuRollout, RolloutBackend
from handsim.correct.config import CorrectionError


def _warp_rollout(threads: int | None = None) -> RolloutBackend:
    """MuJoCo Warp's backend (:mod:`handsim.correct.warp_backend`), imported only when asked for."""
    from handsim.correct.warp_backend import WarpRollout  # lazy: an optional dependency

    return WarpRollout(threads)


BACKENDS = {"cpu": CpuRollout, "warp": _warp_rollout}
"""Rollout backends by name (module docstring)."""


def rollout_backend(name: str = "cpu", threads: int | None = None) -> RolloutBackend:
    """The backend called ``name``.

    Raises:
        CorrectionError: No backend has that name (the message lists them).
    """
    if name not in BACKENDS:
        raise CorrectionError(f"unknown rollout backend {name!r}; backends are {sorted(BACKENDS)}")
    return BACKENDS[name](threads)
