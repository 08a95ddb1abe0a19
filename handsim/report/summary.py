"""The machine-readable summary of a run (``summary.json``); the HTML and Markdown writers render it too."""

from __future__ import annotations

import hashlib
import re
from collections.abc import Sequence
from typing import cast

from handsim.report.aggregate import (
    GROUP_KEYS,
    RANKING,
    distinct,
    group_stats,
    group_table,
    overview,
    rank,
    trial_row,
)
from handsim.report.records import RunRecords
from handsim.runner.records import json_ready

SUMMARY_SCHEMA = 1
WORST_LISTED = 20


def trial_anchors(ids: Sequence[str]) -> dict[str, str]:
    """A unique HTML id per trial id: ``trial-`` and a slug of the id (``Models/20`` → ``trial-models-20``).

    Ids whose slugs coincide get the first 8 hex digits of the id's SHA-1 appended.
    """
    slugs = {i: re.sub(r"[^a-z0-9]+", "-", i.lower()).strip("-") or "trial" for i in ids}
    counts: dict[str, int] = {}
    for slug in slugs.values():
        counts[slug] = counts.get(slug, 0) + 1
    return {
        i: f"trial-{s}" + (f"-{hashlib.sha1(i.encode()).hexdigest()[:8]}" if counts[s] > 1 else "")
        for i, s in slugs.items()
    }


def _replay_metrics(record: dict) -> object:
    return ((record.get("parameters") or {}).get("replay") or {}).get("metrics")


def build_summary(run: RunRecords) -> dict:
    """Everything the report shows except per-trial curves and frames, JSON-ready.

    Args:
        run: The records and run description (:func:`~handsim.report.records.read_run`).

    Returns:
        ``overview``, ``all`` (statistics over every trial), ``groups`` (tables per object, grasp and
        actor), ``ranking`` (how ``worst`` and each trial's ``rank`` are ordered), ``worst`` (the first
        :data:`WORST_LISTED` trials of the ranking), ``trials`` (every trial: its key metrics, rank, reason
        and HTML anchor), the metric spec versions, the distinct software versions, the run's command and
        parameters, and notes on reading the records.
    """
    records = run.records
    ranking = rank(records)
    by_id = {entry["id"]: entry for entry in ranking}
    anchors = trial_anchors([r["id"] for r in records])
    trials = []
    for record in records:
        entry = by_id[record["id"]]
        renders = [r.get("path") for r in record.get("renders") or []]
        trials.append(
            {
                **trial_row(record),
                "rank": entry["rank"],
                "reason": entry["reason"],
                "anchor": anchors[record["id"]],
                "renders": renders,
            }
        )
    spec_versions = sorted(
        {str(r.get("metric_spec_version")) for r in records if r.get("metric_spec_version")}
    )
    info = run.run or {}
    summary = {
        "schema": SUMMARY_SCHEMA,
        "dataset": info.get("dataset"),
        "command": info.get("command"),
        "metric_spec_version": spec_versions[0] if len(spec_versions) == 1 else None,
        "metric_spec_versions": spec_versions,
        "metric_specs": distinct(_replay_metrics(r) for r in records),
        "versions": distinct(r.get("versions") for r in records),
        "run_versions": info.get("versions"),
        "run_parameters": info.get("parameters"),
        "overview": overview(records, run.run),
        "all": group_stats(records),
        "groups": {key: group_table(records, key) for key in GROUP_KEYS},
        "ranking": RANKING,
        "worst": ranking[:WORST_LISTED],
        "trials": trials,
        "notes": list(run.notes),
    }
    return cast(dict, json_ready(summary))
