"""Fuzz every text reader: any bytes either read or raise a HandsimError, never another exception.

Two kinds of input per reader: arbitrary bytes, and the reader's valid sample (``tests/text_samples.py``)
with a few edits — bytes inserted, replaced or deleted, or the file cut short — drawn from tokens that
break parsers (numbers out of range, NaN, separators, line breaks that ``str.splitlines`` knows and
``bytes.split`` does not, invalid UTF-8, a byte-order mark, markup). Hypothesis runs derandomized
(``tests/conftest.py``): the same examples on every run.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from handsim.errors import HandsimError
from tests.text_samples import FORMATS, TextFormat

TOKENS = (
    b" ",
    b"\t",
    b"\n",
    b"\r\n",
    b"\r",
    b"\x0b",
    b"\x0c",
    b"\x1c",
    b"\x85",
    b"\xe2\x80\xa8",  # U+2028, a line break for str.splitlines
    b"\x00",
    b"\xff",
    b"\xc3",
    b"\xef\xbb\xbf",
    b"-",
    b"+",
    b".",
    b"e",
    b"0",
    b"1",
    b"3",
    b"-1",
    b"255",
    b"256",
    b"9" * 40,
    b"1e309",
    b"-1e309",
    b"nan",
    b"inf",
    b"1_0",
    b"\xd9\xa3",  # ARABIC-INDIC DIGIT THREE: int() and float() accept it
    b"#",
    b"<",
    b">",
    b"</",
    b'"',
    b"{",
    b"}",
    b"[",
    b"]",
    b":",
    b",",
    b"null",
    b"true",
    b"OFF",
    b"solid",
    b"element",
    b"end_header",
)


@st.composite
def edited(draw: st.DrawFn, sample: bytes) -> bytes:
    """``sample`` with 1 to 4 edits: an insertion, a replacement, a deletion or a cut."""
    data = bytearray(sample)
    for _ in range(draw(st.integers(min_value=1, max_value=4))):
        at = draw(st.integers(min_value=0, max_value=len(data)))
        token = draw(st.sampled_from(TOKENS) | st.binary(min_size=1, max_size=3))
        kind = draw(st.sampled_from(("insert", "replace", "delete", "cut")))
        if kind == "insert":
            data[at:at] = token
        elif kind == "replace":
            data[at : at + len(token)] = token
        elif kind == "delete":
            del data[at : at + draw(st.integers(min_value=1, max_value=8))]
        else:
            del data[at:]
    return bytes(data)


def read_or_refuse(fmt: TextFormat, data: bytes) -> None:
    """Write ``data`` under the format's file name and read it: a HandsimError is an accepted answer."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / fmt.filename
        path.write_bytes(data)
        try:
            fmt.read(path)
        except HandsimError:
            pass


@pytest.mark.parametrize("fmt", FORMATS, ids=[f.name for f in FORMATS])
def test_any_bytes_read_or_raise_a_handsim_error(fmt: TextFormat) -> None:
    @settings(max_examples=150, suppress_health_check=[HealthCheck.too_slow])
    @given(data=st.binary(max_size=300) | edited(fmt.sample))
    def check(data: bytes) -> None:
        read_or_refuse(fmt, data)

    check()
