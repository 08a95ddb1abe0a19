"""A trajectory's targets against a skeleton's joint limits: the report, the note, explicit clamping.

Recorded glove angles often lie outside a skeleton's anatomical limits (``docs/conventions.md``).
:func:`limit_violations` counts them per DoF; :func:`with_limit_note` adds that count to the trajectory's
notes; :func:`clamp_to_limits` clamps them, but only when called: nothing in handsim clamps a trajectory
implicitly (MuJoCo clamps targets to ``ctrlrange``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import TrajectoryError


@dataclass(frozen=True)
class DofLimitViolation:
    """How one DoF's valid samples compare with its skeleton limits.

    Attributes:
        name: DoF name.
        lower: Lower limit, rad.
        upper: Upper limit, rad.
        below: Number of valid samples below ``lower``.
        above: Number of valid samples above ``upper``.
        worst_below: Largest ``lower - target`` over the samples below, rad (0 when none).
        worst_above: Largest ``target - upper`` over the samples above, rad (0 when none).
        first_frame: First frame with a valid sample outside the limits, or None.
    """

    name: str
    lower: float
    upper: float
    below: int
    above: int
    worst_below: float
    worst_above: float
    first_frame: int | None

    @property
    def count(self) -> int:
        """Valid samples outside the limits (below + above)."""
        return self.below + self.above

    @property
    def worst(self) -> float:
        """Largest excess beyond either limit, rad (0 when none)."""
        return max(self.worst_below, self.worst_above)

    @property
    def worst_deg(self) -> float:
        """Largest excess beyond either limit, degrees."""
        return math.degrees(self.worst)

    def describe(self) -> str:
        """``"282 below by up to 27.62°"``-style summary of the violations (empty when none)."""
        parts = []
        if self.below:
            parts.append(f"{self.below} below by up to {math.degrees(self.worst_below):.2f}°")
        if self.above:
            parts.append(f"{self.above} above by up to {math.degrees(self.worst_above):.2f}°")
        return ", ".join(parts)


@dataclass(frozen=True)
class LimitReport:
    """Valid samples of a trajectory outside a skeleton's DoF limits.

    Attributes:
        dofs: One entry per DoF of the trajectory, in column order (also the DoFs without violations).
        nframes: Frames of the trajectory.
        checked: Valid, finite samples that were compared with the limits (over all DoFs).
        skeleton: Name of the skeleton whose limits were used.
        source: The trajectory's source file ("" when none).
    """

    dofs: tuple[DofLimitViolation, ...]
    nframes: int
    checked: int
    skeleton: str = ""
    source: str = ""

    @property
    def below(self) -> int:
        """Valid samples below their lower limit, all DoFs."""
        return sum(d.below for d in self.dofs)

    @property
    def above(self) -> int:
        """Valid samples above their upper limit, all DoFs."""
        return sum(d.above for d in self.dofs)

    @property
    def total(self) -> int:
        """Valid samples outside their limits, all DoFs."""
        return self.below + self.above

    @property
    def violating(self) -> tuple[DofLimitViolation, ...]:
        """The entries of the DoFs with at least one sample outside the limits."""
        return tuple(d for d in self.dofs if d.count)

    def dof(self, name: str) -> DofLimitViolation:
        """The entry of DoF ``name``.

        Raises:
            TrajectoryError: If the report has no such DoF; the message lists the DoFs it has.
        """
        for d in self.dofs:
            if d.name == name:
                return d
        raise TrajectoryError(f"no DoF {name!r} in the limit report; DoFs are {[d.name for d in self.dofs]}")

    def lines(self) -> list[str]:
        """Human-readable lines for a command-line report (angles in degrees)."""
        what = f"{self.source} against skeleton {self.skeleton!r}" if self.source else f"{self.skeleton!r}"
        if not self.total:
            return [
                f"limit check of {what}: all {self.checked} valid samples of {len(self.dofs)} DoFs are "
                "within the limits"
            ]
        lines = [
            f"limit check of {what}: {self.total} of {self.checked} valid samples outside the limits "
            f"({self.below} below, {self.above} above) in {len(self.violating)} of {len(self.dofs)} DoFs"
        ]
        width = max(len(d.name) for d in self.violating)
        for d in self.violating:
            lines.append(
                f"  {d.name:<{width}}  {d.below:5d} below {math.degrees(d.lower):7.2f}°"
                f"  {d.above:5d} above {math.degrees(d.upper):7.2f}°"
                f"  worst {d.worst_deg:6.2f}° outside  first frame {d.first_frame}"
            )
        return lines


def _limits_for(trajectory: Trajectory, skeleton: Skeleton) -> np.ndarray:
    """Limits (rad) of the trajectory's columns, shape (ndof, 2), looked up by name."""
    missing = [n for n in trajectory.dof_names if n not in skeleton.dof_names]
    if missing:
        raise TrajectoryError(
            f"trajectory DoFs {missing} are not in skeleton {skeleton.name!r}; "
            f"its DoFs are {list(skeleton.dof_names)}"
        )
    return skeleton.limits[[skeleton.dof_index(n) for n in trajectory.dof_names]].reshape(-1, 2)


def _outside(trajectory: Trajectory, limits: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Masks of the valid, finite samples below / above the limits, and of the valid, finite samples."""
    x = np.asarray(trajectory.targets, dtype=float)
    known = np.asarray(trajectory.valid, dtype=bool) & np.isfinite(x)
    return known & (x < limits[:, 0]), known & (x > limits[:, 1]), known


def limit_violations(trajectory: Trajectory, skeleton: Skeleton) -> LimitReport:
    """Count the valid samples of every DoF that lie outside the skeleton's limits.

    A sample exactly at a limit is inside. Invalid and non-finite samples are not checked.

    Args:
        trajectory: The trajectory (targets in rad).
        skeleton: The hand whose DoF limits apply; its DoFs are matched by name, and those the
            trajectory lacks are ignored.

    Returns:
        The report: per DoF the counts below and above, the worst excess (rad) and the first frame.

    Raises:
        TrajectoryError: The trajectory has DoFs the skeleton lacks (the message lists them and the
            skeleton's DoFs).
    """
    limits = _limits_for(trajectory, skeleton)
    low, high, known = _outside(trajectory, limits)
    x = np.asarray(trajectory.targets, dtype=float)
    excess_low = np.where(low, limits[:, 0] - x, 0.0).max(axis=0, initial=0.0)
    excess_high = np.where(high, x - limits[:, 1], 0.0).max(axis=0, initial=0.0)
    either = low | high
    entries = []
    for c, name in enumerate(trajectory.dof_names):
        first = int(np.argmax(either[:, c])) if either[:, c].any() else None
        entries.append(
            DofLimitViolation(
                name=name,
                lower=float(limits[c, 0]),
                upper=float(limits[c, 1]),
                below=int(low[:, c].sum()),
                above=int(high[:, c].sum()),
                worst_below=float(excess_low[c]),
                worst_above=float(excess_high[c]),
                first_frame=first,
            )
        )
    return LimitReport(
        dofs=tuple(entries),
        nframes=trajectory.nframes,
        checked=int(known.sum()),
        skeleton=skeleton.name,
        source=trajectory.source,
    )


def with_limit_note(trajectory: Trajectory, skeleton: Skeleton, what: str = "targets") -> Trajectory:
    """The trajectory with a note counting, per DoF, its valid samples outside the skeleton's limits.

    What every reader that maps a recording onto a skeleton adds (glove recordings, Tzionas motions): the
    position actuators clamp such targets to the joint range, so the user must be told how many and how
    far (:func:`limit_violations`).

    Args:
        trajectory: The trajectory (targets in rad).
        skeleton: The hand whose DoF limits apply (DoFs matched by name).
        what: What the samples are, for the note, e.g. ``"fitted angles"``.

    Returns:
        The trajectory with one note appended.
    """
    report = limit_violations(trajectory, skeleton)
    if not report.total:
        note = f"every valid sample of the {what} lies within its DoF limits"
    else:
        parts = [
            f"{d.name} {d.count}/{report.nframes} (up to {d.worst_deg:.1f}° beyond)" for d in report.violating
        ]
        note = (
            f"{what} outside the DoF limits of {skeleton.name!r} in {report.total} samples (position "
            f"actuators clamp them to the joint range): {', '.join(parts)}"
        )
    return replace(trajectory, notes=(*trajectory.notes, note))


def clamp_to_limits(trajectory: Trajectory, skeleton: Skeleton) -> Trajectory:
    """Clamp the valid samples outside the skeleton's limits to the nearest limit.

    Never called implicitly by handsim: the recorded angles are data (``docs/conventions.md``). Invalid
    and non-finite samples are left as they are; ``valid`` and ``filled`` do not change.

    Args:
        trajectory: The trajectory (targets in rad).
        skeleton: The hand whose DoF limits apply (DoFs matched by name).

    Returns:
        A copy with clamped targets and a note with the counts, e.g. ``"clamped 123 samples of 4 DoFs to
        the skeleton limits: if_mcp_flex (54 below by up to 16.67°), …"``.

    Raises:
        TrajectoryError: The trajectory has DoFs the skeleton lacks (the message lists them).
    """
    report = limit_violations(trajectory, skeleton)
    limits = _limits_for(trajectory, skeleton)
    low, high, _ = _outside(trajectory, limits)
    x = np.array(trajectory.targets, dtype=float)
    x = np.where(low, limits[:, 0], np.where(high, limits[:, 1], x))
    if report.total:
        per_dof = ", ".join(f"{d.name} ({d.describe()})" for d in report.violating)
        note = (
            f"clamped {report.total} samples of {len(report.violating)} DoFs to the limits of skeleton "
            f"{skeleton.name!r}: {per_dof}"
        )
    else:
        note = f"clamped 0 samples: every valid target is within the limits of skeleton {skeleton.name!r}"
    return replace(trajectory, targets=x, notes=(*trajectory.notes, note))
