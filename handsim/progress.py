"""Progress on stderr: a live bar on a terminal; plain lines, or nothing, anywhere else.

A tqdm bar redraws itself in place with carriage returns. On a terminal that is one changing line; in a file
or a pipe (a log, CI output, ``2> run.log``) every redraw stays, and a bar redrawn ten times a second writes
tens of kilobytes of carriage-return lines a minute. So :func:`progress_bar` draws only when stderr is a
terminal and writes nothing otherwise, and a long step that a log should still show (a convex decomposition
of minutes) adds :func:`progress_line`: one plain line when it starts and one when it ends, written only
where the bar is not drawn.
"""

from __future__ import annotations

import sys
from typing import Any

from tqdm import tqdm


def is_terminal() -> bool:
    """Whether stderr is a terminal (False for a file, a pipe, a closed or replaced stream)."""
    try:
        return bool(sys.stderr.isatty())
    except (AttributeError, ValueError, OSError):  # no isatty, or a closed stream
        return False


def progress_bar(*, enabled: bool = True, **options: Any) -> tqdm:
    """A tqdm progress bar on stderr, drawn only when ``enabled`` and stderr is a terminal.

    Args:
        enabled: Whether the caller wants progress shown at all.
        **options: tqdm's options (``total``, ``desc``, ``unit``, ``bar_format``, ``mininterval`` …).

    Returns:
        The bar; where it is not drawn it writes nothing, and its methods still work.
    """
    return tqdm(file=sys.stderr, disable=not (enabled and is_terminal()), **options)


def progress_line(text: str, *, enabled: bool = True) -> None:
    """Write ``text`` as one line on stderr when ``enabled`` and stderr is not a terminal (no bar is drawn).

    Args:
        text: The line, without its end.
        enabled: Whether the caller wants progress shown at all.
    """
    if enabled and not is_terminal():
        print(text, file=sys.stderr, flush=True)
