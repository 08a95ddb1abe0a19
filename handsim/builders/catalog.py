"""The object catalogue: GraspDB14's objects, the bundled Tzionas objects, ARCTIC templates, any mesh file.

* :func:`get` — a catalogue object by name (``"tennis_ball"``, ``"mug"``, ``"tzionas_cube"`` …);
* :func:`get_graspdb` — a GraspDB14 object by its id in the report's Table 4.1;
* :func:`entries` — every catalogue object with its size and mass (what ``handsim catalog`` prints);
* :func:`arctic` — an ARCTIC template folder (ARCTIC cannot be redistributed; point at your copy);
* :func:`resolve` — what the command line accepts: a catalogue name, an ARCTIC template folder, a
  Tzionas ``.SKEL`` or a mesh file.

All return :class:`handsim.datatypes.object_model.ObjectModel`; :func:`handsim.builders.build_object` builds
them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from handsim.assets import TZIONAS_DIR
from handsim.builders.arctic_objects import arctic_object
from handsim.builders.graspdb_objects import (
    GRASPDB_OBJECTS,
    UnknownObjectError,
    graspdb_object,
)
from handsim.datatypes.object_model import ObjectModel, mesh_object
from handsim.datatypes.physical_ranges import DENSITY, OBJECT_MASS
from handsim.errors import InputFileError
from handsim.io.arctic.sequence import ARCTIC_OBJECTS as ARCTIC_NAMES
from handsim.io.mesh import MESH_SUFFIXES, read_mesh
from handsim.io.text_files import require_file
from handsim.io.tzionas.objects import read_tzionas_object

DEFAULT_DENSITY = 1000.0
"""kg/m³ for a mesh file given neither density nor mass (water; plastics are 900–1400)."""

TZIONAS_OBJECTS = {
    "tzionas_cube": ("Models/20/Model_Object_Cube.SKEL", "the 53 mm cube of Tzionas et al. sequence 20"),
    "tzionas_pipe": ("Models/17/Model_Object_Pipe_Gray.SKEL", "the two-part bendable pipe of sequence 17"),
}


@dataclass(frozen=True)
class CatalogEntry:
    """One catalogue object, described without building it.

    Attributes:
        name: Catalogue name.
        source: ``"graspdb14"`` or ``"tzionas"``.
        description: What the object is.
        size: Key dimensions, e.g. ``"Ø 64 mm"``.
        mass_kg: Mass in kg, or None when it is computed from an assumed density.
        graspdb_id: The GraspDB14 object id, or None.
        load: Makes the object model.
    """

    name: str
    source: str
    description: str
    size: str
    mass_kg: float | None
    graspdb_id: int | None
    load: Callable[[], ObjectModel]


def _tzionas_model(name: str) -> ObjectModel:
    model = read_tzionas_object(TZIONAS_DIR / TZIONAS_OBJECTS[name][0])
    return replace(model, name=name)


def entries() -> tuple[CatalogEntry, ...]:
    """Every catalogue object: GraspDB14's in Table 4.1 order, then the Tzionas objects."""
    graspdb = tuple(
        CatalogEntry(
            name=o.name,
            source="graspdb14",
            description=o.description,
            size=o.size_note,
            mass_kg=o.mass_kg,
            graspdb_id=o.graspdb_id,
            load=o.object_model,
        )
        for o in GRASPDB_OBJECTS
    )
    tzionas = tuple(
        CatalogEntry(
            name=name,
            source="tzionas",
            description=description,
            size="53 mm cube" if name == "tzionas_cube" else "350 mm × Ø 48 mm, bends at the middle ±170°",
            mass_kg=None,
            graspdb_id=None,
            load=lambda name=name: _tzionas_model(name),
        )
        for name, (_, description) in TZIONAS_OBJECTS.items()
    )
    return graspdb + tzionas


def names() -> tuple[str, ...]:
    """Names of every catalogue object."""
    return tuple(e.name for e in entries())


def get(name: str) -> ObjectModel:
    """A catalogue object by name.

    Raises:
        UnknownObjectError: No such object; the message lists the valid names.
    """
    for entry in entries():
        if entry.name == name:
            return entry.load()
    raise UnknownObjectError(f"unknown object {name!r}; catalogue objects are: {', '.join(sorted(names()))}")


def get_graspdb(object_id: int) -> ObjectModel:
    """A GraspDB14 object by its id (the report's Table 4.1; file names carry it).

    Raises:
        UnknownObjectError: No such id; the message lists the valid ids.
    """
    return graspdb_object(object_id).object_model()


def arctic(folder: str | Path, *, density: float | None = None, mass: float | None = None) -> ObjectModel:
    """An ARCTIC object template (``…/meta/object_vtemplates/<name>/``) as built.

    With the hinge range, colliding parts and the object's own mass (:mod:`handsim.builders.arctic_objects`).
    """
    return arctic_object(folder, density=density, mass=mass)


def resolve(
    what: str | Path,
    *,
    units: str | None = None,
    density: float | None = None,
    mass: float | None = None,
    force: bool = False,
) -> ObjectModel:
    """An object from a catalogue name, an ARCTIC template folder, a Tzionas ``.SKEL`` or a mesh file.

    Args:
        what: The name or path.
        units: A mesh file's units, ``"m"`` or ``"mm"`` (required for mesh files).
        density: Density in kg/m³ for a mesh file (default 1000, water), or to override a catalogue,
            ARCTIC or Tzionas object's own.
        mass: Total mass in kg instead of a density (the mesh may then be open).
        force: Accept a ``density`` or ``mass`` outside its documented range
            (:mod:`handsim.datatypes.physical_ranges`); checked before any file is read. The built object's
            total mass is checked again by :func:`handsim.builders.objects.prepare_object`.

    Returns:
        The object model.

    Raises:
        OutOfRangeError: ``density`` or ``mass`` is implausible and ``force`` is False.
        UnknownObjectError: Not a path and not a catalogue name (the message lists the names), or the name
            of an ARCTIC object (its template folder is needed).
        InputFileError: A mesh file without ``units``; a path that does not exist (a file or folder name,
            not a catalogue name); a file or name with an extension that is not a mesh's (``.obj``,
            ``.off``, ``.stl``, ``.ply``) or ``.skel``.
    """
    if density is not None:
        DENSITY.check(density, force=force, subject="object ")
    if mass is not None:
        OBJECT_MASS.check(mass, force=force, subject="object ")
    path = Path(what)
    if path.is_dir():
        return arctic(path, density=density, mass=mass)
    suffix = path.suffix.lower()
    _check_path(path, suffix)
    if str(what) in ARCTIC_NAMES and str(what) not in names():
        raise UnknownObjectError(
            f"{what!r} is an ARCTIC object; ARCTIC's templates are not bundled (their licence forbids it): "
            f"pass your template folder, e.g. arctic_data/data/meta/object_vtemplates/{what}"
        )
    if suffix == ".skel":
        return _with_mass(read_tzionas_object(require_file(path)), density, mass)
    if not suffix and path.is_file():
        raise InputFileError(
            f"{path}: a file without a mesh extension; handsim reads meshes {', '.join(MESH_SUFFIXES)} (give "
            "their units), Tzionas object .SKEL files, ARCTIC template folders and catalogue names "
            "(see `handsim catalog`)"
        )
    if suffix in MESH_SUFFIXES:
        return _mesh_file_object(path, units, density, mass)
    return _with_mass(get(str(what)), density, mass)


def _check_path(path: Path, suffix: str) -> None:
    """Refuse an extension handsim reads no object from, or a missing path that is no catalogue name.

    Raises:
        InputFileError: Either, naming what handsim reads (a not-found message says what kind of path).
    """
    if suffix not in ("", ".skel", *MESH_SUFFIXES):
        raise InputFileError(
            f"{path}: unsupported mesh extension {path.suffix!r}; handsim reads meshes "
            f"{', '.join(MESH_SUFFIXES)} (give their units), Tzionas object .SKEL files, ARCTIC template "
            "folders and catalogue names (see `handsim catalog`)"
        )
    if not path.exists() and (len(path.parts) > 1 or suffix) and suffix != ".skel":
        kind = (
            "ARCTIC template folder"
            if path.parent.name == "object_vtemplates"
            else "mesh file"
            if suffix in MESH_SUFFIXES
            else "file or folder"
        )
        raise InputFileError(
            f"{path}: {kind} not found; give a catalogue name (handsim catalog), a mesh file, an ARCTIC "
            "template folder (top.obj + bottom.obj, or mesh.obj + parts.json) or a Tzionas .SKEL"
        )


def _mesh_file_object(
    path: Path, units: str | None, density: float | None, mass: float | None
) -> ObjectModel:
    """An object from a mesh file in the given units; water's density when neither density nor mass is given.

    The mesh must be watertight unless ``mass`` is given (:func:`handsim.io.mesh.read_mesh`).

    Raises:
        InputFileError: No ``units``.
    """
    if units is None:
        raise InputFileError(f"{path}: give the mesh's units ('m' or 'mm'); a wrong guess scales it 1000×")
    mesh = read_mesh(path, units, require_watertight=mass is None)
    assumed = mass is None and density is None
    model = mesh_object(mesh, density=DEFAULT_DENSITY if assumed else density, mass=mass)
    if assumed:
        model = replace(
            model, notes=(*model.notes, f"no density or mass given; {DEFAULT_DENSITY:g} kg/m³ assumed")
        )
    return model


def _with_mass(model: ObjectModel, density: float | None, mass: float | None) -> ObjectModel:
    """The model with a user's density or mass in place of its own (noted), or unchanged."""
    if density is None and mass is None:
        return model
    given = f"mass {mass:g} kg" if mass is not None else f"density {density:g} kg/m³"
    notes = (*model.notes, f"{given} given, replacing the default")
    return replace(model, density=density, mass=mass, notes=notes)
