"""``handsim demo``: the main job on data bundled with the package — build, replay, report.

No arguments and no downloads: the parametric default hand and the object catalogue are checked (built,
compiled, one simulated second with a MuJoCo warning check), then the MIT-licensed Tzionas sample bundled
in ``handsim/assets/tzionas_ijcv16`` (sequence 20: a hand pinching a cube, with its notice) goes through
the same dataset run as ``handsim report``: discovery, replay with collisions on and a free cube, one
record per trial, rendered frames, and the HTML/Markdown/JSON report.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from handsim.cli._common import add_hand_size

DEFAULT_OUT = "handsim-demo"
DEMO_OBJECTS = ("tennis_ball", "mug")
"""Catalogue objects the demo builds into a scene with the default hand (bundled hulls: no decomposition)."""


def _check_default_hand(hand_length: float) -> None:
    import mujoco
    import numpy as np

    from handsim.builders import build_object, build_scene, catalog, default_hand
    from handsim.sim import compile_spec, raise_on_warnings

    start = time.perf_counter()
    hand = default_hand(hand_length)
    model = compile_spec(hand)
    data = mujoco.MjData(model)
    # every joint from rest to the middle of its range and back over one second
    low, high = model.actuator_ctrlrange[:, 0], model.actuator_ctrlrange[:, 1]
    rest, middle = np.clip(0.0, low, high), 0.5 * (low + high)
    steps = round(1.0 / model.opt.timestep)
    for k in range(steps):
        phase = 1.0 - abs(1.0 - 2.0 * k / steps)
        data.ctrl[:] = rest + phase * (middle - rest)
        mujoco.mj_step(model, data)
    raise_on_warnings(data, "demo hand closing and opening")
    objects = [build_object(catalog.get(name)) for name in DEMO_OBJECTS]
    scene = compile_spec(build_scene(hand, objects))
    print(
        f"  default hand {hand_length:g} m: {model.nu} actuated DoFs, 1 s closing/opening, "
        f"0 MuJoCo warnings; scene with {', '.join(DEMO_OBJECTS)} "
        f"({scene.nbody} bodies, {scene.ngeom} geoms) [{time.perf_counter() - start:.1f} s]"
    )


def _run(args: argparse.Namespace) -> int:
    from handsim.assets import TZIONAS_DIR
    from handsim.cli.report import run_and_render

    print("handsim demo: on data bundled with handsim (no downloads)")
    _check_default_hand(args.hand_length)
    print(f"  dataset: the Tzionas/Ballan sample in {TZIONAS_DIR}")
    print("  (MIT licence, Copyright (c) 2014 cvlabbonn: see LICENSE there)")
    out = Path(args.output)
    return run_and_render(
        TZIONAS_DIR,
        out,
        workers=args.workers,
        frames=args.frames,
        command=["handsim", "demo", "-o", str(out)],
    )


def register(commands: argparse._SubParsersAction) -> None:
    """Add the ``demo`` command."""
    demo = commands.add_parser(
        "demo",
        help="build, replay and report on data bundled with handsim (start here)",
        description="Check the parametric default hand and catalogue objects (build, compile, simulate with "
        "a MuJoCo warning check), then replay the bundled MIT-licensed Tzionas sample (a hand pinching a "
        "cube) with collisions on and a free object, and write the dataset report (HTML, Markdown, JSON) "
        f"into OUT (default ./{DEFAULT_OUT}). Running it again reuses the records already there.",
    )
    add_hand_size(demo)
    demo.add_argument("-o", "--output", metavar="OUT", default=DEFAULT_OUT, help="output folder")
    demo.add_argument(
        "--workers", type=int, default=None, metavar="N", help="trials at once (default: every core)"
    )
    demo.add_argument(
        "--frames", type=int, default=4, metavar="N", help="frames rendered per trial (0: none)"
    )
    demo.set_defaults(func=_run)
