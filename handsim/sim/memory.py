"""How much memory a replay takes, and the refusal of a recording too long for this machine.

A replay keeps the simulated state and every sensor value at each control frame (``qpos`` and
``sensordata``, 8-byte floats: :func:`handsim.sim.replay.run_schedule`), because the metrics, the hold
verdict and the plots read them after the run. Its memory therefore grows linearly with the recording:
``frames × (nq + nsensordata) × 8`` bytes for those buffers, times :data:`PEAK_FACTOR` for what the metrics
derive from them. At the default 100 Hz control rate that is about 7 kB per control frame for a glove or
Tzionas hand with one object (34–45 ``qpos`` and 671 sensor values), about 2.7 GB per recorded hour.

Before a replay allocates anything, :func:`check_replay_memory` compares this estimate with a limit: half
of this machine's physical memory, or ``$HANDSIM_MAX_REPLAY_GB`` where set. A recording over it is refused
with the estimate, the limit and what to do (replay a grasp episode, or a lower control rate), instead of
being killed by the operating system part-way through.
"""

from __future__ import annotations

import math
import os

import mujoco

from handsim.errors import TrajectoryError

PEAK_FACTOR = 1.5
"""Peak replay memory over the per-frame buffers: measured 1.29 (a 19,753-frame glove session) and 1.35
(Tzionas sequence 20, 618 frames) with ``tracemalloc``, rounded up for the Python objects it does not see."""

LIMIT_VARIABLE = "HANDSIM_MAX_REPLAY_GB"
"""Environment variable: the most memory, in GB (10⁹ bytes), a replay may need."""


class RecordingTooLongError(TrajectoryError):
    """A recording whose replay would need more memory than the limit (:func:`check_replay_memory`)."""


def replay_memory_bytes(model: mujoco.MjModel, frames: int) -> int:
    """Estimated peak memory of a replay of ``frames`` control frames on ``model``, bytes."""
    return math.ceil(frames * (model.nq + model.nsensordata) * 8 * PEAK_FACTOR)


def replay_memory_limit() -> tuple[int, str]:
    """The most bytes a replay may need, and where that limit comes from (for messages).

    Raises:
        TrajectoryError: ``$HANDSIM_MAX_REPLAY_GB`` is set but is not a positive number.
    """
    text = os.environ.get(LIMIT_VARIABLE, "").strip()
    if text:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise TrajectoryError(f"${LIMIT_VARIABLE}={text!r}: expected a positive number of GB")
        return int(value * 1e9), f"${LIMIT_VARIABLE}"
    physical = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    return physical // 2, f"half of this machine's {physical / 1e9:.1f} GB; ${LIMIT_VARIABLE} sets another"


def _size(count: int) -> str:
    """Bytes for people: GB from 1 GB up, else MB."""
    return f"{count / 1e9:.1f} GB" if count >= 1e9 else f"{count / 1e6:.1f} MB"


def check_replay_memory(model: mujoco.MjModel, frames: int, control_rate: float, source: str = "") -> None:
    """Refuse a replay whose estimated memory (:func:`replay_memory_bytes`) is over the limit.

    Args:
        model: The scene's model.
        frames: Control frames the replay would simulate.
        control_rate: Its control rate, Hz (named in the message).
        source: The recording's file, named in the message ("" for none).

    Raises:
        RecordingTooLongError: The estimate is over :func:`replay_memory_limit`.
    """
    need = replay_memory_bytes(model, frames)
    limit, origin = replay_memory_limit()
    if need <= limit:
        return
    where = f"{source}: " if source else ""
    raise RecordingTooLongError(
        f"{where}replaying {frames:,} control frames ({frames / control_rate:,.0f} s at {control_rate:g} Hz) "
        f"would need about {_size(need)} of memory ({model.nq} state and {model.nsensordata} sensor "
        f"values per frame, kept for the metrics), over the limit of {_size(limit)} ({origin}); "
        "replay one grasp episode (--grasp K) or a part of the recording, or at a lower --rate"
    )
