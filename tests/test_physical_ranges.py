"""Masses and densities outside their documented ranges are refused unless forced (API and command line)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
import trimesh

from handsim.assets import TZIONAS_DIR
from handsim.builders import build_hand, catalog, default_hand, default_skeleton
from handsim.builders.objects import build_object, prepare_object
from handsim.cli import main
from handsim.datatypes.mesh import validate_mesh
from handsim.datatypes.object_model import mesh_object
from handsim.datatypes.physical_ranges import DENSITY, HAND_MASS, OBJECT_MASS, PhysicalRange
from handsim.errors import OutOfRangeError

RANGES = "see docs/objects.md"


def test_ranges_are_the_documented_ones() -> None:
    assert (OBJECT_MASS.low, OBJECT_MASS.high, OBJECT_MASS.unit) == (1e-3, 23.0, "kg")
    assert (DENSITY.low, DENSITY.high, DENSITY.unit) == (10.0, 11_400.0, "kg/m³")
    assert (HAND_MASS.low, HAND_MASS.high, HAND_MASS.unit) == (0.1, 1.0, "kg")
    docs = (Path(__file__).resolve().parents[1] / "docs" / "objects.md").read_text()
    assert "| object mass | 1 g to 23 kg |" in docs
    assert "| object density | 10 to 11,400 kg/m³ |" in docs
    assert "| hand mass | 0.1 to 1.0 kg |" in docs


@pytest.mark.parametrize("value", [1e-3, 0.5, 23.0])
def test_values_inside_a_range_bounds_included_pass(value: float) -> None:
    assert OBJECT_MASS.check(value) == value


@pytest.mark.parametrize(("value", "shown"), [(1e-9, "1e-09"), (1e9, "1e+09"), (23.5, "23.5")])
def test_a_value_outside_the_range_is_refused_with_the_range_and_how_to_force_it(
    value: float, shown: str
) -> None:
    with pytest.raises(OutOfRangeError) as err:
        OBJECT_MASS.check(value, subject="object ")
    assert str(err.value) == (
        f"object mass {shown} kg is outside the plausible 0.001 to 23 kg (household objects a hand grasps), "
        f"{RANGES}; pass force=True to use it anyway"
    )
    assert OBJECT_MASS.check(value, force=True) == value


@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf])
def test_a_value_that_is_not_a_positive_finite_number_is_refused_even_when_forced(value: float) -> None:
    with pytest.raises(OutOfRangeError) as err:
        DENSITY.check(value, force=True)
    assert str(err.value) == f"density {value:g} kg/m³: expected a positive number"


def test_describe_gives_the_range_and_its_basis() -> None:
    assert PhysicalRange("x", 1.0, 2.5, "m", "things").describe() == "1 to 2.5 m (things)"


# --------------------------------------------------------------------------------------------------
# API: resolve, prepare_object / build_object, build_hand


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"mass": 1e-9}, "object mass 1e-09 kg is outside the plausible 0.001 to 23 kg"),
        ({"mass": 1e9}, "object mass 1e+09 kg is outside the plausible 0.001 to 23 kg"),
        ({"density": 1e-6}, "object density 1e-06 kg/m³ is outside the plausible 10 to 11400 kg/m³"),
        ({"density": 1e9}, "object density 1e+09 kg/m³ is outside the plausible 10 to 11400 kg/m³"),
    ],
)
def test_resolve_refuses_an_implausible_mass_or_density_before_reading_anything(kwargs, message) -> None:
    with pytest.raises(
        OutOfRangeError, match=rf"^{re.escape(message)} \(.*\), {RANGES}; pass force=True to use it anyway$"
    ):
        catalog.resolve("no/such/file.obj", units="mm", **kwargs)  # checked before the missing file


def test_resolve_with_force_accepts_them_and_prepare_object_with_force_builds_them() -> None:
    model = catalog.resolve("cube", mass=30.0, force=True)
    with pytest.raises(OutOfRangeError, match=r"^object 'cube' mass 30 kg is outside the plausible"):
        prepare_object(model)
    assert prepare_object(model, force=True).total_mass == pytest.approx(30.0)


def test_build_object_refuses_a_model_density_out_of_range_unless_forced() -> None:
    model = catalog.resolve("cube", density=20_000.0, force=True)  # tungsten
    with pytest.raises(OutOfRangeError) as err:
        build_object(model)
    assert str(err.value) == (
        "object 'cube' density 20000 kg/m³ is outside the plausible 10 to 11400 kg/m³ (expanded polystyrene "
        f"foam to lead), {RANGES}; pass force=True to use it anyway"
    )
    assert build_object(model, force=True).compile().body_mass[1] == pytest.approx(20_000.0 * 0.05**3)


def test_a_mesh_that_weighs_milligrams_is_refused_with_its_volume_and_density() -> None:
    # 50 × 50 × 0.2 mm of water: thick enough for the reader, 0.5 g
    box = trimesh.creation.box((0.05, 0.05, 0.0002))
    model = mesh_object(validate_mesh(box.vertices, box.faces, "plate"), density=1000.0, name="plate")
    with pytest.raises(OutOfRangeError) as err:
        prepare_object(model)
    assert str(err.value) == (
        "object 'plate' mass 0.0005 kg (0.5 cm³ at 1000 kg/m³) is outside the plausible 0.001 to 23 kg "
        f"(household objects a hand grasps), {RANGES}; pass force=True to use it anyway"
    )


def test_a_given_mass_on_a_tiny_mesh_is_an_implausible_density(tmp_path: Path) -> None:
    path = tmp_path / "bead.obj"
    trimesh.creation.box((10.0, 10.0, 10.0)).export(path)  # 1 cm³
    model = catalog.resolve(path, units="mm", mass=20.0)
    with pytest.raises(OutOfRangeError) as err:
        prepare_object(model)
    assert str(err.value) == (
        "object 'bead' density 2e+07 kg/m³ (20 kg over 1 cm³) is outside the plausible 10 to 11400 kg/m³ "
        f"(expanded polystyrene foam to lead), {RANGES}; pass force=True to use it anyway"
    )


@pytest.mark.parametrize("name", catalog.names())
def test_every_catalogue_object_lies_inside_the_ranges(name: str) -> None:
    prepared = prepare_object(catalog.get(name))  # raises when out of range
    volume = sum(p.volume for p in prepared.mass_properties.values())
    assert OBJECT_MASS.problem(prepared.total_mass) is None
    assert DENSITY.problem(prepared.total_mass / volume) is None


@pytest.mark.parametrize("mass", [0.05, 5.0])
def test_build_hand_refuses_a_hand_mass_that_is_not_human(mass: float) -> None:
    with pytest.raises(OutOfRangeError) as err:
        build_hand(default_skeleton(), mass=mass)
    assert str(err.value) == (
        f"hand mass {mass:g} kg is outside the plausible 0.1 to 1 kg (human hands), {RANGES}; pass "
        "force=True to use it anyway"
    )
    assert default_hand(mass=mass, force=True).compile().body_subtreemass[0] == pytest.approx(mass)


# --------------------------------------------------------------------------------------------------
# Command line: exit 2 with the usage before any work, --force


def _first_line_of_error(capsys) -> str:
    err = capsys.readouterr().err.splitlines()
    return next(line for line in err if ": error: " in line)


@pytest.mark.parametrize(
    ("argv", "line"),
    [
        (
            ["build", "object", "mug", "--mass", "1e-9"],
            "handsim build object: error: argument --mass: mass 1e-09 kg is outside the plausible 0.001 to "
            f"23 kg (household objects a hand grasps), {RANGES}; give --force to use it anyway",
        ),
        (
            ["build", "scene", "--object", "mug", "--density", "1e9"],
            "handsim build scene: error: argument --density: density 1e+09 kg/m³ is outside the plausible 10 "
            f"to 11400 kg/m³ (expanded polystyrene foam to lead), {RANGES}; give --force to use it anyway",
        ),
        (
            ["build", "hand", "--default", "--mass", "3"],
            "handsim build hand: error: argument --mass: hand mass 3 kg is outside the plausible 0.1 to 1 kg "
            f"(human hands), {RANGES}; give --force to use it anyway",
        ),
        (
            ["build", "scene", "--hand-mass", "0.01"],
            "handsim build scene: error: argument --hand-mass: hand mass 0.01 kg is outside the plausible "
            f"0.1 to 1 kg (human hands), {RANGES}; give --force to use it anyway",
        ),
        (
            ["replay", "no-such-trial.txt", "--density", "1e-6"],
            "handsim replay: error: argument --density: density 1e-06 kg/m³ is outside the plausible 10 to "
            f"11400 kg/m³ (expanded polystyrene foam to lead), {RANGES}; give --force to use it anyway",
        ),
        (
            ["build", "object", "mug", "--mass", "-1", "--force"],
            "handsim build object: error: argument --mass: mass -1 kg: expected a positive number",
        ),
    ],
)
def test_cli_refuses_implausible_values_with_the_usage_and_exit_2(capsys, argv, line) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert capsys.readouterr().err.splitlines()[0] == line  # the error line first, then the usage


def test_cli_force_builds_an_object_outside_the_range_and_prints_its_mass(capsys, tmp_path: Path) -> None:
    out = tmp_path / "cube.xml"
    assert main(["build", "object", "cube", "--mass", "30", "--force", "-o", str(out)]) == 0
    assert "mass       30000.0 g" in capsys.readouterr().out
    assert out.exists()


def test_cli_replay_force_loads_a_trial_whose_object_mass_is_outside_the_range(tmp_path: Path) -> None:
    from handsim.trials import find_trial, load_trial

    motion = TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION"
    with pytest.raises(OutOfRangeError, match="mass 30 kg is outside the plausible"):
        load_trial(motion, mass=30.0)
    trial = find_trial(motion, mass=30.0, force=True)
    assert trial.force
    assert sum(o.mass for o in load_trial(trial).objects) == pytest.approx(30.0 * len(trial.objects))


def test_cli_prints_a_mass_below_one_gram_without_rounding_it_to_zero(capsys) -> None:
    assert main(["build", "object", "business_card", "--mass", "0.0004", "--force"]) == 0
    assert "mass       0.4 g" in capsys.readouterr().out
