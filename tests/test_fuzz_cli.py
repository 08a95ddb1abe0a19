"""Fuzz the command line's file inputs: ``handsim inspect`` and ``handsim replay`` on random bytes and on
real files cut short never end in a traceback.

Each example writes one file under the name a reader claims it by (a GraspDB14 recording, a scripted grasp,
a Tzionas hand motion beside its skeleton, an ARCTIC sequence) and runs the command in this process, as
``tests/test_bad_inputs.py`` does: an exception other than the ones the command turns into a message would
fail the test with its traceback. A command that ends must exit 0, or 1 or 2 with a first stderr line
``handsim …: error: …`` and nothing after it but the usage.

Bounded: ``replay`` gets only inputs that cannot be a whole recording (random bytes, or a file cut inside
its first rows), so no example simulates; hypothesis runs derandomized (``tests/conftest.py``), the same
few dozen examples each run, a few seconds in all.
"""

from __future__ import annotations

import re
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from handsim.assets import ASSETS_DIR, TZIONAS_DIR
from handsim.cli import main
from tests.text_samples import glove_rows

ERROR_LINE = re.compile(r"handsim( [a-z]+)?: error: \S.*")
"""The first stderr line of a command that fails (exit 1: a handsim or OS error; 2: a usage error)."""

FUZZ = settings(
    max_examples=20,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def _arctic_sample() -> bytes:
    """A valid ARCTIC ``.mano.npy`` (4 frames of both hands)."""
    import io

    from tests.mano_fixtures import mano_hand_params

    buffer = io.BytesIO()
    np.save(buffer, {"right": mano_hand_params(4, 1), "left": mano_hand_params(4, 2, side="left")})
    return buffer.getvalue()


SAMPLES: dict[str, Callable[[], bytes]] = {
    "01_ex01-rad-001-grasp-su01.txt": lambda: glove_rows(6).encode(),
    "tennis_ball.grasp.json": lambda: (ASSETS_DIR / "demo" / "tennis_ball.grasp.json").read_bytes(),
    "Models/20/Model_Hand_R.MOTION": lambda: (
        TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION"
    ).read_bytes(),
    "s01.mano.npy": _arctic_sample,
}
"""Where each reader looks for its file (relative to a fresh folder), with a valid sample of that file."""

FIRST_ROWS = {"01_ex01-rad-001-grasp-su01.txt": 2}
"""Files cut inside their first N lines for ``replay``: too few rows to be a recording."""


def _folder_for(name: str) -> Path:
    """A fresh folder holding what the file ``name`` needs beside it (a Tzionas motion: its sequence)."""
    folder = Path(tempfile.mkdtemp(prefix="handsim-fuzz-"))
    if name.startswith("Models/"):
        shutil.copytree(TZIONAS_DIR / "Models" / "20", folder / "Models" / "20")
        shutil.copytree(TZIONAS_DIR / "Configs" / "20", folder / "Configs" / "20")
    return folder


def _run(capsys: pytest.CaptureFixture[str], argv: list[str]) -> None:
    """Run ``handsim ARGV`` in this process and check how it ended (see the module docstring)."""
    capsys.readouterr()
    try:
        code = main(argv)
    except SystemExit as exit_:  # argparse's usage errors
        code = exit_.code
    err = capsys.readouterr().err.splitlines()
    if code == 0:
        return
    assert code in (1, 2), (code, err)
    assert err and ERROR_LINE.fullmatch(err[0]), err
    assert all(line.startswith(("usage:", " ")) for line in err[1:2]), err


def _fuzz(capsys: pytest.CaptureFixture[str], command: str, name: str, data: bytes) -> None:
    folder = _folder_for(name)
    try:
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        _run(capsys, [command, str(path)])
    finally:
        shutil.rmtree(folder)


@pytest.mark.parametrize("name", list(SAMPLES))
@FUZZ
@given(data=st.binary(max_size=600))
def test_inspect_of_random_bytes_ends_in_a_one_line_error(capsys, name, data):
    _fuzz(capsys, "inspect", name, data)


@pytest.mark.parametrize("name", list(SAMPLES))
@FUZZ
@given(cut=st.floats(0.0, 1.0))
def test_inspect_of_a_real_file_cut_short_ends_in_a_one_line_error_or_reads(capsys, name, cut):
    sample = SAMPLES[name]()
    _fuzz(capsys, "inspect", name, sample[: int(cut * (len(sample) - 1))])


@pytest.mark.parametrize("name", ["01_ex01-rad-001-grasp-su01.txt", "tennis_ball.grasp.json", "s01.mano.npy"])
@FUZZ
@given(data=st.binary(max_size=600))
def test_replay_of_random_bytes_ends_in_a_one_line_error(capsys, name, data):
    _fuzz(capsys, "replay", name, data)


@pytest.mark.parametrize("name", ["01_ex01-rad-001-grasp-su01.txt", "tennis_ball.grasp.json", "s01.mano.npy"])
@FUZZ
@given(cut=st.floats(0.0, 1.0))
def test_replay_of_a_real_file_cut_short_ends_in_a_one_line_error(capsys, name, cut):
    sample = SAMPLES[name]()
    rows = FIRST_ROWS.get(name)
    end = len(b"".join(sample.splitlines(keepends=True)[:rows])) if rows else len(sample.rstrip()) - 1
    _fuzz(capsys, "replay", name, sample[: int(cut * end)])
