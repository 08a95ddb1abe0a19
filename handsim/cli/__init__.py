"""The ``handsim`` command line. Thin: parse arguments, call the library, print.

Every command exits 0 on success, 1 on a handsim error (with a one-line message naming the file, line
and field at fault) or an operating-system error reading or writing a file (one line: the file and the
system's reason), 2 on a usage error (bad arguments, and a bad ``$HANDSIM_THREADS`` for the commands that
simulate, are refused before any work starts; the first line of stderr is ``handsim COMMAND: error: …``),
and 130 when interrupted (Ctrl-C or SIGTERM: one line; files are written atomically, so none is left
half-written). One module per command group registers its parsers.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from collections.abc import Sequence

from handsim.cli import build, catalog, correct, demo, export, replay, report, trajectory
from handsim.cli._common import EXIT_INTERRUPTED, Parser, cli_wording, range_problem
from handsim.errors import HandsimError
from handsim.thread_setting import threads_setting
from handsim.version import __version__

DESCRIPTION = """\
handsim turns captured human hand motion into MuJoCo physics.

Start with `handsim demo` (no arguments; uses data bundled with the package). Build models with
`handsim build hand|object|scene ... -o model.xml`; list the object catalogue with `handsim catalog`;
look at a recording with `handsim inspect RECORDING --plot out.png`; replay a whole dataset and report
on it with `handsim report DATASET -o OUT`; export replayed episodes with `handsim export minari OUT`.
"""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``handsim`` command."""
    parser = Parser(
        prog="handsim", description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--version", action="version", version=f"handsim {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in (demo, build, catalog, trajectory, replay, correct, report, export):
        module.register(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``handsim`` command; returns the process exit code."""
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _terminate) if main_thread else None  # a killed job: as Ctrl-C
    args = None
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        if getattr(args, "func", None) is None:
            parser.print_help()
            return 2
        problem = range_problem(args) or _environment_problem(args)
        if problem is not None:
            args.command_parser.error(problem)  # the problem first, then the usage, on stderr: exit 2
        return args.func(args)
    except HandsimError as exc:
        print(f"handsim: error: {cli_wording(str(exc), args)}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # stdout closed early (`handsim … | head`): stop quietly, as other tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit
        return 1
    except OSError as exc:
        print(f"handsim: error: {os_error_line(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("handsim: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, previous)


def _environment_problem(args: argparse.Namespace) -> str | None:
    """What is wrong with the environment a simulating command reads (``$HANDSIM_THREADS``), or None.

    Checked before any work starts, like the arguments: a bad value would otherwise surface as a traceback
    once the trial has loaded (or, in a dataset run, not at all: its workers use one thread each).
    """
    if not getattr(args, "simulates", False):
        return None
    try:
        threads_setting()
    except ValueError as exc:
        return str(exc)
    return None


def _terminate(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def os_error_line(exc: OSError) -> str:
    """One line for an operating-system error: the file(s) involved and the system's reason."""
    reason = exc.strerror or str(exc) or type(exc).__name__
    files = [str(f) for f in (exc.filename, exc.filename2) if f is not None]
    return f"{' → '.join(files)}: {reason}" if files else reason
