"""Every text reader reads a file saved with a UTF-8 byte-order mark, CRLF line ends and trailing blanks
exactly like the plain file (as Windows editors save them)."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import numpy as np
import pytest

from handsim.assets import TZIONAS_DIR
from handsim.errors import FormatError
from handsim.io import read_skeleton, read_trajectory
from handsim.io.graspdb.calibration import load_calibration
from handsim.io.text_files import decode_text, decode_utf8
from handsim.io.tzionas.objects import read_tzionas_object
from tests.text_samples import FORMATS, TextFormat, as_windows_file


def assert_same(a: object, b: object, where: str = "", moved: tuple[str, str] = ("", "")) -> None:
    """Equal values, recursively through dataclasses, tuples, dicts and arrays.

    ``sha256`` (of the file bytes) is skipped; in text, the folder ``moved[0]`` of ``a`` stands for the
    folder ``moved[1]`` of ``b``.
    """
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        np.testing.assert_array_equal(a, b, err_msg=where)
    elif dataclasses.is_dataclass(a) and not isinstance(a, type):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            if f.name != "sha256":
                assert_same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}", moved)
    elif isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b), where
        for key in a:
            assert_same(a[key], b[key], f"{where}[{key!r}]", moved)
    elif isinstance(a, tuple | list):
        assert type(a) is type(b) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_same(x, y, f"{where}[{i}]", moved)
    elif isinstance(a, str) and moved[0]:
        assert a.replace(moved[0], moved[1]) == b, where
    else:
        assert a == b, where


@pytest.mark.parametrize("fmt", FORMATS, ids=[f.name for f in FORMATS])
def test_bom_crlf_and_trailing_blanks_read_like_the_plain_file(fmt: TextFormat, tmp_path: Path) -> None:
    path = tmp_path / fmt.filename
    path.write_bytes(fmt.sample)
    plain = fmt.read(path)
    windows = as_windows_file(fmt.sample)
    assert windows.startswith(b"\xef\xbb\xbf") and b" \t\r\n" in windows
    path.write_bytes(windows)
    assert_same(fmt.read(path), plain, fmt.name)


@pytest.fixture(scope="module")
def windows_tzionas(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The bundled Tzionas sample with every text file saved as a Windows editor would."""
    root = tmp_path_factory.mktemp("tzionas") / "tzionas_ijcv16"
    shutil.copytree(TZIONAS_DIR, root)
    for path in root.rglob("*"):
        if path.is_file() and path.suffix not in (".md", "") and path.name != "LICENSE":
            path.write_bytes(as_windows_file(path.read_bytes()))
    return root


def test_windows_saved_tzionas_hand_with_mesh_skin_and_voi_reads_like_the_bundled_one(
    windows_tzionas: Path,
) -> None:
    model = "Models/20/Model_Hand_R.SKEL"
    moved = (str(windows_tzionas), str(TZIONAS_DIR))
    assert_same(read_skeleton(windows_tzionas / model), read_skeleton(TZIONAS_DIR / model), "hand", moved)


def test_windows_saved_tzionas_sequence_reads_like_the_bundled_one(windows_tzionas: Path) -> None:
    motion = "Models/20/Model_Hand_R.MOTION"  # with INDEX_BOUNDS.txt, MODELS_INFO.txt and the cube
    moved = (str(windows_tzionas), str(TZIONAS_DIR))
    assert_same(
        read_trajectory(windows_tzionas / motion), read_trajectory(TZIONAS_DIR / motion), "seq", moved
    )


def test_windows_saved_tzionas_pipe_reads_like_the_bundled_one(windows_tzionas: Path) -> None:
    pipe = "Models/17/Model_Object_Pipe_Gray.SKEL"
    moved = (str(windows_tzionas), str(TZIONAS_DIR))
    assert_same(
        read_tzionas_object(windows_tzionas / pipe), read_tzionas_object(TZIONAS_DIR / pipe), "pipe", moved
    )


def test_decode_text_drops_a_bom_and_falls_back_to_latin_1() -> None:
    assert decode_text(b"\xef\xbb\xbf1 2\r\n") == "1 2\r\n"
    assert decode_text(b"caf\xe9") == "café"
    assert decode_text(b"\xef\xbb\xbfcaf\xe9") == "café"


def test_decode_utf8_names_the_file_and_the_byte_offset_counting_the_bom() -> None:
    assert decode_utf8(b"\xef\xbb\xbf{}", "c.json") == "{}"
    with pytest.raises(FormatError, match=r"^c\.json: not UTF-8 text \(invalid start byte at byte 6\)$"):
        decode_utf8(b'\xef\xbb\xbf{"a\xff', "c.json")


def test_calibration_that_is_not_utf8_names_the_byte(tmp_path: Path) -> None:
    path = tmp_path / "c.json"
    path.write_bytes(b'{"format": "\xff"}')
    with pytest.raises(FormatError, match=rf"^{path}: not UTF-8 text \(invalid start byte at byte 12\)$"):
        load_calibration(path)
