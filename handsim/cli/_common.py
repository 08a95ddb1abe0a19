"""Arguments and output helpers shared by the ``handsim`` commands."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from handsim.physical_ranges import PhysicalRange


def add_hand_size(parser: argparse.ArgumentParser) -> None:
    """Add ``--hand-length`` (parametric default hand)."""
    parser.add_argument(
        "--hand-length",
        type=float,
        default=0.19,
        metavar="M",
        help="parametric hand: wrist crease to middle fingertip in metres (default 0.19)",
    )


def add_ranged_float(
    parser: argparse.ArgumentParser,
    container: argparse.ArgumentParser | argparse._ArgumentGroup,
    flag: str,
    value_range: PhysicalRange,
    **kwargs,
) -> None:
    """Add a float option whose value :func:`range_problem` checks against ``value_range`` after parsing.

    Args:
        parser: The command's parser (its usage is printed with the error).
        container: Where the option goes: ``parser`` or one of its (mutually exclusive) groups.
        flag: The option, e.g. ``"--mass"``.
        value_range: Its documented range.
        **kwargs: ``add_argument`` options (``dest``, ``metavar``, ``help`` …).
    """
    action = container.add_argument(flag, type=float, **kwargs)
    checks = (*(parser.get_default("range_checks") or ()), (flag, action.dest, value_range))
    parser.set_defaults(range_checks=checks, command_parser=parser)


def add_object_mass_options(parser: argparse.ArgumentParser, *, forced: bool) -> None:
    """Add ``--density`` or ``--mass`` (one of them) of an object, checked against their ranges.

    Args:
        parser: The command's parser.
        forced: The command also has ``--force`` (:func:`add_force`), which accepts values out of range.
    """
    from handsim.physical_ranges import DENSITY, OBJECT_MASS

    group = parser.add_mutually_exclusive_group()
    unless = " without --force" if forced else ""
    add_ranged_float(
        parser, group, "--density", DENSITY, metavar="KG_M3",
        help=f"object density instead of its own, {DENSITY.describe()}{unless}",
    )  # fmt: skip
    add_ranged_float(
        parser, group, "--mass", OBJECT_MASS, metavar="KG",
        help=f"total object mass instead of a density, {OBJECT_MASS.describe()}{unless}",
    )  # fmt: skip


def add_force(parser: argparse.ArgumentParser) -> None:
    """Add ``--force``: accept a mass or density outside its documented range."""
    parser.add_argument(
        "--force",
        action="store_true",
        help="accept a mass or density outside its documented range (docs/objects.md)",
    )


def range_problem(args: argparse.Namespace) -> str | None:
    """The usage error of the first option of :func:`add_ranged_float` out of its range, or None.

    A value outside the range passes with ``--force`` when the command has it; a value that is not a
    positive finite number never does.
    """
    forced = bool(getattr(args, "force", False))
    for flag, dest, value_range in getattr(args, "range_checks", ()):
        value = getattr(args, dest, None)
        problem = None if value is None else value_range.problem(value)
        if problem is None:
            continue
        if not (math.isfinite(value) and value > 0):
            return f"argument {flag}: {problem}"
        if forced:
            continue
        hint = "; give --force to use it anyway" if hasattr(args, "force") else ""
        return f"argument {flag}: {problem}{hint}"
    return None


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
