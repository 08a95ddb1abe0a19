"""Uniform resampling of a trajectory: every field at a constant rate, gaps and validity carried.

:func:`resample` turns an irregularly sampled recording (GraspDB14 rows come every 15 or 16 ms, with
an occasional dropped sample, 31/32 ms) into samples at a uniform control rate. Rules:

* Output times are ``times[0] + k / rate_hz`` for ``k = 0, 1, …`` up to the last input time (the last
  output sample is at or before it).
* For an output time ``t``, the *bracketing input samples* are ``i`` and ``i + 1`` with
  ``times[i] <= t < times[i + 1]`` (at the last input time: ``n - 2`` and ``n - 1``). An input sample
  whose weight is 0 does not count: at ``t == times[i]`` only sample ``i`` brackets ``t``.
* **Targets** are interpolated linearly per DoF between the valid samples only (valid means
  ``valid`` and finite), so a value never comes from an invalid sample. An output sample is **valid
  only if every bracketing input sample is valid**: one that falls inside, or touches, a gap stays
  invalid (its value is then interpolated across the gap from the nearest valid samples, or held
  beyond the first/last valid one). A DoF with no valid sample keeps its stored values, interpolated
  as they are, all invalid.
* **filled**: an output sample is filled when a bracketing input sample is.
* **Root pose and object poses**: position linearly, quaternion by slerp along the shorter arc (the
  sign of the second quaternion is flipped when the two are in opposite hemispheres; quaternions are
  normalised first). Object articulation linearly. Object samples use only the valid object samples,
  and an output object sample is valid when every bracketing input sample is, as for targets.
* **switch and channels** hold the previous sample (sample-and-hold: the value at the last input time
  at or before ``t``). The switch is a state, and channels may hold anything (counts, flags, angles
  that drive no DoF), so neither is interpolated.
* **Phases**: a phase ``[start, stop)`` covers the input times ``[times[start], times[stop])`` (to the
  end when ``stop`` is the last frame + 1); the new phase covers the output frames whose times lie in
  that interval: ``start`` = first output frame at or after ``times[start]``, ``stop`` = first output
  frame at or after ``times[stop]``. Phases that tile the input tile the output. A phase shorter than
  one output period may hold no output frame; it is dropped and a note says so.
* ``computed``, ``source``, ``sha256`` are carried; notes are extended.

Downsampling interpolates without low-pass filtering: motion faster than half the new rate aliases.

The notes say how the input was sampled, and name its largest gap only where it is one: an interval longer
than :data:`GAP_FACTOR` times the recording's own median interval (a clock's regular period, 33.3 ms at
ARCTIC's 30 Hz, is no gap).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal, get_args

import numpy as np

from handsim.datatypes.rotations import slerp
from handsim.datatypes.trajectory import ObjectTrack, Phase, Trajectory

ResampleMethod = Literal["linear"]
"""Name of a resampling method."""

RESAMPLE_METHODS: tuple[ResampleMethod, ...] = get_args(ResampleMethod)
"""All resampling methods."""

GAP_FACTOR = 1.5
"""An interval between input samples longer than this many median intervals is a gap, and is noted.

One dropped sample makes an interval of two periods; a clock's jitter stays far below 1.5 (GraspDB14's rows
come every 15 or 16 ms: 1.07 of the median at most), and a regular clock has none.
"""


@dataclass(frozen=True)
class ResampleResult:
    """Result of :func:`resample`.

    Attributes:
        trajectory: The resampled trajectory (uniform times).
        largest_gap_s: Largest time between two consecutive input samples, s (0 for one sample).
        largest_gap_at_s: Input time at which that gap starts, s (the first such gap).
        notes: The notes :func:`resample` added to the trajectory's notes.
    """

    trajectory: Trajectory
    largest_gap_s: float
    largest_gap_at_s: float
    notes: tuple[str, ...]


def _check_rate(rate_hz: float) -> float:
    """``rate_hz`` as a float; ValueError unless it is a positive, finite real number (not a bool)."""
    number = isinstance(rate_hz, (int, float, np.integer, np.floating)) and not isinstance(rate_hz, bool)
    if not (number and math.isfinite(rate_hz) and rate_hz > 0):
        raise ValueError(f"rate_hz must be a positive, finite number of samples per second, got {rate_hz!r}")
    return float(rate_hz)


def uniform_times(start: float, stop: float, rate_hz: float) -> np.ndarray:
    """Sample times ``start + k / rate_hz`` from ``start`` up to ``stop`` (included when it falls on one).

    A time within 1e-9 of a period past ``stop`` (rounding) is kept and set to ``stop``, so the last time
    is never after ``stop``.

    Args:
        start: First time, s.
        stop: Last allowed time, s (``>= start``).
        rate_hz: Samples per second, positive and finite.

    Returns:
        The times, s, shape (m,), m >= 1.

    Raises:
        ValueError: ``rate_hz`` is not a positive finite number, or ``stop`` is before ``start``.
    """
    rate = _check_rate(rate_hz)
    if not stop >= start:
        raise ValueError(f"stop time {stop!r} s is before start time {start!r} s")
    count = math.floor((stop - start) * rate + 1e-9) + 1
    times = start + np.arange(count) / rate
    return np.minimum(times, stop)


def _bracket(xp: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bracketing samples ``i``, ``j`` of each ``t`` in increasing ``xp`` and the weight ``w`` of ``j``.

    ``xp[i] <= t < xp[j]`` with ``j = i + 1`` inside the range; ``w`` is clipped to [0, 1], so times
    before the first or after the last sample take the end sample. One sample: ``i = j = 0``, ``w = 0``.
    """
    n = xp.shape[0]
    i = np.clip(np.searchsorted(xp, t, side="right") - 1, 0, max(n - 2, 0))
    j = np.minimum(i + 1, n - 1)
    dt = xp[j] - xp[i]
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(dt > 0, np.clip((t - xp[i]) / np.where(dt > 0, dt, 1.0), 0.0, 1.0), 0.0)
    return i, j, w


def _lerp(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``a + w (b - a)``, exactly ``a`` at ``w = 0`` and ``b`` at ``w = 1``, never outside [a, b]."""
    if a.ndim > w.ndim:
        w = w.reshape(w.shape + (1,) * (a.ndim - w.ndim))
    with np.errstate(invalid="ignore"):
        mixed = np.clip(a + w * (b - a), np.minimum(a, b), np.maximum(a, b))
    return np.where(w == 0, a, np.where(w == 1, b, mixed))


def _output_valid(known: np.ndarray, i: np.ndarray, j: np.ndarray, w: np.ndarray) -> np.ndarray:
    """An output sample is valid when every bracketing input sample with a nonzero weight is known."""
    if known.ndim > w.ndim:
        w = w[:, None]
    return (known[i] | (w == 1)) & (known[j] | (w == 0))


def _resample_column(times: np.ndarray, x: np.ndarray, known: np.ndarray, t: np.ndarray) -> np.ndarray:
    """One target column (T,) at times ``t``, interpolated between its known samples."""
    if known.all() or not known.any():
        i, j, w = _bracket(times, t)
        return _lerp(x[i], x[j], w)
    sub = np.flatnonzero(known)
    i, j, w = _bracket(times[sub], t)
    return _lerp(x[sub[i]], x[sub[j]], w)


def _resample_pose(times: np.ndarray, pose: np.ndarray, known: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Poses (T, 7) at times ``t``: position linear, quaternion slerp, between known samples."""
    rows = np.arange(times.shape[0]) if known.all() or not known.any() else np.flatnonzero(known)
    i, j, w = _bracket(times[rows], t)
    a, b = pose[rows[i]], pose[rows[j]]
    out = np.empty((t.shape[0], 7))
    out[:, :3] = _lerp(a[:, :3], b[:, :3], w)
    out[:, 3:] = slerp(a[:, 3:], b[:, 3:], w)
    return out


def _map_phases(
    phases: tuple[Phase, ...], times: np.ndarray, new_times: np.ndarray
) -> tuple[tuple[Phase, ...], list[str]]:
    """Phases as output frame intervals (see the module docstring); names of the phases dropped."""
    n, m = times.shape[0], new_times.shape[0]
    mapped: list[Phase] = []
    dropped: list[str] = []
    for p in phases:
        start = int(np.searchsorted(new_times, times[p.start], side="left"))
        stop = m if p.stop >= n else int(np.searchsorted(new_times, times[p.stop], side="left"))
        if start < stop:
            mapped.append(Phase(p.name, start, stop))
        else:
            dropped.append(
                f"{p.name!r} [{p.start}, {p.stop}) ({times[p.start]:.4f} s"
                + (f" to {times[p.stop]:.4f} s)" if p.stop < n else " to the end)")
            )
    return tuple(mapped), dropped


def resample(trajectory: Trajectory, rate_hz: float, *, method: ResampleMethod = "linear") -> ResampleResult:
    """Resample a trajectory at a uniform rate (the rules are in the module docstring).

    Args:
        trajectory: The trajectory; its times may be irregular.
        rate_hz: Output samples per second, positive and finite. Higher or lower than the input's rate.
        method: One of :data:`RESAMPLE_METHODS` (``"linear"``: linear interpolation, slerp for rotations).

    Returns:
        The resampled trajectory (times ``times[0] + k / rate_hz``, s, up to the last input time), the
        largest interval between input samples (s) and where it starts (s), and the notes added (the largest
        interval among them only where it exceeds :data:`GAP_FACTOR` median intervals).

    Raises:
        ValueError: ``rate_hz`` is not a positive finite number, or ``method`` is unknown (the message
            lists the methods).
    """
    rate = _check_rate(rate_hz)
    if method not in RESAMPLE_METHODS:
        raise ValueError(f"unknown resampling method {method!r}; methods are {list(RESAMPLE_METHODS)}")
    times = np.asarray(trajectory.times, dtype=float)
    t = uniform_times(float(times[0]), float(times[-1]), rate)
    i, j, w = _bracket(times, t)
    prev = np.clip(np.searchsorted(times, t, side="right") - 1, 0, times.shape[0] - 1)
    x = np.asarray(trajectory.targets, dtype=float)
    known = np.asarray(trajectory.valid, dtype=bool) & np.isfinite(x)
    valid = _output_valid(known, i, j, w)
    root, hand_roots = _resampled_roots(trajectory, times, t)
    phases, dropped = _map_phases(trajectory.phases, times, t)
    intervals = _Intervals.of(times)
    notes = [
        _resample_note(trajectory, intervals.gaps, t.shape[0], rate, method),
        *_gap_notes(trajectory, intervals, rate),
        *_loss_notes(valid, known, dropped, rate),
    ]
    new = replace(
        trajectory,
        times=t,
        targets=_resampled_targets(times, x, known, t, (i, j, w)),
        valid=valid,
        switch=None if trajectory.switch is None else np.asarray(trajectory.switch)[prev].copy(),
        root_pose=root,
        hand_roots=hand_roots,
        channels={name: np.asarray(v)[prev].copy() for name, v in trajectory.channels.items()},
        filled=_resampled_filled(trajectory.filled, i, j, w),
        phases=phases,
        objects=_resampled_objects(trajectory.objects, times, t, (i, j, w)),
        notes=(*trajectory.notes, *notes),
    )
    return ResampleResult(
        trajectory=new, largest_gap_s=intervals.largest, largest_gap_at_s=intervals.at, notes=tuple(notes)
    )


def _resampled_targets(
    times: np.ndarray,
    x: np.ndarray,
    known: np.ndarray,
    t: np.ndarray,
    bracket: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> np.ndarray:
    """Targets at times ``t``: complete columns interpolated at once, the others between valid samples."""
    i, j, w = bracket
    complete = np.flatnonzero(known.all(axis=0))
    targets = np.empty((t.shape[0], x.shape[1]))
    targets[:, complete] = _lerp(x[np.ix_(i, complete)], x[np.ix_(j, complete)], w)
    for c in np.flatnonzero(~known.all(axis=0)):
        targets[:, c] = _resample_column(times, x[:, c], known[:, c], t)
    return targets


def _resampled_filled(
    filled: np.ndarray | None, i: np.ndarray, j: np.ndarray, w: np.ndarray
) -> np.ndarray | None:
    """The output samples that interpolate a filled input sample (with a non-zero weight), or None."""
    if filled is None:
        return None
    f = np.asarray(filled, dtype=bool)
    wc = w[:, None]
    return (f[i] & (wc < 1)) | (f[j] & (wc > 0))


def _resampled_roots(
    trajectory: Trajectory, times: np.ndarray, t: np.ndarray
) -> tuple[np.ndarray | None, dict[str, np.ndarray]]:
    """The root pose and each hand's root pose at times ``t`` (positions interpolated, slerp)."""
    n = times.shape[0]
    root = None
    if trajectory.root_pose is not None:
        root = _resample_pose(times, np.asarray(trajectory.root_pose, dtype=float), np.ones(n, bool), t)
    hand_roots = {
        name: _resample_pose(times, np.asarray(pose, dtype=float), np.ones(n, bool), t)
        for name, pose in trajectory.hand_roots.items()
    }
    return root, hand_roots


def _resampled_objects(
    objects: dict[str, ObjectTrack],
    times: np.ndarray,
    t: np.ndarray,
    bracket: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> dict[str, ObjectTrack]:
    """Each object's pose and articulation at times ``t``, between its valid and finite samples."""
    i, j, w = bracket
    n = times.shape[0]
    out: dict[str, ObjectTrack] = {}
    for name, track in objects.items():
        pose = np.asarray(track.pose, dtype=float)
        ok = np.ones(n, bool) if track.valid is None else np.asarray(track.valid, dtype=bool)
        ok = ok & np.all(np.isfinite(pose), axis=1)
        art = None
        if track.articulation is not None:
            a = np.asarray(track.articulation, dtype=float)
            art = _resample_column(times, a, ok & np.isfinite(a), t)
        out[name] = ObjectTrack(
            pose=_resample_pose(times, pose, ok, t),
            articulation=art,
            valid=None if track.valid is None and ok.all() else _output_valid(ok, i, j, w),
        )
    return out


@dataclass(frozen=True)
class _Intervals:
    """The intervals between input samples: all of them, the largest, where it starts, the median (s)."""

    gaps: np.ndarray
    frame: int
    largest: float
    at: float
    period: float

    @classmethod
    def of(cls, times: np.ndarray) -> _Intervals:
        """The intervals of the input times (the largest and median 0 for a single sample)."""
        n = times.shape[0]
        gaps = np.diff(times)
        k = int(np.argmax(gaps)) if n > 1 else 0
        gap = float(gaps[k]) if n > 1 else 0.0
        period = float(np.median(gaps)) if n > 1 else 0.0
        return cls(gaps, k, gap, float(times[k]), period)


def _resample_note(trajectory: Trajectory, gaps: np.ndarray, m: int, rate: float, method: str) -> str:
    """What was resampled to what: sample counts, rates, the input's spacing and the rules applied."""
    n = gaps.shape[0] + 1
    regular = n >= 2 and float(gaps.max() - gaps.min()) <= 1e-9 * max(1.0, float(gaps.max()))
    if regular or n < 2:
        spacing = "regular"
    else:
        spacing = f"intervals {gaps.min() * 1e3:.1f}–{gaps.max() * 1e3:.1f} ms"
    return (
        f"resampled {n} samples ({trajectory.mean_rate:.2f} Hz mean, {spacing}) to {m} samples at "
        f"{rate:g} Hz by {method} interpolation (targets between valid samples; an output sample is valid "
        "only where its bracketing input samples are; quaternions by slerp; switch and channels hold the "
        "previous sample)"
    )


def _gap_notes(trajectory: Trajectory, intervals: _Intervals, rate: float) -> list[str]:
    """Notes on a gap of more than :data:`GAP_FACTOR` median intervals and on downsampling's aliasing."""
    n = intervals.gaps.shape[0] + 1
    gap, period = intervals.largest, intervals.period
    notes = []
    if n > 1 and gap > GAP_FACTOR * period:
        notes.append(
            f"largest gap between input samples: {gap * 1e3:.1f} ms ({gap / period:.2f} × the median "
            f"interval, {period * 1e3:.1f} ms), from frame {intervals.frame} at {intervals.at:.4f} s "
            f"({gap * rate:.2f} output periods)"
        )
    if n > 1 and rate < trajectory.mean_rate:
        notes.append(
            f"downsampled without low-pass filtering: motion faster than {rate / 2:g} Hz (half the new "
            "rate) aliases"
        )
    return notes


def _loss_notes(valid: np.ndarray, known: np.ndarray, dropped: list[str], rate: float) -> list[str]:
    """Notes on the output samples made invalid by invalid inputs and on phases too short to keep."""
    notes = []
    invalid_out = int((~valid).sum())
    if invalid_out:
        notes.append(
            f"{invalid_out} output samples are invalid (they touch an invalid input sample; "
            f"{int((~known).sum())} input samples were invalid)"
        )
    if dropped:
        notes.append(f"phases holding no output frame at {rate:g} Hz were dropped: {', '.join(dropped)}")
    return notes
