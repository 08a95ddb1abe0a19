"""The ``handsim`` command line. Thin: parse arguments, call the library, print.

Every command exits 0 on success, 1 on a handsim error (with a one-line message naming the file, line
and field at fault), and 2 on a usage error.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from handsim import __version__
from handsim.errors import HandsimError

DESCRIPTION = """\
handsim turns captured human hand motion into MuJoCo physics.

Start with `handsim demo` (no arguments; uses data bundled with the package), or build a hand model from
a skeleton file with `handsim build hand SKELETON -o hand.xml`.
"""


def _hand_spec(args: argparse.Namespace):
    from handsim.builders import build_hand, default_hand
    from handsim.io import read_skeleton

    if args.skeleton is None:
        return default_hand(args.hand_length, args.hand_breadth, mass=args.mass), None
    skeleton = read_skeleton(args.skeleton)
    return build_hand(skeleton, mass=args.mass, collision=args.collision), skeleton


def _cmd_build_hand(args: argparse.Namespace) -> int:
    from handsim.sim import compile_spec, summarize

    if args.skeleton is not None and args.default:
        raise SystemExit("handsim build hand: give a SKELETON file or --default, not both")
    if args.skeleton is None and not args.default:
        raise SystemExit("handsim build hand: give a SKELETON file, or --default for the parametric hand")
    spec, skeleton = _hand_spec(args)
    model = compile_spec(spec)
    if skeleton is not None:
        print(f"skeleton   {skeleton.source} ({skeleton.njoints} joints, {skeleton.ndof} DoFs)")
        for note in skeleton.notes:
            print(f"note       {note}")
    for line in summarize(model).lines():
        print(line)
    if args.output is not None:
        out = Path(args.output)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(spec.to_xml())
        print(f"wrote      {out}")
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    import time

    import mujoco
    import numpy as np

    from handsim.builders import default_hand
    from handsim.sim import compile_spec, raise_on_warnings, summarize

    print("handsim demo: the parametric default hand (Buchholz et al. 1992 proportions)")
    start = time.perf_counter()
    model = compile_spec(default_hand(args.hand_length))
    built = time.perf_counter() - start
    for line in summarize(model).lines():
        print(f"  {line}")
    data = mujoco.MjData(model)
    # Move every joint from rest to the middle of its range and back over one second.
    low, high = model.actuator_ctrlrange[:, 0], model.actuator_ctrlrange[:, 1]
    rest, middle = np.clip(0.0, low, high), 0.5 * (low + high)
    steps = round(1.0 / model.opt.timestep)
    for k in range(steps):
        phase = 1.0 - abs(1.0 - 2.0 * k / steps)
        data.ctrl[:] = rest + phase * (middle - rest)
        mujoco.mj_step(model, data)
    raise_on_warnings(data, "demo hand closing and opening")
    print(f"  built + compiled in {built * 1000:.1f} ms; 1 s of closing/opening simulated, 0 MuJoCo warnings")
    if args.output is not None:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        Path(args.output).write_text(default_hand(args.hand_length).to_xml())
        print(f"  wrote {args.output}")
    return 0


def _add_hand_size(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--hand-length",
        type=float,
        default=0.19,
        metavar="M",
        help="parametric hand: wrist crease to middle fingertip in metres (default 0.19)",
    )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``handsim`` command."""
    parser = argparse.ArgumentParser(
        prog="handsim", description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--version", action="version", version=f"handsim {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")

    demo = commands.add_parser(
        "demo",
        help="build and exercise the default hand on bundled data",
        description="Build the parametric default hand, print its summary and simulate it closing and "
        "opening for one second with a MuJoCo warning check.",
    )
    _add_hand_size(demo)
    demo.add_argument("-o", "--output", metavar="XML", help="also write the hand's MJCF here")
    demo.set_defaults(func=_cmd_demo)

    build = commands.add_parser(
        "build",
        help="build MuJoCo models (MJCF) from skeletons",
        description="Build MuJoCo models and write them as MJCF.",
    )
    build_kinds = build.add_subparsers(dest="kind", metavar="KIND", required=True)
    hand = build_kinds.add_parser(
        "hand",
        help="a hand from a skeleton file or the parametric default",
        description="Build a position-controlled hand from a GraspDB14 .xmlskel or a Tzionas .SKEL "
        "(with .LIMITS, and optionally .MOTION/.OFF/.SKIN/.VOI beside it), or the parametric default hand "
        "(--default). Prints bodies, DoFs, actuators, mass and bounding box; writes MJCF with -o.",
    )
    hand.add_argument("skeleton", nargs="?", metavar="SKELETON_FILE", help=".xmlskel or .SKEL file")
    hand.add_argument("--default", action="store_true", help="use the parametric default hand")
    _add_hand_size(hand)
    hand.add_argument(
        "--hand-breadth",
        type=float,
        default=None,
        metavar="M",
        help="parametric hand: breadth across the metacarpals in metres (default 0.45 × length)",
    )
    hand.add_argument(
        "--mass",
        type=float,
        default=None,
        metavar="KG",
        help="whole-hand mass in kg (default: 0.45 kg scaled with the cube of hand length)",
    )
    hand.add_argument(
        "--collision",
        choices=("capsules", "mesh"),
        default="capsules",
        help="collision shapes: capsules + palm (default) or per-bone hulls of the skinned mesh",
    )
    hand.add_argument("-o", "--output", metavar="XML", help="write the model as MJCF to this file")
    hand.set_defaults(func=_cmd_build_hand)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``handsim`` command; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    try:
        return args.func(args)
    except HandsimError as exc:
        print(f"handsim: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
