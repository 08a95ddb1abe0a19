"""A readable account of a trajectory: timing, columns, phases, gaps and joint-limit violations.

What ``handsim inspect`` prints; plain data in, lines out (no plotting here, see :mod:`handsim.plotting`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handsim.glove.gaps import find_gaps
from handsim.skeleton import Skeleton
from handsim.trajectory import Trajectory
from handsim.trajectory_ops import LimitReport, limit_violations


@dataclass(frozen=True)
class GapSummary:
    """Invalid samples of one DoF.

    Attributes:
        dof: DoF name.
        samples: Invalid (or non-finite) samples.
        runs: Runs of consecutive invalid samples.
        longest: Longest run, frames.
    """

    dof: str
    samples: int
    runs: int
    longest: int


@dataclass(frozen=True)
class TrajectoryReport:
    """Everything :func:`describe` finds.

    Attributes:
        trajectory: The trajectory described.
        largest_gap_s: Largest interval between consecutive samples, seconds.
        largest_gap_at_s: Time of the sample that starts it, seconds.
        gaps: Per DoF with invalid samples.
        limits: The joint-limit report, when a skeleton was given.
    """

    trajectory: Trajectory
    largest_gap_s: float
    largest_gap_at_s: float
    gaps: tuple[GapSummary, ...]
    limits: LimitReport | None

    def lines(self) -> list[str]:
        """Human-readable lines (times in s, angles in degrees)."""
        t = self.trajectory
        out = [f"file       {t.source or '(not from a file)'}"]
        if t.sha256:
            out.append(f"sha256     {t.sha256}")
        out.append(
            f"frames     {t.nframes} over {t.duration:.3f} s ({t.mean_rate:.1f} Hz mean; largest interval "
            f"{self.largest_gap_s * 1000:.1f} ms at {self.largest_gap_at_s:.3f} s)"
        )
        computed = f"; computed: {', '.join(t.computed)}" if t.computed else ""
        out.append(f"DoFs       {len(t.dof_names)}{computed}")
        if t.channels:
            out.append(f"channels   {', '.join(t.channels)} (recorded, drive no DoF)")
        if t.switch is not None:
            on = float(np.mean(t.switch))
            out.append(f"switch     on in {on * 100:.0f} % of the frames")
        if t.root_pose is not None:
            travel = np.linalg.norm(np.diff(t.root_pose[:, :3], axis=0), axis=1).sum()
            out.append(f"root pose  recorded; the wrist travels {travel * 1000:.0f} mm")
        for name, track in t.objects.items():
            art = "" if track.articulation is None else (
                f", articulation {np.degrees(np.nanmin(track.articulation)):.1f}°.."
                f"{np.degrees(np.nanmax(track.articulation)):.1f}°"
            )  # fmt: skip
            travel = np.linalg.norm(np.diff(track.pose[:, :3], axis=0), axis=1).sum()
            out.append(f"object     {name}: pose track, travels {travel * 1000:.0f} mm{art}")
        for phase in t.phases:
            out.append(
                f"phase      {phase.name:10s} frames {phase.start}–{phase.stop - 1} "
                f"({t.times[phase.start]:.2f}–{t.times[phase.stop - 1]:.2f} s)"
            )
        if not self.gaps:
            out.append("gaps       none: every sample is valid")
        for g in self.gaps:
            out.append(
                f"gaps       {g.dof}: {g.samples} invalid samples in {g.runs} runs (longest {g.longest})"
            )
        if t.filled is not None and t.filled.any():
            out.append(f"filled     {int(t.filled.sum())} samples were filled in")
        if self.limits is not None:
            out.extend(self.limits.lines())
        out.extend(f"note       {n}" for n in t.notes)
        return out


def describe(trajectory: Trajectory, skeleton: Skeleton | None = None) -> TrajectoryReport:
    """Timing, gaps and (with a skeleton) joint-limit violations of a trajectory.

    Args:
        trajectory: The trajectory.
        skeleton: The hand it drives; its DoF limits are checked when given.

    Returns:
        The report.
    """
    dt = np.diff(trajectory.times)
    k = int(np.argmax(dt)) if len(dt) else 0
    invalid = ~np.asarray(trajectory.valid, bool) | ~np.isfinite(trajectory.targets)
    per_dof: dict[int, list[int]] = {}
    for column, start, stop in find_gaps(~invalid):
        per_dof.setdefault(column, []).append(stop - start)
    gaps = tuple(
        GapSummary(trajectory.dof_names[c], sum(runs), len(runs), max(runs))
        for c, runs in sorted(per_dof.items())
    )
    return TrajectoryReport(
        trajectory=trajectory,
        largest_gap_s=float(dt[k]) if len(dt) else 0.0,
        largest_gap_at_s=float(trajectory.times[k]),
        gaps=gaps,
        limits=limit_violations(trajectory, skeleton) if skeleton is not None else None,
    )
