"""Builders: plain data in, :class:`mujoco.MjSpec` out. Builders never compile or write files."""

from handsim.builders.default_hand import default_hand, default_skeleton
from handsim.builders.hand import build_hand

__all__ = ["build_hand", "default_hand", "default_skeleton"]
