"""A readable account of a trajectory: timing, columns, phases, gaps and joint-limit violations.

What ``handsim inspect`` prints; plain data in, lines out (no plotting here, see :mod:`handsim.viz.plotting`).
An ARCTIC sequence (two MANO hands and an object, no joint angles until the MANO models convert them) has its
own account, :func:`describe_arctic`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import Trajectory
from handsim.datatypes.trajectory_ops import LimitReport, limit_violations
from handsim.glove.gaps import find_gaps
from handsim.io.arctic.sequence import ArcticSequence

if TYPE_CHECKING:
    from handsim.trials.arctic_hands import SideCheck


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


def _travel_and_speed(positions: np.ndarray, fps: float) -> tuple[float, float, int]:
    """Path length (m), largest speed between frames (m/s) and the frame it ends at."""
    if len(positions) < 2:
        return 0.0, 0.0, 0
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    k = int(np.argmax(steps))
    return float(steps.sum()), float(steps[k] * fps), k + 1


@dataclass(frozen=True)
class ArcticReport:
    """What ``handsim inspect`` shows of an ARCTIC sequence (see :func:`describe_arctic`).

    Attributes:
        sequence: The sequence described.
        sides: Whether ``right`` and ``left`` hold those hands: the side check's verdict
            (:func:`handsim.trials.arctic_hands.hand_side_check`), or why it was not run.
    """

    sequence: ArcticSequence
    sides: SideCheck | str = "not checked"

    def lines(self) -> list[str]:
        """Human-readable lines (lengths in mm, speeds in m/s, angles in degrees and radians)."""
        s = self.sequence
        out = [
            f"file       {s.mano_path} (ARCTIC sequence {s.name}, subject {s.subject or '?'})",
            f"sha256     {s.right.sha256}",
            f"frames     {s.nframes} over {(s.nframes - 1) / s.fps:.3f} s ({s.fps:g} fps)",
        ]
        for hand in (s.right, s.left):
            travel, speed, frame = _travel_and_speed(hand.trans, s.fps)
            out.append(
                f"{hand.side + ' hand':10s} wrist travels {travel * 1000:.0f} mm (fastest {speed:.2f} m/s at "
                f"frame {frame}); shape β {np.array2string(hand.shape[:3], precision=3)}…"
            )
            if hand.fitting_err is None:
                out.append(f"{'':10s} fitting error: not in the file")
            else:
                err = hand.fitting_err
                k = int(np.argmax(err))
                out.append(
                    f"{'':10s} fitting error (as stored, ARCTIC gives no unit): mean {np.mean(err):.4g}, "
                    f"median {np.median(err):.4g}, max {err[k]:.4g} at frame {k}"
                )
        track = s.object
        travel, speed, frame = _travel_and_speed(track.pose[:, :3], s.fps)
        lo, hi = s.articulation_range
        out.append(
            f"object     {s.object_name} ({Path(s.object_path).name}): travels {travel * 1000:.0f} mm "
            f"(fastest {speed:.2f} m/s at frame {frame}); at frame 0 its origin is {track.pose[0, 2]:.3f} m "
            "up (z-up world)"
        )
        out.append(
            f"articul.   {np.degrees(lo):.1f}°..{np.degrees(hi):.1f}° ({lo:.3f}..{hi:.3f} rad) about the "
            "object's (0, 0, −1) axis"
        )
        out.append(f"sha256     {s.object_sha256} (object)")
        notes = (*s.notes, *s.right.notes, *s.left.notes)
        out.extend(f"note       {n}" for n in notes)
        if isinstance(self.sides, str):
            out.append(f"sides      {self.sides}")
        elif self.sides.flags:  # as the replay reports it
            out.extend(f"flag       {flag.line()}" for flag in self.sides.flags)
        else:
            out.append(f"sides      {self.sides.message}")
        return out


def describe_arctic(sequence: ArcticSequence, sides: SideCheck | str = "not checked") -> ArcticReport:
    """Frames, both hands (wrist travel, fitting error), the object and its articulation range, the sides.

    Args:
        sequence: The sequence (:func:`handsim.io.arctic.sequence.read_arctic_sequence`).
        sides: The side check's verdict (:func:`handsim.trials.arctic.sequence_side_check`: a swapped one is
            shown as the replay's ``hands_swapped`` flag), or why it was not run.

    Returns:
        The report.
    """
    return ArcticReport(sequence, sides)
