"""The columns of the report's tables, shared by the HTML and Markdown writers.

A column turns one row (a dict from :mod:`handsim.report.aggregate`) into text; ``numeric`` columns are
right-aligned. A column that only some kinds of trial have (a glove trial's slip and hold, a recorded
object's drift and track) says so with ``shown_if``: :func:`shown` leaves it out of a report in which no
trial has it, so that a report of ARCTIC sequences has no column of dashes for the glove's hold.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from handsim.report import fmt


@dataclass(frozen=True)
class Column:
    """One table column.

    Attributes:
        label: Header text.
        cell: Text of the cell for a row.
        numeric: Right-align the column.
        help: What the column means (a tooltip in HTML, a legend line in Markdown).
        shown_if: Whether a trial (an entry of the summary's ``trials``) has what the column shows; the
            column is left out of a report in which no trial has it. None: every report shows it.
    """

    label: str
    cell: Callable[[dict], str]
    numeric: bool = True
    help: str = ""
    shown_if: Callable[[dict], bool] | None = None


def has(*keys: str) -> Callable[[dict], bool]:
    """A :attr:`Column.shown_if`: the trial has a value (not None) for one of ``keys``."""
    return lambda trial: any(trial.get(k) is not None for k in keys)


def shown(columns: Sequence[Column], trials: Sequence[dict]) -> tuple[Column, ...]:
    """The columns some trial of the report has (:attr:`Column.shown_if`), in their order.

    Args:
        columns: A table's columns.
        trials: Every trial of the report (the summary's ``trials``), not only the table's rows, so that a
            group table and the trials table agree.

    Returns:
        The columns to draw.
    """
    return tuple(c for c in columns if c.shown_if is None or any(map(c.shown_if, trials)))


_HOLD = has("held", "hold_reason")
"""A glove trial: its hold was judged, or not with a reason."""
_TRACK = has("track")
"""A recorded-object trial with a verdict on its track."""


GROUP_COLUMNS: tuple[Column, ...] = (
    Column("trials", lambda r: str(r["trials"])),
    Column("ok", lambda r: str(r["ok"])),
    Column("diverged", lambda r: str(r["diverged"]), help="runs stopped by a MuJoCo divergence"),
    Column("errors", lambda r: str(r["errors"]), help="trials that failed to load or run"),
    Column(
        "flagged",
        lambda r: str(r["flagged"]),
        help="trials flagged not valid (a plausibility flag): left out of every rate and statistic",
    ),
    Column(
        "hold rate",
        lambda r: fmt.rate(r["held"], r["hold_judged"]),
        help="glove trials whose object stayed in hand through the hold window, of those judged",
        shown_if=_HOLD,
    ),
    Column(
        "robust holds",
        lambda r: fmt.rate(r["robust_held"], r["hold_judged"]),
        help="glove trials held with at least 80 % of their robustness ensemble (the top placements and the "
        "winner moved ±2 mm and turned ±5°) held, of those judged",
        shown_if=_HOLD,
    ),
    Column(
        "follow rate",
        lambda r: fmt.rate(r["followed"], r["track_judged"]),
        help="recorded-object trials whose object followed its recorded track (within 2 cm, 30°, hinge 30°) "
        "over every manipulated frame, of those judged",
        shown_if=_TRACK,
    ),
    Column(
        "not judged",
        lambda r: str(r["not_judged"]),
        help="trials whose hold or track could not be judged (too short a window after release, no feasible "
        "placement, no manipulated frames …): left out of the rates",
        shown_if=lambda t: _HOLD(t) or _TRACK(t),
    ),
    Column(
        "slip p50 mm",
        lambda r: fmt.num(r["slip_median_mm"], 1),
        help="median of each trial's max slip",
        shown_if=has("max_slip_mm"),
    ),
    Column(
        "slip max mm",
        lambda r: fmt.num(r["slip_max_mm"], 1),
        help="largest max slip",
        shown_if=has("max_slip_mm"),
    ),
    Column(
        "pen. p50 mm",
        lambda r: fmt.num(r["penetration_p50_mm"]),
        help="median of each trial's max hand–object penetration",
    ),
    Column(
        "pen. p95 mm",
        lambda r: fmt.num(r["penetration_p95_mm"]),
        help="95th percentile of each trial's max penetration",
    ),
    Column(
        "pen. max mm", lambda r: fmt.num(r["penetration_max_mm"]), help="deepest penetration of any trial"
    ),
    Column(
        "drift mean mm",
        lambda r: fmt.num(r["drift_mean_mm"], 1),
        help="mean of each recorded trial's mean object drift",
        shown_if=has("max_drift_mm"),
    ),
    Column(
        "drift max mm",
        lambda r: fmt.num(r["drift_max_mm"], 1),
        help="largest object drift of any trial",
        shown_if=has("max_drift_mm"),
    ),
    Column(
        "limit viol.",
        lambda r: fmt.integer(r["limit_violations"]),
        help="recorded joint angles outside the hand's joint limits (total)",
    ),
    Column(
        "gaps filled",
        lambda r: fmt.integer(r["gaps_filled"]),
        help="invalid samples of the recording filled by interpolation (total)",
    ),
)


def _hand_columns(hand: str) -> tuple[Column, ...]:
    return (
        Column(
            f"{hand} contact frames",
            lambda r: fmt.integer(r[f"{hand}/contact_frames"]),
            help=f"frames in which the {hand} hand touches the object",
        ),
        Column(
            f"{hand} pen. max mm",
            lambda r: fmt.num(r[f"{hand}/max_penetration_mm"]),
            help=f"deepest penetration of the {hand} hand",
        ),
        Column(
            f"{hand} track. mean °",
            lambda r: fmt.num(r[f"{hand}/mean_tracking_error_deg"]),
            help=f"mean joint tracking error of the {hand} hand",
        ),
    )


HAND_COLUMNS: tuple[Column, ...] = (
    *_hand_columns("right"),
    *_hand_columns("left"),
    Column("drift max mm", lambda r: fmt.num(r["max_drift_mm"], 1), help="largest object drift"),
    Column(
        "rot. drift max °",
        lambda r: fmt.num(r["max_rotation_drift_deg"], 1),
        help="largest rotation between the simulated and the recorded object",
    ),
    Column(
        "hinge drift max °",
        lambda r: fmt.num(r["max_articulation_drift_deg"], 1),
        help="largest difference between the simulated and the recorded articulation",
    ),
)
"""The two-hand (ARCTIC, Tzionas) trials' table: each hand's numbers and the object's drift."""

TRIAL_COLUMNS: tuple[Column, ...] = (
    Column("kind", lambda r: fmt.text(r["kind"]), numeric=False),
    Column(
        "outcome",
        lambda r: r["outcome"],
        numeric=False,
        help="held, not held (glove trials), followed, lost (recorded objects: the verdict on the track), "
        "not judged (why: in the trial's section), ran (no hold test or track verdict), flagged (not valid: "
        "out of the rates), diverged, error",
    ),
    Column(
        "on track",
        lambda r: fmt.num(r["track_followed_fraction"]),
        help="recorded-object trials: fraction of the manipulated frames (the recording moves the object "
        "beyond the tolerance from its start) in which the object is within 2 cm, 30°, hinge 30° of it",
        shown_if=_TRACK,
    ),
    Column(
        "robustness",
        lambda r: fmt.num(r["hold_robustness"]),
        help="fraction of the robustness ensemble (the top placements and the winner moved ±2 mm and turned "
        "±5°) whose object was held",
        shown_if=has("hold_robustness"),
    ),
    Column(
        "fit at",
        lambda r: fmt.num(r["fit_fraction"]),
        help="glove trials: fraction of the recorded finger flexion at which the object first fits in the "
        "hand (1 = only when fully closed; lower: the recording closes past the object)",
        shown_if=has("fit_fraction"),
    ),
    Column(
        "closure self-pen. mm",
        lambda r: fmt.num(r["self_penetration_at_closure_mm"], 1),
        help="glove trials: deepest penetration of the hand's own links (thumb through fingers) at closure",
        shown_if=has("self_penetration_at_closure_mm"),
    ),
    Column("object", lambda r: fmt.text(r["object"]), numeric=False, shown_if=has("object")),
    Column("grasp", lambda r: fmt.text(r["grasp"]), numeric=False, shown_if=has("grasp")),
    Column("actor", lambda r: fmt.text(r["actor"]), numeric=False, shown_if=has("actor")),
    Column(
        "slip mm",
        lambda r: fmt.num(r["max_slip_mm"], 1),
        help="max slip relative to the hand",
        shown_if=has("max_slip_mm"),
    ),
    Column("pen. max mm", lambda r: fmt.num(r["max_penetration_mm"]), help="deepest penetration"),
    Column("pen. p95 mm", lambda r: fmt.num(r["p95_penetration_mm"]), help="95th percentile over frames"),
    Column(
        "self-pen. mm",
        lambda r: fmt.num(r["max_self_penetration_mm"]),
        help="hand-only trials: deepest simulated penetration of the hand through itself",
        shown_if=has("max_self_penetration_mm"),
    ),
    Column(
        "drift max mm",
        lambda r: fmt.num(r["max_drift_mm"], 1),
        help="largest object drift",
        shown_if=has("max_drift_mm"),
    ),
    Column(
        "track. mean °", lambda r: fmt.num(r["mean_tracking_error_deg"]), help="mean joint tracking error"
    ),
    Column("limit viol.", lambda r: fmt.integer(r["limit_violations"])),
    Column("gaps filled", lambda r: fmt.integer(r["gaps_filled"])),
    Column("warnings", lambda r: str(r["warnings"]), help="MuJoCo warnings during the run"),
)
