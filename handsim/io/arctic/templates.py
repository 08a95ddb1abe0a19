"""Reader for ARCTIC object templates (``meta/object_vtemplates/<name>/``), spec ``004_…txt``.

A template folder holds the object in its canonical frame, in millimetres, as either

* ``top.obj`` + ``bottom.obj`` — the two parts as separate meshes (preferred when present: each part is
  a closed surface, so its volume and mass are defined), or
* ``mesh.obj`` + ``parts.json`` — one mesh and one 0/1 per vertex: **0 = top, 1 = bottom** (ARCTIC's loader
  adds 1 to the labels and takes part id 1 as the top; its data README says the opposite, and is wrong).

The top part rotates relative to the bottom by the articulation angle θ about the object-frame axis
[0, 0, −1] through the origin (ARCTIC's loader applies ``R_z(−θ)`` to top vertices before the global
rotation and translation), so the object becomes two bodies joined by a hinge with axis (0, 0, −1).
This reader returns the geometry as stored (unlimited hinge, density :data:`ARCTIC_DENSITY` unless given);
:func:`handsim.builders.arctic_objects.arctic_object` adds the hinge range, the colliding parts and the
object's own mass — what handsim builds.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from handsim.datatypes.mesh import Mesh, validate_mesh
from handsim.datatypes.object_model import Hinge, ObjectModel, ObjectPart
from handsim.errors import FormatError, InputFileError, MeshError
from handsim.io.mesh import read_mesh, read_mesh_arrays
from handsim.io.text_files import read_text

ARCTIC_HINGE_AXIS = (0.0, 0.0, -1.0)
"""Articulation axis in the object frame: the top part turns by R_z(−θ)."""

ARCTIC_DENSITY = 300.0
"""Fallback density in kg/m³ for a template given neither density nor mass (the reader's default).
:func:`handsim.builders.arctic_objects.arctic_object` gives ARCTIC's 11 objects their own masses instead;
this density serves templates outside them. 300 kg/m³ is a hollow household item's mean density."""


def read_arctic_template(
    folder: str | Path, *, density: float | None = None, mass: float | None = None
) -> ObjectModel:
    """Read an ARCTIC object template folder as a two-part articulated object.

    Args:
        folder: ``…/object_vtemplates/<name>/`` holding ``top.obj`` + ``bottom.obj`` or ``mesh.obj`` +
            ``parts.json`` (vertices in mm).
        density: Uniform density in kg/m³ (default :data:`ARCTIC_DENSITY` unless ``mass`` is given).
        mass: Total mass in kg instead of a density.

    Returns:
        The object: part ``bottom`` (root) and part ``top`` joined by a hinge about (0, 0, −1); object
        frame = template frame, metres.

    Raises:
        InputFileError: The folder is missing, or holds neither layout.
        FormatError: ``parts.json`` is malformed, or its length differs from ``mesh.obj``'s vertex count.
        MeshError: A part's mesh is invalid (see :func:`handsim.datatypes.mesh.validate_mesh`).
    """
    root = Path(folder)
    if not root.is_dir():
        raise InputFileError(f"{root}: ARCTIC template folder not found")
    name = root.name
    notes: list[str] = []
    if density is None and mass is None:
        density = ARCTIC_DENSITY
        notes.append(f"ARCTIC gives no mass; density {ARCTIC_DENSITY:g} kg/m³ assumed")
    watertight = mass is None
    if (root / "top.obj").is_file() and (root / "bottom.obj").is_file():
        parts = {
            part: read_mesh(root / f"{part}.obj", "mm", require_watertight=watertight)
            for part in ("bottom", "top")
        }
    elif (root / "mesh.obj").is_file():
        parts = _split_by_parts(root / "mesh.obj", root / "parts.json", watertight)
    else:
        raise InputFileError(
            f"{root}: not an ARCTIC object template: expected top.obj + bottom.obj, or mesh.obj + parts.json"
        )
    for mesh in parts.values():
        notes.extend(f"{mesh.source}: {n}" for n in mesh.notes)
    return ObjectModel(
        name=name,
        parts=tuple(ObjectPart(part, parts[part]) for part in ("bottom", "top")),
        density=density,
        mass=mass,
        hinge=Hinge(axis=ARCTIC_HINGE_AXIS),
        source=str(root),
        notes=tuple(notes),
    )


def read_parts_json(path: Path, nvertices: int) -> np.ndarray:
    """Read ``parts.json``: one 0 (top) or 1 (bottom) per vertex of ``mesh.obj``.

    Accepts a JSON list (what ARCTIC ships) or one integer per line.

    Args:
        path: The file.
        nvertices: Vertex count of ``mesh.obj``.

    Returns:
        Boolean array, True for top vertices, shape (nvertices,).

    Raises:
        InputFileError: The file is missing.
        FormatError: Not a list of 0/1 values, or of the wrong length.
    """
    if not path.is_file():
        raise InputFileError(
            f"{path}: parts.json not found; ARCTIC's mesh.obj needs it to tell the top part from the bottom"
        )
    text = read_text(path)
    try:
        values = json.loads(text)
    except json.JSONDecodeError:
        values = text.split()
    if isinstance(values, dict) or not isinstance(values, list):
        raise FormatError(path, f"expected a list of 0/1 part labels, got {type(values).__name__}")
    labels = np.empty(len(values), dtype=np.int64)
    for i, value in enumerate(values):
        if str(value).strip() not in ("0", "1"):
            raise FormatError(path, f"part label {i} is {value!r}; expected 0 (top) or 1 (bottom)")
        labels[i] = int(str(value).strip())
    if len(labels) != nvertices:
        raise FormatError(
            path,
            f"{len(labels)} part labels for the {nvertices} vertices of mesh.obj; expected one per vertex",
        )
    return labels == 0


def _split_by_parts(mesh_path: Path, parts_path: Path, watertight: bool) -> dict[str, Mesh]:
    """Split ``mesh.obj`` into bottom and top meshes by ``parts.json`` labels."""
    vertices, faces = read_mesh_arrays(mesh_path, "mm")
    top = read_parts_json(parts_path, len(vertices))
    faces = np.asarray(faces, dtype=np.int64)
    face_top = top[faces]
    mixed = int(np.sum(face_top.any(axis=1) & ~face_top.all(axis=1)))
    result = {}
    for part, mask in (("bottom", ~face_top.any(axis=1)), ("top", face_top.all(axis=1))):
        if not mask.any():
            raise MeshError(f"{mesh_path}: parts.json gives the {part} part no faces")
        used = np.unique(faces[mask])
        remap = np.full(len(vertices), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        mesh = validate_mesh(
            vertices[used], remap[faces[mask]], f"{mesh_path} ({part})", require_watertight=watertight
        )
        if mixed:
            mesh = Mesh(
                mesh.vertices,
                mesh.faces,
                mesh.source,
                mesh.watertight,
                (*mesh.notes, f"dropped {mixed} faces spanning both parts"),
            )
        result[part] = mesh
    return result
