"""The GraspDB14 object catalogue: report ids and sizes, realistic masses, clean watertight meshes."""

from __future__ import annotations

import itertools

import mujoco
import numpy as np
import pytest
import trimesh
from trimesh.proximity import closest_point_naive

from handsim.builders.graspdb_objects import (
    GRASPDB_OBJECTS,
    GraspDBObject,
    UnknownObjectError,
    clear_mesh_cache,
    graspdb_object,
)
from handsim.datatypes.mesh import validate_mesh
from handsim.errors import HandsimError

# Report (GraspDB14 technical report) Table 4.1, object id -> object name, copied by hand from the spec;
# the carton's "($7.6 \times 26 \times 37.5$ cm^3)" written in Unicode.
TABLE_4_1 = {
    1: "Tennis ball (64 mm diameter)",
    2: "Pen (2 cm diameter)",
    3: "Bottle (8 cm diameter)",
    4: "Mug",
    5: "Glass (62 mm diameter)",
    6: "Bowl",
    7: "Cube",
    8: "Business card",
    9: "Oval jar",
    10: "Bottle crate",
    11: "Classic notebook (15 mm thick)",
    12: "Cylinder 10 mm diameter",
    13: "Cylinder 25 mm diameter",
    14: "Carton lying flat",
    15: "Carton standing (7.6 × 26 × 37.5 cm³)",
    16: "Bottle (cap)",
}
NAMES = {
    1: "tennis_ball",
    2: "pen",
    3: "bottle",
    4: "mug",
    5: "glass",
    6: "bowl",
    7: "cube",
    8: "business_card",
    9: "oval_jar",
    10: "bottle_crate",
    11: "notebook",
    12: "cylinder_10mm",
    13: "cylinder_25mm",
    14: "carton_lying",
    15: "carton_standing",
    16: "bottle_by_cap",
}

# Axis-aligned extents (x, y, z) in mm in the documented frame (z up as placed, x the longest horizontal).
# Report sizes: ball 64, pen 20, bottle 80, glass 62, notebook 15, cylinders 10/25, carton 76 x 260 x 375.
EXTENTS_MM = {
    "tennis_ball": (64, 64, 64),
    "pen": (140, 20, 20),
    "bottle": (80, 80, 280),
    "mug": (114, 82, 95),
    "glass": (62, 62, 100),
    "bowl": (150, 150, 65),
    "cube": (50, 50, 50),
    "business_card": (85, 55, 0.4),
    "oval_jar": (100, 75, 122),
    "bottle_crate": (400, 300, 290),
    "notebook": (210, 130, 15),
    "cylinder_10mm": (200, 10, 10),
    "cylinder_25mm": (200, 25, 25),
    "carton_lying": (375, 260, 76),
    "carton_standing": (260, 76, 375),
    "bottle_by_cap": (80, 80, 280),
}
# Empty cardboard boxes are far lighter than any solid; documented in docs/objects.md.
EMPTY_CARTONS = {"carton_lying", "carton_standing"}
MASS_RANGES_KG = {
    "tennis_ball": (0.0560, 0.0594),  # ITF rules, Appendix I
    "mug": (0.300, 0.350),
    "bottle": (1.0, 1.1),  # 1 l of water plus a PET bottle
    "bottle_by_cap": (1.0, 1.1),
    "bottle_crate": (1.5, 2.0),  # empty
    "business_card": (0.001, 0.003),
}
OBJECTS = {o.name: o for o in GRASPDB_OBJECTS}
ALL = pytest.mark.parametrize("obj", GRASPDB_OBJECTS, ids=lambda o: o.name)
WITH_PRIMITIVES = [o for o in GRASPDB_OBJECTS if o.primitives]
DECOMPOSED = [o for o in GRASPDB_OBJECTS if not o.primitives]


def _quat_matrix(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _primitive_volume(p) -> float:
    s = p.size
    return {
        "sphere": lambda: 4 / 3 * np.pi * s[0] ** 3,
        "box": lambda: 8 * s[0] * s[1] * s[2],
        "cylinder": lambda: np.pi * s[0] ** 2 * 2 * s[1],
        "capsule": lambda: np.pi * s[0] ** 2 * 2 * s[1] + 4 / 3 * np.pi * s[0] ** 3,
    }[p.kind]()


def _primitive_bounds(p) -> tuple[np.ndarray, np.ndarray]:
    """Exact axis-aligned bounds of a primitive in the object frame."""
    rot = _quat_matrix(p.quat)
    if p.kind == "sphere":
        half = np.full(3, p.size[0])
    elif p.kind == "box":
        half = np.abs(rot) @ np.asarray(p.size)
    else:  # cylinder / capsule along the local z axis
        axis = rot[:, 2]
        r, h = p.size
        half = h * np.abs(axis) + r * np.sqrt(np.clip(1 - axis**2, 0, None))
        if p.kind == "capsule":
            half = h * np.abs(axis) + r
    return np.asarray(p.pos) - half, np.asarray(p.pos) + half


def _concavity_depth(obj: GraspDBObject) -> float:
    """A lower bound on the largest distance from the convex hull's surface to the mesh, metres."""
    mesh = obj.mesh().to_trimesh()
    points, _ = trimesh.sample.sample_surface(mesh.convex_hull, 400, seed=0)
    _, distance, _ = closest_point_naive(mesh, points)
    return float(distance.max())


def test_ids_and_descriptions_match_report_table_4_1():
    assert {o.graspdb_id: o.description for o in GRASPDB_OBJECTS} == TABLE_4_1
    assert {o.graspdb_id: o.name for o in GRASPDB_OBJECTS} == NAMES
    assert len(GRASPDB_OBJECTS) == 16


@ALL
def test_mesh_passes_validation_unchanged_and_is_a_closed_solid(obj):
    mesh = obj.mesh()
    assert mesh.notes == ()
    again = validate_mesh(mesh.vertices, mesh.faces, "again", require_watertight=True)
    assert again.notes == ()
    np.testing.assert_array_equal(again.vertices, mesh.vertices)
    np.testing.assert_array_equal(again.faces, mesh.faces)
    tm = mesh.to_trimesh()
    assert mesh.watertight and tm.is_watertight and tm.is_winding_consistent
    assert mesh.volume > 0
    assert len(mesh.faces) < 5000


@ALL
def test_mesh_has_the_documented_size_in_the_documented_frame(obj):
    mesh = obj.mesh()
    expected = np.asarray(EXTENTS_MM[obj.name], float) * 1e-3
    tol = np.minimum(0.5e-3, 0.01 * expected)
    np.testing.assert_array_less(np.abs(mesh.extent - expected), tol + 1e-12)
    # origin at the centre of the bounding box
    np.testing.assert_allclose(mesh.vertices.min(axis=0) + mesh.vertices.max(axis=0), 0, atol=1e-12)


@pytest.mark.parametrize(("name", "top_mm", "diameter_mm"), [("bottle", 20, 30), ("oval_jar", 14, 70)])
def test_bottle_cap_and_jar_lid_have_the_report_diameter(name, top_mm, diameter_mm):
    v = OBJECTS[name].mesh().vertices
    top = v[v[:, 2] > v[:, 2].max() - top_mm * 1e-3]
    np.testing.assert_allclose(top.max(axis=0)[:2] - top.min(axis=0)[:2], diameter_mm * 1e-3, atol=1e-9)


def test_carton_lies_on_its_largest_face_and_stands_on_its_long_narrow_face():
    lying, standing = OBJECTS["carton_lying"].mesh().extent, OBJECTS["carton_standing"].mesh().extent
    assert lying[2] == pytest.approx(0.076) and standing[2] == pytest.approx(0.375)
    np.testing.assert_allclose(sorted(lying), sorted(standing))


@ALL
def test_density_is_physically_plausible(obj):
    low, high = (20, 100) if obj.name in EMPTY_CARTONS else (50, 3000)
    assert low <= obj.density_kg_m3 <= high
    assert obj.density_kg_m3 == pytest.approx(obj.mass_kg / obj.mesh().volume)


@pytest.mark.parametrize("name", sorted(MASS_RANGES_KG))
def test_mass_is_in_the_published_or_typical_range(name):
    low, high = MASS_RANGES_KG[name]
    assert low <= OBJECTS[name].mass_kg <= high


@pytest.mark.parametrize("obj", WITH_PRIMITIVES, ids=lambda o: o.name)
def test_primitives_enclose_the_mesh_volume_and_lie_inside_its_bounds(obj):
    mesh = obj.mesh()
    volume = sum(_primitive_volume(p) for p in obj.primitives)
    assert volume == pytest.approx(mesh.volume, rel=0.01)
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    for p in obj.primitives:
        p_lo, p_hi = _primitive_bounds(p)
        assert np.all(p_lo >= lo - 1e-9) and np.all(p_hi <= hi + 1e-9), p


@pytest.mark.parametrize("obj", WITH_PRIMITIVES, ids=lambda o: o.name)
def test_primitives_compiled_by_mujoco_have_the_mesh_volume_and_bounds(obj):
    geom_type = {
        "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
        "box": mujoco.mjtGeom.mjGEOM_BOX,
        "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
        "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
    }
    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body()
    for p in obj.primitives:
        size = [*p.size, 0.0, 0.0][:3]
        body.add_geom(type=geom_type[p.kind], size=size, pos=list(p.pos), quat=list(p.quat), density=1000)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    mesh = obj.mesh()
    assert model.body_mass[1] == pytest.approx(1000 * mesh.volume, rel=0.01)
    corners = np.array(list(itertools.product((-1, 1), repeat=3)), float)
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    for g in range(model.ngeom):
        centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
        world = data.geom_xpos[g] + (centre + corners * half) @ data.geom_xmat[g].reshape(3, 3).T
        assert np.all(world.min(axis=0) >= lo - 1e-9) and np.all(world.max(axis=0) <= hi + 1e-9)


def test_crate_boxes_do_not_overlap_and_make_up_the_mesh_exactly():
    crate = OBJECTS["bottle_crate"]
    boxes = [_primitive_bounds(p) for p in crate.primitives]
    assert all(p.kind == "box" and p.quat == (1.0, 0.0, 0.0, 0.0) for p in crate.primitives)
    for (lo_a, hi_a), (lo_b, hi_b) in itertools.combinations(boxes, 2):
        overlap = np.clip(np.minimum(hi_a, hi_b) - np.maximum(lo_a, lo_b), 0, None)
        assert np.prod(overlap) < 1e-15
    total = sum(_primitive_volume(p) for p in crate.primitives)
    assert total == pytest.approx(crate.mesh().volume, rel=1e-9)


def test_mug_handle_lies_outside_the_body_so_no_volume_is_counted_twice():
    parts = sorted(OBJECTS["mug"].mesh().to_trimesh().split(only_watertight=True), key=lambda m: -m.volume)
    assert len(parts) == 2
    body, handle = parts
    axis = (body.bounds[0] + body.bounds[1]) / 2
    radius = body.bounds[1][0] - axis[0]
    # the body lies inside the cylinder of this radius; the handle in the half-space x >= axis + radius
    assert np.hypot(*(body.vertices[:, :2] - axis[:2]).T).max() <= radius + 1e-12
    assert handle.vertices[:, 0].min() >= axis[0] + radius - 1e-12


@pytest.mark.parametrize("obj", DECOMPOSED, ids=lambda o: o.name)
def test_objects_without_primitives_are_genuinely_concave(obj):
    # Their convex hull lies at least 3 mm off the surface somewhere (a third of a fingertip pad), so MuJoCo's
    # implicit convex hull would be a wrong collision shape and a decomposition is needed.
    assert _concavity_depth(obj) >= 3e-3


def test_mesh_is_cached_read_only_and_deterministic(monkeypatch, tmp_path):
    # each call generates: the process cache is cleared and the disk cache (handsim.builders.mesh_cache)
    # is an empty folder each time
    monkeypatch.setenv("HANDSIM_CACHE_DIR", str(tmp_path / "first"))
    clear_mesh_cache()
    obj = graspdb_object("mug")
    first = obj.mesh()
    assert obj.mesh() is first
    with pytest.raises(ValueError):
        first.vertices[0, 0] = 1.0
    clear_mesh_cache()
    monkeypatch.setenv("HANDSIM_CACHE_DIR", str(tmp_path / "second"))
    second = obj.mesh()
    clear_mesh_cache()  # later tests read the user's cache again
    assert second is not first
    np.testing.assert_array_equal(second.vertices, first.vertices)
    np.testing.assert_array_equal(second.faces, first.faces)


def test_lookup_by_name_and_by_id_give_the_same_object():
    for obj in GRASPDB_OBJECTS:
        assert graspdb_object(obj.name) is obj
        assert graspdb_object(obj.graspdb_id) is obj
    assert graspdb_object(np.int64(15)).name == "carton_standing"


def test_lookup_raises_error_if_object_name_is_unknown():
    with pytest.raises(UnknownObjectError) as info:
        graspdb_object("teapot")
    assert str(info.value) == (
        "unknown object 'teapot'; catalogue objects are: bottle, bottle_by_cap, bottle_crate, bowl, "
        "business_card, carton_lying, carton_standing, cube, cylinder_10mm, cylinder_25mm, glass, mug, "
        "notebook, oval_jar, pen, tennis_ball"
    )
    assert isinstance(info.value, HandsimError) and isinstance(info.value, KeyError)


def test_lookup_raises_error_if_object_id_is_unknown():
    with pytest.raises(UnknownObjectError) as info:
        graspdb_object(17)
    assert str(info.value) == (
        "unknown GraspDB object id 17; catalogue ids are: 1 (tennis_ball), 2 (pen), 3 (bottle), 4 (mug), "
        "5 (glass), 6 (bowl), 7 (cube), 8 (business_card), 9 (oval_jar), 10 (bottle_crate), 11 (notebook), "
        "12 (cylinder_10mm), 13 (cylinder_25mm), 14 (carton_lying), 15 (carton_standing), 16 (bottle_by_cap)"
    )


@pytest.mark.parametrize("bad", [True, 3.0, None])
def test_lookup_raises_error_if_key_is_neither_name_nor_id(bad):
    with pytest.raises(UnknownObjectError, match="expected an object name or GraspDB id"):
        graspdb_object(bad)


@ALL
def test_object_model_carries_mesh_primitives_and_mass(obj):
    model = obj.object_model()
    part = model.parts[0]
    assert model.name == obj.name and part.mesh is obj.mesh() and part.primitives == obj.primitives
    assert model.density * part.mesh.volume == pytest.approx(obj.mass_kg, rel=1e-12)
