"""MuJoCo warning counters.

MuJoCo does not raise when a simulation goes wrong: it counts the event in ``data.warning`` (and, for a
diverged state, resets it). Every stepping loop in handsim checks these counters.
"""

from __future__ import annotations

import mujoco

from handsim.errors import SimulationError

WARNING_NAMES: tuple[str, ...] = tuple(
    mujoco.mjtWarning(i).name for i in range(int(mujoco.mjtWarning.mjNWARNING))
)


def warning_counts(data: mujoco.MjData) -> dict[str, int]:
    """Non-zero warning counters of ``data``, by MuJoCo warning name (e.g. ``mjWARN_BADQACC``)."""
    return {
        name: int(data.warning[i].number) for i, name in enumerate(WARNING_NAMES) if data.warning[i].number
    }


def raise_on_warnings(data: mujoco.MjData, context: str) -> None:
    """Raise :class:`SimulationError` naming the warnings if any counter is non-zero.

    Args:
        data: The simulation data.
        context: What was being simulated, for the message.
    """
    counts = warning_counts(data)
    if counts:
        detail = ", ".join(f"{k} ×{v}" for k, v in counts.items())
        raise SimulationError(f"{context}: MuJoCo warnings at t={data.time:.4f} s: {detail}")
