"""The ``handsim`` command line. Thin: parse arguments, call the library, print.

Every command exits 0 on success, 1 on a handsim error (with a one-line message naming the file, line
and field at fault), and 2 on a usage error. One module per command group registers its parsers.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from handsim import __version__
from handsim.cli import build, catalog, demo, export, replay, report, trajectory
from handsim.cli._common import range_problem
from handsim.errors import HandsimError

DESCRIPTION = """\
handsim turns captured human hand motion into MuJoCo physics.

Start with `handsim demo` (no arguments; uses data bundled with the package). Build models with
`handsim build hand|object|scene ... -o model.xml`; list the object catalogue with `handsim catalog`;
look at a recording with `handsim inspect RECORDING --plot out.png`; replay a whole dataset and report
on it with `handsim report DATASET -o OUT`; export replayed episodes with `handsim export minari OUT`.
"""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``handsim`` command."""
    parser = argparse.ArgumentParser(
        prog="handsim", description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--version", action="version", version=f"handsim {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in (demo, build, catalog, trajectory, replay, report, export):
        module.register(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``handsim`` command; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    problem = range_problem(args)
    if problem is not None:
        args.command_parser.error(problem)  # usage and the problem on stderr, exit 2
    try:
        return args.func(args)
    except HandsimError as exc:
        print(f"handsim: error: {exc}", file=sys.stderr)
        return 1
