"""One small valid sample of every text format handsim reads, with the reader that reads it.

Used by the encoding test (BOM, CRLF and trailing blanks read like the plain file) and by the fuzz test
(any bytes either read or raise a HandsimError). Every sample is made here or taken from the bundled
data, so neither test needs ``../shared``.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timedelta
from pathlib import Path

import trimesh

from handsim.assets import TZIONAS_DIR
from handsim.glove import GloveCalibration
from handsim.io.graspdb.annotations import read_phase_annotations
from handsim.io.graspdb.calibration import load_calibration
from handsim.io.graspdb.glove import read_graspdb_glove, read_graspdb_raw
from handsim.io.graspdb.xmlskel import read_xmlskel
from handsim.io.mesh import read_mesh_arrays
from handsim.io.off import read_off
from handsim.io.scripted import read_scripted_grasp
from handsim.io.tzionas.configs import read_index_bounds, read_models_info
from handsim.io.tzionas.motion_file import read_motion
from handsim.io.tzionas.skel import read_limits, read_skel
from handsim.io.tzionas.surface import read_skin, read_voi
from tests.test_io_tzionas import LIMITS, MOTION, OFF, SKEL, SKIN

BONES = ["Lower Arm", "Fing.0", "Fing.1"]


@dataclass(frozen=True)
class TextFormat:
    """A text format: the file name a sample is written under, the sample, and the reader."""

    name: str
    filename: str
    sample: bytes
    read: Callable[[Path], object]


def glove_rows(n: int = 4, counts: bool = False, step_ms: int = 16) -> str:
    """``n`` GraspDB14 rows 16 ms apart: angles in radians, or (``counts``) raw counts."""
    start = datetime(2014, 9, 15, 8, 2, 9, 24000)
    lines = []
    for i in range(n):
        d = start + timedelta(milliseconds=step_ms * i)
        seconds = d.second + d.microsecond / 1e6
        stamp = f"{d.year} {d.month:02d} {d.day:02d} {d.hour:02d} {d.minute:02d} {seconds:08.5f}"
        values = (
            [str(100 + k + i) for k in range(23)] if counts else [f"{0.01 * (k + i):.5f}" for k in range(23)]
        )
        lines.append(f"{stamp} 1 {' '.join(values)} \n")
    return "".join(lines)


def _calibration() -> bytes:
    gains = tuple(-0.015 - 0.0001 * i for i in range(23))
    offsets = tuple(100.0 + i for i in range(23))
    calibration = GloveCalibration(gains=gains, offsets=offsets, provenance="sample")
    return json.dumps(calibration.to_dict(), indent=2).encode()


XMLSKEL = """<skeleton>
<units><angle>deg</angle><length>mm</length></units>
<joint><name>root</name><id>1</id><position>0 0 0</position>
<limits><rotx>-180 180</rotx><roty>0 0</roty><rotz>0 0</rotz></limits>
<joint><name>a-mcp</name><id>2</id><position>10 -20 0</position>
<limits><rotx>0 90</rotx><roty>0 0</roty><rotz>-10 20</rotz></limits>
<joint><name>a-tip</name><id>3</id><position>0 -60 0</position>
<limits><rotx>0 0</rotx><roty>0 0</roty><rotz>0 0</rotz></limits></joint></joint></joint>
</skeleton>
"""

ANNOTATION = "# interval   annotation\n   1    2    .rest\n   3    4    reach-closing\n"

VOI = "1\n2\n3\n4\n0\n\n0\n1\n2\n3\n4\n"


def _box(file_type: str) -> bytes:
    """A 50 mm box as OBJ, ASCII STL, ASCII PLY or OFF text, comments dropped (so a BOM meets data)."""
    exported = trimesh.creation.box((50.0, 50.0, 50.0)).export(
        file_type=file_type, **({"encoding": "ascii"} if file_type == "ply" else {})
    )
    text = exported.decode() if isinstance(exported, bytes) else exported
    return "".join(line + "\n" for line in text.splitlines() if not line.startswith("#")).encode()


FORMATS: tuple[TextFormat, ...] = (
    TextFormat("graspdb rad", "01_ex01-rad-001-grasp-su01.txt", glove_rows().encode(), read_graspdb_glove),
    TextFormat(
        "graspdb raw", "01_ex01-raw-001-grasp-su01.txt", glove_rows(counts=True).encode(), read_graspdb_raw
    ),
    TextFormat("glove calibration", "calibration.json", _calibration(), load_calibration),
    TextFormat(
        "phase annotation",
        "01_ex01-rad-001-grasp-su01_annot-.txt",
        ANNOTATION.encode(),
        read_phase_annotations,
    ),
    TextFormat("xmlskel", "hand.xmlskel", XMLSKEL.encode(), read_xmlskel),
    TextFormat("SKEL", "m.SKEL", SKEL.encode(), read_skel),
    TextFormat("LIMITS", "m.LIMITS", LIMITS.encode(), lambda p: read_limits(p, BONES, root=BONES[0])),
    TextFormat("MOTION", "m.MOTION", MOTION.encode(), lambda p: read_motion(p, BONES, expected_frames=2)),
    TextFormat("Tzionas OFF", "m.OFF", OFF.encode(), read_off),
    TextFormat("SKIN", "m.SKIN", SKIN.encode(), lambda p: read_skin(p, BONES, 5)),
    TextFormat("VOI", "m.VOI", VOI.encode(), read_voi),
    TextFormat(
        "INDEX_BOUNDS",
        "INDEX_BOUNDS.txt",
        (TZIONAS_DIR / "Configs/20/INDEX_BOUNDS.txt").read_bytes(),
        read_index_bounds,
    ),
    TextFormat(
        "MODELS_INFO",
        "MODELS_INFO.txt",
        (TZIONAS_DIR / "Configs/20/MODELS_INFO.txt").read_bytes(),
        read_models_info,
    ),
    TextFormat(
        "scripted grasp",
        "tennis_ball.grasp.json",
        (TZIONAS_DIR.parent / "demo" / "tennis_ball.grasp.json").read_bytes(),
        read_scripted_grasp,
    ),
    *(
        TextFormat(
            f"{kind.upper()} mesh", f"box.{kind}", _box(file_type), lambda p: read_mesh_arrays(p, "mm")
        )
        for kind, file_type in (("obj", "obj"), ("stl", "stl_ascii"), ("ply", "ply"), ("off", "off"))
    ),
)
"""Every text format, by name."""


def as_windows_file(data: bytes) -> bytes:
    """The bytes as a Windows editor may save them: a UTF-8 byte-order mark, CRLF, blanks before each end."""
    lines = data.replace(b"\r\n", b"\n").split(b"\n")
    return b"\xef\xbb\xbf" + b" \t\r\n".join(lines)
