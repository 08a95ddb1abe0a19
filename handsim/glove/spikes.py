"""Single-sample spikes in glove recordings: found, marked invalid, filled by the gap filler, reported.

A CyberGlove row now and then holds values no hand can reach in one sample interval: many sensors jump by
1–2 rad and the next row is back where the hand was (often the first or the last row of a recording). Left
in, such a row drives the hand through an impossible motion and the replay reports it as a 90° tracking
"error". A finger joint moves at most :data:`MAX_JOINT_SPEED` (its derivation is in
``docs/cyberglove.md``, "Single-sample spikes").

Rule (per DoF ``x``, times ``t``, speed bound ``v``): an inner sample ``k`` *spikes* in a DoF when it is
reached faster than ``v`` from ``k - 1``, is left faster than ``v`` towards ``k + 1`` in the opposite
direction, and ``k - 1`` and ``k + 1`` are within ``v`` of each other (the motion reverts at the next
sample). The first sample spikes when it is left faster than ``v`` while samples 1 → 2 move slower than
``v``; the last, likewise with the two samples before it. A sample is a **spike** when at least
:data:`MIN_SPIKE_DOFS` DoFs spike there and neither neighbour is also a spike (a single sample, not an
oscillation). A fast movement that does not revert is no spike, however fast.

:func:`remove_spikes` marks a spike sample invalid (``Trajectory.valid``) in every DoF whose value there
differs from a neighbouring sample's, and fills those samples with :func:`handsim.glove.gaps.fill_gaps`
(``linear``: between the neighbours; the first or last sample takes its neighbour's value).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from handsim.datatypes.trajectory import Trajectory
from handsim.glove.gaps import fill_gaps

FASTEST_FINGER_MOVEMENT_S = 0.09
"""Duration of the fastest voluntary finger movements, s: rapid finger–thumb pinches from an open hand
last about 90 ms (Cole & Abbs 1986, "Coordination of three-joint digit movements for rapid finger-thumb
grasp", J Neurophysiol 55(6):1407–1423)."""

BELL_PEAK_TO_MEAN = 1.875
"""Peak over mean speed of a single-peaked, bell-shaped (minimum-jerk) movement (Flash & Hogan 1985,
J Neurosci 5(7):1688–1703); fast finger movements have such profiles (Darling, Cole & Abbs 1988, Exp Brain
Res 73:225–235)."""

FINGER_RANGE_RAD = math.radians(120.0)
"""The largest range of a finger joint, rad: 120° (little-finger DIP of the GraspDB14 default skeleton and
of the parametric hand; PIPs 100–110°)."""

MAX_JOINT_SPEED = BELL_PEAK_TO_MEAN * FINGER_RANGE_RAD / FASTEST_FINGER_MOVEMENT_S
"""Fastest a finger joint angle can change, rad/s (≈ 43.6 rad/s, 2500°/s): a joint's whole range crossed
in the fastest voluntary finger movement, at its bell-shaped peak speed. An upper bound: the pinches behind
it cover a fraction of the range. At the glove's 60 Hz a sample may move at most 0.73 rad."""

MIN_SPIKE_DOFS = 2
"""A spike moves at least this many DoFs beyond :data:`MAX_JOINT_SPEED` ("several sensors"): a glitch of
one glove sample, not of one sensor's reading."""


@dataclass(frozen=True)
class Spike:
    """One single-sample spike.

    Attributes:
        frame: The sample, 0-based.
        time: Its time, s.
        dofs: The DoFs that spike there (jump beyond the speed bound and revert).
        jump: The largest of their jumps from the neighbouring sample, rad.
        speed: The fastest of those jumps, rad/s.
    """

    frame: int
    time: float
    dofs: tuple[str, ...]
    jump: float
    speed: float

    def describe(self) -> str:
        """One line for people."""
        return (
            f"frame {self.frame} ({self.time:.3f} s): {len(self.dofs)} DoFs jump and revert, up to "
            f"{self.jump:.2f} rad at {self.speed:.0f} rad/s ({', '.join(self.dofs)})"
        )


def _spiking(x: np.ndarray, times: np.ndarray, max_speed: float) -> np.ndarray:
    """Per sample and DoF: the sample spikes in that DoF (see the module docstring), (T, ndof) bool."""
    n = x.shape[0]
    out = np.zeros(x.shape, dtype=bool)
    if n < 3:
        return out
    dt = np.diff(times)[:, None]
    step = np.diff(x, axis=0)
    fast = np.abs(step) > max_speed * dt  # (T-1, ndof): the move from sample i to i+1 is too fast
    back = np.abs(x[2:] - x[:-2]) <= max_speed * (dt[1:] + dt[:-1])
    opposite = np.sign(step[:-1]) != np.sign(step[1:])
    out[1:-1] = fast[:-1] & fast[1:] & opposite & back
    out[0] = fast[0] & ~fast[1]
    out[-1] = fast[-1] & ~fast[-2]
    return out


def find_spikes(
    trajectory: Trajectory, *, max_speed: float = MAX_JOINT_SPEED, min_dofs: int = MIN_SPIKE_DOFS
) -> tuple[Spike, ...]:
    """The single-sample spikes of a recording (the rule is in the module docstring).

    Args:
        trajectory: Joint targets, rad; invalid or non-finite samples never spike.
        max_speed: Speed bound, rad/s.
        min_dofs: Fewest DoFs that must spike at a sample.

    Returns:
        The spikes in frame order.

    Raises:
        ValueError: ``max_speed`` is not positive and finite, or ``min_dofs`` is below 1.
    """
    if not (math.isfinite(max_speed) and max_speed > 0):
        raise ValueError(f"max_speed must be a positive number of rad/s, got {max_speed!r}")
    if min_dofs < 1:
        raise ValueError(f"min_dofs must be at least 1, got {min_dofs}")
    x = np.asarray(trajectory.targets, dtype=float)
    times = np.asarray(trajectory.times, dtype=float)
    ok = np.asarray(trajectory.valid, dtype=bool) & np.isfinite(x)
    x = np.where(ok, x, np.nan)  # comparisons with NaN are False: invalid samples never spike
    spiking = _spiking(x, times, max_speed)
    candidate = spiking.sum(axis=1) >= min_dofs
    isolated = candidate.copy()
    isolated[1:] &= ~candidate[:-1]
    isolated[:-1] &= ~candidate[1:]
    spikes = []
    for k in np.flatnonzero(isolated):
        cols = np.flatnonzero(spiking[k])
        near = [j for j in (k - 1, k + 1) if 0 <= j < x.shape[0]]
        jumps = np.array([np.abs(x[k, cols] - x[j, cols]) for j in near])
        speeds = np.array([jumps[i] / abs(times[k] - times[j]) for i, j in enumerate(near)])
        spikes.append(
            Spike(
                frame=int(k),
                time=float(times[k]),
                dofs=tuple(trajectory.dof_names[c] for c in cols),
                jump=float(jumps.max()),
                speed=float(speeds.max()),
            )
        )
    return tuple(spikes)


def remove_spikes(
    trajectory: Trajectory, *, max_speed: float = MAX_JOINT_SPEED, min_dofs: int = MIN_SPIKE_DOFS
) -> tuple[Trajectory, tuple[Spike, ...]]:
    """Find single-sample spikes, mark them invalid and fill them by linear gap filling.

    Args:
        trajectory: Joint targets, rad.
        max_speed: Speed bound, rad/s (:data:`MAX_JOINT_SPEED`).
        min_dofs: Fewest DoFs that must spike at a sample (:data:`MIN_SPIKE_DOFS`).

    Returns:
        The trajectory (unchanged when there is no spike; else with the spike samples filled,
        ``filled`` set there, a note listing the spikes and the gap filler's note) and the spikes. The gap
        filler fills every invalid sample, so give a recording as read (a glove reader marks every sample
        valid) for only the spikes to be filled.

    Raises:
        ValueError: As :func:`find_spikes`.
    """
    spikes = find_spikes(trajectory, max_speed=max_speed, min_dofs=min_dofs)
    if not spikes:
        return trajectory, spikes
    x = np.asarray(trajectory.targets, dtype=float)
    valid = np.array(trajectory.valid, dtype=bool)
    n = x.shape[0]
    for spike in spikes:
        k = spike.frame
        near = [j for j in (k - 1, k + 1) if 0 <= j < n]
        differs = np.any([x[k] != x[j] for j in near], axis=0)
        valid[k] &= ~differs
    listed = "; ".join(s.describe() for s in spikes)
    note = (
        f"{len(spikes)} single-sample spike{'s' if len(spikes) != 1 else ''} (DoFs jumping faster than "
        f"{max_speed:.1f} rad/s and back at the next sample, docs/cyberglove.md) marked invalid and filled: "
        f"{listed}"
    )
    marked = dataclasses.replace(trajectory, valid=valid, notes=(*trajectory.notes, note))
    return fill_gaps(marked, "linear"), spikes


__all__ = [
    "BELL_PEAK_TO_MEAN",
    "FASTEST_FINGER_MOVEMENT_S",
    "FINGER_RANGE_RAD",
    "MAX_JOINT_SPEED",
    "MIN_SPIKE_DOFS",
    "Spike",
    "find_spikes",
    "remove_spikes",
]
