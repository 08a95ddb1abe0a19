"""A two-hand Tzionas sequence made from the bundled sample (sequence 20: the right hand pinching a cube).

The left hand is a copy of ``Model_Hand_R`` (its ``.SKEL``, ``.LIMITS``, ``.MOTION``, ``.OFF``, ``.SKIN``)
named ``Model_Hand_L``, its recorded global pose moved by :data:`LEFT_SHIFT_MM` along the camera's x axis
(``.MOTION`` format, ``../shared/specs`` README §.MOTION: one line per bone name, then one line per frame
``R (3×3, row-major) T (3)`` in mm, row 0 the rigging pose): every bone's origin ``T`` in every frame row
(rows 1 …; the rigging row 0 and the meshes are kept, so the hand's rest shape is the right hand's) moves by
the shift, a rigid translation of the whole recorded hand. Its bones keep their names (``Lower Arm R`` …): the
scene prefixes each hand's elements, so the names never meet.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from handsim.assets import TZIONAS_DIR

LEFT_SHIFT_MM = (250.0, 0.0, 0.0)
"""The left hand's recorded pose = the right hand's moved 25 cm along the camera's x (image right): the
hands, about 20 cm long, never overlap."""
COPIED = ("SKEL", "LIMITS", "MOTION", "OFF", "SKIN")
"""The right hand's files copied to ``Model_Hand_L.*``."""


def shifted_motion(text: str, shift_mm: tuple[float, float, float]) -> str:
    """A ``.MOTION``'s text with every bone origin moved by ``shift_mm`` in every frame row but row 0."""
    out, row = [], -1
    for line in text.splitlines():
        fields = line.split()
        if len(fields) != 12:  # a bone name: its rows follow, the rigging pose first
            out.append(line)
            row = 0
            continue
        if row > 0:
            values = [float(v) for v in fields]
            values[9:12] = [values[9 + i] + shift_mm[i] for i in range(3)]
            line = " ".join(f"{v:.6g}" for v in values) + " "
        out.append(line)
        row += 1
    return "\n".join(out) + "\n"


def truncated_motion(text: str, rows: int) -> str:
    """A ``.MOTION``'s text with only its first ``rows`` rows (the rigging row 0 included) per bone."""
    out, row = [], 0
    for line in text.splitlines():
        if len(line.split()) != 12:
            row = 0
        elif row >= rows:
            continue
        else:
            row += 1
        out.append(line)
    return "\n".join(out) + "\n"


def two_hand_sample(root: Path, *, shift_mm: tuple[float, float, float] = LEFT_SHIFT_MM) -> Path:
    """Copy the bundled sample to ``root`` and give sequence 20 a left hand listed in its MODELS_INFO.txt.

    Returns:
        The sequence's ``Models/20`` folder.
    """
    shutil.copytree(TZIONAS_DIR, root)
    models = root / "Models" / "20"
    for ext in COPIED:
        source = models / f"Model_Hand_R.{ext}"
        target = models / f"Model_Hand_L.{ext}"
        if ext == "MOTION":
            target.write_text(shifted_motion(source.read_text(), shift_mm))
        else:
            shutil.copyfile(source, target)
    (root / "Configs" / "20" / "MODELS_INFO.txt").write_text(
        "3\nModel_Hand_R\nModel_Hand_L\nModel_Object_Cube\n"
    )
    return models
