"""Counts: histograms of per-trial values and horizontal stacked bars per category."""

from __future__ import annotations

import math
from collections.abc import Sequence
from html import escape

from handsim.report.charts.axes import (
    BOTTOM,
    CHAR_W,
    PALETTE,
    RIGHT,
    TOP,
    Plot,
    axis_labels,
    empty_chart,
    finite,
    left_margin,
    legend,
    line,
    nice_step,
    open_svg,
    rect,
    text,
    tick_label,
    ticks,
    widen,
    x_axis,
    y_axis,
)


def _median(data: Sequence[float]) -> float:
    n = len(data)
    return data[n // 2] if n % 2 else (data[n // 2 - 1] + data[n // 2]) / 2


def _short(value: float) -> str:
    """Three significant digits, without an exponent below 1000."""
    return f"{value:.0f}" if abs(value) >= 100 else f"{value:.3g}"


def bin_counts(values: Sequence[float]) -> tuple[list[float], list[int]]:
    """Round bin edges and the count of ``values`` in each bin.

    About √n bins (4 to 24) whose width is a round number (:func:`~handsim.report.charts.axes.nice_step`);
    a bin holds ``edge_k ≤ v < edge_k+1``, the last one its right edge too.

    Returns:
        The edges (one more than the bins) and the counts.
    """
    data = sorted(values)
    lo, hi = widen(data[0], data[-1])
    step = nice_step(hi - lo, min(24, max(4, math.ceil(math.sqrt(len(data))))))
    start = math.floor(lo / step + 1e-9) * step
    count = max(1, math.floor((hi - start) / step + 1e-9) + 1)
    counts = [0] * count
    for v in data:
        counts[min(count - 1, max(0, math.floor((v - start) / step + 1e-9)))] += 1
    return [round(start + k * step, 12) for k in range(count + 1)], counts


def histogram(
    values: Sequence[float],
    *,
    title: str,
    x_label: str,
    colour: str = PALETTE[0],
    width: float = 420,
    height: float = 220,
) -> str:
    """A histogram of ``values`` (:func:`bin_counts`) with the median marked.

    Returns:
        The ``<svg>`` element; a chart saying "no values" when ``values`` has no finite value.
    """
    data = sorted(float(v) for v in values if finite(v))
    if not data:
        return empty_chart(title, "no values", width)
    edges, counts = bin_counts(data)
    step = edges[1] - edges[0]
    y_ticks = [t for t in ticks(0, max(counts), 4) if float(t).is_integer()]
    left = left_margin([tick_label(v, 1.0) for v in y_ticks])
    plot = Plot(left, width - RIGHT, TOP + 10, height - BOTTOM, edges[0], edges[-1], 0.0, y_ticks[-1])
    parts = open_svg(width, height, title)
    parts += y_axis(plot, y_ticks)
    for k, n in enumerate(counts):
        if n:
            x0, x1 = plot.sx(edges[k]) + 0.5, plot.sx(edges[k + 1]) - 0.5
            tip = f"{tick_label(edges[k], step)}–{tick_label(edges[k + 1], step)}: {n}"
            parts.append(rect("bar", x0, plot.sy(n), x1 - x0, plot.bottom - plot.sy(n), colour, tip))
    parts += x_axis(plot, edges[:: math.ceil(len(edges) / 8)])
    parts += axis_labels(plot, x_label, "trials")
    median = _median(data)
    x = plot.sx(median)
    parts.append(line("ref", x, x, plot.top, plot.bottom))
    right_half = x > (plot.left + plot.right) / 2
    label = f"median {_short(median)} · n = {len(data)}"
    parts.append(
        text("marker", x - 3 if right_half else x + 3, plot.top - 4, label, "end" if right_half else "start")
    )
    return "".join([*parts, "</svg>"])


def stacked_bars(
    categories: Sequence[str],
    stacks: Sequence[tuple[str, Sequence[int], str]],
    *,
    title: str,
    x_label: str,
    width: float = 560,
) -> str:
    """Horizontal bars, one per category, each stacked from ``stacks`` (label, count per category, colour).

    Returns:
        The ``<svg>`` element; a chart saying "no trials" when there is no category.
    """
    if not categories:
        return empty_chart(title, "no trials", width)
    totals = [sum(s[1][i] for s in stacks) for i in range(len(categories))]
    names = [c if len(c) <= 28 else c[:27] + "…" for c in categories]
    left = min(220.0, 16.0 + max(len(n) for n in names) * CHAR_W)
    row = 22.0
    x_ticks = [t for t in ticks(0, max(max(totals), 1), 5) if float(t).is_integer()]
    plot = Plot(left, width - RIGHT - 30, TOP, TOP + row * len(categories), 0.0, x_ticks[-1], 0.0, 1.0)
    used = [(label, colour) for label, counts, colour in stacks if any(counts)]
    keys, keys_h = legend(used, left, width, plot.bottom + 40)
    parts = open_svg(width, plot.bottom + 40 + keys_h, title)
    parts += [line("grid", plot.sx(v), plot.sx(v), plot.top, plot.bottom) for v in x_ticks]
    parts += x_axis(plot, x_ticks)
    parts.append(text("label", (plot.left + plot.right) / 2, plot.bottom + 32, escape(x_label), "middle"))
    for i, (name, full) in enumerate(zip(names, categories, strict=True)):
        y = plot.top + i * row
        parts.append(
            text("tick", left - 6, y + row / 2 + 4, f"<title>{escape(full)}</title>{escape(name)}", "end")
        )
        x = 0.0
        for label, counts, colour in stacks:
            n = counts[i]
            if n:
                tip = f"{full}: {n} {label}"
                parts.append(
                    rect("bar", plot.sx(x), y + 3, plot.sx(x + n) - plot.sx(x), row - 6, colour, tip)
                )
                x += n
        parts.append(text("tick", plot.sx(x) + 4, y + row / 2 + 4, str(totals[i])))
    parts.append(line("axis", left, left, plot.top, plot.bottom))
    parts += keys
    return "".join([*parts, "</svg>"])
