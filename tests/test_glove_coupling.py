"""DIP coupling: DIP from PIP, and the relation the GraspDB14 glove software used."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from handsim.datatypes.trajectory import Trajectory
from handsim.errors import TrajectoryError
from handsim.glove import CYBERGLOVE, DIP_PIP_RATIO, couple_dip, cyberglove_dip
from handsim.io.graspdb.glove import read_graspdb_glove

REAL_TRIALS = (
    "r_01_11_ex03-rad-004-grasp-su04.txt",
    "01_ex01-rad-002-grasp-su01.txt",
    "04_ex01-rad-045-grasp-su03.txt",
)
FINGERS = ("if", "mf", "rf", "lf")
DIPS = tuple(f"{f}_dip_flex" for f in FINGERS)


def _trajectory(n: int = 4, computed: tuple[str, ...] = (), filled: bool = False) -> Trajectory:
    names = ("if_mcp_flex", *(f"{f}_{j}_flex" for f in FINGERS for j in ("pip", "dip")))
    rng = np.random.default_rng(0)
    targets = rng.uniform(-0.2, 1.6, size=(n, len(names)))
    valid = np.ones(targets.shape, dtype=bool)
    valid[1, names.index("mf_pip_flex")] = False
    filled_mask = None
    if filled:
        filled_mask = np.zeros(targets.shape, dtype=bool)
        filled_mask[2, names.index("rf_pip_flex")] = True
    return Trajectory(
        times=np.arange(n) / 60.0,
        dof_names=names,
        targets=targets,
        valid=valid,
        computed=computed,
        filled=filled_mask,
        notes=("read",),
    )


# --------------------------------------------------------------------------------------------------
# The glove software's relation, measured on the real files


@pytest.mark.parametrize("name", REAL_TRIALS)
def test_glove_software_dip_is_pip_times_abs_017_minus_032_pip(graspdb_dir: Path, name: str) -> None:
    traj = read_graspdb_glove(graspdb_dir / name)
    for finger in FINGERS:
        pip, dip = traj.column(f"{finger}_pip_flex"), traj.column(f"{finger}_dip_flex")
        # the files round to 5 decimals
        np.testing.assert_allclose(dip, cyberglove_dip(pip), rtol=0, atol=5.1e-6)


def test_glove_software_dip_is_far_from_two_thirds_of_pip(graspdb_dir: Path) -> None:
    ratios = []
    for name in REAL_TRIALS:
        traj = read_graspdb_glove(graspdb_dir / name)
        for finger in FINGERS:
            pip, dip = traj.column(f"{finger}_pip_flex"), traj.column(f"{finger}_dip_flex")
            bent = np.abs(pip) > 0.1
            ratios.append(dip[bent] / pip[bent])
    all_ratios = np.concatenate(ratios)
    assert all_ratios.size == 2858
    assert 0.0 < all_ratios.min() < 0.002
    assert 0.32 < all_ratios.max() < 0.33
    assert all_ratios.max() < DIP_PIP_RATIO / 2


def test_cyberglove_mode_reproduces_the_real_file(graspdb_dir: Path) -> None:
    traj = read_graspdb_glove(graspdb_dir / REAL_TRIALS[0])
    coupled = couple_dip(traj, CYBERGLOVE)
    np.testing.assert_allclose(coupled.targets, traj.targets, rtol=0, atol=5.1e-6)
    assert coupled.computed == traj.computed


def test_cyberglove_dip_values() -> None:
    np.testing.assert_allclose(
        cyberglove_dip([0.0, 0.5, 17 / 32, 1.0, -0.5]), [0.0, 0.005, 0.0, 0.15, -0.165]
    )


# --------------------------------------------------------------------------------------------------
# Coupling a trajectory


def test_default_coupling_sets_dip_to_two_thirds_pip_and_marks_it_computed() -> None:
    traj = _trajectory()
    coupled = couple_dip(traj)
    for finger in FINGERS:
        np.testing.assert_allclose(
            coupled.column(f"{finger}_dip_flex"),
            2 / 3 * traj.column(f"{finger}_pip_flex"),
            rtol=0,
            atol=1e-15,
        )
    np.testing.assert_array_equal(coupled.column("if_mcp_flex"), traj.column("if_mcp_flex"))
    assert coupled.computed == DIPS
    assert coupled.notes == (
        "read",
        "DIP coupling: if_dip_flex = 0.6667·if_pip_flex; mf_dip_flex = 0.6667·mf_pip_flex; "
        "rf_dip_flex = 0.6667·rf_pip_flex; lf_dip_flex = 0.6667·lf_pip_flex",
    )
    np.testing.assert_array_equal(traj.targets, _trajectory().targets)  # input untouched


def test_coupled_dip_takes_the_pip_validity_and_filled_mask() -> None:
    traj = _trajectory(filled=True)
    coupled = couple_dip(traj)
    j = traj.dof_names.index
    assert not coupled.valid[1, j("mf_dip_flex")]
    assert coupled.filled is not None
    assert coupled.filled[2, j("rf_dip_flex")]
    assert coupled.valid.sum() == coupled.valid.size - 2


def test_per_finger_coupling_keeps_fingers_set_to_none_or_missing() -> None:
    traj = _trajectory(computed=("lf_dip_flex",))
    coupled = couple_dip(traj, {"if": 0.5, "mf": None, "rf": CYBERGLOVE})
    np.testing.assert_allclose(coupled.column("if_dip_flex"), 0.5 * traj.column("if_pip_flex"))
    np.testing.assert_array_equal(coupled.column("mf_dip_flex"), traj.column("mf_dip_flex"))
    np.testing.assert_allclose(coupled.column("rf_dip_flex"), cyberglove_dip(traj.column("rf_pip_flex")))
    np.testing.assert_array_equal(coupled.column("lf_dip_flex"), traj.column("lf_dip_flex"))
    assert coupled.computed == ("lf_dip_flex", "if_dip_flex", "rf_dip_flex")
    assert coupled.notes[-1] == (
        "DIP coupling: if_dip_flex = 0.5·if_pip_flex; mf_dip_flex kept; "
        "rf_dip_flex = rf_pip_flex·|0.17 − 0.32·rf_pip_flex| (GraspDB14 glove software); lf_dip_flex kept"
    )


def test_coupling_off_keeps_the_values_and_says_so() -> None:
    traj = _trajectory()
    coupled = couple_dip(traj, None)
    np.testing.assert_array_equal(coupled.targets, traj.targets)
    assert coupled.computed == ()
    assert coupled.notes[-1] == (
        "DIP coupling off: DIP values kept as they were (the glove software's, for a rad file)"
    )


def test_coupling_a_trajectory_without_dips_is_an_error() -> None:
    traj = _trajectory()
    keep = [i for i, n in enumerate(traj.dof_names) if n != "rf_dip_flex"]
    names = tuple(traj.dof_names[i] for i in keep)
    cut = dataclasses.replace(traj, dof_names=names, targets=traj.targets[:, keep], valid=traj.valid[:, keep])
    with pytest.raises(
        TrajectoryError,
        match=r"^cannot couple the rf DIP: no DoF 'rf_dip_flex'; DoFs are \['if_mcp_flex', 'if_pip_flex', ",
    ):
        couple_dip(cut)
    couple_dip(cut, {"if": 0.6})  # fingers not coupled need no columns


@pytest.mark.parametrize(
    ("ratio", "message"),
    [
        (
            {"thumb": 0.5},
            r"^unknown fingers \['thumb'\] in the DIP coupling; fingers are \['if', 'mf', 'rf', 'lf'\]$",
        ),
        (
            float("nan"),
            r"^DIP coupling of finger 'if' must be a finite ratio, 'cyberglove' or None, got nan$",
        ),
        (
            "two thirds",
            r"^DIP coupling of finger 'if' must be a finite ratio, 'cyberglove' or None, got 'two thirds'$",
        ),
        (
            {"mf": True},
            r"^DIP coupling of finger 'mf' must be a finite ratio, 'cyberglove' or None, got True$",
        ),
    ],
)
def test_bad_coupling_is_an_error(ratio: object, message: str) -> None:
    with pytest.raises(TrajectoryError, match=message):
        couple_dip(_trajectory(), ratio)  # type: ignore[arg-type]


@settings(max_examples=40, deadline=None)
@given(
    ratio=st.floats(min_value=-2, max_value=2),
    pip=st.lists(st.floats(min_value=-0.5, max_value=2.0), min_size=1, max_size=20),
)
def test_ratio_coupling_is_linear_in_pip(ratio: float, pip: list[float]) -> None:
    n = len(pip)
    names = ("if_pip_flex", "if_dip_flex")
    targets = np.column_stack([pip, np.zeros(n)])
    traj = Trajectory(np.arange(n) * 0.016, names, targets, np.ones((n, 2), dtype=bool))
    coupled = couple_dip(traj, {"if": ratio})
    np.testing.assert_array_equal(coupled.column("if_dip_flex"), ratio * np.array(pip))
