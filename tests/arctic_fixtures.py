"""Synthetic ARCTIC object templates in the public structure, and recordings of them.

ARCTIC's templates cannot be redistributed, so these are plausible stand-ins for six of its 11 objects,
with the real layout (``../shared/data/SOURCES.md``): vertices in **millimetres** in the object's canonical
frame, either ``top.obj`` + ``bottom.obj`` or ``mesh.obj`` + ``parts.json`` (one label per vertex,
**0 = top, 1 = bottom**). As in ARCTIC, the hinge is the canonical z axis through the origin and the top part
turns by ``R_z(−θ)``: each lid lies along −x from the hinge, closed at θ = 0, opening towards positive θ.
The canonical +y is the object's up; :data:`UPRIGHT` turns it to the world's +z (ARCTIC's world is z-up).

Sizes follow ARCTIC's purchase list where it gives them (the A4 wooden box 338 × 248 × 100 mm, the toy
laptop 320 × 200 mm, a 500 ml ketchup bottle); the others are typical sizes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import trimesh

UPRIGHT = (math.pi / 2, 0.0, 0.0)
"""Axis-angle turning a template's +y (up) to the world's +z: R_x(90°)."""

_LOCAL_TO_TEMPLATE = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
"""Builder frame (X, Y horizontal, Z up) → template frame: X → x, Y → −z, Z → y (a rotation)."""


def block(x: tuple[float, float], y: tuple[float, float], z: tuple[float, float]) -> trimesh.Trimesh:
    """An axis-aligned box in template coordinates (mm)."""
    box = trimesh.creation.box(extents=(x[1] - x[0], y[1] - y[0], z[1] - z[0]))
    box.apply_translation([(x[0] + x[1]) / 2, (y[0] + y[1]) / 2, (z[0] + z[1]) / 2])
    return box


def _upright(mesh: trimesh.Trimesh, centre_x: float, base_y: float, centre_z: float = 0.0) -> trimesh.Trimesh:
    """A mesh built with Z up around the origin (base at Z = 0), stood up in the template frame."""
    out = mesh.copy()
    transform = np.eye(4)
    transform[:3, :3] = _LOCAL_TO_TEMPLATE
    transform[:3, 3] = [centre_x, base_y, centre_z]
    out.apply_transform(transform)
    return out


def tray(half_x: float, half_z: float, height: float, wall: float, floor: float) -> trimesh.Trimesh:
    """An open rectangular tray (walls ``wall`` thick, a floor ``floor`` thick), Z up, base at Z = 0.

    A 4-section revolve of the wall profile (a square), turned 45° and stretched to the rectangle: one
    closed, watertight, concave surface (no boolean operations needed).
    """
    t = wall / min(half_x, half_z)
    profile = np.array([[0, 0], [1, 0], [1, height], [1 - t, height], [1 - t, floor], [0, floor], [0, 0]])
    mesh = trimesh.creation.revolve(profile, sections=4)
    turn = trimesh.transformations.rotation_matrix(math.pi / 4, [0, 0, 1])
    mesh.apply_transform(turn)
    mesh.apply_scale([half_x * math.sqrt(2), half_z * math.sqrt(2), 1.0])
    return mesh


def bottle() -> trimesh.Trimesh:
    """A 500 ml squeeze bottle with a shoulder and a cap seat, Z up, base at Z = 0 (190 mm tall)."""
    profile = np.array([[0, 0], [32, 0], [32, 150], [24, 168], [20, 170], [20, 190], [0, 190], [0, 0]])
    return trimesh.creation.revolve(profile, sections=24)


def disk(radius: float, height: float) -> trimesh.Trimesh:
    """A cylinder, Z up, base at Z = 0."""
    cylinder = trimesh.creation.cylinder(radius=radius, height=height, sections=24)
    cylinder.apply_translation([0.0, 0.0, height / 2])
    return cylinder


def template_parts() -> dict[str, tuple[trimesh.Trimesh, trimesh.Trimesh, str]]:
    """Object name → (bottom, top, layout), template frame in mm; layout ``"parts"`` or ``"mesh"``."""
    return {
        # A4 wooden box: a 90 mm tray and a 10 mm lid hinged on the back top edge.
        "box": (
            _upright(tray(124.0, 169.0, 90.0, 8.0, 8.0), -124.0, -90.0),
            block((-248.0, 0.0), (0.0, 10.0), (-169.0, 169.0)),
            "parts",
        ),
        # Toy laptop: a 20 mm base and a 12 mm screen, 320 × 200 mm.
        "laptop": (
            block((-200.0, 0.0), (-20.0, 0.0), (-160.0, 160.0)),
            block((-200.0, 0.0), (0.0, 12.0), (-160.0, 160.0)),
            "mesh",
        ),
        # Toy waffle iron: a base with a 15 mm deep plate recess, and a 35 mm lid.
        "waffleiron": (
            _upright(tray(90.0, 100.0, 45.0, 15.0, 30.0), -90.0, -45.0),
            block((-180.0, 0.0), (0.0, 35.0), (-100.0, 100.0)),
            "parts",
        ),
        # A5 planner: the page block with the back cover, and the 2.5 mm front cover on the spine.
        "notebook": (
            block((-148.0, 0.0), (-13.0, 0.0), (-105.0, 105.0)),
            block((-148.0, 0.0), (0.0, 2.5), (-105.0, 105.0)),
            "parts",
        ),
        # Ketchup: the bottle (cap seat up to y = 0) and the flip lid hinged at the cap's back edge.
        "ketchup": (
            _upright(bottle(), -20.0, -190.0),
            _upright(disk(20.0, 8.0), -20.0, 0.0),
            "mesh",
        ),
        # Flip phone: two 100 × 52 mm halves.
        "phone": (
            block((-100.0, 0.0), (-11.0, 0.0), (-26.0, 26.0)),
            block((-100.0, 0.0), (0.0, 9.0), (-26.0, 26.0)),
            "parts",
        ),
    }


RECORDED_ARTICULATION = {
    "box": (0.0, 1.2),
    "laptop": (0.0, 1.6),
    "waffleiron": (0.0, 1.0),
    "notebook": (0.0, 2.5),
    "ketchup": (0.0, 2.0),
    "phone": (0.0, 2.6),
}
"""Articulation (rad) each synthetic recording runs between: from closed to open and back."""


def write_obj(path: Path, mesh: trimesh.Trimesh) -> None:
    """Write an OBJ with 6 decimals (mm), vertices in mesh order."""
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in mesh.vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces]
    path.write_text("\n".join(lines) + "\n")


def write_template(
    folder: Path, name: str, parts: tuple[trimesh.Trimesh, trimesh.Trimesh, str] | None = None
) -> Path:
    """Write ``folder/<name>/`` in its layout; returns the template folder.

    ``parts``: (bottom, top, layout) in mm, layout ``"parts"`` (top.obj + bottom.obj) or ``"mesh"``
    (mesh.obj + parts.json); default :func:`template_parts`' of ``name``.
    """
    bottom, top, layout = parts or template_parts()[name]
    out = folder / name
    out.mkdir(parents=True)
    if layout == "parts":
        write_obj(out / "bottom.obj", bottom)
        write_obj(out / "top.obj", top)
    else:
        write_obj(out / "mesh.obj", trimesh.util.concatenate([top, bottom]))
        labels = [0] * len(top.vertices) + [1] * len(bottom.vertices)  # ARCTIC: 0 = top, 1 = bottom
        (out / "parts.json").write_text(json.dumps(labels))
    return out


def read_obj_vertices(path: Path) -> np.ndarray:
    """The ``v`` lines of an OBJ, as written (mm), independent of handsim's readers."""
    rows = [line.split()[1:4] for line in path.read_text().splitlines() if line.startswith("v ")]
    return np.array(rows, dtype=float)


def template_vertices_mm(folder: Path) -> dict[str, np.ndarray]:
    """Part → its template vertices in mm, read from the files independently (``parts.json``: 0 = top)."""
    if (folder / "top.obj").is_file():
        return {part: read_obj_vertices(folder / f"{part}.obj") for part in ("bottom", "top")}
    vertices = read_obj_vertices(folder / "mesh.obj")
    labels = np.array(json.loads((folder / "parts.json").read_text()))
    return {"top": vertices[labels == 0], "bottom": vertices[labels == 1]}


def recording(name: str, n: int = 40) -> np.ndarray:
    """An ARCTIC object recording, float32 (n, 7): upright, ~1 m up, articulation closed → open → closed."""
    lo, hi = RECORDED_ARTICULATION[name]
    t = np.arange(n) / 30.0
    art = lo + (hi - lo) * 0.5 * (1.0 - np.cos(2.0 * np.pi * t / t[-1]))
    rotvec = np.tile(UPRIGHT, (n, 1)) + 0.1 * np.sin(2.0 * np.pi * 0.5 * t)[:, None] * [0.0, 0.3, 1.0]
    trans = np.array([30.0, -40.0, 1020.0]) + np.column_stack([20.0 * np.sin(t), 10.0 * t, 0.0 * t])
    return np.column_stack([art, rotvec, trans]).astype(np.float32)
