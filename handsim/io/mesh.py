"""Reader for object meshes (OBJ, OFF, STL, PLY) with explicit units."""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from handsim.datatypes.mesh import Mesh, principal_extents, validate_mesh
from handsim.errors import InputFileError, MeshError
from handsim.io.mesh_counts import check_ascii_ply, check_stl
from handsim.io.obj import check_obj
from handsim.io.off import parse_off
from handsim.io.text_files import UTF8_BOM, decode_text, decode_text_file, read_bytes

MESH_SUFFIXES = (".obj", ".off", ".stl", ".ply")
UNIT_SCALES = {"m": 1.0, "mm": 1e-3}
PLAUSIBLE_EXTENT_M = (0.005, 0.6)  # graspable objects: 5 mm to 0.6 m
MIN_THICKNESS_M = 1e-4
"""Thinnest object a mesh file may describe, m: a sheet of 80 g/m² office paper is about 0.1 mm thick
(the catalogue's thinnest object, the business card, is 0.4 mm); see docs/objects.md."""


def read_mesh(path: str | Path, units: str, *, require_watertight: bool = True) -> Mesh:
    """Read a triangle mesh and convert it to metres.

    Args:
        path: An ``.obj``, ``.off``, ``.stl`` or ``.ply`` file.
        units: The unit the file's coordinates are in: ``"m"`` or ``"mm"`` (ARCTIC and Tzionas meshes are
            mm). There is no default: a wrong guess would silently scale the object by 1000.
        require_watertight: See :func:`handsim.datatypes.mesh.validate_mesh`.

    Returns:
        The validated, repaired mesh in metres.

    Raises:
        InputFileError: Missing or unreadable file, or an unsupported extension.
        FormatError: An OFF file that does not follow its format.
        MeshError: An unknown unit; a file without faces; an object whose largest extent is outside
            5 mm – 0.6 m in the given unit (the message suggests the other unit) or that is thinner than
            :data:`MIN_THICKNESS_M`; or any problem :func:`validate_mesh` finds.
    """
    vertices, faces = read_mesh_arrays(path, units)
    return validate_mesh(vertices, faces, str(Path(path)), require_watertight=require_watertight)


def read_mesh_arrays(path: str | Path, units: str) -> tuple[np.ndarray, np.ndarray]:
    """Read a mesh file's vertices (converted to metres, file order kept) and faces, without validation.

    For readers that index vertices in file order (ARCTIC's ``parts.json``) before validating the mesh
    with :func:`handsim.datatypes.mesh.validate_mesh`. Text files may start with a UTF-8 byte-order mark and
    use
    CRLF line ends; OFF files are read by :func:`handsim.io.off.parse_off` (counts checked), the other
    formats by trimesh.

    Args:
        path: An ``.obj``, ``.off``, ``.stl`` or ``.ply`` file.
        units: ``"m"`` or ``"mm"``.

    Returns:
        Vertices (V, 3) in metres and faces (F, 3).

    Raises:
        InputFileError: Missing or unreadable file, or an unsupported extension.
        FormatError: An OFF file that does not follow its format, an OBJ with a malformed vertex or face
            line (:func:`handsim.io.obj.check_obj`), an ASCII PLY or binary STL that holds fewer or more
            elements than its header promises, a text mesh in UTF-16 or with NUL bytes (file, line and
            field named).
        MeshError: An unknown unit, an unparsable file, a file without faces, an implausible size or an
            object thinner than :data:`MIN_THICKNESS_M` (see :func:`read_mesh`).
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
    if suffix == ".off":
        vertices, faces = parse_off(decode_text_file(data, p), p, UNIT_SCALES[units])
    else:
        data = _without_text_bom(data, suffix)
        if suffix == ".stl":
            check_stl(p, data)
        elif suffix == ".ply":
            check_ascii_ply(p, decode_text(data))
        else:
            check_obj(p, decode_text_file(data, p))
        vertices, faces = _trimesh_arrays(p, data)
        vertices = vertices * UNIT_SCALES[units]
    if len(faces) == 0:
        _no_faces(p, suffix, data, len(vertices))
    if len(vertices) and np.all(np.isfinite(vertices)):
        _check_size(p, vertices, units)
    return vertices, faces


def _no_faces(p: Path, suffix: str, data: bytes, nvertices: int) -> None:
    """Raise the error of a file from which no face was read: a point cloud, or not that format at all."""
    kind = suffix[1:].upper()
    if suffix == ".obj":
        nvertices = _obj_vertex_lines(data)
    elif nvertices == 0:
        raise MeshError(f"{p}: no triangle could be read from it as {kind}; is it a valid {kind} file?")
    lines = " (OBJ 'f' lines)" if suffix == ".obj" else ""
    raise MeshError(
        f"{p}: the file holds {nvertices} vertices but no faces; a mesh needs triangles or polygons{lines} "
        "that close its surface, not a point cloud"
    )


def _without_text_bom(data: bytes, suffix: str) -> bytes:
    """The bytes without a UTF-8 byte-order mark before a text OBJ, ASCII STL (``solid``) or PLY header."""
    rest = data[len(UTF8_BOM) :]
    text_start = {".obj": b"", ".stl": b"solid", ".ply": b"ply"}[suffix]
    return rest if data.startswith(UTF8_BOM) and rest.lstrip().startswith(text_start) else data


def _trimesh_arrays(p: Path, data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (file units) and faces of an OBJ, STL or PLY file, read by trimesh."""
    import trimesh  # lazy: trimesh + SciPy; MESH_SUFFIXES and the OFF reader need neither

    suffix = p.suffix.lower()
    options = {"maintain_order": True} if suffix == ".obj" else {}
    try:
        with _quiet_trimesh():
            loaded = trimesh.load_mesh(
                trimesh.util.wrap_as_stream(data), file_type=suffix[1:], process=False, **options
            )
        if isinstance(loaded, trimesh.Scene):
            geometries = [g for g in loaded.geometry.values() if isinstance(g, trimesh.Trimesh)]
            loaded = trimesh.util.concatenate(geometries) if geometries else trimesh.Trimesh()
        vertices = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=float).reshape(-1, 3)
        faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    except Exception as exc:  # trimesh raises many types for malformed files
        raise MeshError(f"{p}: cannot parse as {suffix[1:].upper()}: {exc}") from exc
    return vertices, faces


@contextlib.contextmanager
def _quiet_trimesh() -> Iterator[None]:
    """Silence trimesh's logger while it reads a file.

    On a malformed file trimesh logs the traceback of every fallback it tries; handsim reports the
    failure itself, in one line.
    """
    log = logging.getLogger("trimesh")
    level = log.level
    log.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        log.setLevel(level)


def _obj_vertex_lines(data: bytes) -> int:
    """Number of ``v`` (vertex) lines in an OBJ file."""
    return sum(1 for line in decode_text(data).splitlines() if line.split()[:1] == ["v"])


def _check_size(p: Path, vertices: np.ndarray, units: str) -> None:
    """Refuse an object whose largest extent is implausible for ``units`` or that is thinner than a sheet."""
    largest = float(np.max(vertices.max(axis=0) - vertices.min(axis=0)))
    low, high = PLAUSIBLE_EXTENT_M
    if not low <= largest <= high:
        other = "mm" if units == "m" else "m"
        raise MeshError(
            f"{p}: the object is {largest:.4g} m across in units={units!r}, outside the plausible "
            f"{low * 1000:g} mm – {high:g} m; are the coordinates in {other}? (pass units={other!r})"
        )
    thickness = float(principal_extents(vertices).min())
    if thickness < MIN_THICKNESS_M:
        raise MeshError(
            f"{p}: the object is {thickness * 1000:.3g} mm thick (its smallest extent along its principal "
            f"axes), thinner than the {MIN_THICKNESS_M * 1000:g} mm handsim accepts (a sheet of paper); a "
            "surface this thin has no usable volume, mass or contact"
        )
