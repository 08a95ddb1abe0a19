"""Numbers of a report, computed from records alone: pure functions over record dicts.

Per-trial values come from a record's ``summary`` (mm, degrees, seconds as its key names say),
``trajectory_quality`` and ``meta``; missing, null or non-finite values are ``None`` and are left out of
every statistic (a statistic over no values is ``None``). Trials flagged not valid (a plausibility flag,
``summary["valid"]`` false) are counted as their own outcome, ``flagged``, and left out of every rate,
statistic and distribution: their numbers judge nothing.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Iterable, Sequence

import numpy as np

from handsim.report.records import STATUSES, natural_key, number
from handsim.runner.records import record_valid

GROUP_KEYS: tuple[str, ...] = ("object", "grasp", "actor")
KINDS: tuple[str, ...] = ("graspdb", "tzionas", "arctic")
DISTRIBUTIONS: dict[str, str] = {
    "max_penetration_mm": "Max penetration per trial (mm)",
    "max_slip_mm": "Max slip per glove trial (mm)",
    "max_drift_mm": "Max object drift per recorded trial (mm)",
    "mean_tracking_error_deg": "Mean tracking error per trial (deg)",
}
RANKING = (
    "Errors first, then diverged runs, then trials flagged not valid, then trials whose object was lost "
    "(glove trials not held, recorded trials whose object left its track), then trials whose hold or track "
    "could not be judged, then every other trial; within each of these tiers by max penetration (deepest "
    "first), then by max drift (largest first), then by trial id."
)
_TIERS = ("error", "diverged", "flagged", "not held", "not judged", "ok")
OUTCOMES: tuple[str, ...] = (
    "held", "not held", "followed", "lost", "not judged", "ran", "flagged", "diverged", "error",
)  # fmt: skip
"""How a trial ended: its object held or not (glove trials), followed or lost (recorded-object trials: the
verdict on its track), its hold or track not judged (with the reason: too short a window after release, an
infeasible placement, no manipulated frames …), ran without a hold or track verdict, ran but flagged not
valid (a plausibility flag: its numbers judge nothing), diverged, failed."""
TRACK_OUTCOMES = ("followed", "lost", "not judged")
"""The verdicts on a recorded object's track (the summary's ``track``)."""
ROBUST = 0.8
"""A held trial counts as robustly held when at least this fraction of its robustness ensemble held."""


def summary_value(record: dict, key: str) -> float | None:
    """A finite number from the record's summary, or None."""
    return number((record.get("summary") or {}).get(key))


def held(record: dict) -> bool | None:
    """Whether the glove trial held its object: the summary's ``held`` (else the hold outcome's), or None."""
    value = (record.get("summary") or {}).get("held")
    if value is None:
        value = (record.get("hold") or {}).get("held")
    return value if isinstance(value, bool) else None


def track(record: dict) -> str | None:
    """The verdict on a recorded object's track (:data:`TRACK_OUTCOMES`), or None.

    None: no verdict (a glove or hand-only trial, or a record written before the verdict existed).
    """
    value = (record.get("summary") or {}).get("track")
    return value if value in TRACK_OUTCOMES else None


def followed(record: dict) -> bool | None:
    """Whether the recorded object followed its track: True, False (lost), or None (not judged, none)."""
    value = track(record)
    return None if value in (None, "not judged") else value == "followed"


def hold_judged(record: dict) -> bool:
    """The trial has a hold outcome (a glove trial) that was judged (held or not held)."""
    return held(record) is not None


def has_hold(record: dict) -> bool:
    """The trial has a hold outcome, judged or not (a glove trial that ran)."""
    return record.get("hold") is not None


def quality_value(record: dict, key: str) -> float | None:
    """A finite number from the record's ``trajectory_quality``, or None."""
    return number((record.get("trajectory_quality") or {}).get(key))


def meta_value(record: dict, key: str) -> str | None:
    """A ``meta`` field as text, or None when absent or null."""
    value = (record.get("meta") or {}).get(key)
    return None if value is None else str(value)


def count(value: float | None) -> int | None:
    """A count as a whole number, or None."""
    return None if value is None else round(value)


def percentile(values: Sequence[float], q: float) -> float | None:
    """The ``q``-th percentile (0–100, linear interpolation between order statistics), None for none."""
    return float(np.percentile(np.asarray(values, dtype=float), q)) if len(values) else None


def _stat(values: Sequence[float], fn: Callable[[np.ndarray], float]) -> float | None:
    return float(fn(np.asarray(values, dtype=float))) if len(values) else None


def _present(values: Iterable[float | None]) -> list[float]:
    return [v for v in values if v is not None]


def _total(values: Iterable[float | None]) -> int | None:
    present = _present(values)
    return int(sum(present)) if present else None


def outcome(record: dict) -> str:
    """The trial's entry of :data:`OUTCOMES`."""
    if record["status"] != "ok":
        return record["status"]
    if not record_valid(record):
        return "flagged"
    value = held(record)
    if value is None:
        return "not judged" if has_hold(record) else track(record) or "ran"
    return "held" if value else "not held"


def invalid_reasons(record: dict) -> list[str]:
    """The reasons of the flags that make the trial not valid (empty for a valid one)."""
    return [
        str(f.get("reason")) for f in record.get("flags") or [] if isinstance(f, dict) and f.get("invalid")
    ]


def outcome_counts(records: Sequence[dict], key: Callable[[dict], str | None]) -> dict[str, dict[str, int]]:
    """Trials per :data:`OUTCOMES` entry for each value of ``key(record)`` (values in natural order)."""
    counts: dict[str, dict[str, int]] = {}
    for record in records:
        value = key(record)
        label = "—" if value is None else value
        counts.setdefault(label, dict.fromkeys(OUTCOMES, 0))[outcome(record)] += 1
    return {k: counts[k] for k in sorted(counts, key=natural_key)}


HANDS = ("right", "left")
"""The hands of a two-hand (ARCTIC, Tzionas) record, whose summary has ``<hand>/<key>`` numbers."""
HAND_ROW_KEYS = (
    *(f"{h}/{k}" for h in HANDS for k in ("contact_frames", "max_penetration_mm", "mean_tracking_error_deg")),
    "max_rotation_drift_deg",
    "max_articulation_drift_deg",
)
"""What a two-hand trial's row adds: each hand's contacts, penetration and tracking, the object's drift."""


def has_hands(record: dict) -> bool:
    """The record is of a two-hand scene (its summary has per-hand numbers)."""
    return f"{HANDS[0]}/contact_frames" in (record.get("summary") or {})


def trial_row(record: dict) -> dict:
    """The key facts and metrics of one trial (JSON-ready; ``None`` where a value does not exist)."""
    error = record.get("error") or {}
    diverged = record.get("diverged") or {}
    warnings = record.get("warnings") or []
    return {
        "id": record["id"],
        "kind": record.get("kind"),
        "status": record["status"],
        "outcome": outcome(record),
        **{key: meta_value(record, key) for key in ("object", "grasp", "actor", "scenario")},
        "frames": count(summary_value(record, "frames")),
        "duration_s": summary_value(record, "duration_s"),
        "held": held(record),
        "hold_reason": (record.get("hold") or {}).get("reason"),
        "track": track(record),
        "track_reason": (record.get("summary") or {}).get("track_reason") if track(record) else None,
        "track_followed_fraction": summary_value(record, "track_followed_fraction"),
        "hold_robustness": summary_value(record, "hold_robustness"),
        "fit_fraction": summary_value(record, "fit_fraction"),
        "self_penetration_at_closure_mm": summary_value(record, "self_penetration_at_closure_mm"),
        "valid": record_valid(record),
        "flags": [str(f.get("code")) for f in record.get("flags") or [] if isinstance(f, dict)],
        "time_held_s": summary_value(record, "time_held_s"),
        "max_slip_mm": summary_value(record, "max_slip_mm"),
        "max_penetration_mm": summary_value(record, "max_penetration_mm"),
        "p95_penetration_mm": summary_value(record, "p95_penetration_mm"),
        "max_self_penetration_mm": summary_value(record, "max_self_penetration_mm"),
        "mean_drift_mm": summary_value(record, "mean_drift_mm"),
        "max_drift_mm": summary_value(record, "max_drift_mm"),
        "mean_tracking_error_deg": summary_value(record, "mean_tracking_error_deg"),
        "max_tracking_error_deg": summary_value(record, "max_tracking_error_deg"),
        "limit_violations": count(quality_value(record, "limit_violations")),
        "gaps_filled": count(quality_value(record, "gaps_filled")),
        "warnings": len(warnings),
        "diverged_at_step": count(number(diverged.get("step"))),
        "error_type": error.get("type"),
        **({k: summary_value(record, k) for k in HAND_ROW_KEYS} if has_hands(record) else {}),
    }


def group_stats(records: Sequence[dict]) -> dict:
    """Statistics over a group of trials.

    Returns:
        ``trials`` and counts per status, and ``flagged`` (trials flagged not valid, of any status: left out
        of everything below but the totals); ``held`` of ``hold_judged`` (valid glove trials whose hold was
        judged: those not judged are counted in ``not_judged`` and left out of the rates) and
        ``hold_rate``; ``followed`` of ``track_judged`` (valid recorded-object trials whose track was judged;
        those not judged are counted in ``not_judged`` too) and ``follow_rate``; ``robust_held`` (held, with
        at least :data:`ROBUST` of the robustness ensemble held) and ``robustness_mean`` (over judged trials
        with an ensemble); ``slip_median_mm``/``slip_max_mm`` over each trial's max slip;
        ``penetration_p50_mm``/``_p95_mm``/``_max_mm`` over each trial's max penetration;
        ``drift_mean_mm`` (mean of each trial's mean drift) and ``drift_max_mm``; totals of
        ``limit_violations`` and ``gaps_filled`` over every trial (None if no trial reports them).
    """
    status = Counter(r["status"] for r in records)
    valid = [r for r in records if record_valid(r)]
    holds = [h for h in map(held, valid) if h is not None]
    judged = [r for r in valid if hold_judged(r)]
    follows = [f for f in map(followed, valid) if f is not None]
    robustness = _present(summary_value(r, "hold_robustness") for r in judged)
    slip = _present(summary_value(r, "max_slip_mm") for r in valid)
    penetration = _present(summary_value(r, "max_penetration_mm") for r in valid)
    drift_mean = _present(summary_value(r, "mean_drift_mm") for r in valid)
    drift_max = _present(summary_value(r, "max_drift_mm") for r in valid)
    return {
        "trials": len(records),
        "ok": status["ok"],
        "diverged": status["diverged"],
        "errors": status["error"],
        "flagged": len(records) - len(valid),
        "held": sum(holds),
        "hold_judged": len(holds),
        "hold_rate": sum(holds) / len(holds) if holds else None,
        "followed": sum(follows),
        "track_judged": len(follows),
        "follow_rate": sum(follows) / len(follows) if follows else None,
        "not_judged": sum(
            1 for r in valid if (has_hold(r) and not hold_judged(r)) or track(r) == "not judged"
        ),
        "robust_held": sum(
            1 for r in judged if held(r) and (summary_value(r, "hold_robustness") or 0.0) >= ROBUST
        ),
        "robustness_mean": _stat(robustness, np.mean),
        "slip_median_mm": _stat(slip, np.median),
        "slip_max_mm": _stat(slip, np.max),
        "penetration_p50_mm": percentile(penetration, 50),
        "penetration_p95_mm": percentile(penetration, 95),
        "penetration_max_mm": _stat(penetration, np.max),
        "drift_mean_mm": _stat(drift_mean, np.mean),
        "drift_max_mm": _stat(drift_max, np.max),
        "limit_violations": _total(quality_value(r, "limit_violations") for r in records),
        "gaps_filled": _total(quality_value(r, "gaps_filled") for r in records),
    }


def group_table(records: Sequence[dict], key: str) -> list[dict]:
    """One row of :func:`group_stats` per value of ``meta[key]`` (trials without a value: group None).

    Rows are in natural order of the group value, the None group last; an empty list when no trial has a
    value for ``key``.
    """
    groups: dict[str | None, list[dict]] = {}
    for record in records:
        groups.setdefault(meta_value(record, key), []).append(record)
    if set(groups) <= {None}:
        return []
    order = sorted((g for g in groups if g is not None), key=natural_key) + ([None] if None in groups else [])
    return [{"group": g, **group_stats(groups[g])} for g in order]


def overview(records: Sequence[dict], run: dict | None) -> dict:
    """Trial counts by status and kind, and what discovery found besides trials."""
    discovery = (run or {}).get("discovery") or {}
    by_kind: dict[str, dict[str, int]] = {}
    for record in records:
        counts = by_kind.setdefault(str(record.get("kind")), dict.fromkeys(STATUSES, 0))
        counts[record["status"]] += 1
    kinds = [k for k in KINDS if k in by_kind] + sorted(set(by_kind) - set(KINDS))
    discovered = number(discovery.get("trials"))
    return {
        "dataset": (run or {}).get("dataset"),
        "trials": len(records),
        "discovered_trials": None if discovered is None else int(discovered),
        "by_status": {s: sum(1 for r in records if r["status"] == s) for s in STATUSES},
        "by_kind": {k: by_kind[k] for k in kinds},
        "companion": list(discovery.get("companion") or []),
        "unknown": list(discovery.get("unknown") or []),
    }


def _tier(record: dict) -> int:
    if record["status"] == "error":
        return 0
    if record["status"] == "diverged":
        return 1
    if not record_valid(record):
        return 2
    value = held(record)
    if value is False or followed(record) is False:
        return 3
    return 4 if value is None and (has_hold(record) or track(record) == "not judged") else 5


def _reason(record: dict) -> str:
    tier = _tier(record)
    if tier == 0:
        error = record.get("error") or {}
        message = str(error.get("message") or "").strip().splitlines()
        return f"{error.get('type') or 'unknown error'}" + (f": {message[0]}" if message else "")
    if tier == 1:
        diverged = record.get("diverged") or {}
        where = f" at step {diverged['step']}" if diverged.get("step") is not None else ""
        return f"MuJoCo {diverged.get('name') or 'divergence'}{where}"
    if tier == 2:
        return "not valid: " + ("; ".join(invalid_reasons(record)) or "flagged")
    parts = []
    verdict = (record.get("summary") or {}).get("track_reason") if track(record) else None
    if tier == 3 and has_hold(record):
        reason = (record.get("hold") or {}).get("reason")
        parts.append(f"object lost: {reason}" if reason else "object not held")
    elif tier == 3:
        parts.append(f"object {verdict}" if verdict else "object lost")
    if tier == 4:
        parts.append(str((record.get("hold") or {}).get("reason") or verdict or "hold not judged"))
    no_object = (record.get("summary") or {}).get("hold_reason") if not has_hold(record) else None
    if no_object:  # a hand-only trial: why its hold and drift are not judged
        parts.append(str(no_object))
    penetration = summary_value(record, "max_penetration_mm")
    if penetration is not None:
        parts.append(f"max penetration {penetration:.2f} mm")
    self_penetration = summary_value(record, "max_self_penetration_mm")
    if self_penetration is not None:
        parts.append(f"max self-penetration {self_penetration:.2f} mm")
    drift = summary_value(record, "max_drift_mm")
    if drift is not None:
        parts.append(f"max drift {drift:.1f} mm")
    return "; ".join(parts) or "no metrics"


def rank(records: Sequence[dict]) -> list[dict]:
    """Trials worst first (see :data:`RANKING`), each with its rank (1 = worst), tier and a reason."""

    def key(record: dict) -> tuple:
        penetration = summary_value(record, "max_penetration_mm")
        drift = summary_value(record, "max_drift_mm")
        return (
            _tier(record),
            -(penetration if penetration is not None else -math.inf),
            -(drift if drift is not None else -math.inf),
            natural_key(record["id"]),
        )

    ordered = sorted(records, key=key)
    return [
        {"rank": i, "id": r["id"], "tier": _TIERS[_tier(r)], "reason": _reason(r)}
        for i, r in enumerate(ordered, start=1)
    ]


def distributions(records: Sequence[dict]) -> dict[str, list[float]]:
    """Per-trial values of each :data:`DISTRIBUTIONS` metric.

    Trials without the value, and trials flagged not valid, are left out.
    """
    valid = [r for r in records if record_valid(r)]
    return {key: _present(summary_value(r, key) for r in valid) for key in DISTRIBUTIONS}


def distinct(values: Iterable[object]) -> list[dict]:
    """Distinct JSON values with how many times each occurs, in order of first occurrence."""
    seen: list[dict] = []
    for value in values:
        for entry in seen:
            if entry["value"] == value:
                entry["trials"] += 1
                break
        else:
            seen.append({"value": value, "trials": 1})
    return seen
