"""``handsim demo``: build and exercise the default hand on bundled data."""

from __future__ import annotations

import argparse
from pathlib import Path

from handsim.cli._common import add_hand_size


def _run(args: argparse.Namespace) -> int:
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


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``demo`` command."""
    demo = commands.add_parser(
        "demo",
        help="build and exercise the default hand on bundled data",
        description="Build the parametric default hand, print its summary and simulate it closing and "
        "opening for one second with a MuJoCo warning check.",
    )
    add_hand_size(demo)
    demo.add_argument("-o", "--output", metavar="XML", help="also write the hand's MJCF here")
    demo.set_defaults(func=_run)
