"""Filling gaps (runs of invalid samples) in joint-angle trajectories.

Five methods follow §3.7 of the thesis on 3D hand motion from 2D video (``../shared/specs/001_…``, text
and the ``fillInVertexUse…`` functions of its Appendix B); a sixth, ``linear``, interpolates. The thesis
fills 2-D feature-point coordinates frame by frame, each frame from the frames before it (already
complete, earlier missing values filled); here the same rules act on joint angles (rad). For a missing
sample ``x[t]`` of a DoF, with ``d = x[t-1] - x[t-2]`` (``x[t-1]``, ``x[t-2]`` measured or filled
before):

``previous_value`` (method 1)
    ``x[t] = x[t-1]``.
``previous_difference`` (method 2)
    ``x[t] = x[t-1] + d`` — a gap becomes a straight-line extrapolation of the last step.
``interfinger_trend`` (method 3, "interfinger dependency")
    Like method 2, but the step is reversed, ``x[t] = x[t-1] - d``, when the reference ``r`` turned at
    ``t-2`` against the DoF's own direction: ``r[t-3] < r[t-2] > r[t-1]`` (peak) while ``d > 0``, or
    ``r[t-3] > r[t-2] < r[t-1]`` (trough) while ``d < 0`` (Table 3.1: A = 3, 5, 7, ? and B = 3, 5, 4 give
    7 − 2 = 5). The reference is the same DoF of the *neighbouring finger* — index → middle → ring →
    little → ring, none for the thumb — as in the thesis' ``m_interdepNeighbors`` table. (The thesis'
    prose also calls it the "parent"/"depended-on" point; its code and Table 3.1's caption make it the
    neighbouring finger.)
``intrafinger_trend`` (method 4, "intrafinger dependency")
    Method 3 with the reference on the *same finger*: the DoF of the same kind (flexion → flexion) of the
    parent joint, e.g. DIP flexion → PIP flexion → MCP flexion; none when the parent is the root (the
    thesis' MCPs refer to themselves; ``m_interdepIntraFingerNeighbors``).
``intrafinger_rate`` (method 5)
    "In addition to the directional cue from the parent, we also use its value change rate": the DoF
    moves by its intra-finger reference's last step, ``x[t] = x[t-1] + (r[t-1] - r[t-2])``; a turn of
    the reference therefore turns the DoF too. *Choice:* the thesis' code uses, on the frame of a turn
    only, a relative rate ``x[t-1]·|Δr|/r[t-2]`` with a sign that keeps the old direction; that
    contradicts its own text ("changes the direction accordingly") and divides by an angle that may be 0,
    so it is not reproduced.
``linear``
    Straight line in time between the last valid sample before and the first valid one after the gap.

Decisions where the thesis is silent or does not fit offline joint-angle data:

* Invalid means ``~valid | ~isfinite(targets)``. Valid samples are never changed.
* References must be *measured* (valid and finite in the input) at the frames used (``t-3 … t-1`` for the
  trends, ``t-2``, ``t-1`` for the rate), so a gap of the reference never drives a false turn (the thesis'
  spike 3). Otherwise — or when a DoF has no reference (a thumb DoF for method 3, an MCP for methods
  4 and 5, a reference that is not a column of the trajectory) — the sample falls back to
  ``previous_difference``, which is exactly what the thesis' self-references give. A sample with only one
  previous sample falls back to ``previous_value``. Each fallback is counted in the notes.
* Methods 1–5 are causal like the thesis': they use frames before ``t`` only, the reference's too, although
  an offline recording has the reference at ``t`` (so ``intrafinger_rate`` follows it one frame late).
  Turns are strict three-frame extrema, as in the thesis' code: a plateau (repeated sample) is no turn.
* The methods are per frame, not per second (as in the thesis); only ``linear`` uses the sample times.
* A gap at the start of the recording (no previous sample; the thesis assumes a perfect first frame)
  takes the first valid sample after it, for every method. ``linear`` holds the last valid sample over a
  gap at the end. A DoF with no valid sample at all is left unfilled.
* Gaps longer than ``max_gap`` frames are left unfilled (``valid`` stays False) and reported.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field, replace
from typing import Literal, get_args

import numpy as np
import numpy.typing as npt

from handsim.datatypes.skeleton import Dof, Skeleton
from handsim.datatypes.trajectory import Trajectory

GapMethod = Literal[
    "previous_value",
    "previous_difference",
    "interfinger_trend",
    "intrafinger_trend",
    "intrafinger_rate",
    "linear",
]
"""Name of a gap-filling method; the first five are the thesis' methods 1–5 in order."""

GAP_METHODS: tuple[GapMethod, ...] = get_args(GapMethod)
"""All gap-filling methods, thesis methods 1–5 first, then ``linear``."""

REFERENCE_METHODS: tuple[GapMethod, ...] = ("interfinger_trend", "intrafinger_trend", "intrafinger_rate")
"""Methods that follow a reference DoF and so need the skeleton."""

_FALLBACKS = {
    "no_reference": "used previous_difference (no reference DoF in the trajectory)",
    "reference_invalid": "used previous_difference (reference DoF not measured at the frames used)",
    "one_previous": "used previous_value (only one previous sample)",
    "start": "took the first valid sample after the gap (gap at the start of the recording)",
    "end": "hold the last valid sample (gap at the end of the recording, nothing to interpolate to)",
}


def _check_method(method: str) -> None:
    if method not in GAP_METHODS:
        raise ValueError(f"unknown gap filling method {method!r}; methods are {list(GAP_METHODS)}")


def find_gaps(valid: npt.ArrayLike) -> list[tuple[int, int, int]]:
    """Runs of invalid samples, column by column.

    Args:
        valid: Validity mask, shape (T, ndof); True where a sample is usable.

    Returns:
        ``(column, start, stop)`` for every maximal run of False in a column (``stop`` one past the last
        invalid frame), sorted by column, then start.

    Raises:
        ValueError: If ``valid`` is not 2-D.
    """
    v = np.asarray(valid, dtype=bool)
    if v.ndim != 2:
        raise ValueError(f"valid must be a 2-D (T, ndof) mask, got shape {v.shape}")
    pad = np.zeros((v.shape[1], 1), dtype=np.int8)
    edges = np.diff(np.hstack([pad, (~v).T.astype(np.int8), pad]), axis=1)
    starts = np.argwhere(edges == 1)
    stops = np.argwhere(edges == -1)
    return [(int(c), int(s), int(e)) for (c, s), (_, e) in zip(starts, stops, strict=True)]


def _same_kind(skeleton: Skeleton, joint: int, kind: str) -> str | None:
    return next((d.name for d in skeleton.dofs_of(skeleton.joints[joint].name) if d.kind == kind), None)


def _intrafinger(skeleton: Skeleton, dof: Dof) -> str | None:
    parent = skeleton.joints[skeleton.joint_index(dof.joint)].parent
    return None if parent < 1 else _same_kind(skeleton, parent, dof.kind)


def _interfinger(skeleton: Skeleton) -> dict[str, str | None]:
    chains = []  # per finger, thumb first: joint indices from the fingertip up to below the root
    for tip in skeleton.fingertips:
        chain, j = [], skeleton.joint_index(tip)
        while j > 0:
            chain.append(j)
            j = skeleton.joints[j].parent
        chains.append(chain)
    counts = np.bincount([j for c in chains for j in c], minlength=skeleton.njoints)
    out: dict[str, str | None] = {d.name: None for d in skeleton.dofs}
    fingers = chains[1:]
    if len(fingers) < 2:
        return out
    for i, chain in enumerate(fingers):
        other = fingers[i + 1] if i + 1 < len(fingers) else fingers[i - 1]
        for depth, j in enumerate(chain):
            if counts[j] != 1 or depth >= len(other):
                continue
            for dof in skeleton.dofs_of(skeleton.joints[j].name):
                out[dof.name] = _same_kind(skeleton, other[depth], dof.kind)
    return out


def reference_dofs(skeleton: Skeleton, method: GapMethod) -> dict[str, str | None]:
    """The reference DoF each DoF of ``skeleton`` follows under ``method``.

    ``intrafinger_*``: the DoF of the same kind of the parent joint (PIP flexion → MCP flexion), unless
    the parent is the root (the wrist is on no finger).
    ``interfinger_trend``: the DoF of the same kind of the joint as far from the fingertip on the
    neighbouring finger, fingers taken in :attr:`Skeleton.fingertips` order with the first one the thumb
    (no neighbour): index → middle → ring → little, and the last finger → the one before it.

    Args:
        skeleton: The hand.
        method: A gap-filling method.

    Returns:
        DoF name → reference DoF name, or None where there is none (every DoF for a method that uses no
        reference).

    Raises:
        ValueError: If ``method`` is unknown; the message lists the methods.
    """
    _check_method(method)
    if method == "interfinger_trend":
        return _interfinger(skeleton)
    if method in REFERENCE_METHODS:
        return {d.name: _intrafinger(skeleton, d) for d in skeleton.dofs}
    return {d.name: None for d in skeleton.dofs}


def _extrapolate(
    method: GapMethod,
    x: np.ndarray,
    avail: np.ndarray,
    ref: np.ndarray | None,
    ref_ok: np.ndarray | None,
    span: tuple[int, int],
    reasons: list[str],
) -> None:
    """Fill ``x[start:stop]`` in place, frame by frame, by one of the thesis' methods 1–5."""
    for t in range(*span):
        prev = x[t - 1]
        has2 = t >= 2 and bool(avail[t - 2])
        d = prev - x[t - 2] if has2 else 0.0
        step = d
        reason = "" if has2 or method == "previous_value" else "one_previous"
        if method == "previous_value":
            step = 0.0
        elif method in REFERENCE_METHODS:
            back = 2 if method == "intrafinger_rate" else 3
            if ref is None or ref_ok is None:
                reason = "no_reference"
            elif t < back or not ref_ok[t - back : t].all():
                reason = "reference_invalid"
            elif method == "intrafinger_rate":
                step, reason = ref[t - 1] - ref[t - 2], ""
            elif has2:
                r3, r2, r1 = ref[t - 3], ref[t - 2], ref[t - 1]
                turned = (r3 < r2 > r1 and d > 0) or (r3 > r2 < r1 and d < 0)
                step = -d if turned else d
        x[t] = prev + step
        avail[t] = True
        reasons.append(reason)


def _count(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def _names(columns: set[int], dof_names: tuple[str, ...]) -> str:
    return ", ".join(dof_names[c] for c in sorted(columns))


def fill_gaps(
    trajectory: Trajectory,
    method: GapMethod = "linear",
    skeleton: Skeleton | None = None,
    *,
    max_gap: int | None = None,
) -> Trajectory:
    """Fill the invalid samples of a trajectory (see the module docstring for the methods).

    Args:
        trajectory: The trajectory; samples with ``valid`` False or a non-finite target are gaps.
        method: One of :data:`GAP_METHODS`.
        skeleton: The hand whose DoFs the columns are (matched by name). Needed by the reference methods
            (:data:`REFERENCE_METHODS`) to find each DoF's reference; ignored by the others.
        max_gap: Longest gap to fill, in frames; longer gaps are left unfilled. None fills every gap.

    Returns:
        A new trajectory: filled targets (rad); ``filled`` True where filled (OR-ed with the input's);
        ``valid`` True where the input was valid and finite or a value was filled, False elsewhere;
        ``notes`` extended with what was filled, every fallback and what was left unfilled.

    Raises:
        ValueError: If ``method`` is unknown (the message lists the methods), a reference method gets no
            skeleton, or ``max_gap`` is below 1.
    """
    _check_arguments(method, skeleton, max_gap)
    names = trajectory.dof_names
    x = np.array(trajectory.targets, dtype=float)
    known = np.asarray(trajectory.valid, dtype=bool) & np.isfinite(x)
    avail = known.copy()
    refs: dict[str, str | None] = {}
    if skeleton is not None and method in REFERENCE_METHODS:
        refs = reference_dofs(skeleton, method)
    report = _GapReport()
    for c, s, e in find_gaps(known):
        if s == 0 and e == x.shape[0]:
            report.empty.add(c)
            continue
        if max_gap is not None and e - s > max_gap:
            report.too_long.append((c, s, e))
            continue
        reasons = _fill_gap(method, trajectory.times, x, known, avail, refs, names, (c, s, e))
        avail[s:e, c] = True
        report.add_filled((c, s, e), reasons)
    new = avail & ~known
    notes = [*trajectory.notes, *_fill_notes(report, int(new.sum()), names, method, max_gap)]
    filled = new if trajectory.filled is None else new | np.asarray(trajectory.filled, dtype=bool)
    return replace(trajectory, targets=x, valid=avail, filled=filled, notes=tuple(notes))


def _check_arguments(method: str, skeleton: Skeleton | None, max_gap: int | None) -> None:
    """Refuse an unknown method, a reference method without a skeleton, or a ``max_gap`` below 1.

    Raises:
        ValueError: Any of these.
    """
    _check_method(method)
    if method in REFERENCE_METHODS and skeleton is None:
        raise ValueError(
            f"gap filling method {method!r} needs the hand skeleton to find each DoF's reference DoF; "
            "pass skeleton="
        )
    if max_gap is not None and max_gap < 1:
        raise ValueError(f"max_gap must be at least 1 frame, got {max_gap}")


@dataclass
class _GapReport:
    """The gaps of a trajectory as filling went: filled, too long, empty columns, and the fallbacks used."""

    filled: list[tuple[int, int, int]] = field(default_factory=list)
    too_long: list[tuple[int, int, int]] = field(default_factory=list)
    empty: set[int] = field(default_factory=set)
    fallbacks: dict[str, set[int]] = field(default_factory=lambda: defaultdict(set))
    fallback_counts: dict[str, int] = field(default_factory=lambda: defaultdict(int))

    def add_filled(self, gap: tuple[int, int, int], reasons: list[str]) -> None:
        """Count a filled gap (column, start, stop) and each sample's fallback reason ("" for none)."""
        self.filled.append(gap)
        for reason in reasons:
            if reason:
                self.fallbacks[reason].add(gap[0])
                self.fallback_counts[reason] += 1


def _fill_gap(
    method: str,
    times: np.ndarray,
    x: np.ndarray,
    known: np.ndarray,
    avail: np.ndarray,
    refs: dict[str, str | None],
    names: tuple[str, ...],
    gap: tuple[int, int, int],
) -> list[str]:
    """Fill one gap (column, start, stop) of ``x`` in place; return each sample's fallback reason.

    A gap at the start holds the first valid value; ``linear`` holds the last value at the end and
    interpolates inside; the reference methods extrapolate from the reference DoF (:func:`_extrapolate`).
    """
    c, s, e = gap
    col = x[:, c]
    if s == 0:
        col[:e], reasons = col[e], ["start"] * e
    elif method == "linear" and e == x.shape[0]:
        col[s:], reasons = col[s - 1], ["end"] * (e - s)
    elif method == "linear":
        col[s:e] = np.interp(times[s:e], times[[s - 1, e]], col[[s - 1, e]])
        reasons = [""] * (e - s)
    else:
        r_name = refs.get(names[c])
        r = names.index(r_name) if r_name in names else None
        ref, ref_ok = (None, None) if r is None else (x[:, r], known[:, r])
        reasons = []
        _extrapolate(method, col, avail[:, c], ref, ref_ok, (s, e), reasons)
    return reasons


def _fill_notes(
    report: _GapReport, new: int, names: tuple[str, ...], method: str, max_gap: int | None
) -> list[str]:
    """The notes on what was filled (``new`` samples), every fallback and what was left unfilled."""
    notes = []
    if report.filled:
        longest = max(e - s for _, s, e in report.filled)
        notes.append(
            f"filled {_count(new, 'sample')} in {_count(len(report.filled), 'gap')} "
            f"(longest {_count(longest, 'frame')}) of "
            f"{_names({c for c, _, _ in report.filled}, names)} by {method}"
        )
    elif not report.too_long and not report.empty:
        notes.append(f"no invalid samples to fill by {method}")
    for reason, text in _FALLBACKS.items():
        if report.fallback_counts[reason]:
            counted = _count(report.fallback_counts[reason], "sample")
            notes.append(f"{method}: {counted} of {_names(report.fallbacks[reason], names)} {text}")
    if report.too_long:
        too_long = report.too_long
        longest = max(e - s for _, s, e in too_long)
        notes.append(
            f"left unfilled: {_count(sum(e - s for _, s, e in too_long), 'sample')} in "
            f"{_count(len(too_long), 'gap')} longer than max_gap={max_gap} frames (longest {longest}) of "
            f"{_names({c for c, _, _ in too_long}, names)}"
        )
    if report.empty:
        notes.append(f"left unfilled: {_names(report.empty, names)} (no valid sample)")
    return notes


__all__ = ["GAP_METHODS", "REFERENCE_METHODS", "GapMethod", "fill_gaps", "find_gaps", "reference_dofs"]
