"""Start-up of the ``handsim`` command: help and light commands import none of the heavy stacks.

What is imported is checked, not how long it takes (timings live in docs/cli.md, measured by hand).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
GRASPDB = ROOT.parent / "shared" / "data" / "graspdb14"
HEAVY = ("mujoco", "coacd", "trimesh", "matplotlib", "scipy")

# In a fresh interpreter: run `handsim ARGS` for each ARGS in sys.argv[1] (a JSON list; "HELP" stands for
# every command's and subcommand's --help) and print, per run, the heavy modules imported so far.
PROBE = textwrap.dedent(
    """
    import argparse, contextlib, io, json, sys
    from handsim.cli import build_parser, main

    def helps(parser, prefix=()):
        yield [*prefix, "--help"]
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    yield from helps(sub, (*prefix, name))

    runs = json.loads(sys.argv[1])
    runs = [args for run in runs for args in (helps(build_parser()) if run == "HELP" else [run])]
    heavy = sys.argv[2].split(",")
    for args in runs:
        with contextlib.redirect_stdout(io.StringIO()):
            try:
                code = main(args)
            except SystemExit as exc:
                code = exc.code
        print(json.dumps([args, code, [m for m in heavy if m in sys.modules]]))
    """
)


def _imports_of(*runs: str | list[str], env: dict | None = None) -> list[tuple[list[str], int, list[str]]]:
    """(arguments, exit code, heavy modules imported by then) of each run, all in one fresh process.

    ``env``: variables to set in that process on top of this one's.
    """
    done = subprocess.run(
        [sys.executable, "-c", PROBE, json.dumps(list(runs)), ",".join(HEAVY)],
        cwd=ROOT,
        env={**os.environ, **(env or {})},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return [tuple(json.loads(line)) for line in done.stdout.splitlines()]


def test_help_of_every_command_imports_no_heavy_module():
    results = _imports_of("HELP")
    commands = {" ".join(args[:-1]) for args, _, _ in results}
    assert {"", "build", "build object", "replay", "report", "export minari"} <= commands
    for args, code, heavy in results:
        assert (code, heavy) == (0, []), args


def test_a_bad_thread_setting_is_refused_before_importing_the_simulation(tmp_path: Path):
    from handsim.assets import TZIONAS_DIR

    [(_, code, heavy)] = _imports_of(
        ["replay", str(TZIONAS_DIR / "Models" / "20")], env={"HANDSIM_THREADS": "0"}
    )
    assert (code, heavy) == (2, [])


def test_catalog_imports_no_heavy_module():
    [(_, code, heavy)] = _imports_of(["catalog"])
    assert (code, heavy) == (0, [])


def test_inspect_of_a_glove_recording_imports_no_heavy_module():
    recording = GRASPDB / "r_01_11_ex03-rad-004-grasp-su04.txt"
    if not recording.is_file():
        pytest.skip(f"sample data not found: {recording}")
    [(_, code, heavy)] = _imports_of(["inspect", str(recording)])
    assert (code, heavy) == (0, [])


def _run_cli(args: list[str], env: dict) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "handsim.cli", *args],
        cwd=ROOT,
        env={**os.environ, **env},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr


def test_a_warm_glove_replay_imports_no_trimesh(tmp_path: Path):
    # The ARCTIC fit checks (trimesh) are imported where they run, not with the trial kinds; with the mesh
    # and the placement cached, a glove replay needs MuJoCo and SciPy (the hand builder's hulls) only.
    recording = GRASPDB / "r_01_11_ex03-rad-004-grasp-su04.txt"
    if not recording.is_file():
        pytest.skip(f"sample data not found: {recording}")
    env = {"HANDSIM_CACHE_DIR": str(tmp_path)}
    _run_cli(["replay", str(recording)], env)
    [(_, code, heavy)] = _imports_of(["replay", str(recording)], env=env)
    assert (code, heavy) == (0, ["mujoco", "scipy"])


def test_a_warm_catalogue_object_build_imports_neither_trimesh_nor_scipy(tmp_path: Path):
    # The first build generates the mug's mesh (trimesh) and caches it; the next process reads the mesh
    # from the cache, its hulls from the bundled cache and its mass from numpy (0.6 s instead of 1.5 s):
    # the same model.
    env = {"HANDSIM_CACHE_DIR": str(tmp_path)}
    _run_cli(["build", "object", "mug", "-o", str(tmp_path / "cold.xml")], env)
    [(_, code, heavy)] = _imports_of(["build", "object", "mug", "-o", str(tmp_path / "mug.xml")], env=env)
    assert (code, heavy) == (0, ["mujoco"])
    assert (tmp_path / "mug.xml").read_text() == (tmp_path / "cold.xml").read_text()
