"""Arguments and output helpers shared by the ``handsim`` commands."""

from __future__ import annotations

import argparse
from pathlib import Path


def add_hand_size(parser: argparse.ArgumentParser) -> None:
    """Add ``--hand-length`` (parametric default hand)."""
    parser.add_argument(
        "--hand-length",
        type=float,
        default=0.19,
        metavar="M",
        help="parametric hand: wrist crease to middle fingertip in metres (default 0.19)",
    )


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path``, creating its folder, and return the path."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    return out
