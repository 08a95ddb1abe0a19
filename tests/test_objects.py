"""Object builder, ARCTIC templates and Tzionas objects: compile, mass, articulation, drop test, bad input."""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from handsim.builders.decomposition_types import DecompositionParams
from handsim.builders.objects import build_object, object_bounds, prepare_object
from handsim.datatypes.object_model import Hinge, ObjectModel, ObjectPart, Primitive, mesh_object
from handsim.errors import FormatError, InputFileError, ModelError
from handsim.io.arctic.templates import read_arctic_template
from handsim.io.tzionas.objects import read_tzionas_object
from handsim.sim import compile_spec
from handsim.sim.stability.drop import drop_test

FAST = DecompositionParams(resolution=500, preprocess_resolution=30, mcts_iterations=60, max_convex_hull=8)


def _write_obj(path: Path, mesh: trimesh.Trimesh) -> None:
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in mesh.vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces]
    path.write_text("\n".join(lines) + "\n")


def _arctic_parts_mm() -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A cup (concave bottom) and an off-centre lid (top), in millimetres, ARCTIC-style canonical frame."""
    profile = np.array([[0, 0], [40, 0], [40, 40], [36, 40], [36, 4], [0, 4], [0, 0]], dtype=float)
    bottom = trimesh.creation.revolve(profile, sections=32)
    top = trimesh.creation.box((80.0, 60.0, 6.0))
    top.apply_translation([12.0, 0.0, 44.0])
    return bottom, top


@pytest.fixture(scope="module")
def arctic_folder(tmp_path_factory) -> Path:
    """A synthetic template in ARCTIC's layout: mesh.obj + parts.json and top.obj + bottom.obj."""
    folder = tmp_path_factory.mktemp("object_vtemplates") / "cup"
    folder.mkdir()
    bottom, top = _arctic_parts_mm()
    _write_obj(folder / "bottom.obj", bottom)
    _write_obj(folder / "top.obj", top)
    _write_obj(folder / "mesh.obj", trimesh.util.concatenate([bottom, top]))
    labels = [1] * len(bottom.vertices) + [0] * len(top.vertices)  # ARCTIC: 0 = top, 1 = bottom
    (folder / "parts.json").write_text(json.dumps(labels))
    return folder


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("coacd_cache")


@pytest.fixture(scope="module")
def arctic_spec(arctic_folder, cache_dir) -> mujoco.MjSpec:
    return build_object(read_arctic_template(arctic_folder), FAST, cache_dir=cache_dir)


def test_arctic_template_reads_two_parts_in_metres_with_hinge_about_minus_z(arctic_folder):
    model = read_arctic_template(arctic_folder)
    assert [p.name for p in model.parts] == ["bottom", "top"]
    assert model.hinge == Hinge(axis=(0.0, 0.0, -1.0))
    bottom, top = _arctic_parts_mm()
    np.testing.assert_allclose(model.parts[1].mesh.extent, top.extents / 1000, atol=1e-12)
    assert model.parts[0].mesh.volume == pytest.approx(
        bottom.volume * 1e-9, rel=1e-6
    )  # 6 decimals in the OBJ


def test_arctic_mesh_obj_with_parts_json_gives_the_same_parts(arctic_folder, tmp_path):
    split = tmp_path / "cup"
    split.mkdir()
    for name in ("mesh.obj", "parts.json"):
        (split / name).write_bytes((arctic_folder / name).read_bytes())
    a, b = read_arctic_template(arctic_folder), read_arctic_template(split)
    for pa, pb in zip(a.parts, b.parts, strict=True):
        assert pa.mesh.volume == pytest.approx(pb.mesh.volume, rel=1e-12)
        np.testing.assert_allclose(np.sort(pa.mesh.vertices, axis=0), np.sort(pb.mesh.vertices, axis=0))


@pytest.mark.slow
@pytest.mark.parametrize("theta", [0.0, 0.4, 1.3, -2.0])
def test_arctic_hinge_matches_the_arctic_formula(arctic_folder, arctic_spec, theta):
    model = compile_spec(arctic_spec)
    data = mujoco.MjData(model)
    rotvec, t = np.array([0.3, -1.1, 0.5]), np.array([0.1, -0.2, 0.3])
    quat = Rotation.from_rotvec(rotvec).as_quat(scalar_first=True)
    data.qpos[:7] = [*t, *quat]
    data.qpos[model.jnt_qposadr[model.joint("hinge").id]] = theta
    mujoco.mj_kinematics(model, data)
    top = model.body("top")
    v = trimesh.load_mesh(arctic_folder / "top.obj", process=False).vertices[:20] / 1000.0
    simulated = data.xpos[top.id] + v @ data.xmat[top.id].reshape(3, 3).T
    # ARCTIC: the top part turns by R_z(-theta) in the object frame, then the global pose applies.
    expected = Rotation.from_rotvec(rotvec).apply(Rotation.from_euler("z", -theta).apply(v)) + t
    np.testing.assert_allclose(simulated, expected, atol=1e-9)


@pytest.mark.slow
def test_arctic_object_drops_onto_the_table_and_rests_without_warnings(arctic_spec):
    result = drop_test(arctic_spec)
    assert result.warnings == {}
    assert result.rest_time is not None and result.rest_time < 2.0


def test_simulated_mass_equals_mesh_volume_times_density(arctic_folder, cache_dir):
    model = read_arctic_template(arctic_folder, density=800.0)
    compiled = compile_spec(build_object(model, FAST, cache_dir=cache_dir))
    volume = sum(p.mesh.volume for p in model.parts)
    assert compiled.body("bottom").subtreemass[0] == pytest.approx(volume * 800.0, rel=1e-9)


def test_second_build_hits_the_cache_with_identical_hulls(arctic_folder, cache_dir):
    model = read_arctic_template(arctic_folder)
    first = prepare_object(model, FAST, cache_dir=cache_dir)
    second = prepare_object(model, FAST, cache_dir=cache_dir)
    assert second.decompositions["bottom"].from_cache
    for a, b in zip(first.decompositions["bottom"].hulls, second.decompositions["bottom"].hulls, strict=True):
        np.testing.assert_array_equal(a.vertices, b.vertices)
    assert "top" in second.decompositions and second.decompositions["top"].skipped == "mesh is convex"


def test_arctic_folder_without_parts_json_raises_error(arctic_folder, tmp_path):
    folder = tmp_path / "cup"
    folder.mkdir()
    (folder / "mesh.obj").write_bytes((arctic_folder / "mesh.obj").read_bytes())
    with pytest.raises(
        InputFileError,
        match=r"^.*cup/parts\.json: parts\.json not found; ARCTIC's mesh\.obj needs it to tell the top part "
        r"from the bottom$",
    ):
        read_arctic_template(folder)


def test_arctic_parts_json_with_wrong_vertex_count_raises_error(arctic_folder, tmp_path):
    folder = tmp_path / "cup"
    folder.mkdir()
    (folder / "mesh.obj").write_bytes((arctic_folder / "mesh.obj").read_bytes())
    labels = json.loads((arctic_folder / "parts.json").read_text())
    (folder / "parts.json").write_text(json.dumps(labels[:-3]))
    with pytest.raises(
        FormatError,
        match=rf"^.*parts\.json: {len(labels) - 3} part labels for the {len(labels)} vertices of mesh\.obj; "
        r"expected one per vertex$",
    ):
        read_arctic_template(folder)


def test_arctic_parts_json_with_a_bad_label_raises_error(arctic_folder, tmp_path):
    folder = tmp_path / "cup"
    folder.mkdir()
    (folder / "mesh.obj").write_bytes((arctic_folder / "mesh.obj").read_bytes())
    labels = json.loads((arctic_folder / "parts.json").read_text())
    labels[5] = 2
    (folder / "parts.json").write_text(json.dumps(labels))
    with pytest.raises(
        FormatError, match=r"^.*parts\.json: part label 5 is 2; expected 0 \(top\) or 1 \(bottom\)$"
    ):
        read_arctic_template(folder)


def test_folder_that_is_not_a_template_raises_error(tmp_path):
    with pytest.raises(
        InputFileError, match=r"not an ARCTIC object template: expected top\.obj \+ bottom\.obj"
    ):
        read_arctic_template(tmp_path)


def test_arctic_template_in_metres_is_refused_as_implausibly_small(tmp_path):
    folder = tmp_path / "tiny"
    folder.mkdir()
    bottom, top = _arctic_parts_mm()
    _write_obj(folder / "bottom.obj", bottom.apply_scale(1e-3))
    _write_obj(folder / "top.obj", top.apply_scale(1e-3))
    with pytest.raises(Exception, match=r"are the coordinates in m\? \(pass units='m'\)"):
        read_arctic_template(folder)


def test_object_model_needs_exactly_one_of_density_and_mass():
    mesh = read_mesh_box()
    with pytest.raises(ModelError, match=r"^object 'box': give exactly one of density and mass$"):
        ObjectModel("box", (ObjectPart("body", mesh),))
    with pytest.raises(ModelError, match=r"^object 'box': density must be a positive number, got -1.0$"):
        ObjectModel("box", (ObjectPart("body", mesh),), density=-1.0)


def read_mesh_box():
    from handsim.datatypes.mesh import validate_mesh

    box = trimesh.creation.box((0.04, 0.05, 0.06))
    return validate_mesh(box.vertices, box.faces, "box")


def test_box_object_has_the_analytic_mass_and_inertia():
    model = mesh_object(read_mesh_box(), density=500.0, name="box")
    compiled = compile_spec(build_object(model))
    body = compiled.body("body")
    mass = 500.0 * 0.04 * 0.05 * 0.06
    assert body.mass[0] == pytest.approx(mass, rel=1e-12)
    expected = mass / 12 * np.array([0.05**2 + 0.06**2, 0.04**2 + 0.06**2, 0.04**2 + 0.05**2])
    np.testing.assert_allclose(np.sort(body.inertia), np.sort(expected), rtol=1e-9)
    lower, upper = object_bounds(build_object(model))
    np.testing.assert_allclose(upper - lower, [0.04, 0.05, 0.06], atol=1e-12)


def test_open_mesh_with_density_raises_error_suggesting_a_mass():
    from handsim.datatypes.mesh import validate_mesh

    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.03)
    keep = sphere.triangles_center[:, 2] < 0.0
    mesh = validate_mesh(sphere.vertices, sphere.faces[keep], "bowl", require_watertight=False)
    with pytest.raises(
        ModelError, match=r"^object 'bowl': parts \['body'\] are not watertight, so a density gives no mass; "
    ):
        mesh_object(mesh, density=1000.0)
    sphere_hull = (Primitive("sphere", (0.03,)),)  # exact collision shape: no CoACD on the open shell
    prepared = prepare_object(ObjectModel("bowl", (ObjectPart("body", mesh, sphere_hull),), mass=0.2))
    assert prepared.total_mass == pytest.approx(0.2)
    assert "convex hulls" in prepared.notes[0]


# ------------------------------------------------------------------------------------- Tzionas objects


def test_tzionas_cube_builds_with_its_own_hull_and_rests(tzionas_dir, cache_dir):
    model = read_tzionas_object(tzionas_dir / "Models/20/Model_Object_Cube.SKEL")
    prepared = prepare_object(model, cache_dir=cache_dir)
    assert prepared.decompositions["body"].skipped == "mesh is convex"
    np.testing.assert_allclose(model.parts[0].mesh.extent, 0.053, atol=1e-4)
    result = drop_test(build_object(model, cache_dir=cache_dir))
    assert result.ok, result
    assert result.mass == pytest.approx(model.parts[0].mesh.volume * model.density, rel=1e-9)


def test_tzionas_pipe_splits_at_its_joint_and_bends_within_its_limits(tzionas_dir, cache_dir):
    model = read_tzionas_object(tzionas_dir / "Models/17/Model_Object_Pipe_Gray.SKEL")
    assert [p.name for p in model.parts] == ["Bone001", "Bone002"]
    assert model.hinge.axis == (0.0, 1.0, 0.0)
    assert model.hinge.range == pytest.approx((-np.radians(170), np.radians(170)))
    whole = trimesh.load_mesh(tzionas_dir / "Models/17/Model_Object_Pipe_Gray.OFF", process=False)
    assert sum(p.mesh.volume for p in model.parts) == pytest.approx(whole.volume * 1e-9, rel=1e-6)
    spec = build_object(model, cache_dir=cache_dir)
    compiled = compile_spec(spec)
    hinge = compiled.joint("hinge")
    np.testing.assert_allclose(compiled.jnt_range[hinge.id], np.radians([-170, 170]))
    data = mujoco.MjData(compiled)
    data.qpos[compiled.jnt_qposadr[hinge.id]] = np.radians(90)
    mujoco.mj_kinematics(compiled, data)
    # Bending about +y by 90°: the child half, along +x at rest, points along -z.
    tip = data.xpos[compiled.body("Bone002").id] + data.xmat[compiled.body("Bone002").id].reshape(3, 3) @ [
        0.175,
        0,
        0,
    ]
    np.testing.assert_allclose(tip, [0, 0, -0.175], atol=1e-9)
    result = drop_test(spec)
    assert result.ok, result
