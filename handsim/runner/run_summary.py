"""What a dataset run did, counted from its records: trials by status, the hold rate, the failures' errors.

:class:`RunSummary` is what :func:`handsim.runner.execute.run_dataset` returns; :func:`records_line` and
:func:`failure_counts` say the same of any run's records (``handsim report`` uses them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from handsim.runner.records import record_valid


@dataclass(frozen=True)
class RunSummary:
    """What a dataset run did.

    Attributes:
        out: The output folder.
        trials: Trials selected for this run.
        skipped: Of those, already recorded before this call (resumed).
        ran: Ids of the trials run by this call, in the order they finished.
        ok: Selected trials whose record says ``ok``.
        diverged: … ``diverged``.
        failed: … ``error``.
        flagged: Of the ``ok`` and ``diverged`` ones, those flagged not valid (``summary["valid"]`` false).
        held: Valid glove trials whose object was held through the hold window.
        hold_trials: Valid glove trials whose hold was judged (held or not held): the hold rate's
            denominator.
        notes: What was repaired or skipped (a truncated records line …).
        wall_s: Wall-clock time of this call, s.
        failures: The failed trials' errors (:func:`failure_counts`): (error type, trials, first message),
            most frequent first.
        not_judged: Valid glove trials whose hold was not judged (``held`` None: too short a window after
            the release, no feasible placement …); in no rate.
    """

    out: str
    trials: int
    skipped: int
    ran: tuple[str, ...]
    ok: int
    diverged: int
    failed: int
    flagged: int
    held: int
    hold_trials: int
    notes: tuple[str, ...]
    wall_s: float
    failures: tuple[tuple[str, int, str], ...] = ()
    not_judged: int = 0

    @property
    def all_failed(self) -> bool:
        """Every selected trial (one at least) has an ``error`` record: the run produced no result."""
        return self.trials > 0 and self.failed == self.trials

    def line(self) -> str:
        """One line for people: trial counts by status and the hold rate."""
        keys = ("ok", "diverged", "failed", "flagged", "held", "hold_trials", "not_judged")
        counts = {k: getattr(self, k) for k in keys}
        return _line(self.trials, counts)


def failure_counts(records: Sequence[dict]) -> tuple[tuple[str, int, str], ...]:
    """The errors of the failed trials among ``records``, counted by exception type.

    Args:
        records: Records (any status).

    Returns:
        One (error type, trials, first line of the first such trial's message) per type, most frequent
        first (ties by type name).
    """
    found: dict[str, list] = {}
    for record in records:
        if record["status"] != "error":
            continue
        error = record.get("error") or {}
        lines = str(error.get("message") or "").strip().splitlines()
        entry = found.setdefault(str(error.get("type") or "unknown error"), [0, lines[0] if lines else ""])
        entry[0] += 1
    ordered = sorted(found.items(), key=lambda item: (-item[1][0], item[0]))
    return tuple((kind, n, first) for kind, (n, first) in ordered)


def _line(trials: int, counts: dict) -> str:
    text = f"{trials} trials: {counts['ok']} ok, {counts['diverged']} diverged, {counts['failed']} failed"
    if counts["flagged"]:
        text += f" ({counts['flagged']} flagged not valid, left out of the rates)"
    if counts["hold_trials"]:
        rate = 100.0 * counts["held"] / counts["hold_trials"]
        text += f"; held {counts['held']} of {counts['hold_trials']} judged glove trials ({rate:.0f} %)"
    if counts["not_judged"]:
        text += f"; {counts['not_judged']} glove trials not judged (left out of the hold rate)"
    return text


def records_line(records: Sequence[dict]) -> str:
    """One line for people about a run's records: trial counts by status and the hold rate."""
    return _line(len(records), status_counts(records, {r["id"] for r in records}))


def status_counts(records: Sequence[dict], ids: set[str]) -> dict:
    """The counts of :class:`RunSummary` over the records of the trials ``ids``.

    Returns:
        ``ok``, ``diverged``, ``failed``, ``flagged`` (not valid), ``held``, ``hold_trials`` (judged) and
        ``not_judged`` (glove trials whose hold was not judged).
    """
    mine = [r for r in records if r["id"] in ids]
    valid = [r for r in mine if record_valid(r)]
    outcomes = [r["summary"]["held"] for r in valid if r.get("summary") and "held" in r["summary"]]
    held = [h for h in outcomes if h is not None]
    return {
        "ok": sum(r["status"] == "ok" for r in mine),
        "diverged": sum(r["status"] == "diverged" for r in mine),
        "failed": sum(r["status"] == "error" for r in mine),
        "flagged": len(mine) - len(valid),
        "held": sum(bool(h) for h in held),
        "hold_trials": len(held),
        "not_judged": len(outcomes) - len(held),
    }
