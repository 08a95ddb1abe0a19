"""Chart scaffolding: round ticks, SVG primitives, and a plot frame with axes, grid, legend and markers."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from html import escape

PALETTE: tuple[str, ...] = (
    "#0072b2",
    "#e69f00",
    "#009e73",
    "#d55e00",
    "#cc79a7",
    "#56b4e9",
    "#7f7f7f",
    "#000000",
)
CHAR_W = 6.4  # approximate width of an 11 px sans-serif character, px
TOP, BOTTOM, RIGHT = 30.0, 38.0, 14.0
LEGEND_ROW = 18.0


def f1(value: float) -> str:
    """A coordinate with one decimal (never ``-0.0``)."""
    text = f"{value:.1f}"
    return "0.0" if text == "-0.0" else text


def finite(value: float | None) -> bool:
    """``value`` is a finite number."""
    return value is not None and math.isfinite(value)


def line(cls: str, x1: float, x2: float, y1: float, y2: float) -> str:
    """A ``<line>``."""
    return f'<line class="{cls}" x1="{f1(x1)}" x2="{f1(x2)}" y1="{f1(y1)}" y2="{f1(y2)}"/>'


def text(cls: str, x: float, y: float, content: str, anchor: str = "start", extra: str = "") -> str:
    """A ``<text>``; ``content`` is markup (escape text first)."""
    middle = "" if anchor == "start" else f' text-anchor="{anchor}"'
    return f'<text class="{cls}" x="{f1(x)}" y="{f1(y)}"{middle}{extra}>{content}</text>'


def rect(cls: str, x: float, y: float, w: float, h: float, fill: str | None = None, tip: str = "") -> str:
    """A ``<rect>``, with a tooltip when ``tip`` is given."""
    colour = f' fill="{fill}"' if fill else ""
    body = f"><title>{escape(tip)}</title></rect>" if tip else "/>"
    return f'<rect class="{cls}" x="{f1(x)}" y="{f1(y)}" width="{f1(w)}" height="{f1(h)}"{colour}{body}'


def nice_step(span: float, count: int) -> float:
    """A round step (1, 2, 2.5 or 5 × 10ⁿ) dividing ``span`` into about ``count`` intervals."""
    raw = span / max(count, 1)
    if raw <= 0 or not math.isfinite(raw):
        return 1.0
    power = 10.0 ** math.floor(math.log10(raw))
    for factor in (1.0, 2.0, 2.5, 5.0, 10.0):
        if factor * power >= raw * (1 - 1e-9):
            return factor * power
    return 10.0 * power


def widen(lo: float, hi: float) -> tuple[float, float]:
    """A non-empty range around ``lo == hi`` (±0.5 at zero, else ±10 %)."""
    if hi > lo:
        return lo, hi
    return (lo - 0.5, hi + 0.5) if lo == 0 else (lo - abs(lo) * 0.1, hi + abs(hi) * 0.1)


def ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    """Round tick values covering ``[lo, hi]`` (the first ≤ lo, the last ≥ hi)."""
    lo, hi = widen(lo, hi)
    step = nice_step(hi - lo, count)
    start = math.floor(lo / step + 1e-9)
    stop = math.ceil(hi / step - 1e-9)
    return [round(k * step, 12) for k in range(start, stop + 1)]


def tick_label(value: float, step: float) -> str:
    """``value`` with as many decimals as ``step`` needs."""
    decimals = max(0, -math.floor(math.log10(step) + 1e-9)) if step > 0 else 0
    if decimals and abs(step * 10**decimals - round(step * 10**decimals)) > 1e-6:
        decimals += 1  # 2.5, 0.25
    label = f"{value:.{decimals}f}"
    return label.lstrip("-") if float(label) == 0 else label


def open_svg(width: float, height: float, title: str) -> list[str]:
    """The opening of a chart: the ``<svg>`` tag, its accessible title and the visible title."""
    return [
        f'<svg class="chart" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {f1(width)} {f1(height)}" '
        f'width="{f1(width)}" height="{f1(height)}" role="img">',
        f"<title>{escape(title)}</title>",
        text("title", 2, 16, escape(title)),
    ]


def empty_chart(title: str, message: str, width: float = 560, height: float = 120) -> str:
    """A chart frame that says why there is nothing to draw."""
    parts = open_svg(width, height, title)
    parts.append(text("empty", width / 2, height / 2 + 10, escape(message), "middle"))
    return "".join([*parts, "</svg>"])


def legend(
    items: Sequence[tuple[str, str]], left: float, width: float, top: float
) -> tuple[list[str], float]:
    """Legend entries (label, colour) in rows from ``top``; returns the elements and the height used."""
    parts, x, y = [], left, top + 12
    for label, colour in items:
        w = 22 + len(label) * CHAR_W + 14
        if x + w > width and x > left:
            x, y = left, y + LEGEND_ROW
        key = rect("key", x, y - 8, 14, 4, colour) + text("", x + 20, y - 2, escape(label))
        parts.append(f'<g class="legend">{key}</g>')
        x += w
    return parts, (y - top + LEGEND_ROW - 6) if items else 0.0


def left_margin(labels: Sequence[str]) -> float:
    """Room for the y tick labels and the rotated y axis label, px."""
    return 30.0 + max((len(s) for s in labels), default=1) * CHAR_W


@dataclass(frozen=True)
class Plot:
    """The data-to-pixel mapping of a plot area."""

    left: float
    right: float
    top: float
    bottom: float
    x_lo: float
    x_hi: float
    y_lo: float
    y_hi: float

    def sx(self, v: float) -> float:
        """X pixel of data value ``v``."""
        return self.left + (v - self.x_lo) / (self.x_hi - self.x_lo) * (self.right - self.left)

    def sy(self, v: float) -> float:
        """Y pixel of data value ``v``."""
        return self.bottom - (v - self.y_lo) / (self.y_hi - self.y_lo) * (self.bottom - self.top)


def y_axis(plot: Plot, y_ticks: list[float]) -> list[str]:
    """Horizontal grid lines with their labels."""
    step = y_ticks[1] - y_ticks[0] if len(y_ticks) > 1 else 1.0
    parts = []
    for v in y_ticks:
        parts.append(line("grid", plot.left, plot.right, plot.sy(v), plot.sy(v)))
        parts.append(text("tick", plot.left - 6, plot.sy(v) + 4, tick_label(v, step), "end"))
    return parts


def x_axis(plot: Plot, x_ticks: list[float]) -> list[str]:
    """The x axis line, tick marks and labels (ticks outside the plotted range are left out)."""
    step = x_ticks[1] - x_ticks[0] if len(x_ticks) > 1 else 1.0
    parts = [line("axis", plot.left, plot.right, plot.bottom, plot.bottom)]
    for v in x_ticks:
        if plot.x_lo - 1e-9 <= v <= plot.x_hi + 1e-9:
            parts.append(line("axis", plot.sx(v), plot.sx(v), plot.bottom, plot.bottom + 4))
            parts.append(text("tick", plot.sx(v), plot.bottom + 16, tick_label(v, step), "middle"))
    return parts


def axis_labels(plot: Plot, x_label: str, y_label: str) -> list[str]:
    """The axis titles (the y one rotated)."""
    middle = (plot.top + plot.bottom) / 2
    return [
        text("label", (plot.left + plot.right) / 2, plot.bottom + 32, escape(x_label), "middle"),
        text("label", 12, middle, escape(y_label), "middle", f' transform="rotate(-90 12 {f1(middle)})"'),
    ]


@dataclass(frozen=True)
class Markers:
    """Reference marks drawn over a time chart.

    Attributes:
        hlines: Horizontal dashed lines (y, label), e.g. a threshold.
        vlines: Vertical dashed lines (x, label), e.g. the release.
        vspans: Shaded x ranges (start, stop, label), e.g. the hold window.
    """

    hlines: Sequence[tuple[float, str]] = ()
    vlines: Sequence[tuple[float, str]] = ()
    vspans: Sequence[tuple[float, float, str]] = ()


@dataclass(frozen=True)
class Frame:
    """A plot with everything but its data: drawn under (``back``) and over (``front``) the data."""

    plot: Plot
    back: list[str]
    front: list[str]

    def svg(self, data: list[str]) -> str:
        """The finished chart."""
        return "".join([*self.back, *data, *self.front, "</svg>"])


def time_frame(
    x_range: tuple[float, float],
    y_values: Sequence[float],
    *,
    title: str,
    x_label: str,
    y_label: str,
    keys: Sequence[tuple[str, str]] = (),
    y_min: float | None = None,
    markers: Markers | None = None,
    width: float = 560,
    height: float = 240,
) -> Frame:
    """Axes for data over ``x_range`` with values ``y_values``: grid, ticks, labels, legend and markers.

    Args:
        x_range: Smallest and largest x.
        y_values: The data's y values (the axis covers them, ``y_min`` and the ``hlines``).
        title: Chart title.
        x_label: X axis label (with units).
        y_label: Y axis label (with units).
        keys: Legend entries (label, colour); none drawn when empty.
        y_min: Lowest y the axis must show (e.g. 0 for distances), or None.
        markers: Reference lines and shaded ranges, or None.
        width: Width, px.
        height: Height of the plot area plus its axes, px (the legend adds rows below).
    """
    markers = markers or Markers()
    x_lo, x_hi = widen(*x_range)
    y_all = [*y_values, *(y for y, _ in markers.hlines if finite(y)), *([y_min] if y_min is not None else [])]
    y_ticks = ticks(min(y_all), max(y_all))
    step = y_ticks[1] - y_ticks[0] if len(y_ticks) > 1 else 1.0
    left = left_margin([tick_label(v, step) for v in y_ticks])
    plot = Plot(left, width - RIGHT, TOP, height - BOTTOM, x_lo, x_hi, y_ticks[0], y_ticks[-1])
    key_parts, key_h = legend(keys, left, width, height)
    back = open_svg(width, height + key_h, title)
    for start, stop, label in markers.vspans:
        a, b = plot.sx(max(start, x_lo)), plot.sx(min(stop, x_hi))
        if b > a:
            back.append(rect("span", a, plot.top, b - a, plot.bottom - plot.top))
            back.append(text("marker", a + 3, plot.top + 11, escape(label)))
    back += y_axis(plot, y_ticks)
    back += x_axis(plot, ticks(x_lo, x_hi, 6))
    back += axis_labels(plot, x_label, y_label)
    front = []
    for k, (x, label) in enumerate(markers.vlines):
        if finite(x) and x_lo <= x <= x_hi:
            front.append(line("ref", plot.sx(x), plot.sx(x), plot.top, plot.bottom))
            front.append(text("marker", plot.sx(x) + 3, plot.bottom - 4 - 12 * (k % 2), escape(label)))
    for y, label in markers.hlines:
        if finite(y):
            front.append(line("ref", plot.left, plot.right, plot.sy(y), plot.sy(y)))
            front.append(text("marker", plot.right - 2, plot.sy(y) - 3, escape(label), "end"))
    return Frame(plot, back, front + key_parts)
