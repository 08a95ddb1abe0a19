"""Tzionas/Ballan objects (``Model_Object_*.SKEL`` + ``.LIMITS`` + ``.OFF`` [+ ``.SKIN``]) as object models.

A rigid object (one bone, e.g. the cube of sequence 20) is its ``.OFF`` mesh. An articulated object
(two bones, e.g. the pipe of sequence 17) is cut into one part per bone by the plane through the second
bone's joint, normal to that bone (the cut is capped; the skinning weights must agree with the cut),
and the second bone's single ``.LIMITS`` DoF becomes the hinge: its axis and range, through the joint.

The object frame is the mesh frame (the rigging pose's world frame, metres), so a bone transform ``M_k``
of frame k of the object's ``.MOTION`` moves the object by ``M_k · M_0⁻¹``. The files give no masses;
densities are assumptions, listed in :data:`TZIONAS_DENSITIES` and the model's notes.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from handsim.datatypes.mesh import boundary_loops, cap_loops, validate_mesh
from handsim.datatypes.object_model import Hinge, ObjectModel, ObjectPart
from handsim.datatypes.skeleton import SkinnedMesh, mj_name
from handsim.errors import MeshError, SkeletonError
from handsim.io.tzionas.skeleton import read_tzionas_skeleton

TZIONAS_DENSITIES = {"Model_Object_Cube": 600.0, "Model_Object_Pipe_Gray": 150.0}
"""Assumed densities in kg/m³: the 53 mm cube as wood (~89 g); the 350 × 48 mm grey bendable pipe as
foamed plastic (~94 g)."""
DEFAULT_DENSITY = 500.0


def read_tzionas_object(skel_path: str | Path, *, density: float | None = None) -> ObjectModel:
    """Read a Tzionas/Ballan object model.

    Args:
        skel_path: The object's ``.SKEL``; its ``.LIMITS``, ``.OFF`` (and ``.SKIN`` for two bones) must lie
            beside it.
        density: Density in kg/m³ (default: :data:`TZIONAS_DENSITIES`, else 500).

    Returns:
        A one-part object, or two parts joined by a hinge.

    Raises:
        SkeletonError: No mesh beside the ``.SKEL``, more than two bones, or a second bone without exactly
            one DoF.
        MeshError: The mesh or a part is invalid.
    """
    path = Path(skel_path)
    skeleton = read_tzionas_skeleton(path)
    mesh = skeleton.mesh
    if mesh is None:
        raise SkeletonError(f"{path}: no .OFF mesh beside it; an object needs its surface")
    stem = path.stem
    notes = list(skeleton.notes)
    if density is None:
        density = TZIONAS_DENSITIES.get(stem, DEFAULT_DENSITY)
        notes.append(f"the files give no mass; density {density:g} kg/m³ assumed")
    bones = [j for j in skeleton.joints if not j.name.endswith("_tip")]
    name = stem.removeprefix("Model_Object_").lower()
    source = str(path.with_suffix(".OFF"))
    if len(bones) == 1:
        part = validate_mesh(mesh.vertices, mesh.faces, source)
        notes.extend(part.notes)
        return ObjectModel(
            name, (ObjectPart("body", part),), density=density, source=str(path), notes=tuple(notes)
        )
    if len(bones) != 2:
        raise SkeletonError(f"{path}: {len(bones)} bones; handsim builds objects of one or two rigid parts")
    child = bones[1]
    dofs = skeleton.dofs_of(child.name)
    if len(dofs) != 1:
        raise SkeletonError(
            f"{path}: bone {child.name!r} has {len(dofs)} DoFs in the .LIMITS; a hinge needs exactly one"
        )
    dof = dofs[0]
    rest = skeleton.forward_kinematics(skeleton.zero_pose())
    index = skeleton.joint_index(child.name)
    axis = rest.frames[index] @ dof.axis  # the DoF axis is in the bone's frame; the hinge's in the mesh frame
    tip = [j for j in skeleton.joints if j.parent == index]
    if len(tip) != 1:
        raise SkeletonError(
            f"{path}: bone {child.name!r} needs exactly one child joint to give its direction"
        )
    direction = rest.positions[skeleton.joint_index(tip[0].name)] - rest.positions[index]
    normal = direction / np.linalg.norm(direction)
    parts = _split_at_joint(mesh, [b.name for b in bones], rest.positions[index], normal, source)
    for part in parts:
        notes.extend(f"{part.mesh.source}: {n}" for n in part.mesh.notes)
    return ObjectModel(
        name=name,
        parts=tuple(parts),
        density=density,
        hinge=Hinge(
            axis=tuple(float(a) for a in axis),
            pos=tuple(float(p) for p in rest.positions[index]),
            range=(dof.lower, dof.upper),
        ),
        source=str(path),
        notes=tuple(notes),
    )


def _split_at_joint(
    mesh: SkinnedMesh, bones: list[str], origin: np.ndarray, normal: np.ndarray, source: str
) -> list[ObjectPart]:
    """One watertight part per bone: the mesh cut by the plane through the child's joint.

    The plane passes through the child bone's rest position, normal to the bone. Faces on either side
    (vertices on the plane belong to both) form the parts, and each cut is capped. The skinning weights
    must agree: a vertex off the plane whose heaviest bone is on the other side is counted, and more
    than 1 % of such vertices is an error.
    """
    v, f = mesh.vertices, mesh.faces
    signed = (v - origin) @ normal
    tol = 1e-6 * float(np.ptp(v, axis=0).max())
    straddling = int(np.sum((signed[f] > tol).any(axis=1) & (signed[f] < -tol).any(axis=1)))
    if straddling:
        raise MeshError(
            f"{source}: {straddling} faces cross the plane of joint {bones[1]!r}; handsim splits an "
            "articulated mesh only along a ring of vertices on that plane"
        )
    heaviest = np.asarray(mesh.weights).argmax(axis=1)
    child = mesh.bones.index(bones[1])
    off_plane = np.abs(signed) > tol
    disagree = int(np.sum(off_plane & ((signed > 0) != (heaviest == child))))
    if disagree > 0.01 * off_plane.sum():
        raise MeshError(
            f"{source}: {disagree} of {int(off_plane.sum())} vertices are skinned to the bone on the other "
            f"side of joint {bones[1]!r}; the skinning does not split the mesh there"
        )
    parts = []
    for bone, side in zip(bones, (-1.0, 1.0), strict=True):
        keep = (side * signed[f] >= -tol).all(axis=1)
        used = np.unique(f[keep])
        remap = np.full(len(v), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        pv, pf = v[used], remap[f[keep]]
        loops = boundary_loops(pf)
        pv, pf = cap_loops(pv, pf, loops)
        part = validate_mesh(pv, pf, f"{source} ({bone})")
        note = (
            f"cut at joint {bones[1]!r} ({len(loops)} cut capped); skinning agrees on "
            f"{int(off_plane.sum()) - disagree} of {int(off_plane.sum())} vertices off the cut"
        )
        parts.append(ObjectPart(mj_name(bone), replace(part, notes=(note, *part.notes))))
    return parts
