"""Reader for object meshes (OBJ, OFF, STL, PLY) with explicit units."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from handsim.errors import InputFileError, MeshError
from handsim.io._text import read_bytes
from handsim.mesh import Mesh, validate_mesh

MESH_SUFFIXES = (".obj", ".off", ".stl", ".ply")
UNIT_SCALES = {"m": 1.0, "mm": 1e-3}
PLAUSIBLE_EXTENT_M = (0.005, 0.6)  # graspable objects: 5 mm to 0.6 m


def read_mesh(path: str | Path, units: str, *, require_watertight: bool = True) -> Mesh:
    """Read a triangle mesh and convert it to metres.

    Args:
        path: An ``.obj``, ``.off``, ``.stl`` or ``.ply`` file.
        units: The unit the file's coordinates are in: ``"m"`` or ``"mm"`` (ARCTIC and Tzionas meshes are
            mm). There is no default: a wrong guess would silently scale the object by 1000.
        require_watertight: See :func:`handsim.mesh.validate_mesh`.

    Returns:
        The validated, repaired mesh in metres.

    Raises:
        InputFileError: Missing or unreadable file, or an unsupported extension.
        MeshError: An unknown unit; an object whose largest extent is outside 5 mm – 0.6 m in the given
            unit (the message suggests the other unit); or any problem :func:`validate_mesh` finds.
    """
    vertices, faces = read_mesh_arrays(path, units)
    return validate_mesh(vertices, faces, str(Path(path)), require_watertight=require_watertight)


def read_mesh_arrays(path: str | Path, units: str) -> tuple[np.ndarray, np.ndarray]:
    """Read a mesh file's vertices (converted to metres, file order kept) and faces, without validation.

    For readers that index vertices in file order (ARCTIC's ``parts.json``) before validating the mesh
    with :func:`handsim.mesh.validate_mesh`.

    Args:
        path: An ``.obj``, ``.off``, ``.stl`` or ``.ply`` file.
        units: ``"m"`` or ``"mm"``.

    Returns:
        Vertices (V, 3) in metres and faces (F, 3).

    Raises:
        InputFileError: Missing or unreadable file, or an unsupported extension.
        MeshError: An unknown unit, an unparsable file, or an implausible size (see :func:`read_mesh`).
    """
    p = Path(path)
    if units not in UNIT_SCALES:
        raise MeshError(f"{p}: unknown units {units!r}; expected one of {sorted(UNIT_SCALES)}")
    suffix = p.suffix.lower()
    data = read_bytes(p)
    if suffix not in MESH_SUFFIXES:
        raise InputFileError(
            f"{p}: unknown mesh file type {p.suffix!r}; handsim reads {', '.join(MESH_SUFFIXES)}"
        )
    options = {"maintain_order": True} if suffix == ".obj" else {}
    try:
        loaded = trimesh.load_mesh(
            trimesh.util.wrap_as_stream(data), file_type=suffix[1:], process=False, **options
        )
    except Exception as exc:  # trimesh raises many types for malformed files
        raise MeshError(f"{p}: cannot parse as {suffix[1:].upper()}: {exc}") from exc
    if isinstance(loaded, trimesh.Scene):
        geometries = list(loaded.geometry.values())
        if not geometries:
            raise MeshError(f"{p}: the file holds no mesh")
        loaded = trimesh.util.concatenate(geometries)
    vertices = np.asarray(loaded.vertices, dtype=float) * UNIT_SCALES[units]
    faces = np.asarray(loaded.faces)
    if len(vertices) and np.all(np.isfinite(vertices)):
        largest = float(np.max(vertices.max(axis=0) - vertices.min(axis=0)))
        low, high = PLAUSIBLE_EXTENT_M
        if not low <= largest <= high:
            other = "mm" if units == "m" else "m"
            raise MeshError(
                f"{p}: the object is {largest:.4g} m across in units={units!r}, outside the plausible "
                f"{low * 1000:g} mm – {high:g} m; are the coordinates in {other}? (pass units={other!r})"
            )
    return vertices, faces
