"""Mesh reading with explicit units, validation (errors before native code) and safe repairs."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from handsim.datatypes.mesh import boundary_loops, cap_loops, principal_extents, validate_mesh
from handsim.errors import FormatError, InputFileError, MeshError
from handsim.io.mesh import read_mesh

BOX = trimesh.creation.box((0.05, 0.04, 0.03))


def _box():
    return np.array(BOX.vertices), np.array(BOX.faces)


@pytest.mark.parametrize("ext", ["obj", "off", "stl", "ply"])
def test_read_mesh_reads_every_format_in_mm_as_metres(tmp_path, ext):
    path = tmp_path / f"box.{ext}"
    trimesh.creation.box((50.0, 40.0, 30.0)).export(path)
    mesh = read_mesh(path, "mm")
    np.testing.assert_allclose(mesh.extent, [0.05, 0.04, 0.03], atol=1e-12)
    assert mesh.volume == pytest.approx(6e-5)
    assert mesh.watertight


def test_read_mesh_raises_error_if_mm_file_is_read_as_m(tmp_path):
    path = tmp_path / "box.obj"
    trimesh.creation.box((50.0, 40.0, 30.0)).export(path)
    with pytest.raises(
        MeshError,
        match=r"box\.obj: the object is 50 m across in units='m', outside the "
        r"plausible 5 mm – 0.6 m; are the coordinates in mm\? \(pass units='mm'\)",
    ):
        read_mesh(path, "m")


def test_read_mesh_raises_error_if_m_file_is_read_as_mm(tmp_path):
    path = tmp_path / "box.obj"
    BOX.export(path)
    with pytest.raises(MeshError, match=r"0.05 mm|5e-05 m across in units='mm'.*are the coordinates in m\?"):
        read_mesh(path, "mm")


def test_read_mesh_raises_error_if_units_are_unknown(tmp_path):
    path = tmp_path / "box.obj"
    BOX.export(path)
    with pytest.raises(MeshError, match=r"unknown units 'cm'; expected one of \['m', 'mm'\]"):
        read_mesh(path, "cm")


def test_read_mesh_raises_error_if_extension_is_unknown(tmp_path):
    path = tmp_path / "box.dae"
    path.write_text("x")
    with pytest.raises(InputFileError, match=r"unknown mesh file type '\.dae'; handsim reads \.obj, \.off"):
        read_mesh(path, "m")


def test_read_mesh_raises_error_if_file_is_missing(tmp_path):
    with pytest.raises(InputFileError, match=r"nope\.stl: file not found"):
        read_mesh(tmp_path / "nope.stl", "m")


def test_validate_raises_error_if_fewer_than_4_vertices():
    with pytest.raises(
        MeshError, match=r"m: a mesh needs at least 4 vertices of 3 coordinates, got shape \(3, 3\)"
    ):
        validate_mesh(np.eye(3), [[0, 1, 2]], "m")


def test_validate_raises_error_if_a_vertex_is_not_finite():
    v, f = _box()
    v[5, 1] = np.nan
    with pytest.raises(MeshError, match=r"m: vertex 5 is not finite .*1 non-finite vertices in all"):
        validate_mesh(v, f, "m")


def test_validate_raises_error_if_a_face_index_is_out_of_range():
    v, f = _box()
    f[3, 2] = 8
    with pytest.raises(MeshError, match=r"m: face 3 has vertex index 8 outside 0\.\.7"):
        validate_mesh(v, f, "m")


def test_validate_raises_error_if_there_are_no_faces():
    v, _ = _box()
    with pytest.raises(MeshError, match=r"expected triangles of shape \(F, 3\) with F > 0, got shape \(0,\)"):
        validate_mesh(v, [], "m")


def test_validate_raises_error_if_mesh_is_flat():
    v = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0.1, 0.1, 0]], dtype=float)
    with pytest.raises(MeshError, match=r"m: the mesh is flat or degenerate"):
        validate_mesh(v, [[0, 1, 2], [1, 3, 2], [0, 2, 1], [1, 2, 3]], "m")


def test_validate_repairs_inverted_winding_and_reports_it():
    v, f = _box()
    mesh = validate_mesh(v, f[:, ::-1], "m")
    assert mesh.volume == pytest.approx(6e-5)
    assert "inverted faces pointing inwards" in mesh.notes


def test_validate_repairs_inconsistent_winding_and_reports_it():
    v, f = _box()
    f = f.copy()
    f[0] = f[0, ::-1]
    mesh = validate_mesh(v, f, "m")
    assert mesh.volume == pytest.approx(6e-5)
    assert "made face winding consistent" in mesh.notes


def test_validate_merges_unmerged_vertices_and_reports_it():
    v, f = _box()
    soup = v[f].reshape(-1, 3)
    mesh = validate_mesh(soup, np.arange(len(soup)).reshape(-1, 3), "m")
    assert len(mesh.vertices) == 8
    assert mesh.watertight
    assert "merged 28 duplicate vertices" in mesh.notes


def test_validate_fills_a_small_hole_and_reports_it():
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.03)
    mesh = validate_mesh(sphere.vertices, sphere.faces[1:], "m")
    assert mesh.watertight
    assert mesh.volume == pytest.approx(sphere.volume)
    assert "filled 1 small holes (at most 64 edges each) with 1 faces" in mesh.notes


def test_validate_fills_a_many_edged_hole_with_a_fan_and_reports_it():
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.03)
    keep = sphere.triangles_center[:, 2] < 0.027  # removes a polar cap: one hole of a few dozen edges
    loops = boundary_loops(sphere.faces[keep])
    assert len(loops) == 1 and 8 < len(loops[0]) <= 64
    mesh = validate_mesh(sphere.vertices, sphere.faces[keep], "m")
    assert mesh.watertight
    assert mesh.volume == pytest.approx(sphere.volume, rel=1e-2)  # the flat cap cuts off a thin dome
    assert f"filled 1 small holes (at most 64 edges each) with {len(loops[0])} faces" in mesh.notes


def test_cap_loops_closes_a_cut_tube_with_outward_winding():
    tube = trimesh.creation.cylinder(radius=0.02, height=0.1, sections=40)
    keep = tube.triangles_center[:, 2] < 0.04  # drop the top cap: one 40-edge loop
    loops = boundary_loops(tube.faces[keep])
    v, f = cap_loops(tube.vertices, tube.faces[keep], loops)
    capped = trimesh.Trimesh(v, f, process=False)
    assert capped.is_watertight and capped.is_winding_consistent
    assert capped.volume == pytest.approx(tube.volume, rel=1e-9)


def test_validate_raises_error_if_mesh_stays_open():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.03)
    keep = sphere.triangles_center[:, 2] < 0.0  # a hemisphere: one 96-edge hole
    with pytest.raises(
        MeshError, match=r"m: the mesh is not watertight after repair .* give the object's mass"
    ):
        validate_mesh(sphere.vertices, sphere.faces[keep], "m")


def test_validate_accepts_an_open_mesh_when_watertightness_is_not_required():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.03)
    keep = sphere.triangles_center[:, 2] < 0.0
    mesh = validate_mesh(sphere.vertices, sphere.faces[keep], "m", require_watertight=False)
    assert not mesh.watertight


def test_tzionas_cube_and_pipe_meshes_read_in_mm(tzionas_dir):
    cube = read_mesh(tzionas_dir / "Models/20/Model_Object_Cube.OFF", "mm")
    np.testing.assert_allclose(cube.extent, [0.053] * 3, atol=1e-4)
    assert cube.watertight
    pipe = read_mesh(tzionas_dir / "Models/17/Model_Object_Pipe_Gray.OFF", "mm")
    assert pipe.extent.max() == pytest.approx(0.35, abs=1e-3)


def _box_text(file_type: str) -> str:
    text = trimesh.creation.box((50.0, 40.0, 30.0)).export(file_type=file_type)
    return "".join(line + "\n" for line in text.splitlines() if not line.startswith("#"))


def test_obj_without_faces_is_reported_as_vertices_without_faces(tmp_path):
    path = tmp_path / "cloud.obj"
    path.write_text("".join(line + "\n" for line in _box_text("obj").splitlines() if line.startswith("v ")))
    with pytest.raises(MeshError) as err:
        read_mesh(path, "mm")
    assert str(err.value) == (
        f"{path}: the file holds 8 vertices but no faces; a mesh needs triangles or polygons (OBJ 'f' lines) "
        "that close its surface, not a point cloud"
    )


@pytest.mark.parametrize(
    ("counts", "expected"),
    [("8 13 0", "8 vertices and 13 faces"), ("9 12 0", "9 vertices and 12 faces")],
)
def test_off_header_promising_more_than_the_file_holds_names_the_header_line(tmp_path, counts, expected):
    lines = _box_text("off").splitlines()
    assert lines[1] == "8 12 0"
    lines[1] = counts
    path = tmp_path / "box.off"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError) as err:
        read_mesh(path, "mm")
    held = "8 vertex and 12 face lines" if counts == "8 13 0" else "9 vertex and 11 face lines"
    assert str(err.value) == (
        f"{path}:2 [counts]: the header promises {expected}, but the file ends after {held} (line 22)"
    )


def test_off_header_promising_fewer_faces_than_the_file_holds_is_an_error(tmp_path):
    lines = _box_text("off").splitlines()
    lines[1] = "8 11 0"
    path = tmp_path / "box.off"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError) as err:
        read_mesh(path, "mm")
    assert (
        str(err.value)
        == f"{path}:22 [end]: unexpected content after the 11 faces the header (line 2) promises"
    )


def test_off_with_face_colours_and_a_coff_header_reads(tmp_path):
    lines = _box_text("off").splitlines()
    lines[0] = "COFF"
    lines[2:10] = [f"{line} 255 0 0 255" for line in lines[2:10]]
    lines[10:] = [f"{line} 0.5 0.5 0.5" for line in lines[10:]]
    path = tmp_path / "box.off"
    path.write_text("\n".join(lines) + "\n")
    assert read_mesh(path, "mm").volume == pytest.approx(6e-5)


def test_mesh_thinner_than_a_sheet_of_paper_is_refused_with_its_thickness(tmp_path):
    path = tmp_path / "foil.obj"
    trimesh.creation.box((50.0, 50.0, 0.003)).export(path)  # 3 µm thick, 0.0075 g of water
    with pytest.raises(MeshError) as err:
        read_mesh(path, "mm")
    assert str(err.value) == (
        f"{path}: the object is 0.003 mm thick (its smallest extent along its principal axes), thinner "
        "than the 0.1 mm handsim accepts (a sheet of paper); a surface this thin has no usable volume, "
        "mass or contact"
    )


def test_thickness_is_measured_across_a_tilted_plate():
    plate = trimesh.creation.box((0.05, 0.05, 0.001))
    plate.apply_transform(trimesh.transformations.rotation_matrix(0.7, [1.0, 1.0, 0.0]))
    extents = principal_extents(plate.vertices)
    assert extents[2] == pytest.approx(0.001, rel=1e-9)
    assert np.ptp(plate.vertices, axis=0).min() > 0.02  # an axis-aligned box would call it 20+ mm thick


def test_a_business_card_thick_mesh_is_accepted(tmp_path):
    path = tmp_path / "card.obj"
    trimesh.creation.box((85.0, 55.0, 0.4)).export(path)
    assert read_mesh(path, "mm").extent[2] == pytest.approx(0.0004)


@pytest.mark.parametrize(("faces", "present"), [("13", 20), ("11", 20), ("899999999", 20)])
def test_ascii_ply_header_promising_other_counts_than_the_file_holds_is_an_error(tmp_path, faces, present):
    text = trimesh.creation.box((50.0, 40.0, 30.0)).export(file_type="ply", encoding="ascii").decode()
    assert "element face 12\n" in text
    path = tmp_path / "box.ply"
    path.write_text(text.replace("element face 12\n", f"element face {faces}\n"))
    with pytest.raises(FormatError) as err:
        read_mesh(path, "mm")
    promised = 8 + int(faces)
    assert str(err.value) == (
        f"{path}:10 [header]: the header promises elements 8 'vertex', {faces} 'face' ({promised} data "
        f"lines), but {present} follow it"
    )


def test_binary_stl_shorter_than_its_triangle_count_is_an_error(tmp_path):
    data = trimesh.creation.box((50.0, 40.0, 30.0)).export(file_type="stl")
    path = tmp_path / "box.stl"
    path.write_bytes(data[:-10])
    with pytest.raises(FormatError) as err:
        read_mesh(path, "mm")
    assert str(err.value) == (
        f"{path} [triangle count]: the binary STL header promises 12 triangles (684 bytes), but the file has "
        "674 bytes"
    )
    path.write_bytes(data)
    assert read_mesh(path, "mm").volume == pytest.approx(6e-5)


def test_trimesh_logs_nothing_while_handsim_reads_a_malformed_file(tmp_path, caplog):
    path = tmp_path / "bad.stl"  # a facet normal that is no number: trimesh logs a traceback, then reads it
    path.write_text(
        "solid x\nfacet normal 0 0 zz\nouter loop\nvertex 0 0 0\nvertex 50 0 0\nvertex 0 50 0\nendloop\n"
        "endfacet\nendsolid\n"
    )
    with caplog.at_level("DEBUG", logger="trimesh"), pytest.raises(MeshError):
        read_mesh(path, "mm")
    assert [r for r in caplog.records if r.name.startswith("trimesh")] == []


def test_a_file_trimesh_reads_nothing_from_is_not_called_a_point_cloud(tmp_path):
    path = tmp_path / "bad.stl"
    path.write_text("solid x\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 zz\n")
    with pytest.raises(MeshError) as err:
        read_mesh(path, "mm")
    assert str(err.value) == f"{path}: no triangle could be read from it as STL; is it a valid STL file?"
