"""The Markdown report (GitHub tables): overview, group tables, worst trials, all trials, reproducibility."""

from __future__ import annotations

import json
import shlex
from collections.abc import Callable, Sequence
from urllib.parse import quote

from handsim.report import fmt
from handsim.report.aggregate import GROUP_KEYS
from handsim.report.columns import GROUP_COLUMNS, HAND_COLUMNS, TRIAL_COLUMNS, Column, shown
from handsim.report.files import group_files
from handsim.report.records import STATUSES

HTML_NAME = "report.html"
GROUP_TITLES = {"object": "By object", "grasp": "By grasp type", "actor": "By actor"}


def cell(text: object) -> str:
    """Text safe inside a GitHub table cell (pipes escaped, line breaks removed)."""
    return str(text).replace("\\", "\\\\").replace("|", "\\|").replace("\r", " ").replace("\n", " ")


def link_text(text: object) -> str:
    """Text safe inside a Markdown link label."""
    return cell(text).replace("[", "\\[").replace("]", "\\]")


def _table(headers: Sequence[str], rows: Sequence[Sequence[str]], numeric: Sequence[bool]) -> list[str]:
    lines = ["| " + " | ".join(cell(h) for h in headers) + " |"]
    lines.append("|" + "|".join("---:" if n else "---" for n in numeric) + "|")
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return lines


def _column_table(
    columns: Sequence[Column],
    rows: Sequence[dict],
    first: tuple[str, Callable[[dict], str]],
    total: dict | None,
) -> list[str]:
    body = [[first[1](r), *(cell(c.cell(r)) for c in columns)] for r in rows]
    if total is not None:
        body.append(["**all**", *(f"**{cell(c.cell(total))}**" for c in columns)])
    return _table([first[0], *(c.label for c in columns)], body, [False, *(c.numeric for c in columns)])


def _frames(trial: dict) -> str:
    renders = [p for p in trial["renders"] if p]
    return ", ".join(f"[{link_text(p.rsplit('/', 1)[-1])}]({quote(p)})" for p in renders) or fmt.MISSING


def _overview(summary: dict) -> list[str]:
    """The title, the run in one paragraph, and the dataset: trials by kind, companion and unknown files."""
    o = summary["overview"]
    out = [
        f"# handsim physics-plausibility report — {cell(fmt.text(summary['dataset']))}",
        "",
        f"{o['trials']} trials: {o['by_status']['ok']} ok, {o['by_status']['diverged']} diverged, "
        f"{o['by_status']['error']} errors; {summary['all']['flagged']} flagged not valid (left out of "
        "every rate and statistic). Metric spec "
        f"{', '.join(summary['metric_spec_versions']) or fmt.MISSING}. Plots, per-trial curves and frames: "
        f"[{HTML_NAME}]({HTML_NAME}). The terms (outcomes, hold rate, robustness, fit at, on track …) are "
        "defined in handsim's docs/concepts.md.",
        "",
        "## Dataset overview",
        "",
    ]
    if o["discovered_trials"] is not None and o["discovered_trials"] != o["trials"]:
        out += [f"Discovery found {o['discovered_trials']} trials; {o['trials']} have records.", ""]
    kind_rows = [
        [cell(k), *(str(v[s]) for s in STATUSES), str(sum(v.values()))] for k, v in o["by_kind"].items()
    ]
    out += [*_table(["kind", *STATUSES, "trials"], kind_rows, [False, True, True, True, True]), ""]
    for key, title in (("companion", "Companion files"), ("unknown", "Unknown files (not used)")):
        entries = o[key]
        out += [f"{title}: {len(entries) or 'none'}.", ""]
        out += [
            f"- `{cell(fmt.text(g.path))}`{cell(g.count_text())} — {cell(fmt.text(g.reason))}"
            for g in group_files(entries)
        ]
        out += [""] if entries else []
    return out


def _groups(summary: dict) -> list[str]:
    """One table per group-by field that some trial has, each with its total row."""
    out = ["## Groups", ""]
    group_columns = shown(GROUP_COLUMNS, summary["trials"])
    out += [f"- **{c.label}**: {c.help}" for c in group_columns if c.help] + [""]
    for key in GROUP_KEYS:
        rows = summary["groups"][key]
        if not rows:  # no trial has this field (no grasp type outside glove datasets): no table
            continue
        out += [f"### {GROUP_TITLES[key]}", ""]
        out += _column_table(group_columns, rows, (key, lambda r: cell(fmt.text(r["group"]))), summary["all"])
        out += [""]
    return out


def _trials(summary: dict) -> list[str]:
    """The worst trials first, then every trial, then the two-hand trials' per-hand numbers."""
    trials = {t["id"]: t for t in summary["trials"]}
    out = ["## Worst trials first", "", f"Ranking: {summary['ranking']}", ""]
    for w in summary["worst"]:
        t = trials[w["id"]]
        out.append(
            f"{w['rank']}. [{link_text(w['id'])}]({HTML_NAME}#{t['anchor']}) — **{t['outcome']}** — "
            f"{cell(w['reason'])} — frames: {_frames(t)}"
        )
    out += ["", "## All trials", ""]
    out += _column_table(
        shown(TRIAL_COLUMNS, summary["trials"]),
        summary["trials"],
        ("trial", lambda r: f"[{link_text(r['id'])}]({HTML_NAME}#{r['anchor']})"),
        None,
    )
    two_hands = [t for t in summary["trials"] if "right/contact_frames" in t]
    if two_hands:
        out += ["", "## Two-hand trials", ""]
        out += [f"- **{c.label}**: {c.help}" for c in HAND_COLUMNS if c.help] + [""]
        out += _column_table(
            HAND_COLUMNS,
            two_hands,
            ("trial", lambda r: f"[{link_text(r['id'])}]({HTML_NAME}#{r['anchor']})"),
            None,
        )
    return out


def _reproducibility(summary: dict) -> list[str]:
    """The command line, metric spec and versions the records were made with, and the records' notes."""
    out = ["", "## Reproducibility", ""]
    command = summary["command"]
    if isinstance(command, list):
        out += ["Command line:", "", "```", shlex.join(str(c) for c in command), "```", ""]
    out += [f"Metric spec version: {', '.join(summary['metric_spec_versions']) or fmt.MISSING}.", ""]
    for v in summary["versions"]:
        out += [
            f"Versions of {v['trials']} trial(s):",
            "",
            "```json",
            json.dumps(v["value"], indent=2, sort_keys=True),
        ]
        out += ["```", ""]
    if summary["notes"]:
        out += ["Notes on the records:", ""] + [f"- {n}" for n in summary["notes"]] + [""]
    out += ["Re-render from the records alone: `handsim report --render-only OUT/`.", ""]
    return out


def render_markdown(summary: dict) -> str:
    """The Markdown report of ``summary`` (:func:`~handsim.report.summary.build_summary`)."""
    return "\n".join([*_overview(summary), *_groups(summary), *_trials(summary), *_reproducibility(summary)])
