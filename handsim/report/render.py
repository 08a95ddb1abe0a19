"""Render a run's report files from its records: ``report.html``, ``report.md`` and ``summary.json``."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from handsim.files import write_atomic
from handsim.report.frames import DEFAULT_EMBED_BUDGET, FrameBudget
from handsim.report.html_doc import render_html
from handsim.report.markdown import HTML_NAME, render_markdown
from handsim.report.records import read_run
from handsim.report.summary import build_summary

MARKDOWN_NAME = "report.md"
JSON_NAME = "summary.json"


@dataclass(frozen=True)
class ReportFiles:
    """The files a report consists of.

    Attributes:
        html: The self-contained HTML page.
        markdown: The Markdown version (tables and worst trials; links to the HTML and the frames).
        json: The machine-readable summary.
        notes: What reading the records had to decide (a cut-off line, a value the report cannot use …),
            also listed in the report under "Notes on the records".
    """

    html: Path
    markdown: Path
    json: Path
    notes: tuple[str, ...] = ()


def render_report(out_dir: str | Path, *, embed_budget: int = DEFAULT_EMBED_BUDGET) -> ReportFiles:
    """Render the report of a dataset run from its records alone (no simulation).

    The same records give byte-identical files: records are ordered by trial id, and nothing but what the
    records and ``run.json`` carry goes into the files (no clock, no paths of this machine other than
    recorded ones).

    Args:
        out_dir: The folder ``handsim report DATASET -o OUT`` wrote (``records.jsonl``, ``run.json``,
            ``frames/``); the report files are written there.
        embed_budget: Bytes of rendered PNG frames embedded into the HTML at most; frames past it are
            linked by their path relative to ``out_dir`` instead.

    Returns:
        The paths written, and the notes on reading the records.

    Raises:
        InputFileError: ``out_dir`` has no ``records.jsonl``.
        RecordsError: A record or ``run.json`` is malformed.
    """
    run = read_run(out_dir)
    summary = build_summary(run)
    files = ReportFiles(
        html=run.out_dir / HTML_NAME,
        markdown=run.out_dir / MARKDOWN_NAME,
        json=run.out_dir / JSON_NAME,
        notes=run.notes,
    )
    text = json.dumps(summary, indent=2, sort_keys=True, ensure_ascii=False, allow_nan=False) + "\n"
    write_atomic(files.json, text.encode("utf-8"))
    write_atomic(files.markdown, render_markdown(summary).encode("utf-8"))
    write_atomic(files.html, render_html(run, summary, FrameBudget(embed_budget)).encode("utf-8"))
    return files
