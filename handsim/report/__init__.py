"""Reports of dataset runs, rendered from the run's records alone.

``render_report(OUT)`` reads ``OUT/records.jsonl`` and ``OUT/run.json`` and writes ``OUT/report.html`` (one
self-contained page: inline CSS, SVG plots, frames as ``data:`` URIs, no scripts), ``OUT/report.md`` and
``OUT/summary.json``. Modules: :mod:`~handsim.report.records` (reading), :mod:`~handsim.report.aggregate`
(numbers), :mod:`~handsim.report.summary` (the JSON summary), :mod:`~handsim.report.charts` (SVG charts),
:mod:`~handsim.report.html_doc`, :mod:`~handsim.report.html_trial` and :mod:`~handsim.report.html_curves`
(HTML), :mod:`~handsim.report.markdown` (Markdown).
"""

from handsim.report.records import RunRecords, read_run
from handsim.report.render import ReportFiles, render_report
from handsim.report.summary import build_summary

__all__ = ["ReportFiles", "RunRecords", "build_summary", "read_run", "render_report"]
