"""What the dataset-run tests share: the run configuration, the sample's trial ids, datasets made from the
bundled Tzionas sequence, and the checks of records and their rendered frames."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

from handsim.assets import TZIONAS_DIR
from handsim.runner.renders import headless_glfw
from handsim.sim.replay import ReplayConfig
from tests.tzionas_fixtures import shifted_motion

CONFIG = ReplayConfig(stability_at="grasp")
GRASPDB_IDS = [  # each trial holds one grasp episode
    "graspdb14/01_ex01-rad-002-grasp-su01.txt#1",
    "graspdb14/04_ex01-rad-045-grasp-su03.txt#1",
    "graspdb14/r_01_11_ex03-rad-004-grasp-su04.txt#1",
]
SESSION = "graspdb14/sessions/01_11_ex03-rad-004-grasp-su04.txt"  # a whole glove session: 51 grasp episodes
SESSION_IDS = [f"{SESSION}#{k}" for k in range(1, 52)]
TZIONAS_ID = "tzionas_ijcv16/Models/20"


def without_timing(records: list[dict]) -> dict[str, dict]:
    """The records by id, each without its ``timing`` (the one field that differs run to run)."""
    return {r["id"]: {k: v for k, v in r.items() if k != "timing"} for r in records}


def _renders_in_this_process() -> bool:
    """True when this test process can render offscreen (MuJoCo took EGL/OSMesa, or there is a display).

    MuJoCo picks its OpenGL backend when first imported; a test module importing ``mujoco`` before
    ``handsim`` (which selects EGL without a display) leaves the whole test process on GLFW.
    """
    return not headless_glfw()


def check_renders(record: dict, out: Path, count: int) -> None:
    """The record has ``count`` frames whose files match their hashes, or (no OpenGL here) a note instead."""
    if not _renders_in_this_process():
        assert record["renders"] == []
        assert record["notes"][-1].startswith(
            "frames not rendered: HandsimError: MuJoCo was imported with its GLFW"
        )
        return
    assert len(record["renders"]) == count
    for render in record["renders"]:
        assert hashlib.sha256((out / render["path"]).read_bytes()).hexdigest() == render["sha256"]


def tzionas_copies(root: Path, sequences: list[int]) -> Path:
    """A Tzionas dataset whose sequences are copies of the bundled sequence 20, the k-th after the first with
    its recorded hand moved k µm: distinct recordings (discovery replays byte-identical copies once)."""
    for k, n in enumerate(sequences):
        shutil.copytree(TZIONAS_DIR / "Models" / "20", root / "Models" / str(n))
        shutil.copytree(TZIONAS_DIR / "Configs" / "20", root / "Configs" / str(n))
        if k:
            motion = root / "Models" / str(n) / "Model_Hand_R.MOTION"
            motion.write_text(shifted_motion(motion.read_text(), (0.0, 0.0, k * 1e-3)))
    return root


def dataset_in(folder: Path) -> Path:
    """A small dataset (bundled Tzionas sequence 20, a malformed glove recording) copied into ``folder``."""
    data = tzionas_copies(folder, [20])
    (data / "01_ex01-rad-002-grasp-su01.txt").write_text("2014 09 12 08 49 21.71200 1 0.1 garbage\n")
    return data
