"""Plausibility gates: inputs that cannot give a meaningful physical answer are refused or flagged.

A replay always returns its numbers; these gates say when the numbers mean nothing, so that a user never
reads "held" or "warnings none" off a trial that could not have been judged.

* :func:`check_control_rate` refuses a control rate too low for the metrics: a control frame must be at
  most half the shortest time the metrics judge (:func:`min_control_rate`).
* :func:`replay_flags` flags a replay (:class:`~handsim.datatypes.flags.Flag`): the recording's own flags
  (:attr:`Trajectory.flags`, e.g. ARCTIC hands that look swapped), too few frames, the hand starting inside
  the object, a recorded track jumping faster than anything a hand moves, targets beyond the joint limits.
  (A hold window too short to judge holding is the hold judgement's own "not judged":
  :func:`handsim.sim.summary.hold_outcome`.) A flag with ``invalid`` set makes the replay *not valid*
  (``summary["valid"]`` false): its numbers are reported but excluded from a dataset's rates; the
  joint-limit flag is a note (the actuators clamp such targets to the limits).

Thresholds are in :class:`PlausibilitySpec` (sources in ``docs/replay.md``, "Plausibility flags").
"""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass

import numpy as np

from handsim.datatypes.flags import Flag
from handsim.datatypes.trajectory import Trajectory
from handsim.sim.control import ControlSchedule
from handsim.sim.drive import ScenarioSwitches
from handsim.sim.metrics import FrameMetrics
from handsim.sim.scene.compiled import SimScene
from handsim.sim.scene.layout import SceneLayout
from handsim.sim.specs import MetricSpec

FLAG_FRAMES_LISTED = 10
"""Most frame indices a flag lists (the count is always given)."""


def shortest_judged_time(spec: MetricSpec) -> float:
    """The shortest time the metrics judge, s: the contact gap, or the release delay when shorter (and > 0).

    The glove scenario's contact gap (``spec.contact_gap``: an object untouched this long is lost) and
    release delay (``spec.release_delay``: the grip acts this long before the support goes off; 0 = at
    once, which times nothing).
    """
    times = [spec.contact_gap] + ([spec.release_delay] if spec.release_delay > 0 else [])
    return min(times)


def min_control_rate(spec: MetricSpec) -> float:
    """The lowest control rate the metrics can be judged at, Hz.

    Two control frames within :func:`shortest_judged_time`. At the defaults (0.1 s contact gap and release
    delay) that is 20 Hz; the recordings handsim reads are sampled at 30 Hz (Tzionas, ARCTIC) to 60 Hz
    (GraspDB14), and the default control rate is 100 Hz.

    Args:
        spec: The metric parameters.

    Returns:
        The minimum control rate, Hz.
    """
    return 2.0 / shortest_judged_time(spec)


def check_control_rate(rate_hz: float, spec: MetricSpec) -> float:
    """A control rate as a float, refused when it is not a number or below :func:`min_control_rate`.

    Args:
        rate_hz: The requested control rate, Hz.
        spec: The metric parameters it must resolve.

    Returns:
        The rate, Hz.

    Raises:
        ValueError: The rate is not a finite number, or is below the minimum; the message says why.
    """
    minimum = min_control_rate(spec)
    shortest = shortest_judged_time(spec)
    number = isinstance(rate_hz, numbers.Real) and not isinstance(rate_hz, bool)
    rate = float(rate_hz) if number else math.nan
    if not (math.isfinite(rate) and rate >= minimum):
        got = f"{rate:g}" if number else repr(rate_hz)
        raise ValueError(
            f"expected a control rate of at least {minimum:g} Hz (two control frames within the "
            f"{shortest:g} s contact gap and release delay the metrics judge), got {got}"
        )
    return rate


@dataclass(frozen=True)
class PlausibilitySpec:
    """Thresholds of the plausibility flags (sources and measurements in ``docs/replay.md``).

    Attributes:
        max_initial_penetration: Deepest hand–object penetration allowed when hand–object contacts start
            acting (frame 0 of a recorded replay; the contact frame of a glove replay), m. 5 mm: more than
            a fingertip pad compresses when grasping (a few mm) and 2.5× the glove placement's 2 mm
            (``MetricSpec.placement_penetration``); deeper, the solver's push-out decides what happens next.
        max_track_speed: Fastest a recorded track (an object, the hand root) may move between two valid
            samples, m/s. 10 m/s: about 50× the fastest track of the Tzionas sample (0.19 m/s) and 10× the
            ~1 m/s peak wrist speed of reach-to-grasp movements; a faster jump is a tracking error.
    """

    max_initial_penetration: float = 0.005
    max_track_speed: float = 10.0

    def to_dict(self) -> dict:
        """JSON-ready thresholds."""
        return asdict(self)


def limit_violations(trajectory: Trajectory, layout: SceneLayout) -> dict[str, tuple[int, float]]:
    """Valid target samples beyond the joint limits, per hand DoF the trajectory drives.

    Args:
        trajectory: Joint targets (radians), by DoF name.
        layout: The scene's hand: DoF names and their ranges (the actuators' ``ctrlrange``).

    Returns:
        DoF name → (samples outside the range, largest excess in radians), for DoFs with a violation, in
        the hand's DoF order.
    """
    column = {name: c for c, name in enumerate(trajectory.dof_names)}
    targets = np.asarray(trajectory.targets, dtype=float)
    valid = np.asarray(trajectory.valid, dtype=bool)
    found: dict[str, tuple[int, float]] = {}
    for name, (low, high) in zip(layout.dof_names, layout.ctrl_range, strict=True):
        c = column.get(name)
        if c is None:
            continue
        x = targets[:, c]
        checked = valid[:, c] & np.isfinite(x)
        excess = np.where(checked, np.maximum(low - x, x - high), 0.0)
        outside = int((excess > 0.0).sum())
        if outside:
            found[name] = (outside, float(excess.max()))
    return found


def track_jumps(times: np.ndarray, positions: np.ndarray, valid: np.ndarray | None, max_speed: float):
    """Samples reached faster than ``max_speed`` from the previous valid sample.

    Args:
        times: Sample times, s (T,).
        positions: Positions, m (T, 3).
        valid: Usable samples (T,), or None for all.
        max_speed: Threshold, m/s.

    Returns:
        The indices of the samples reached too fast (ascending) and the fastest speed between valid
        samples, m/s (0 with fewer than two).
    """
    t = np.asarray(times, dtype=float)
    p = np.asarray(positions, dtype=float)
    ok = np.all(np.isfinite(p), axis=1)
    if valid is not None:
        ok &= np.asarray(valid, dtype=bool)
    index = np.flatnonzero(ok)
    if index.size < 2:
        return np.zeros(0, dtype=np.int64), 0.0
    speed = np.linalg.norm(np.diff(p[index], axis=0), axis=1) / np.diff(t[index])
    return index[1:][speed > max_speed], float(speed.max())


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _frames_text(frames: np.ndarray) -> str:
    listed = ", ".join(str(int(f)) for f in frames[:FLAG_FRAMES_LISTED])
    more = f" and {frames.size - FLAG_FRAMES_LISTED} more" if frames.size > FLAG_FRAMES_LISTED else ""
    return listed + more


def _jump_flags(trajectory: Trajectory, limits: PlausibilitySpec) -> list[Flag]:
    tracks = [("hand root", trajectory.root_pose, None)] if trajectory.root_pose is not None else []
    tracks += [(f"{name} hand root", pose, None) for name, pose in trajectory.hand_roots.items()]
    tracks += [(f"object {name!r}", t.pose, t.valid) for name, t in trajectory.objects.items()]
    flags = []
    for name, pose, valid in tracks:
        frames, fastest = track_jumps(
            trajectory.times, np.asarray(pose)[:, :3], valid, limits.max_track_speed
        )
        if frames.size:
            flags.append(
                Flag(
                    "track_jump",
                    True,
                    f"the recorded {name} track jumps faster than {limits.max_track_speed:g} m/s into "
                    f"{frames.size} of {trajectory.nframes} samples (up to {fastest:.3g} m/s; samples "
                    f"{_frames_text(frames)})",
                    {
                        "track": name,
                        "samples": frames[:FLAG_FRAMES_LISTED].tolist(),
                        "count": int(frames.size),
                        "max_speed_m_s": fastest,
                        "threshold_m_s": limits.max_track_speed,
                    },
                )
            )
    return flags


def _limit_flag(trajectory: Trajectory, layout: SceneLayout) -> Flag | None:
    found = limit_violations(trajectory, layout)
    if not found:
        return None
    total = sum(n for n, _ in found.values())
    worst = sorted(found.items(), key=lambda item: (-item[1][0], item[0]))
    listed = ", ".join(f"{name} {n} (up to {math.degrees(e):.1f}°)" for name, (n, e) in worst[:5])
    more = f" and {len(worst) - 5} more DoFs" if len(worst) > 5 else ""
    return Flag(
        "joint_limits",
        False,
        f"{total} target samples beyond the joint limits in {len(found)} of {len(layout.dof_names)} DoFs "
        f"(the actuators clamp them to the limits): {listed}{more}",
        {
            "samples": total,
            "dofs": {
                name: {"samples": n, "max_excess_deg": math.degrees(e)} for name, (n, e) in found.items()
            },
        },
    )


def replay_flags(
    scene: SimScene,
    trajectory: Trajectory,
    schedule: ControlSchedule,
    switches: ScenarioSwitches,
    frames: FrameMetrics,
    limits: PlausibilitySpec | None = None,
) -> tuple[Flag, ...]:
    """The plausibility flags of a replay, from its inputs and per-frame metrics.

    Args:
        scene: The replayed scene.
        trajectory: The trajectory as given to the replay (before resampling).
        schedule: Its control frames.
        switches: When contacts started acting.
        frames: The per-frame metrics of the frames simulated.
        limits: Thresholds (default :class:`PlausibilitySpec`).

    Returns:
        The flags, the recording's own first, then the invalidating ones, in a fixed order.
    """
    limits = limits or PlausibilitySpec()
    flags: list[Flag] = list(trajectory.flags)  # the recording's own (e.g. ARCTIC hands that look swapped)
    if schedule.frames < 2:
        flags.append(
            Flag(
                "too_few_frames",
                True,
                f"{schedule.frames} control frame from {_count(trajectory.nframes, 'sample')} over "
                f"{trajectory.duration * 1000:.3g} ms: nothing was simulated (a replay needs 2 frames, "
                f"{schedule.frame_dt * 1000:g} ms apart at this rate)",
                {"frames": schedule.frames, "samples": trajectory.nframes, "duration_s": trajectory.duration},
            )
        )
    start = switches.contact_frame
    if scene.layout.objects and start < frames.penetration.shape[0]:
        depth = float(frames.penetration[start])
        if depth > limits.max_initial_penetration:
            when = "at the start" if start == 0 else f"when contacts start acting (frame {start})"
            flags.append(
                Flag(
                    "initial_penetration",
                    True,
                    f"the hand is {depth * 1000:.1f} mm inside the object {when}, more than "
                    f"{limits.max_initial_penetration * 1000:g} mm: the solver pushes them apart, and what "
                    "follows is not the recording's",
                    {
                        "depth_mm": depth * 1000.0,
                        "frame": int(start),
                        "threshold_mm": limits.max_initial_penetration * 1000.0,
                    },
                )
            )
    flags += _jump_flags(trajectory, limits)
    note = _limit_flag(trajectory, scene.layout)
    if note is not None:
        flags.append(note)
    return tuple(flags)


def is_valid(flags: tuple[Flag, ...]) -> bool:
    """No flag makes the replay invalid."""
    return not any(f.invalid for f in flags)
