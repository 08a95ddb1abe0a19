"""The GraspDB14 objects (report Table 4.1, ids 1–16) as generated meshes with realistic sizes and masses.

The report gives only a few sizes (tennis ball 64 mm, pen 2 cm, bottle 8 cm and its cap 3 cm, oval jar lid
7 cm, glass 62 mm, notebook 15 mm thick, cylinders 10 and 25 mm, carton 7.6 × 26 × 37.5 cm); every other
dimension and every mass is a typical real-world value, chosen and explained in each object's
``size_note`` and ``notes`` and in ``docs/objects.md``.

Frame of every object: origin at the centre of the mesh's axis-aligned bounding box, z up as the object
stands or lies on the table in the recordings, x along the longest horizontal extent (the mug's handle
points to +x), units metres. Meshes are generated (no files, no randomness), watertight without any repair
by :func:`handsim.datatypes.mesh.validate_mesh`, and cached per process. Objects whose collision shape is
exactly a
set of MuJoCo primitives carry them in ``primitives`` (no convex decomposition needed); the hollow or
waisted ones have ``primitives == ()`` and must be decomposed.

No MuJoCo imports here: plain data and numpy; the meshes are generated, with trimesh, by
:mod:`handsim.builders.graspdb_meshes` when first asked for.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from handsim.builders.graspdb_shapes import Q_Z_TO_X, box_primitive, crate_boxes
from handsim.datatypes.mesh import Mesh, validate_mesh
from handsim.datatypes.object_model import ObjectModel, ObjectPart, Primitive
from handsim.errors import HandsimError

__all__ = [
    "GRASPDB_OBJECTS",
    "GraspDBObject",
    "Primitive",
    "UnknownObjectError",
    "clear_mesh_cache",
    "graspdb_object",
]


class UnknownObjectError(HandsimError, KeyError):
    """A name or GraspDB id that is not in the catalogue; the message lists the valid ones."""

    def __str__(self) -> str:
        # KeyError would print the message quoted; show it as written.
        return str(self.args[0]) if self.args else ""


@dataclass(frozen=True)
class GraspDBObject:
    """One object of the GraspDB14 catalogue.

    Attributes:
        name: Snake-case name, e.g. ``"tennis_ball"``, ``"carton_standing"``.
        graspdb_id: The object id of report Table 4.1 (first field of a motion file name).
        description: The object as the report names it in Table 4.1.
        mass_kg: Mass in kg (see ``notes`` for the source or the reasoning).
        size_note: The key dimensions in mm and where they come from.
        primitives: The exact collision shape as MuJoCo primitives in the object frame, or ``()`` when the
            mesh must be decomposed into convex hulls.
        notes: Decisions taken for this object (material, fill, what the report leaves open).
    """

    name: str
    graspdb_id: int
    description: str
    mass_kg: float
    size_note: str
    primitives: tuple[Primitive, ...]
    notes: tuple[str, ...]

    def mesh(self) -> Mesh:
        """The object's watertight triangle mesh in metres, in the object frame (cached).

        Cached per process, and on disk across processes (:mod:`handsim.builders.mesh_cache`). The arrays
        are read-only: they are shared by every caller.
        """
        return _cached_mesh(self.name)

    @property
    def density_kg_m3(self) -> float:
        """Mass divided by the mesh's enclosed volume, kg/m³ (uniform density giving ``mass_kg``)."""
        return self.mass_kg / self.mesh().volume

    def object_model(self) -> ObjectModel:
        """The object as a one-part `ObjectModel` for the object builder.

        The density is chosen so that mesh volume × density equals ``mass_kg``.
        """
        return ObjectModel(
            name=self.name,
            parts=(ObjectPart("body", self.mesh(), self.primitives),),
            density=self.density_kg_m3,
            source=f"GraspDB14 object {self.graspdb_id} ({self.description}), generated",
            notes=(self.size_note, *self.notes),
        )


def clear_mesh_cache() -> None:
    """Forget this process's meshes (read back from the disk cache, or regenerated identically, next call)."""
    _cached_mesh.cache_clear()


# --------------------------------------------------------------------------------------------------------
# The catalogue

_TENNIS_BALL = (Primitive("sphere", (0.032,)),)
_PEN = (Primitive("cylinder", (0.010, 0.070), quat=Q_Z_TO_X),)
_CUBE = (Primitive("box", (0.025, 0.025, 0.025)),)
_CARD = (Primitive("box", (0.0425, 0.0275, 0.0002)),)
_NOTEBOOK = (Primitive("box", (0.105, 0.065, 0.0075)),)
_CYLINDER_10 = (Primitive("cylinder", (0.005, 0.100), quat=Q_Z_TO_X),)
_CYLINDER_25 = (Primitive("cylinder", (0.0125, 0.100), quat=Q_Z_TO_X),)
_CARTON_LYING = (Primitive("box", (0.1875, 0.130, 0.038)),)
_CARTON_STANDING = (Primitive("box", (0.130, 0.038, 0.1875)),)
_CRATE = tuple(box_primitive(lo, hi) for lo, hi in crate_boxes())

_BOTTLE_NOTES = (
    "filled: the report says the bottle 'is filled with water but stays closed'; modelled as a 1.0 l PET "
    "bottle (80 mm is the usual diameter of 1 l PET bottles; a 1.5 l one is about 90 mm): 1000 g water + "
    "about 35 g bottle and cap",
    "the closed outer surface (body with grip waist, shoulder, neck ring, cap) is the collision and mass "
    "shape; uniform density over it is right for the water, which is 97 % of the mass (no sloshing)",
)

GRASPDB_OBJECTS: tuple[GraspDBObject, ...] = (
    GraspDBObject(
        name="tennis_ball",
        graspdb_id=1,
        description="Tennis ball (64 mm diameter)",
        mass_kg=0.0575,
        size_note="diameter 64 mm (report Table 4.1)",
        primitives=_TENNIS_BALL,
        notes=("mass 57.5 g: middle of the ITF range 56.0–59.4 g",),
    ),
    GraspDBObject(
        name="pen",
        graspdb_id=2,
        description="Pen (2 cm diameter)",
        mass_kg=0.020,
        size_note="diameter 20 mm (report Table 4.1); length 140 mm (typical, chosen: a capped pen/marker)",
        primitives=_PEN,
        notes=(
            "lies on the table with its axis along x",
            "a plain cylinder (the cap and tip are not modelled); 20 g: a 2 cm thick plastic pen or "
            "marker weighs 15–25 g",
        ),
    ),
    GraspDBObject(
        name="bottle",
        graspdb_id=3,
        description="Bottle (8 cm diameter)",
        mass_kg=1.035,
        size_note="diameter 80 mm (report Table 4.1), cap 30 mm (report Table 3.3); height 280 mm "
        "(typical, chosen: 1.0 l PET water bottle)",
        primitives=(),
        notes=_BOTTLE_NOTES,
    ),
    GraspDBObject(
        name="mug",
        graspdb_id=4,
        description="Mug",
        mass_kg=0.340,
        size_note="outer diameter 82 mm, height 95 mm, wall 5 mm, handle reaching 32 mm out (typical, "
        "chosen: a standard ceramic mug, about 350 ml to the brim; the report gives no size)",
        primitives=(),
        notes=(
            "empty (the report does not say it held liquid in transport)",
            "340 g: ceramic mugs of this size weigh 300–350 g; gives stoneware density ≈ 2.3 g/cm³",
            "the handle is a separate closed tube whose end caps touch the outer wall (no shared volume)",
        ),
    ),
    GraspDBObject(
        name="glass",
        graspdb_id=5,
        description="Glass (62 mm diameter)",
        mass_kg=0.170,
        size_note="outer diameter 62 mm (report Table 4.1); height 100 mm, wall 2.5 mm, base 8 mm (typical, "
        "chosen: a straight 0.2 l tumbler)",
        primitives=(),
        notes=("empty; 170 g is the mesh volume times soda-lime glass density 2.5 g/cm³",),
    ),
    GraspDBObject(
        name="bowl",
        graspdb_id=6,
        description="Bowl",
        mass_kg=0.450,
        size_note="rim diameter 150 mm, height 65 mm, foot 80 mm, wall 5 mm (typical, chosen: a ceramic "
        "cereal bowl; the report gives no size)",
        primitives=(),
        notes=(
            "empty; 450 g: the mesh volume times stoneware density ≈ 2.3 g/cm³ (ceramic bowls of this "
            "size weigh 350–500 g)",
        ),
    ),
    GraspDBObject(
        name="cube",
        graspdb_id=7,
        description="Cube",
        mass_kg=0.088,
        size_note="edge 50 mm (typical, chosen: a wooden toy cube; the report gives no size)",
        primitives=_CUBE,
        notes=("88 g: solid beech (about 700 kg/m³)",),
    ),
    GraspDBObject(
        name="business_card",
        graspdb_id=8,
        description="Business card",
        mass_kg=0.0016,
        size_note="85 × 55 × 0.4 mm (typical, chosen: the common European card size on 350 g/m² board)",
        primitives=_CARD,
        notes=(
            "lies flat; 1.6 g = 350 g/m² × 85 mm × 55 mm",
            "thinner (0.4 mm) than one finger pad's compression at 1 N (1.5 mm): a pinch presses a pad past "
            "its far face, so a hold of it is not judged (docs/objects.md, Thin walls)",
        ),
    ),
    GraspDBObject(
        name="oval_jar",
        graspdb_id=9,
        description="Oval jar",
        mass_kg=0.250,
        size_note="lid diameter 70 mm (report Table 3.3), lid height 14 mm; oval body 100 × 75 mm, "
        "height 122 mm with the lid (typical, chosen)",
        primitives=(),
        notes=(
            "the lid is part of this object, closed: it has no id of its own (report Table 4.1), and the "
            "controlled-transport grasp (power disk, grasp 10) holds the jar by its lid",
            "empty glass jar with a metal lid, 250 g; the mass is spread uniformly over the closed outer "
            "surface, so the inertia is that of a solid, not of a shell (about 1.5× too small)",
            "opening and screwing the lid (object-use scenario) would need a second, jointed body; not "
            "modelled",
        ),
    ),
    GraspDBObject(
        name="bottle_crate",
        graspdb_id=10,
        description="Bottle crate",
        mass_kg=1.800,
        size_note="outer 400 × 300 × 290 mm, walls and floor 4 mm, 4 × 5 cells with 3 mm dividers 150 mm "
        "high, central handle bar 160 × 25 × 25 mm (typical, chosen: a German 20 × 0.5 l beer crate)",
        primitives=_CRATE,
        notes=(
            "empty; 1.8 kg: empty HDPE crates of this kind weigh 1.5–2 kg (a full one, about 17 kg, is not "
            "lifted with one hand's wrap or hook grasp as in grasps 3 and 15)",
            "the grasps (medium wrap, fixed hook) hold the central handle bar",
            "solid walls and dividers stand for the real ribbed ones, so the mean density is low (≈ 0.6 "
            "g/cm³)",
        ),
    ),
    GraspDBObject(
        name="notebook",
        graspdb_id=11,
        description="Classic notebook (15 mm thick)",
        mass_kg=0.300,
        size_note="thickness 15 mm (report Table 4.1); 210 × 130 mm (typical, chosen: a large-format "
        "hardcover 'classic' notebook)",
        primitives=_NOTEBOOK,
        notes=("lies flat, closed; 300 g: paper and board at about 0.73 g/cm³",),
    ),
    GraspDBObject(
        name="cylinder_10mm",
        graspdb_id=12,
        description="Cylinder 10 mm diameter",
        mass_kg=0.011,
        size_note="diameter 10 mm (report Table 4.1); length 200 mm (typical, chosen: same length as the 25 "
        "mm cylinder)",
        primitives=_CYLINDER_10,
        notes=("lies on the table with its axis along x; 11 g: a beech dowel (about 700 kg/m³)",),
    ),
    GraspDBObject(
        name="cylinder_25mm",
        graspdb_id=13,
        description="Cylinder 25 mm diameter",
        mass_kg=0.069,
        size_note="diameter 25 mm (report Table 4.1); length 200 mm (typical, chosen: long enough for the "
        "whole-hand wraps of grasps 2, 4, 17 and 32)",
        primitives=_CYLINDER_25,
        notes=("lies on the table with its axis along x; 69 g: a beech rod (about 700 kg/m³)",),
    ),
    GraspDBObject(
        name="carton_lying",
        graspdb_id=14,
        description="Carton lying flat",
        mass_kg=0.300,
        size_note="76 × 260 × 375 mm (report Fig. 3.11 and Table 4.1); lying on its largest face: x 375, "
        "y 260, z 76 mm",
        primitives=_CARTON_LYING,
        notes=(
            "the same carton as carton_standing (id 15), placed differently",
            "empty corrugated cardboard box (the report does not say what it held), 300 g; so its mean "
            "density is only about 40 kg/m³",
        ),
    ),
    GraspDBObject(
        name="carton_standing",
        graspdb_id=15,
        description="Carton standing (7.6 × 26 × 37.5 cm³)",
        mass_kg=0.300,
        size_note="76 × 260 × 375 mm (report Fig. 3.11 and Table 4.1); standing on a 260 × 76 mm face: "
        "x 260, y 76, z 375 mm",
        primitives=_CARTON_STANDING,
        notes=(
            "the same carton as carton_lying (id 14), placed differently",
            "empty corrugated cardboard box (the report does not say what it held), 300 g; so its mean "
            "density is only about 40 kg/m³",
        ),
    ),
    GraspDBObject(
        name="bottle_by_cap",
        graspdb_id=16,
        description="Bottle (cap)",
        mass_kg=1.035,
        size_note="the bottle of id 3: diameter 80 mm, cap 30 mm (report Tables 4.1 and 3.3), height 280 mm "
        "(typical, chosen)",
        primitives=(),
        notes=(
            "id 16 is the bottle grasped by its 30 mm cap (tripod, grasp 14), not a loose cap: the report's "
            "objects (Fig. 3.11) include no separate cap, and 'Oval jar (lid)' likewise names the jar held "
            "by its lid; same geometry and mass as 'bottle'",
            *_BOTTLE_NOTES,
        ),
    ),
)

_BY_NAME = {o.name: o for o in GRASPDB_OBJECTS}
_BY_ID = {o.graspdb_id: o for o in GRASPDB_OBJECTS}


@functools.cache
def _cached_mesh(name: str) -> Mesh:
    # lazy: the disk cache (handsim.builders.mesh_cache) keeps trimesh and SciPy off a warm build
    from handsim.builders.mesh_cache import generated_mesh

    mesh = generated_mesh(name, lambda: _generate(name))
    mesh.vertices.flags.writeable = False
    mesh.faces.flags.writeable = False
    return mesh


def _generate(name: str) -> Mesh:
    """Generate and validate the mesh of ``name`` (trimesh and SciPy)."""
    from handsim.builders.graspdb_meshes import generate_mesh

    obj = _BY_NAME[name]
    vertices, faces = generate_mesh(name, obj.primitives)
    return validate_mesh(vertices, faces, f"graspdb14:{name}", require_watertight=True)


def graspdb_object(name_or_id: str | int) -> GraspDBObject:
    """Look an object up by its name or by its GraspDB id (report Table 4.1).

    Every id names exactly one entry: the carton's two placements have their own ids (14 lying, 15
    standing), and id 16 (the bottle held by its cap) is an entry of its own with the bottle's geometry.

    Args:
        name_or_id: A catalogue name such as ``"mug"``, or an id 1–16.

    Returns:
        The object.

    Raises:
        UnknownObjectError: The name or id is not in the catalogue (the message lists the valid ones).
    """
    if isinstance(name_or_id, str):
        if name_or_id in _BY_NAME:
            return _BY_NAME[name_or_id]
        raise UnknownObjectError(
            f"unknown object {name_or_id!r}; catalogue objects are: {', '.join(sorted(_BY_NAME))}"
        )
    if isinstance(name_or_id, (int, np.integer)) and not isinstance(name_or_id, bool):
        if int(name_or_id) in _BY_ID:
            return _BY_ID[int(name_or_id)]
        listing = ", ".join(f"{i} ({o.name})" for i, o in sorted(_BY_ID.items()))
        raise UnknownObjectError(f"unknown GraspDB object id {int(name_or_id)}; catalogue ids are: {listing}")
    raise UnknownObjectError(
        f"expected an object name or GraspDB id, got {name_or_id!r}; catalogue objects are: "
        f"{', '.join(sorted(_BY_NAME))}"
    )
