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


def non_negative_int(text: str) -> int:
    """An argparse type: a whole number ≥ 0 (a usage error, exit 2, otherwise)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number ≥ 0, got {value}")
    return value


def positive_int(text: str) -> int:
    """An argparse type: a whole number ≥ 1 (a usage error, exit 2, otherwise)."""
    value = non_negative_int(text)
    if value == 0:
        raise argparse.ArgumentTypeError("expected a number ≥ 1, got 0")
    return value


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path``, creating its folder, and return the path."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    return out
