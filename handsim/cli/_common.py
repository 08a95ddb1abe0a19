"""Arguments and output helpers shared by the ``handsim`` commands.

Argument types here validate before any work starts: a bad value is a usage error (exit 2) whose first
line is ``handsim COMMAND: error: argument --OPTION: …`` (:class:`Parser` puts the message before the usage).
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, Protocol

from handsim.files import write_atomic
from handsim.trials.options import (
    OptionSpec,
    TrialOptions,
    option_names,
    option_spec,
    parse_positive_number,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from handsim.datatypes.physical_ranges import PhysicalRange

EXIT_INTERRUPTED = 130
"""Exit code after Ctrl-C or SIGTERM (128 + SIGINT, as a shell reports it)."""


class Commands(Protocol):
    """What a command's ``register`` needs of the ``handsim`` subcommands (``add_subparsers()``'s result).

    Named by what it does rather than by argparse's private class, which the standard library does not export.
    """

    def add_parser(self, name: str, **kwargs: Any) -> argparse.ArgumentParser:
        """Add the subcommand ``name`` and return its parser."""


class ArgumentContainer(Protocol):
    """A parser or one of its argument groups: anything options are added to."""

    def add_argument(self, *flags: str, **kwargs: Any) -> argparse.Action:
        """Add one option."""


class Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors print the error line first, then the usage (exit 2).

    Subcommand parsers are made of the same class, so every ``handsim`` command reports
    ``handsim COMMAND: error: MESSAGE`` as the first line of stderr.
    """

    def error(self, message: str) -> NoReturn:
        """Print ``PROG: error: MESSAGE`` and the usage to stderr and exit with status 2."""
        self.exit(2, f"{self.prog}: error: {message}\n{self.format_usage()}")


PYTHON_WORDING: tuple[tuple[str, re.Pattern[str], str], ...] = (
    (
        "units",
        re.compile(r"give the mesh's units \('m' or 'mm'\)"),
        "give the mesh's units (--units m or --units mm)",
    ),
    ("units", re.compile(r"\bin units='(mm?)'"), r"with --units \1"),
    ("units", re.compile(r"\(pass units='(mm?)'\)"), r"(give --units \1)"),
    ("force", re.compile(r"\bpass force=True\b"), "give --force"),
)
"""Library phrases that name a Python keyword argument, each with the command option it stands for: the
option's ``dest``, the phrase, and its command-line wording (:func:`cli_wording`)."""


def cli_wording(message: str, args: argparse.Namespace | None) -> str:
    """``message`` with the Python keyword arguments it suggests named as the command's options instead.

    The library words its errors for Python callers (``pass units='mm'``, ``pass force=True``); a user of the
    command line typed ``--units`` or ``--force``. A phrase is reworded only when the command has that
    option, so a command without it keeps the library's wording.

    Args:
        message: The error message.
        args: The parsed arguments of the command that failed, or None before parsing.

    Returns:
        The message as the command line should show it.
    """
    if args is None:
        return message
    for dest, phrase, wording in PYTHON_WORDING:
        if hasattr(args, dest):
            message = phrase.sub(wording, message)
    return message


def usage_error(command: str, message: str) -> int:
    """Print a usage error found after parsing (``handsim COMMAND: error: …``) and return exit code 2."""
    print(f"handsim {command}: error: {message}", file=sys.stderr)
    return 2


def add_hand_size(parser: argparse.ArgumentParser) -> None:
    """Add ``--hand-length`` (parametric default hand)."""
    parser.add_argument(
        "--hand-length",
        type=positive_number,
        default=0.19,
        metavar="M",
        help="parametric hand: wrist crease to middle fingertip in metres (default 0.19)",
    )


def argument_type(parse: Callable[[str], Any]) -> Callable[[str], Any]:
    """An argparse type from a parser that raises ``ValueError``: its message becomes the usage error's."""

    def convert(text: str) -> Any:
        try:
            return parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = parse.__name__
    return convert


def positive_number(text: str) -> float:
    """An argparse type: a finite number > 0 (lengths, masses, densities; a usage error otherwise).

    Whether the value is plausible (a hand length in metres, a household object's mass) is the builder's to
    say; this refuses only what is no quantity at all (:func:`handsim.trials.options.parse_positive_number`).
    """
    return argument_type(parse_positive_number)(text)


def add_ranged_float(
    parser: argparse.ArgumentParser,
    container: ArgumentContainer,
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


def add_trial_options(
    parser: argparse.ArgumentParser, names: Sequence[str] | None = None, *, forced: bool | None = None
) -> None:
    """Add the flags of trial options (:class:`~handsim.trials.options.TrialOptions`), as their metadata says.

    Each flag's name, value, type, choices and help are its field's
    :class:`~handsim.trials.options.OptionSpec`; its ``dest`` is the field's name, so that
    :func:`trial_options_from_args` reads them back. Options with a documented range are checked after
    parsing (:func:`range_problem`); options marked exclusive of each other share a group.

    Args:
        parser: The command's parser.
        names: The options, in the order ``--help`` lists them; default every one, in the fields' order.
        forced: The command has ``--force`` (their help says that it accepts a value out of range);
            default: ``"force"`` is among ``names``.
    """
    names = option_names() if names is None else tuple(names)
    forced = "force" in names if forced is None else forced
    groups: dict[str, ArgumentContainer] = {}
    for name in names:
        spec = option_spec(name)
        if spec.exclusive and spec.exclusive not in groups:
            groups[spec.exclusive] = parser.add_mutually_exclusive_group()
        _add_option(parser, groups.get(spec.exclusive, parser), name, spec, forced)
    given = (*(parser.get_default("trial_options") or ()), *names)
    parser.set_defaults(trial_options=given)


def _add_option(
    parser: argparse.ArgumentParser, container: ArgumentContainer, name: str, spec: OptionSpec, forced: bool
) -> None:
    """Add one trial option's flag to ``container`` (``parser`` or one of its groups)."""
    if spec.switch:
        container.add_argument(spec.flag, dest=name, action="store_true", help=spec.help)
        return
    kwargs: dict[str, Any] = {"dest": name, "default": None, "help": spec.help}
    if spec.metavar is not None:
        kwargs["metavar"] = spec.metavar
    if spec.choices is not None:
        kwargs["choices"] = spec.choices
    if spec.value_range is not None:
        kwargs["help"] += " without --force" if forced else ""
        add_ranged_float(parser, container, spec.flag, spec.value_range, **kwargs)
        return
    if spec.parse is not None:
        kwargs["type"] = argument_type(spec.parse)
    container.add_argument(spec.flag, **kwargs)


def trial_options_from_args(args: argparse.Namespace) -> TrialOptions:
    """The trial options a command's parsed arguments give (the flags :func:`add_trial_options` added)."""
    return TrialOptions(**{name: getattr(args, name) for name in getattr(args, "trial_options", ())})


def add_object_mass_options(parser: argparse.ArgumentParser, *, forced: bool) -> None:
    """Add ``--density`` or ``--mass`` (one of them) of an object, checked against their ranges.

    Args:
        parser: The command's parser.
        forced: The command also has ``--force`` (:func:`add_force`), which accepts values out of range.
    """
    add_trial_options(parser, ("density", "mass"), forced=forced)


def add_force(parser: argparse.ArgumentParser) -> None:
    """Add ``--force``: accept a mass or density outside its documented range."""
    add_trial_options(parser, ("force",))


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


def _whole_number(text: str, minimum: int) -> int:
    """``text`` as a whole number ≥ ``minimum``; an argparse type error saying what is accepted otherwise."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number ≥ {minimum}, got {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"expected a whole number ≥ {minimum}, got {value}")
    return value


def non_negative_int(text: str) -> int:
    """An argparse type: a whole number ≥ 0 (a usage error, exit 2, otherwise)."""
    return _whole_number(text, 0)


def positive_int(text: str) -> int:
    """An argparse type: a whole number ≥ 1 (a usage error, exit 2, otherwise)."""
    return _whole_number(text, 1)


def control_rate(text: str) -> float:
    """An argparse type: a control rate in Hz, at least the replay's minimum at the default metrics.

    See :func:`handsim.sim.plausibility.min_control_rate` (20 Hz).
    """
    # lazy: the simulation stack (MuJoCo) is slow to import, and --help must not wait for it
    from handsim.sim.plausibility import check_control_rate
    from handsim.sim.specs import MetricSpec

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of Hz, got {text!r}") from None
    try:
        return check_control_rate(value, MetricSpec())
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_control_rate(parser: argparse.ArgumentParser) -> None:
    """Add ``--rate HZ`` (the replay's control rate, checked by :func:`control_rate`)."""
    parser.add_argument(
        "--rate",
        type=control_rate,
        default=100.0,
        metavar="HZ",
        help="control rate (default 100; at least 20: two frames within the metrics' 0.1 s contact gap)",
    )


def _blocking_file(path: Path) -> Path | None:
    """The nearest existing ancestor of ``path`` when it is not a folder (nothing can be created there)."""
    for parent in path.parents:
        if parent.exists():
            return None if parent.is_dir() else parent
    return None


def output_file(text: str) -> Path:
    """An argparse type: a file to write (created or replaced), not a folder, its folder creatable."""
    if not text:
        raise argparse.ArgumentTypeError("expected a file name, got ''")
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a folder; expected a file name to write")
    blocking = _blocking_file(path)
    if blocking is not None:
        raise argparse.ArgumentTypeError(f"cannot create {text}: {blocking} is a file, not a folder")
    return path


def output_dir(text: str) -> Path:
    """An argparse type: a folder to write into (created if missing), not an existing file."""
    if not text:
        raise argparse.ArgumentTypeError("expected a folder name, got ''")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} exists and is not a folder; expected an output folder")
    blocking = _blocking_file(path)
    if blocking is not None:
        raise argparse.ArgumentTypeError(f"cannot create {text}: {blocking} is a file, not a folder")
    return path


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically, creating its folder, and return the path."""
    return write_atomic(path, text.encode("utf-8"))


def add_arctic_options(parser: argparse.ArgumentParser) -> None:
    """``--mano-dir`` and ``--templates``: what an ARCTIC sequence needs besides its files."""
    add_trial_options(parser, ("mano_dir", "templates"))
