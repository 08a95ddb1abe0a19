"""Volume, centre of mass and inertia of a closed triangle mesh, with numpy alone.

The polyhedral mass properties of D. Eberly ("Polyhedral Mass Properties (Revisited)", Geometric Tools,
2002: https://www.geometrictools.com/Documentation/PolyhedralMassProperties.pdf), written with the same
numpy operations in the same order as ``trimesh.triangles.mass_properties`` (trimesh 4–5, MIT licence), so
the numbers are bitwise trimesh's (pinned in ``tests/test_mesh_mass.py``). Having them here keeps trimesh
and SciPy (0.7 s to import) off the paths that only need a mesh's volume or mass: building a catalogue
object whose hulls are cached.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

_DIVISORS = np.array([6, 24, 24, 24, 60, 60, 60, 120, 120, 120], dtype=np.float64)


@dataclass(frozen=True)
class MeshMass:
    """Mass properties of a closed mesh of uniform density.

    Attributes:
        volume: Enclosed volume, m³ (negative for a mesh whose faces point inwards).
        mass: density × volume, kg.
        center_mass: Centre of mass, m, shape (3,).
        inertia: Inertia tensor about the centre of mass, kg·m², shape (3, 3).
    """

    volume: float
    mass: float
    center_mass: np.ndarray
    inertia: np.ndarray


def _integrals(vertices: npt.ArrayLike, faces: npt.ArrayLike) -> np.ndarray:
    """Eberly's ten volume integrals (1, x, y, z, x², y², z², xy, yz, zx) over the enclosed solid."""
    triangles = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    edges = triangles[:, 1:, :] - triangles[:, :2, :]
    crosses = np.cross(edges[:, 0], edges[:, 1])
    p0, p1, p2 = triangles[:, 0, :], triangles[:, 1, :], triangles[:, 2, :]
    f1 = p0 + p1 + p2
    f2 = p0**2 + p1**2 + p0 * p1 + p2 * f1
    f3 = (p0**3) + (p0**2) * (p1) + (p0) * (p1**2) + (p1**3) + (p2 * f2)
    g0 = f2 + (p0 + f1) * p0
    g1 = f2 + (p1 + f1) * p1
    g2 = f2 + (p2 + f1) * p2
    integral = np.zeros((10, len(f1)))
    integral[0] = crosses[:, 0] * f1[:, 0]
    integral[1:4] = (crosses * f2).T
    integral[4:7] = (crosses * f3).T
    for i in range(3):
        j = np.mod(i + 1, 3)
        integral[i + 7] = crosses[:, i] * (
            (triangles[:, 0, j] * g0[:, i])
            + (triangles[:, 1, j] * g1[:, i])
            + (triangles[:, 2, j] * g2[:, i])
        )
    return integral.sum(axis=1) / _DIVISORS


def mesh_volume(vertices: npt.ArrayLike, faces: npt.ArrayLike) -> float:
    """Enclosed volume of a closed triangle mesh, m³ (meaningful only for a watertight mesh).

    Args:
        vertices: Vertex positions, shape (V, 3).
        faces: Triangles as vertex indices, shape (F, 3), outward winding.
    """
    return float(_integrals(vertices, faces)[0])


def mesh_mass(vertices: npt.ArrayLike, faces: npt.ArrayLike, density: float = 1.0) -> MeshMass:
    """Mass, centre of mass and inertia of a closed triangle mesh of uniform density.

    Args:
        vertices: Vertex positions, m, shape (V, 3).
        faces: Triangles as vertex indices, shape (F, 3), outward winding.
        density: kg/m³.

    Returns:
        The mass properties (the inertia about the centre of mass, in the mesh's axes).
    """
    integrated = _integrals(vertices, faces)
    volume = integrated[0]
    center_mass = integrated[1:4] / volume
    inertia = np.zeros((3, 3))
    inertia[0, 0] = integrated[5] + integrated[6] - (volume * (center_mass[[1, 2]] ** 2).sum())
    inertia[1, 1] = integrated[4] + integrated[6] - (volume * (center_mass[[0, 2]] ** 2).sum())
    inertia[2, 2] = integrated[4] + integrated[5] - (volume * (center_mass[[0, 1]] ** 2).sum())
    inertia[0, 1] = -(integrated[7] - (volume * np.prod(center_mass[[0, 1]])))
    inertia[1, 2] = -(integrated[8] - (volume * np.prod(center_mass[[1, 2]])))
    inertia[0, 2] = -(integrated[9] - (volume * np.prod(center_mass[[0, 2]])))
    inertia[2, 0] = inertia[0, 2]
    inertia[2, 1] = inertia[1, 2]
    inertia[1, 0] = inertia[0, 1]
    return MeshMass(
        volume=float(volume),
        mass=float(density * volume),
        center_mass=np.asarray(center_mass, dtype=float),
        inertia=np.asarray(inertia * density, dtype=float),
    )
