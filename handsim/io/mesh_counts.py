"""Checks that a binary STL or an ASCII PLY holds what its header promises, before trimesh reads it.

trimesh reads past such promises silently: an ASCII PLY whose header promises more faces than follow
loads with the faces present, a binary STL whose triangle count exceeds its size loads empty. handsim
refuses both, naming the header's promise and what the file holds. (OFF headers are checked by
:func:`handsim.io.off.parse_off`; OBJ has no header.)
"""

from __future__ import annotations

from pathlib import Path

from handsim.errors import FormatError

STL_HEADER_BYTES = 84
"""80 bytes of free text, then the triangle count (uint32, little-endian)."""
STL_TRIANGLE_BYTES = 50
"""Normal and three vertices (12 float32) and a 2-byte attribute per triangle."""


def check_stl(path: str | Path, data: bytes) -> None:
    """Refuse a binary STL whose size is not the one its triangle count gives.

    A file that starts with ``solid`` and does not have a binary STL's size is ASCII, and trimesh reads it.

    Raises:
        FormatError: The file is neither ASCII (``solid``) nor a binary STL of the size its count gives.
    """
    if len(data) >= STL_HEADER_BYTES:
        count = int.from_bytes(data[80:STL_HEADER_BYTES], "little")
        size = STL_HEADER_BYTES + STL_TRIANGLE_BYTES * count
        if len(data) == size:
            return
    if data.lstrip().startswith(b"solid"):
        return
    if len(data) < STL_HEADER_BYTES:
        msg = f"{len(data)} bytes: not ASCII STL (no 'solid') and shorter than a binary STL's 84-byte header"
        raise FormatError(path, msg, field="header")
    raise FormatError(
        path,
        f"the binary STL header promises {count} triangles ({size} bytes), but the file has {len(data)} "
        "bytes",
        field="triangle count",
    )


def check_ascii_ply(path: str | Path, text: str) -> None:
    """Refuse an ASCII PLY whose data lines are not as many as its ``element`` lines promise.

    Each element instance (a vertex, a face …) of an ASCII PLY is one line after ``end_header``. Binary
    PLY files are left to trimesh (it checks their length), as are headers it cannot read.

    Raises:
        FormatError: The count of non-blank lines after ``end_header`` differs from the sum of the element
            counts (the message names the header's ``end_header`` line and both numbers).
    """
    lines = text.splitlines()
    end = next((i for i, line in enumerate(lines) if line.strip() == "end_header"), None)
    if end is None or not any(line.split()[:2] == ["format", "ascii"] for line in lines[:end]):
        return
    elements = []
    for line in lines[:end]:
        tokens = line.split()
        if tokens[:1] == ["element"] and len(tokens) == 3 and tokens[2].isdecimal():
            elements.append((tokens[1], int(tokens[2])))
    promised = sum(n for _, n in elements)
    present = sum(1 for line in lines[end + 1 :] if line.strip())
    if present != promised:
        listing = ", ".join(f"{n} {name!r}" for name, n in elements)
        msg = f"the header promises elements {listing} ({promised} data lines), but {present} follow it"
        raise FormatError(path, msg, line=end + 1, field="header")


__all__ = ["check_ascii_ply", "check_stl"]
