"""Tests of handsim.datatypes.mesh_mass: a mesh's mass properties with numpy alone, bitwise trimesh's."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from handsim.builders.catalog import entries
from handsim.datatypes.mesh_mass import mesh_mass, mesh_volume


def _catalogue_meshes():
    for entry in entries():
        for part in entry.load().parts:
            yield pytest.param(part.mesh, id=f"{entry.name}:{part.name}")


@pytest.mark.parametrize("mesh", _catalogue_meshes())
def test_mass_properties_are_bitwise_trimeshs_on_every_catalogue_mesh(mesh) -> None:
    reference = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    expected = trimesh.triangles.mass_properties(reference.triangles, density=1234.5)
    got = mesh_mass(mesh.vertices, mesh.faces, density=1234.5)
    assert got.volume == float(reference.volume) == mesh_volume(mesh.vertices, mesh.faces) == mesh.volume
    assert got.mass == expected.mass
    np.testing.assert_array_equal(got.center_mass, expected.center_mass)
    np.testing.assert_array_equal(got.inertia, expected.inertia)


def test_a_box_has_the_textbook_mass_properties() -> None:
    # An independent computation: a 0.1 x 0.2 x 0.3 m box of 1000 kg/m³ centred at (1, 2, 3).
    a, b, c = 0.1, 0.2, 0.3
    box = trimesh.creation.box((a, b, c))
    vertices = np.asarray(box.vertices) + np.array([1.0, 2.0, 3.0])
    got = mesh_mass(vertices, np.asarray(box.faces), density=1000.0)
    mass = 1000.0 * a * b * c
    assert got.volume == pytest.approx(a * b * c, rel=1e-12)
    assert got.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(got.center_mass, [1.0, 2.0, 3.0], rtol=1e-12)
    expected = mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    np.testing.assert_allclose(got.inertia, expected, rtol=1e-9, atol=1e-12)  # cancellation off the origin


def test_faces_pointing_inwards_give_a_negative_volume() -> None:
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    assert mesh_volume(np.asarray(box.vertices), np.asarray(box.faces)[:, ::-1]) == pytest.approx(-1.0)
