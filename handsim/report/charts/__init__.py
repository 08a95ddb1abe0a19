"""Dependency-free SVG charts for the HTML report: line and stacked-area charts, histograms, bar charts.

Each chart function returns one ``<svg>`` element as text, to be inlined into an HTML page whose
stylesheet styles the classes used here (``chart``, ``grid``, ``axis``, ``tick``, ``label``, ``title``,
``legend``, ``marker``, ``ref``, ``span``, ``line``, ``area``, ``bar``, ``empty``). Coordinates are written
with one decimal, so the same data gives the same bytes. Missing values (None or NaN) break a line instead
of being drawn as zero.
"""

from handsim.report.charts.axes import PALETTE, Markers, empty_chart, nice_step, tick_label, ticks
from handsim.report.charts.bars import histogram, stacked_bars
from handsim.report.charts.lines import Series, area_chart, decimate, line_chart

__all__ = [
    "PALETTE",
    "Markers",
    "Series",
    "area_chart",
    "decimate",
    "empty_chart",
    "histogram",
    "line_chart",
    "nice_step",
    "stacked_bars",
    "tick_label",
    "ticks",
]
