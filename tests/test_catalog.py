"""The object catalogue: every object builds, drops onto the table and rests; lookups and their errors."""

from __future__ import annotations

import importlib.metadata

import mujoco
import pytest

from handsim.builders import catalog
from handsim.builders.decomposition_types import DecompositionParams
from handsim.builders.graspdb_objects import UnknownObjectError
from handsim.builders.hull_cache import BUNDLED_CACHE_DIR, cache_key
from handsim.builders.objects import build_object, object_spec, prepare_object
from handsim.builders.scene import build_scene
from handsim.errors import InputFileError
from handsim.sim import compile_spec, warning_counts
from handsim.sim.stability.drop import drop_test

NAMES = catalog.names()


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("coacd_cache")


@pytest.mark.parametrize("name", NAMES)
def test_catalogue_object_drops_onto_the_table_and_rests_without_warnings(name, cache_dir):
    model = catalog.get(name)
    prepared = prepare_object(model, cache_dir=cache_dir)
    result = drop_test(object_spec(prepared))
    assert result.warnings == {}
    assert result.rest_time is not None and result.rest_time < 2.0, result
    assert abs(result.final_height) < 0.002, result  # it rests as placed, not tipped over
    volume = sum(p.mesh.volume for p in model.parts)
    assert result.mass == pytest.approx(volume * model.density, rel=0.01)


def test_catalogue_lists_every_graspdb_object_and_the_tzionas_objects():
    entries = catalog.entries()
    assert sorted(e.graspdb_id for e in entries if e.graspdb_id is not None) == list(range(1, 17))
    assert {"tzionas_cube", "tzionas_pipe"} <= set(NAMES)
    assert len(set(NAMES)) == len(NAMES)


def test_get_graspdb_by_id_equals_get_by_name():
    ball = catalog.get_graspdb(1)
    assert ball.name == "tennis_ball"
    assert ball.density == pytest.approx(catalog.get("tennis_ball").density)


def test_get_unknown_name_raises_error_listing_the_catalogue():
    with pytest.raises(
        UnknownObjectError, match=r"^unknown object 'teapot'; catalogue objects are: (.+, )+"
    ) as info:
        catalog.get("teapot")
    for name in NAMES:
        assert name in str(info.value)


@pytest.mark.parametrize("what", ["foo.xyz", "foo.DAE", "teapot.glb"])
def test_resolve_of_an_unsupported_extension_names_it_and_lists_what_handsim_reads(what):
    with pytest.raises(InputFileError) as err:
        catalog.resolve(what)
    suffix = what[what.index(".") :]
    assert str(err.value) == (
        f"{what}: unsupported mesh extension {suffix!r}; handsim reads meshes .obj, .off, .stl, .ply (give "
        "their units), Tzionas object .SKEL files, ARCTIC template folders and catalogue names (see "
        "`handsim catalog`)"
    )


def test_resolve_of_a_file_without_extension_is_not_looked_up_in_the_catalogue(tmp_path):
    path = tmp_path / "mug"
    path.write_text("v 0 0 0\n")
    with pytest.raises(InputFileError, match=rf"^{path}: a file without a mesh extension; handsim reads"):
        catalog.resolve(path)


def test_resolve_of_a_missing_tzionas_skel_says_file_not_found():
    with pytest.raises(InputFileError, match=r"^nope\.SKEL: file not found$"):
        catalog.resolve("nope.SKEL")


def test_resolve_mesh_file_without_units_raises_error(tmp_path):
    path = tmp_path / "thing.stl"
    path.write_bytes(b"")
    with pytest.raises(InputFileError, match=r"thing\.stl: give the mesh's units \('m' or 'mm'\)"):
        catalog.resolve(path)


def test_resolve_mesh_file_assumes_water_density_and_says_so(tmp_path):
    import trimesh

    path = tmp_path / "block.stl"
    trimesh.creation.box((40.0, 30.0, 20.0)).export(path)
    model = catalog.resolve(path, units="mm")
    assert model.density == 1000.0
    assert "no density or mass given; 1000 kg/m³ assumed" in model.notes
    assert model.parts[0].mesh.volume == pytest.approx(24e-6)


def _bundled_coacd_version() -> str:
    return (BUNDLED_CACHE_DIR / "COACD_VERSION").read_text().strip()


def test_concave_catalogue_objects_are_decomposed_in_the_bundled_cache():
    if importlib.metadata.version("coacd") != _bundled_coacd_version():
        pytest.skip(
            f"the bundled hulls were made with coacd {_bundled_coacd_version()}, "
            f"this is {importlib.metadata.version('coacd')}: they are decomposed anew"
        )
    params = DecompositionParams()
    for name in NAMES:
        for part in catalog.get(name).parts:
            if part.primitives or part.mesh.to_trimesh().convex_hull.volume < part.mesh.volume * 1.001:
                continue
            key = cache_key(part.mesh, params)
            assert (BUNDLED_CACHE_DIR / "coacd" / key[:2] / f"{key}.npz").is_file(), (name, part.name)


def test_scene_with_hand_and_catalogue_object_compiles_with_prefixes_and_cameras(cache_dir):
    from handsim.builders import default_hand

    scene = build_scene(default_hand(), [build_object(catalog.get("mug"), cache_dir=cache_dir)])
    model = compile_spec(scene)
    names = [model.body(i).name for i in range(model.nbody)]
    assert "hand/root" in names and "obj/body" in names
    assert model.joint("obj/free").type == mujoco.mjtJoint.mjJNT_FREE
    assert model.ncam == 2 and model.camera("hand_cam") is not None
    assert model.opt.impratio == 10.0 and model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    data = mujoco.MjData(model)
    for _ in range(250):
        mujoco.mj_step(model, data)
    assert not any(warning_counts(data).values())


def test_scene_with_two_objects_numbers_their_prefixes(cache_dir):
    objects = [build_object(catalog.get(n), cache_dir=cache_dir) for n in ("cube", "tennis_ball")]
    model = compile_spec(build_scene(None, objects))
    assert model.body("obj0/body") is not None and model.body("obj1/body") is not None


def test_resolve_applies_a_given_mass_or_density_to_catalogue_and_tzionas_objects():
    from handsim.assets import TZIONAS_DIR

    cube = catalog.resolve("cube", mass=0.2)
    assert cube.mass == 0.2 and cube.density is None
    assert "mass 0.2 kg given, replacing the default" in cube.notes
    pipe = catalog.resolve(TZIONAS_DIR / "Models/17/Model_Object_Pipe_Gray.SKEL", density=300.0)
    assert pipe.density == 300.0
    assert catalog.resolve("cube") == catalog.get("cube")
