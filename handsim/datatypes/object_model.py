"""Graspable objects as plain data: parts with meshes (SI units), exact primitives, a hinge, a density.

:class:`ObjectModel` is what readers and the catalogue produce and what
:func:`handsim.builders.build_object` turns into a MuJoCo spec. No MuJoCo objects live here.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.datatypes.mesh import Mesh
from handsim.errors import ModelError

PRIMITIVE_KINDS = ("sphere", "box", "cylinder", "capsule")


@dataclass(frozen=True)
class Primitive:
    """An exact collision shape (a MuJoCo primitive geom) in the object frame.

    Attributes:
        kind: ``"sphere"``, ``"box"``, ``"cylinder"`` or ``"capsule"``.
        size: MuJoCo's size convention in metres: sphere (r,), box (hx, hy, hz), cylinder (r, half height),
            capsule (r, half length of the segment).
        pos: Centre in the object frame, metres.
        quat: Orientation in the object frame (w, x, y, z).
    """

    kind: str
    size: tuple[float, ...]
    pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        nsize = {"sphere": 1, "box": 3, "cylinder": 2, "capsule": 2}
        if self.kind not in nsize:
            raise ModelError(f"unknown primitive kind {self.kind!r}; expected one of {list(PRIMITIVE_KINDS)}")
        if len(self.size) != nsize[self.kind] or not all(np.isfinite(s) and s > 0 for s in self.size):
            raise ModelError(f"a {self.kind} needs {nsize[self.kind]} positive sizes, got {tuple(self.size)}")


@dataclass(frozen=True)
class ObjectPart:
    """One rigid part of an object.

    Attributes:
        name: Body name (``body`` for a one-part object; ``top``/``bottom`` for ARCTIC templates).
        mesh: The part's surface in the object frame (metres); watertight unless the object's mass is given.
        primitives: Exact collision shapes in the object frame; when given, the mesh is not decomposed and
            serves only for the visual and the mass properties.
    """

    name: str
    mesh: Mesh
    primitives: tuple[Primitive, ...] = ()


@dataclass(frozen=True)
class Hinge:
    """The joint between the two parts of an articulated object (object frame at articulation 0).

    Attributes:
        axis: Unit rotation axis; a positive angle turns the child about it right-handedly.
        pos: A point on the axis, metres.
        range: Angle limits in radians, or None for an unlimited hinge.
        holds_pose: The hinge is stiff enough to hold the child part against gravity in any pose (a laptop
            lid, a bendable pipe): the builder gives it dry friction of 1.5 × the child's largest gravity
            torque. False: a free-swinging hinge (damping only).
        parts_collide: The two parts collide with each other (a lid rests on its base instead of sinking
            into it). The builder adds explicit contact pairs between their collision geoms; MuJoCo
            otherwise never collides a body with its parent.
    """

    axis: tuple[float, float, float]
    pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    range: tuple[float, float] | None = None
    holds_pose: bool = True
    parts_collide: bool = False

    def __post_init__(self) -> None:
        if self.range is not None:
            lo, hi = self.range
            if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
                raise ModelError(f"hinge range must be two finite angles, lower < upper; got {self.range}")


@dataclass(frozen=True)
class ObjectModel:
    """A graspable object as plain data.

    Attributes:
        name: Model name (snake_case).
        parts: The root part first; a second part is joined to it by ``hinge``.
        density: Material density in kg/m³ (mass = mesh volume × density). Exactly one of ``density`` and
            ``mass`` is given.
        mass: Total mass in kg, distributed over the parts by volume (their meshes may then be open, and
            the volume comes from their convex hulls).
        hinge: The articulation of a two-part object.
        source: Where the object came from.
        notes: Decisions and repairs, for the user to see.
    """

    name: str
    parts: tuple[ObjectPart, ...]
    density: float | None = None
    mass: float | None = None
    hinge: Hinge | None = None
    source: str = ""
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not self.parts:
            raise ModelError(f"object {self.name!r} has no parts")
        if len({p.name for p in self.parts}) != len(self.parts):
            raise ModelError(f"object {self.name!r} has duplicate part names {[p.name for p in self.parts]}")
        if (self.density is None) == (self.mass is None):
            raise ModelError(f"object {self.name!r}: give exactly one of density and mass")
        for what, value in (("density", self.density), ("mass", self.mass)):
            if value is not None and not (np.isfinite(value) and value > 0):
                raise ModelError(f"object {self.name!r}: {what} must be a positive number, got {value}")
        if len(self.parts) > 2 or (len(self.parts) == 2) != (self.hinge is not None):
            raise ModelError(
                f"object {self.name!r}: an object has one part, or two parts joined by a hinge; "
                f"got {len(self.parts)} parts and {'a' if self.hinge else 'no'} hinge"
            )
        if self.density is not None:
            open_parts = [p.name for p in self.parts if not p.mesh.watertight]
            if open_parts:
                raise ModelError(
                    f"object {self.name!r}: parts {open_parts} are not watertight, so a density gives no "
                    "mass; give the object's mass instead"
                )


def mesh_object(
    mesh: Mesh, *, density: float | None = None, mass: float | None = None, name: str = ""
) -> ObjectModel:
    """A one-part object from a mesh.

    Args:
        mesh: The object's surface (object frame = mesh frame), metres.
        density: Density in kg/m³ (the mesh must be watertight).
        mass: Total mass in kg, instead of a density.
        name: Model name (default: the mesh file's stem).

    Returns:
        The object model.
    """
    name = name or Path(mesh.source).stem or "object"
    return ObjectModel(
        name=name,
        parts=(ObjectPart("body", mesh),),
        density=density,
        mass=mass,
        source=mesh.source,
        notes=mesh.notes,
    )
