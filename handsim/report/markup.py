"""Small HTML building blocks for the report: escaping, badges, tables, definition lists."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from html import escape

from handsim.report.columns import Column


def esc(value: object) -> str:
    """``value`` as HTML-escaped text (quotes included, so it is safe in attributes too)."""
    return escape(str(value), quote=True)


def badge(label: str) -> str:
    """A coloured pill for a status or outcome (``ok``, ``diverged``, ``error``, ``held``, ``not held``)."""
    return f'<span class="badge {esc(label.replace(" ", "-"))}">{esc(label)}</span>'


def link(anchor: str, label: str) -> str:
    """A link to an element of the page."""
    return f'<a href="#{esc(anchor)}">{esc(label)}</a>'


def table(
    columns: Sequence[Column],
    rows: Sequence[dict],
    *,
    first: tuple[str, Callable[[dict], str]] | None = None,
    total: dict | None = None,
    badges: Sequence[str] = ("status", "outcome"),
) -> str:
    """A data table.

    Args:
        columns: The columns (their cells are escaped text).
        rows: One dict per row.
        first: A leading column (header, function returning the cell's HTML), e.g. a link.
        total: A last row set apart (same keys as the rows; ``first`` gets ``"all"``).
        badges: Labels of columns whose cells are shown as :func:`badge`.

    Returns:
        The table, wrapped in a horizontally scrolling ``div``.
    """
    head = [f"<th>{esc(first[0])}</th>"] if first else []
    head += [
        f'<th class="{"n" if c.numeric else "t"}"'
        + (f' title="{esc(c.help)}"' if c.help else "")
        + f">{esc(c.label)}</th>"
        for c in columns
    ]

    def row_html(row: dict, first_cell: str | None, cls: str = "") -> str:
        cells = [f"<td>{first_cell}</td>"] if first else []
        for c in columns:
            value = c.cell(row)
            content = badge(value) if c.label in badges else esc(value)
            cells.append(f'<td class="{"n" if c.numeric else "t"}">{content}</td>')
        return f"<tr{cls}>" + "".join(cells) + "</tr>"

    body = [row_html(r, first[1](r) if first else None) for r in rows]
    if total is not None:
        body.append(row_html(total, "all", ' class="total"'))
    return (
        '<div class="scroll"><table class="data"><thead><tr>'
        + "".join(head)
        + "</tr></thead><tbody>"
        + "".join(body)
        + "</tbody></table></div>"
    )


def simple_table(headers: Sequence[str], rows: Sequence[Sequence[str]], numeric: Sequence[bool] = ()) -> str:
    """A table of already-formatted text cells (escaped here)."""
    flags = list(numeric) + [False] * (len(headers) - len(numeric))
    head = "".join(
        f'<th class="{"n" if n else "t"}">{esc(h)}</th>' for h, n in zip(headers, flags, strict=True)
    )
    body = "".join(
        "<tr>"
        + "".join(f'<td class="{"n" if n else "t"}">{esc(v)}</td>' for v, n in zip(r, flags, strict=True))
        + "</tr>"
        for r in rows
    )
    table_html = f'<table class="data"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>'
    return f'<div class="scroll">{table_html}</div>'


def numbers(items: Sequence[tuple[str, str]]) -> str:
    """A grid of ``label: value`` pairs."""
    return (
        '<dl class="numbers">'
        + "".join(f"<div><dt>{esc(k)}</dt><dd>{esc(v)}</dd></div>" for k, v in items)
        + "</dl>"
    )
