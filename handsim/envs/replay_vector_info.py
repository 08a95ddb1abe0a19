"""The ``info`` of :class:`~handsim.envs.replay_vector_env.ReplayVectorEnv`: gymnasium's dict of arrays.

A vector environment's ``info`` holds, per key, one array over the worlds and a boolean mask ``_key``
saying which worlds the key holds a value for (as :class:`gymnasium.vector.SyncVectorEnv` merges the
single environments' dicts). These functions build and change such dicts; the numbers themselves come
from the single environment's task, so each world's values are those a :class:`ReplayEnv
<handsim.envs.replay_env.ReplayEnv>` would give.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from handsim.envs.replay_reward import STEP_NUMBERS
from handsim.sim.stepper import WarningEvent


def reset_info(frames: np.ndarray, times: np.ndarray, numbers: np.ndarray) -> dict[str, Any]:
    """The ``info`` of a reset of every world.

    Args:
        frames: Each world's start frame.
        times: Each frame's time, s (the schedule's).
        numbers: Each world's reset values of :data:`~handsim.envs.replay_reward.STEP_NUMBERS` (worlds,
            numbers).
    """
    n = frames.size
    everyone = np.ones(n, bool)
    infos: dict[str, Any] = {
        "frame": frames,
        "_frame": everyone,
        "time": times[frames],
        "_time": everyone.copy(),
        "recording": np.zeros(n, np.int64),  # one recording (several are refused)
        "_recording": everyone.copy(),
    }
    for key, column in zip(STEP_NUMBERS, numbers.T, strict=True):
        infos[key], infos[f"_{key}"] = column.copy(), everyone.copy()
    return infos


def put_step_numbers(
    infos: dict[str, Any],
    columns: np.ndarray,
    mask: np.ndarray,
    diverged: np.ndarray,
    clipped: np.ndarray,
    warnings: dict[int, tuple[WarningEvent, ...]],
) -> None:
    """Put the stepped worlds' numbers, divergence, clipped actions and warnings in ``infos``.

    Args:
        infos: The step's info, changed in place.
        columns: The reward, then each of :data:`~handsim.envs.replay_reward.STEP_NUMBERS`, per world.
        mask: The worlds that stepped.
        diverged: Whether each world diverged.
        clipped: How many action elements of each world were clipped.
        warnings: The worlds with MuJoCo warnings, and those warnings.
    """
    for key, column in zip(STEP_NUMBERS, columns[1:], strict=True):
        infos[key], infos[f"_{key}"] = column, mask
    infos["diverged"], infos["_diverged"] = diverged, mask
    infos["action_clipped"], infos["_action_clipped"] = clipped, mask
    if warnings:
        described = np.full(mask.size, None, dtype=object)
        for i, events in warnings.items():
            described[i] = tuple(e.describe() for e in events)
        infos["warnings"] = described
        infos["_warnings"] = np.array([w is not None for w in described])


def put_reset_numbers(infos: dict[str, Any], reset_numbers: dict[int, tuple[float, ...]], n: int) -> None:
    """Give each reset world's info the reset's :data:`~handsim.envs.replay_reward.STEP_NUMBERS`.

    As :class:`~gymnasium.vector.SyncVectorEnv` gives them.

    Args:
        infos: The step's info, changed in place (a missing key is added, masked to the reset worlds).
        reset_numbers: World → the numbers its reset returned.
        n: Number of worlds.
    """
    for column, key in enumerate(STEP_NUMBERS):
        if key not in infos:
            infos[key], infos[f"_{key}"] = np.zeros(n), np.zeros(n, bool)
        values, mask = infos[key], infos[f"_{key}"].copy()
        for i, numbers in reset_numbers.items():
            values[i], mask[i] = numbers[column], True
        infos[f"_{key}"] = mask


def final_info(infos: dict[str, Any], ended: np.ndarray) -> dict[str, Any]:
    """The ended worlds' part of a step's info (``info["final_info"]`` of a same-step autoreset).

    Args:
        infos: The step's info.
        ended: The worlds that ended.

    Returns:
        Each key with a value for an ended world, its other worlds' values blanked (0 or None) and masked.
    """
    final: dict[str, Any] = {}
    for key, value in infos.items():
        if key.startswith("_"):
            continue
        mask = infos[f"_{key}"] & ended
        if not mask.any():
            continue
        column = np.array(value, copy=True)
        column[~mask] = None if column.dtype == object else 0
        final[key], final[f"_{key}"] = column, mask
    return final
