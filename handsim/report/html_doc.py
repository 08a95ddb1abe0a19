"""The HTML report: one self-contained page (inline CSS and SVG, frames as ``data:`` URIs, no scripts)."""

from __future__ import annotations

from handsim.report import fmt
from handsim.report.aggregate import (
    DISTRIBUTIONS,
    GROUP_KEYS,
    OUTCOMES,
    distributions,
    meta_value,
    outcome_counts,
    summary_value,
)
from handsim.report.charts import PALETTE, histogram, stacked_bars
from handsim.report.columns import GROUP_COLUMNS, HAND_COLUMNS, TRIAL_COLUMNS, shown
from handsim.report.files import group_files
from handsim.report.frames import FrameBudget, load_frames
from handsim.report.html_repro import reproducibility
from handsim.report.html_trial import trial_section
from handsim.report.markup import badge, esc, link, simple_table, table
from handsim.report.records import STATUSES, RunRecords
from handsim.report.style import CSS, STATUS_COLOURS

GROUP_TITLES = {"object": "By object", "grasp": "By grasp type", "actor": "By actor"}
_NAV = (
    ("overview", "Overview"),
    ("groups", "Groups"),
    ("distributions", "Distributions"),
    ("worst", "Worst trials"),
    ("trials", "All trials"),
    ("reproducibility", "Reproducibility"),
)


def _outcome_chart(records: tuple[dict, ...], key, title: str) -> str:
    counts = outcome_counts(records, key)
    stacks = [(o, [counts[c][o] for c in counts], STATUS_COLOURS[o]) for o in OUTCOMES]
    return stacked_bars(list(counts), stacks, title=title, x_label="trials")


def _file_list(entries: list, title: str) -> str:
    if not entries:
        return f'<p class="note">{esc(title)}: none.</p>'
    rows = [[g.what(), fmt.text(g.reason)] for g in group_files(e or {} for e in entries)]
    return f"<h3>{esc(title)} ({len(entries)})</h3>" + simple_table(["path", "reason"], rows)


def _overview(run: RunRecords, summary: dict) -> str:
    o, total = summary["overview"], summary["all"]
    cards = [
        ("trials", str(o["trials"]), ""),
        ("ok", str(o["by_status"]["ok"]), "ok"),
        ("diverged", str(o["by_status"]["diverged"]), "diverged"),
        ("errors", str(o["by_status"]["error"]), "error"),
        ("flagged not valid", str(total["flagged"]), ""),
        ("hold rate", fmt.rate(total["held"], total["hold_judged"]), ""),
        ("follow rate", fmt.rate(total["followed"], total["track_judged"]), ""),
        ("max penetration mm", fmt.num(total["penetration_max_mm"]), ""),
    ]
    rates = {c.label for c in shown(GROUP_COLUMNS, summary["trials"])}  # a rate only where trials have it
    cards = [card for card in cards if card[0] not in ("hold rate", "follow rate") or card[0] in rates]
    cards_html = (
        '<div class="cards">'
        + "".join(
            f'<div class="card {c}"><div class="v">{esc(v)}</div><div class="k">{esc(k)}</div></div>'
            for k, v, c in cards
        )
        + "</div>"
    )
    discovered = o["discovered_trials"]
    coverage = ""
    if discovered is not None and discovered != o["trials"]:
        coverage = (
            f'<p class="reason">Discovery found {discovered} trials; {o["trials"]} have records '
            "(an unfinished run: rerun the same command to resume).</p>"
        )
    kind_rows = [[k, *(str(v[s]) for s in STATUSES), str(sum(v.values()))] for k, v in o["by_kind"].items()]
    notes = "".join(f"<li>{esc(n)}</li>" for n in summary["notes"])
    return (
        '<section class="block" id="overview"><h2>Dataset overview</h2>'
        + cards_html
        + coverage
        + '<div class="grid2"><div>'
        + simple_table(["kind", *STATUSES, "trials"], kind_rows, [False, True, True, True, True])
        + "</div><div>"
        + _outcome_chart(run.records, lambda r: r.get("kind"), "Outcome by kind")
        + "</div></div>"
        + _file_list(o["companion"], "Companion files (read with a trial)")
        + _file_list(o["unknown"], "Unknown files (not used)")
        + (f'<h3>Notes on the records</h3><ul class="plain">{notes}</ul>' if notes else "")
        + "</section>"
    )


_GROUP_NOTES = (
    (
        "hold rate",
        "Hold rate: glove trials whose object stayed in hand through the hold window, of those judged.",
    ),
    (
        "follow rate",
        "Follow rate: recorded-object trials whose object stayed within the tolerance of its recorded track "
        "over every frame the recording moves it, of those judged.",
    ),
    ("slip max mm", "Slip and penetration statistics are over each trial's maximum."),
    ("drift mean mm", "Drift mean is the mean of each trial's mean drift."),
)
"""The groups' note, a sentence per column it explains, each only where that column is shown."""


def _groups(run: RunRecords, summary: dict) -> str:
    columns = shown(GROUP_COLUMNS, summary["trials"])
    labels = {c.label for c in columns}
    explained = [text for label, text in _GROUP_NOTES if label in labels]
    if "slip max mm" not in labels:
        explained.append("Penetration statistics are over each trial's maximum.")
    parts = [
        '<section class="block" id="groups"><h2>Groups</h2>',
        f'<p class="note">{" ".join(explained)} Trials flagged not valid (a plausibility flag) are counted '
        "but left out of the rates and the statistics. Limit violations and gaps filled are totals over the "
        "group's recordings. Hover a header for its meaning.</p>",
    ]
    for key in GROUP_KEYS:
        rows = summary["groups"][key]
        if not rows:  # no trial has this field (no grasp type outside glove datasets): no table
            continue
        parts.append(f"<h3>{GROUP_TITLES[key]}</h3>")
        parts.append(
            table(columns, rows, first=(key, lambda r: esc(fmt.text(r["group"]))), total=summary["all"])
        )
        if key == "object":
            parts.append(_outcome_chart(run.records, lambda r: meta_value(r, "object"), "Outcome by object"))
    parts.append("</section>")
    return "".join(parts)


def _distributions(run: RunRecords) -> str:
    """A histogram per metric that some trial has (flagged ones too): no slip chart without glove trials."""
    values = distributions(run.records)
    charts = [
        histogram(values[key], title=title, x_label=title.rsplit("(", 1)[-1].rstrip(")"), colour=PALETTE[i])
        for i, (key, title) in enumerate(DISTRIBUTIONS.items())
        if any(summary_value(r, key) is not None for r in run.records)
    ]
    return (
        '<section class="block" id="distributions"><h2>Distributions</h2>'
        '<p class="note">One value per trial; trials without the metric (e.g. drift for glove trials) and '
        "trials flagged not valid are left out. The dashed line marks the median.</p>"
        '<div class="grid2">' + "".join(f"<div>{c}</div>" for c in charts) + "</div></section>"
    )


def _worst(summary: dict, anchors: dict[str, str], outcomes: dict[str, str]) -> str:
    items = "".join(
        f"<li>{link(anchors[w['id']], w['id'])} {badge(outcomes[w['id']])} — {esc(w['reason'])}</li>"
        for w in summary["worst"]
    )
    shown = len(summary["worst"])
    return (
        '<section class="block" id="worst"><h2>Worst trials first</h2>'
        f'<p class="note">Ranking: {esc(summary["ranking"])} The first {shown} of '
        f"{len(summary['trials'])} are listed; every trial's rank is on its section.</p>"
        f'<ol class="worst">{items}</ol></section>'
    )


def _index(summary: dict) -> str:
    return (
        '<section class="block" id="trials"><h2>All trials</h2>'
        '<p class="note">Click a trial for its curves, numbers and frames. Ordered by id.</p>'
        '<div class="scroll tall">'
        + table(
            shown(TRIAL_COLUMNS, summary["trials"]),
            summary["trials"],
            first=("trial", lambda r: link(r["anchor"], r["id"])),
        )
        + "</div>"
        + _two_hands(summary)
        + "</section>"
    )


def _two_hands(summary: dict) -> str:
    """The table of the two-hand trials: each hand's numbers and the object's drift ("" if none)."""
    rows = [t for t in summary["trials"] if "right/contact_frames" in t]
    if not rows:
        return ""
    return (
        "<h3>Two-hand trials</h3>"
        "<p class=\"note\">Each hand's contacts, penetration and tracking; the object's drift in position, "
        "rotation and articulation. Hover a header for its meaning.</p>"
        '<div class="scroll">'
        + table(HAND_COLUMNS, rows, first=("trial", lambda r: link(r["anchor"], r["id"])))
        + "</div>"
    )


def render_html(run: RunRecords, summary: dict, frame_budget: FrameBudget | None = None) -> str:
    """The report page.

    Args:
        run: The records and run description.
        summary: :func:`~handsim.report.summary.build_summary` of ``run``.
        frame_budget: How many bytes of rendered frames to embed (default
            :data:`~handsim.report.frames.DEFAULT_EMBED_BUDGET`); frames beyond it are linked.

    Returns:
        The HTML document.
    """
    budget = frame_budget or FrameBudget()
    anchors = {t["id"]: t["anchor"] for t in summary["trials"]}
    outcomes = {t["id"]: t["outcome"] for t in summary["trials"]}
    title = f"handsim report — {fmt.text(summary['dataset'])}"
    o = summary["overview"]
    spec = ", ".join(summary["metric_spec_versions"]) or fmt.MISSING
    sections = [
        trial_section(record, row, load_frames(record, run.out_dir, budget), len(run.records))
        for record, row in zip(run.records, summary["trials"], strict=True)
    ]
    return "".join(
        [
            '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{esc(title)}</title><style>{CSS}</style></head><body>",
            '<header class="top"><h1>handsim physics-plausibility report</h1>',
            f'<div class="sub">{esc(fmt.text(summary["dataset"]))} · {fmt.plural(o["trials"], "trial")} · '
            f"{o['by_status']['ok']} ok · {o['by_status']['diverged']} diverged · "
            f"{o['by_status']['error']} errors · metric spec {esc(spec)} · terms: handsim's "
            "docs/concepts.md</div></header>",
            '<nav class="toc">' + "".join(link(a, label) for a, label in _NAV) + "</nav><main>",
            _overview(run, summary),
            _groups(run, summary),
            _distributions(run),
            _worst(summary, anchors, outcomes),
            _index(summary),
            '<h2 id="trial-pages">Trials</h2>',
            *sections,
            reproducibility(run, summary),
            "</main><footer>Rendered from records.jsonl and run.json by handsim.report; no simulation was "
            "run to make this page.</footer></body></html>\n",
        ]
    )
