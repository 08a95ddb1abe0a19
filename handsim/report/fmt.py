"""Text for numbers and missing values, shared by the HTML and Markdown writers."""

from __future__ import annotations

import math

MISSING = "—"


def num(value: float | None, digits: int = 2) -> str:
    """``value`` with ``digits`` decimals, or :data:`MISSING` when None or not finite."""
    if value is None or isinstance(value, bool) or not math.isfinite(value):
        return MISSING
    text = f"{value:.{digits}f}"
    return text.lstrip("-") if float(text) == 0 else text  # "0.00", not "-0.00"


def integer(value: float | None) -> str:
    """``value`` as a whole number, or :data:`MISSING`."""
    return MISSING if value is None or not math.isfinite(value) else str(round(value))


def yes_no(value: bool | None) -> str:
    """``yes``/``no``, or :data:`MISSING` when None."""
    return MISSING if value is None else ("yes" if value else "no")


def rate(count: int, total: int) -> str:
    """``count`` of ``total`` as a percentage with the counts, e.g. ``67% (2/3)``; :data:`MISSING` for 0/0."""
    return MISSING if total == 0 else f"{100.0 * count / total:.0f}% ({count}/{total})"


def text(value: object) -> str:
    """``value`` as text, :data:`MISSING` when None or empty."""
    return MISSING if value is None or value == "" else str(value)


def plural(n: int, noun: str) -> str:
    """``n`` and ``noun``, with an ``s`` unless ``n`` is 1 (``1 trial``, ``3 trials``)."""
    return f"{n} {noun}{'' if n == 1 else 's'}"
