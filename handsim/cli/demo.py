"""``handsim demo``: the main job on data bundled with the package — build, replay, report.

No arguments and no downloads: the parametric default hand and the object catalogue are checked (built,
compiled, one simulated second with a MuJoCo warning check), then the MIT-licensed Tzionas sample bundled
in ``handsim/assets/tzionas_ijcv16`` (sequence 20: a hand pinching a cube, with its notice) goes through
the same dataset run as ``handsim report`` together with the synthetic scripted grasps bundled in
``handsim/assets/demo`` (the default hand closing around catalogue objects, glove scenario; written for
handsim, not recordings): discovery, replay with collisions on and free objects, one record per trial,
rendered frames, and one HTML/Markdown/JSON report.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.cli._common import Commands, add_hand_size, non_negative_int, output_dir, positive_int
from handsim.cli.report import run_and_render

if TYPE_CHECKING:
    from handsim.trials import Discovery

DEFAULT_OUT = "handsim-demo"
DEMO_OBJECTS = ("tennis_ball", "mug")
"""Catalogue objects the demo builds into a scene with the default hand (bundled hulls: no decomposition)."""


def _check_default_hand(hand_length: float) -> None:
    # lazy: MuJoCo and the builders, only when the demo runs
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


def demo_discovery() -> Discovery:
    """The demo's dataset: the bundled Tzionas sample and the bundled scripted grasps, as one discovery.

    Each folder is discovered on its own and its ids and paths are made relative to
    :data:`handsim.assets.ASSETS_DIR` (``tzionas_ijcv16/Models/20``, ``demo/tennis_ball.grasp.json``), so
    they stay unique and name where the files are.

    Returns:
        The combined discovery, rooted at the assets folder, entries sorted by id.
    """
    # lazy: the trial loaders, only when the demo runs
    from handsim.trials import CompanionFile, Discovery, UnknownFile, discover

    entries, companions, unknown = [], [], []
    for folder in (TZIONAS_DIR, ASSETS_DIR / "demo"):
        found = discover(folder)
        prefix = Path(found.root).relative_to(ASSETS_DIR).as_posix() + "/"
        for e in found.entries:
            inputs = tuple(replace(i, path=prefix + i.path) for i in e.inputs)
            entries.append(replace(e, id=prefix + e.id, inputs=inputs))
        companions += [CompanionFile(prefix + c.path, c.reason) for c in found.companions]
        unknown += [UnknownFile(prefix + u.path, u.reason) for u in found.unknown]
    return Discovery(
        root=str(ASSETS_DIR),
        entries=tuple(sorted(entries, key=lambda e: e.id)),
        companions=tuple(sorted(companions, key=lambda c: c.path)),
        unknown=tuple(sorted(unknown, key=lambda u: u.path)),
    )


def _run(args: argparse.Namespace) -> int:
    print("handsim demo: on data bundled with handsim (no downloads)")
    _check_default_hand(args.hand_length)
    print(f"  dataset: the Tzionas/Ballan sample in {TZIONAS_DIR}")
    print("  (MIT licence, Copyright (c) 2014 cvlabbonn: see LICENSE there)")
    print(f"  and the synthetic scripted grasps in {ASSETS_DIR / 'demo'}")
    print("  (written for handsim, not recordings: the default hand closing around catalogue objects)")
    out = Path(args.output)
    return run_and_render(
        demo_discovery(),
        out,
        workers=args.workers,
        frames=args.frames,
        command=["handsim", "demo", "-o", str(out)],
    )


def register(commands: Commands) -> None:
    """Add the ``demo`` command."""
    demo = commands.add_parser(
        "demo",
        help="build, replay and report on data bundled with handsim (start here)",
        description="Check the parametric default hand and catalogue objects (build, compile, simulate with "
        "a MuJoCo warning check), then replay the bundled MIT-licensed Tzionas sample (a hand pinching a "
        "cube) and the bundled synthetic scripted grasps (the default hand closing around catalogue "
        "objects) with collisions on and free objects, and write one dataset report (HTML, Markdown, JSON) "
        f"into OUT (default ./{DEFAULT_OUT}). Running it again reuses the records already there.",
    )
    add_hand_size(demo)
    demo.add_argument(
        "-o", "--output", type=output_dir, metavar="OUT", default=DEFAULT_OUT, help="output folder"
    )
    demo.add_argument(
        "--workers", type=positive_int, default=None, metavar="N", help="trials at once (default: every core)"
    )
    demo.add_argument(
        "--frames", type=non_negative_int, default=4, metavar="N", help="frames rendered per trial (0: none)"
    )
    demo.set_defaults(func=_run, simulates=True, command_parser=demo)
