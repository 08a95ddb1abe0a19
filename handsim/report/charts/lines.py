"""Curves over time: line charts and stacked-area charts."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from handsim.report.charts.axes import PALETTE, Markers, empty_chart, f1, finite, time_frame


@dataclass(frozen=True)
class Series:
    """One curve.

    Attributes:
        label: Legend text.
        x: X values.
        y: Y values (None or NaN where there is no value).
        colour: CSS colour; None takes the next one of :data:`~handsim.report.charts.axes.PALETTE`.
    """

    label: str
    x: Sequence[float]
    y: Sequence[float | None]
    colour: str | None = None


def _points(x: Sequence[float], y: Sequence[float | None]) -> list[tuple[float, float | None]]:
    return [
        (float(a) if finite(a) else math.nan, float(b) if finite(b) else None)
        for a, b in zip(x, y, strict=True)
    ]


def keep_indices(y: Sequence[float | None], max_points: int) -> list[int]:
    """Indices of at most about ``max_points`` samples keeping each bucket's minimum and maximum.

    Buckets are equal runs of samples; a bucket with missing values keeps its first missing one, so gaps
    stay gaps. The choice is deterministic.
    """
    n = len(y)
    if n <= max_points:
        return list(range(n))
    buckets = max(1, max_points // 2)
    size = n / buckets
    kept: list[int] = []
    for b in range(buckets):
        lo, hi = round(b * size), round((b + 1) * size)
        valid = [i for i in range(lo, hi) if y[i] is not None]
        chosen = {lo, hi - 1} if not valid else {min(valid, key=y.__getitem__), max(valid, key=y.__getitem__)}
        if valid and len(valid) < hi - lo:
            chosen.add(next(i for i in range(lo, hi) if y[i] is None))
        kept.extend(sorted(chosen))
    return kept


def decimate(
    x: Sequence[float], y: Sequence[float | None], max_points: int
) -> list[tuple[float, float | None]]:
    """The points of a line :func:`keep_indices` keeps (missing values as None)."""
    points = _points(x, y)
    return [points[i] for i in keep_indices([p[1] for p in points], max_points)]


def flat_thinned(points: Sequence[tuple[str, str]]) -> list[tuple[str, str]]:
    """Pixel points (x, y text) without those inside a horizontal run (the same y as both neighbours).

    Drawing the result gives the same picture; step-like data (contact counts, zero penetration) shrinks
    to its corners.
    """
    return [
        p
        for i, p in enumerate(points)
        if i == 0 or i == len(points) - 1 or not (points[i - 1][1] == p[1] == points[i + 1][1])
    ]


def _path(points: Sequence[tuple[str, str]]) -> str:
    return "M" + "L".join(f"{x} {y}" for x, y in flat_thinned(points))


def line_chart(
    series: Sequence[Series],
    *,
    title: str,
    x_label: str,
    y_label: str,
    y_min: float | None = None,
    markers: Markers | None = None,
    width: float = 560,
    height: float = 240,
    max_points: int = 400,
) -> str:
    """A line chart with axes, ticks, grid, axis labels and (for several series) a legend.

    Args:
        series: The lines.
        title: Chart title.
        x_label: X axis label (with units).
        y_label: Y axis label (with units).
        y_min: Lowest y the axis must show (e.g. 0 for distances), or None to fit the data.
        markers: Reference lines and shaded ranges, or None.
        width: Width, px.
        height: Height of the plot area plus its axes, px (the legend adds rows below).
        max_points: Points drawn per series at most (see :func:`decimate`).

    Returns:
        The ``<svg>`` element; a chart saying "no data" when no series has a finite point.
    """
    lines = [decimate(s.x, s.y, max_points) for s in series]
    xs = [x for pts in lines for x, y in pts if y is not None and math.isfinite(x)]
    if not xs:
        return empty_chart(title, "no data", width)
    colours = [s.colour or PALETTE[i % len(PALETTE)] for i, s in enumerate(series)]
    keys = [(s.label, c) for s, c in zip(series, colours, strict=True)] if len(series) > 1 else []
    ys = [y for pts in lines for _, y in pts if y is not None]
    drawn = time_frame(
        (min(xs), max(xs)),
        ys,
        title=title,
        x_label=x_label,
        y_label=y_label,
        keys=keys,
        y_min=y_min,
        markers=markers,
        width=width,
        height=height,
    )
    paths = []
    for pts, colour in zip(lines, colours, strict=True):
        runs: list[list[tuple[str, str]]] = [[]]
        for x, y in pts:
            if y is None or not math.isfinite(x):
                runs.append([])
            else:
                runs[-1].append((f1(drawn.plot.sx(x)), f1(drawn.plot.sy(y))))
        d = "".join(_path(run) for run in runs if run)
        if d:
            paths.append(f'<path class="line" d="{d}" stroke="{colour}"/>')
    return drawn.svg(paths)


def area_chart(
    x: Sequence[float],
    layers: Sequence[tuple[str, Sequence[float | None]]],
    *,
    title: str,
    x_label: str,
    y_label: str,
    y_min: float | None = None,
    markers: Markers | None = None,
    width: float = 560,
    height: float = 240,
    max_points: int = 400,
) -> str:
    """Stacked areas: each layer (label, values) drawn on top of the ones before it.

    Missing values count as zero. Samples are thinned to about ``max_points`` keeping the minima and
    maxima of the total (:func:`keep_indices`).

    Args:
        x: X values, shared by the layers.
        layers: The layers, bottom first.
        title: Chart title.
        x_label: X axis label (with units).
        y_label: Y axis label (with units).
        y_min: Lowest y the axis must show, or None (the stack starts at 0 anyway).
        markers: Reference lines and shaded ranges, or None.
        width: Width, px.
        height: Height of the plot area plus its axes, px (the legend adds rows below).
        max_points: Samples drawn at most.

    Returns:
        The ``<svg>`` element; a chart saying "no data" without samples or layers.
    """
    columns = [i for i, v in enumerate(x) if finite(v)]
    if not layers or not columns:
        return empty_chart(title, "no data", width)
    values = [[float(ys[i]) if finite(ys[i]) else 0.0 for i in range(len(x))] for _, ys in layers]
    totals = [sum(column) for column in zip(*values, strict=True)]
    keep = [columns[k] for k in keep_indices([totals[i] for i in columns], max_points)]
    xs = [float(x[i]) for i in keep]
    colours = [PALETTE[i % len(PALETTE)] for i in range(len(layers))]
    keys = [(label, c) for (label, _), c in zip(layers, colours, strict=True)]
    drawn = time_frame(
        (min(xs), max(xs)),
        [0.0, *totals],
        title=title,
        x_label=x_label,
        y_label=y_label,
        keys=keys,
        y_min=y_min,
        markers=markers,
        width=width,
        height=height,
    )
    sx, sy = drawn.plot.sx, drawn.plot.sy
    below = [0.0] * len(keep)
    shapes = []
    for layer, colour in zip(values, colours, strict=True):
        above = [b + layer[i] for b, i in zip(below, keep, strict=True)]
        if any(layer[i] for i in keep):
            top = flat_thinned([(f1(sx(a)), f1(sy(b))) for a, b in zip(xs, above, strict=True)])
            bottom = flat_thinned([(f1(sx(a)), f1(sy(b))) for a, b in zip(xs, below, strict=True)])
            shapes.append(f'<path class="area" d="{_path(top + bottom[::-1])}Z" fill="{colour}"/>')
        below = above
    return drawn.svg(shapes)
