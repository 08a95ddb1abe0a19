"""ARCTIC objects as built: hinge range rule, lid–base contact pairs, per-object masses, the drop acceptance,
and the ARCTIC object convention pinned against an independent numpy computation (issue 13)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from handsim.builders.arctic_objects import (
    ARCTIC_OBJECTS,
    HINGE_MARGIN,
    arctic_hinge_range,
    arctic_object,
)
from handsim.builders.catalog import resolve
from handsim.builders.decomposition_types import DecompositionParams
from handsim.builders.graspdb_objects import UnknownObjectError
from handsim.builders.objects import build_object
from handsim.cli import main
from handsim.errors import InputFileError, ModelError
from handsim.io.arctic.sequence import ARCTIC_OBJECTS as ARCTIC_NAMES
from handsim.io.arctic.sequence import read_arctic_object
from handsim.sim import compile_spec
from handsim.sim.stability.drop import drop_test
from tests.arctic_fixtures import (
    RECORDED_ARTICULATION,
    recording,
    template_parts,
    template_vertices_mm,
    write_template,
)
from tests.mano_fixtures import write_arctic_object_npy

FAST = DecompositionParams(resolution=500, preprocess_resolution=30, mcts_iterations=60, max_convex_hull=8)
NAMES = tuple(template_parts())
IMPACT_TOLERANCE = math.radians(0.5)
"""How far a dropped lid may dip past its range at impact (soft constraints); measured ≤ 0.17°."""


@pytest.fixture(scope="module")
def templates(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("object_vtemplates")
    return {name: write_template(folder, name) for name in NAMES}


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory) -> str:
    return str(tmp_path_factory.mktemp("coacd_cache"))


def upright_quat(rec: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(rec[0, 1:4].astype(float)).as_quat(scalar_first=True)


# --------------------------------------------------------------------------------------------------
# Acceptance: every template rests after a 2 s drop, its lid within its range


@pytest.mark.parametrize("start", [0.0, 0.8], ids=["closed", "open"])
@pytest.mark.parametrize("name", NAMES)
def test_every_arctic_template_rests_after_a_drop_with_its_lid_in_range(templates, cache_dir, name, start):
    rec = recording(name)
    model = arctic_object(templates[name], articulation=rec[:, 0])
    result = drop_test(
        build_object(model, FAST, cache_dir=cache_dir), quat=upright_quat(rec), articulation=start
    )
    assert result.warnings == {}
    assert result.rest_time is not None and result.rest_time < 2.0
    assert result.hinge_range == pytest.approx(model.hinge.range)
    assert result.hinge_outside() <= IMPACT_TOLERANCE
    assert result.mass == pytest.approx(ARCTIC_OBJECTS[name].mass, rel=1e-9)


def test_lid_rests_on_its_base_through_contact_pairs_even_without_a_range(templates, cache_dir):
    model = arctic_object(templates["waffleiron"])
    quat = upright_quat(recording("waffleiron"))
    unlimited = replace(model, hinge=replace(model.hinge, range=None))
    spec = build_object(unlimited, FAST, cache_dir=cache_dir)
    bottom = [g.name for g in spec.geoms if g.parent.name == "bottom" and g.contype]
    top = [g.name for g in spec.geoms if g.parent.name == "top" and g.contype]
    pairs = [(p.geomname1, p.geomname2) for p in spec.pairs]
    assert pairs == [(a, b) for a in bottom for b in top] and len(pairs) == len(bottom) * len(top) > 1
    assert drop_test(spec, quat=quat).hinge_span[0] > -IMPACT_TOLERANCE
    loose = replace(unlimited, hinge=replace(unlimited.hinge, parts_collide=False))
    sunk = drop_test(build_object(loose, FAST, cache_dir=cache_dir), quat=quat)
    assert sunk.hinge_span[0] < math.radians(-10.0)  # the lid falls into the base without the pairs


def test_contact_pairs_do_not_change_any_other_collision(templates, cache_dir):
    compiled = compile_spec(build_object(arctic_object(templates["box"]), FAST, cache_dir=cache_dir))
    assert compiled.npair > 0
    for k in range(compiled.npair):
        bodies = {
            compiled.body(compiled.geom_bodyid[g]).name
            for g in (compiled.pair_geom1[k], compiled.pair_geom2[k])
        }
        assert bodies == {"bottom", "top"}
    assert compiled.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_FILTERPARENT == 0


# --------------------------------------------------------------------------------------------------
# The ARCTIC convention against numpy


@pytest.mark.parametrize("name", ["box", "laptop", "ketchup"])  # top/bottom.obj and mesh.obj + parts.json
def test_simulated_object_geometry_equals_arctic_formula_at_the_recorded_frame_0(
    templates, cache_dir, tmp_path, name
):
    rec = recording(name)
    rec[:, 0] += np.float32(0.35)  # frame 0 partly open, so the articulation matters
    path = tmp_path / f"{name}_use_01.object.npy"
    write_arctic_object_npy(path, rec)
    raw = np.load(path).astype(float)[0]  # independent of handsim's reader
    theta, rotation, translation_mm = raw[0], Rotation.from_rotvec(raw[1:4]).as_matrix(), raw[4:]
    r_top = Rotation.from_rotvec([0.0, 0.0, -theta]).as_matrix()  # about (0, 0, -1) by theta
    expected = {
        part: (v @ (rotation @ (r_top if part == "top" else np.eye(3))).T + translation_mm) / 1000.0
        for part, v in template_vertices_mm(templates[name]).items()
    }
    track = read_arctic_object(path)
    built = arctic_object(templates[name], articulation=track.articulation)
    model = compile_spec(build_object(built, FAST, cache_dir=cache_dir))
    data = mujoco.MjData(model)
    hinge = model.jnt_qposadr[model.joint("hinge").id]
    # Reference: the object at the template pose (identity, articulation 0) — world = template frame.
    data.qpos[:7] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    data.qpos[hinge] = 0.0
    mujoco.mj_kinematics(model, data)
    in_geom = {}
    for part in expected:
        geom = model.geom(f"{part}_visual")
        v = template_vertices_mm(templates[name])[part] / 1000.0
        in_geom[part] = (v - data.geom_xpos[geom.id]) @ data.geom_xmat[geom.id].reshape(3, 3)
        # The compiled mesh (float32, recentred on its geom) holds exactly these template vertices.
        mesh = model.mesh_vert[model.mesh_vertadr[geom.dataid[0]] :][: model.mesh_vertnum[geom.dataid[0]]]
        gap, _ = cKDTree(mesh).query(in_geom[part])
        assert gap.max() < 1e-6
    # The recorded frame 0: MuJoCo's geom poses carry the template vertices where ARCTIC's formula does.
    data.qpos[:7] = track.pose[0]
    data.qpos[hinge] = track.articulation[0]
    mujoco.mj_kinematics(model, data)
    for part, world in expected.items():
        geom = model.geom(f"{part}_visual")
        simulated = data.geom_xpos[geom.id] + in_geom[part] @ data.geom_xmat[geom.id].reshape(3, 3).T
        np.testing.assert_allclose(simulated, world, rtol=0, atol=1e-9)


# --------------------------------------------------------------------------------------------------
# Hinge range rule, masses


def test_hinge_range_is_the_recorded_range_plus_a_margin_never_below_closed():
    (lo, hi), note = arctic_hinge_range("laptop", [0.05, 0.9, 1.4])
    assert (lo, hi) == (0.0, 1.4 + HINGE_MARGIN)
    assert note == "hinge range 0.0°..90.2°: the recorded 2.9°..80.2° ± 10°, never below the closed pose 0°"
    (lo, hi), _ = arctic_hinge_range("laptop", [0.8, 1.4])
    assert (lo, hi) == (0.8 - HINGE_MARGIN, 1.4 + HINGE_MARGIN)


def test_recording_below_the_closed_pose_is_noted_and_stopped_there():
    (lo, hi), note = arctic_hinge_range("box", [-0.2, 0.5])
    assert (lo, hi) == (0.0, 0.5 + HINGE_MARGIN)
    assert note.endswith(
        "; the recording goes 11.5° below the closed pose, where the parts would overlap: the hinge stops "
        "there"
    )


def test_hinge_range_without_recording_is_the_objects_default():
    assert arctic_hinge_range("scissors") == (
        (0.0, math.radians(60.0)),
        "hinge range 0°..60° (scissors's default; no recording)",
    )
    assert arctic_hinge_range("teapot") == (
        (0.0, math.pi / 2),
        "hinge range 0°..90° (the default for objects outside ARCTIC's 11; no recording)",
    )
    with pytest.raises(
        ModelError, match=r"^box: the recorded articulation must be finite angles, got 2 values$"
    ):
        arctic_hinge_range("box", [0.1, np.nan])


def test_every_arctic_object_has_a_default_mass_and_opening():
    assert set(ARCTIC_OBJECTS) == set(ARCTIC_NAMES)
    for info in ARCTIC_OBJECTS.values():
        assert 0.05 <= info.mass <= 1.5 and 0 < info.opening <= math.pi and info.mass_basis


def test_default_mass_is_noted_and_mass_or_density_override_it(templates):
    model = arctic_object(templates["phone"])
    assert model.mass == 0.1 and model.density is None
    assert "mass 0.1 kg: phone's default (assumption: flip phones weigh 90–120 g)" in model.notes
    assert arctic_object(templates["phone"], mass=0.2).mass == 0.2
    dense = arctic_object(templates["phone"], density=800.0)
    assert (dense.mass, dense.density) == (None, 800.0)
    with pytest.raises(ModelError, match=r"^give mass or density, not both$"):
        arctic_object(templates["phone"], mass=0.2, density=800.0)


def test_template_outside_arcticss_objects_keeps_the_fallback_density(tmp_path, templates):
    folder = tmp_path / "teapot"
    folder.mkdir()
    for f in templates["phone"].iterdir():
        (folder / f.name).write_bytes(f.read_bytes())
    model = arctic_object(folder)
    assert (model.mass, model.density) == (None, 300.0)
    assert model.hinge.range == (0.0, math.pi / 2) and model.hinge.parts_collide


# --------------------------------------------------------------------------------------------------
# Command line and catalogue


def test_build_object_on_an_arctic_template_prints_range_mass_and_rules(capsys, templates, cache_dir):
    assert main(["build", "object", str(templates["notebook"]), "--cache-dir", cache_dir]) == 0
    out = capsys.readouterr().out
    assert "hinge      axis (0.0, 0.0, -1.0) through (0.0, 0.0, 0.0) m, 0.000 .. 3.142 rad" in out
    assert "mass       600.0 g" in out
    assert "note       mass 0.6 kg: notebook's default" in out
    assert "note       hinge range 0°..180° (notebook's default; no recording)" in out


def test_build_object_with_mass_overrides_the_default(capsys, templates, cache_dir):
    assert main(["build", "object", str(templates["phone"]), "--mass", "0.15", "--cache-dir", cache_dir]) == 0
    assert "mass       150.0 g" in capsys.readouterr().out


def test_build_object_on_a_missing_template_folder_says_so(capsys, tmp_path):
    missing = tmp_path / "meta" / "object_vtemplates" / "waffleiron"
    assert main(["build", "object", str(missing)]) == 1
    err = capsys.readouterr().err
    assert err.strip() == (
        f"handsim: error: {missing}: ARCTIC template folder not found; give a catalogue name (handsim "
        "catalog), a mesh file, an ARCTIC template folder (top.obj + bottom.obj, or mesh.obj + parts.json) "
        "or a Tzionas .SKEL"
    )


def test_an_arctic_object_name_asks_for_its_template_folder():
    with pytest.raises(UnknownObjectError) as err:
        resolve("waffleiron")
    assert str(err.value) == (
        "'waffleiron' is an ARCTIC object; ARCTIC's templates are not bundled (their licence forbids it): "
        "pass your template folder, e.g. arctic_data/data/meta/object_vtemplates/waffleiron"
    )
    with pytest.raises(InputFileError, match=r"missing\.obj: mesh file not found; give a catalogue name"):
        resolve("missing.obj", units="mm")


def test_recordings_of_the_fixture_span_their_articulation():
    for name, (lo, hi) in RECORDED_ARTICULATION.items():
        art = recording(name)[:, 0]
        assert art.min() == pytest.approx(lo, abs=1e-6) and art.max() == pytest.approx(hi, abs=0.01)
