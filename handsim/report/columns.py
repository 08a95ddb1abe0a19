"""The columns of the report's tables, shared by the HTML and Markdown writers.

A column turns one row (a dict from :mod:`handsim.report.aggregate`) into text; ``numeric`` columns are
right-aligned.
"""

from __future__ import annotations

from collections.abc import Callable
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
    """

    label: str
    cell: Callable[[dict], str]
    numeric: bool = True
    help: str = ""


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
    ),
    Column(
        "robust holds",
        lambda r: fmt.rate(r["robust_held"], r["hold_judged"]),
        help="glove trials held with at least 80 % of their robustness ensemble (the top placements and the "
        "winner moved ±2 mm and turned ±5°) held, of those judged",
    ),
    Column(
        "follow rate",
        lambda r: fmt.rate(r["followed"], r["track_judged"]),
        help="recorded-object trials whose object followed its recorded track (within 2 cm, 30°, hinge 30°) "
        "over every manipulated frame, of those judged",
    ),
    Column(
        "not judged",
        lambda r: str(r["not_judged"]),
        help="trials whose hold or track could not be judged (too short a window after release, no feasible "
        "placement, no manipulated frames …): left out of the rates",
    ),
    Column("slip p50 mm", lambda r: fmt.num(r["slip_median_mm"], 1), help="median of each trial's max slip"),
    Column("slip max mm", lambda r: fmt.num(r["slip_max_mm"], 1), help="largest max slip"),
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
    ),
    Column("drift max mm", lambda r: fmt.num(r["drift_max_mm"], 1), help="largest object drift of any trial"),
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
    ),
    Column(
        "robustness",
        lambda r: fmt.num(r["hold_robustness"]),
        help="fraction of the robustness ensemble (the top placements and the winner moved ±2 mm and turned "
        "±5°) whose object was held",
    ),
    Column(
        "fit at",
        lambda r: fmt.num(r["fit_fraction"]),
        help="glove trials: fraction of the recorded finger flexion at which the object first fits in the "
        "hand (1 = only when fully closed; lower: the recording closes past the object)",
    ),
    Column(
        "closure self-pen. mm",
        lambda r: fmt.num(r["self_penetration_at_closure_mm"], 1),
        help="glove trials: deepest penetration of the hand's own links (thumb through fingers) at closure",
    ),
    Column("object", lambda r: fmt.text(r["object"]), numeric=False),
    Column("grasp", lambda r: fmt.text(r["grasp"]), numeric=False),
    Column("actor", lambda r: fmt.text(r["actor"]), numeric=False),
    Column("slip mm", lambda r: fmt.num(r["max_slip_mm"], 1), help="max slip relative to the hand"),
    Column("pen. max mm", lambda r: fmt.num(r["max_penetration_mm"]), help="deepest penetration"),
    Column("pen. p95 mm", lambda r: fmt.num(r["p95_penetration_mm"]), help="95th percentile over frames"),
    Column(
        "self-pen. mm",
        lambda r: fmt.num(r["max_self_penetration_mm"]),
        help="hand-only trials: deepest simulated penetration of the hand through itself",
    ),
    Column("drift max mm", lambda r: fmt.num(r["max_drift_mm"], 1), help="largest object drift"),
    Column(
        "track. mean °", lambda r: fmt.num(r["mean_tracking_error_deg"]), help="mean joint tracking error"
    ),
    Column("limit viol.", lambda r: fmt.integer(r["limit_violations"])),
    Column("gaps filled", lambda r: fmt.integer(r["gaps_filled"])),
    Column("warnings", lambda r: str(r["warnings"]), help="MuJoCo warnings during the run"),
)
