"""CyberGlove calibration: the linear model, its JSON file, and estimation from a calibration sequence."""

from __future__ import annotations

import json
import math
import re
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from handsim.errors import FormatError, InputFileError
from handsim.glove import (
    CALIBRATION_PROTOCOL,
    DEFAULT_COUPLING,
    DEFAULT_GAINS,
    SENSOR_NAMES,
    AbductionCoupling,
    CalibrationError,
    GloveCalibration,
    apply_calibration,
    estimate_calibration,
)
from handsim.glove.calibration import FORMAT, VERSION
from handsim.io.graspdb.calibration import calibration_from_dict, load_calibration, save_calibration
from handsim.io.graspdb.glove import read_graspdb_raw

IDX = {name: i for i, name in enumerate(SENSOR_NAMES)}
UNMEASURED = ("I-DIPJ", "I-AA", "M-DIPJ", "R-DIPJ", "L-DIPJ")  # 0 counts on the 18-sensor glove
FITTED = ("T-MCPJ", "I-MCPJ", "M-MCPJ", "MI-AA", "R-MCPJ", "RM-AA", "L-MCPJ", "LR-AA")

# --------------------------------------------------------------------------------------------------
# Synthetic calibration sequence following spec §3.5


def _pose(**degrees: float) -> np.ndarray:
    angles = np.zeros(23)
    for key, value in degrees.items():
        angles[IDX[key.replace("_", "-")]] = math.radians(value)
    return angles


def _synthetic_sequence(
    seed: int = 0, hold: int = 30, move: int = 15, noise: float = 0.4, extra_press: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Raw counts and switch of a calibration take, from known gains and offsets.

    Each segment moves (``move`` frames) from the previous pose to its pose and holds it (``hold``
    frames); the static OFF segments hold the previous segment's pose throughout. Counts get Gaussian
    noise (sigma ``noise``) and are rounded to integers. The five sensors the 18-sensor glove lacks
    read 0.
    """
    rng = np.random.default_rng(seed)
    gains = np.array(DEFAULT_GAINS) * rng.uniform(0.8, 1.2, 23)
    offsets = rng.uniform(110.0, 140.0, 23)
    for name in UNMEASURED:
        gains[IDX[name]] = 0.0
        offsets[IDX[name]] = 0.0

    def unknown() -> np.ndarray:
        return rng.uniform(-0.3, 0.3, 23)

    def wedges(mi: int, rm: int, lr: int) -> np.ndarray:
        return _pose(MI_AA=25 * mi, RM_AA=25 * rm, LR_AA=25 * lr)

    targets: list[np.ndarray | None] = [
        np.zeros(23),  # 0 ON: into the flat unspread hand
        None,  # 1 OFF: flat unspread hand held
        unknown(),  # 2 ON: into the flat spread hand
        None,  # 3 OFF
        unknown(),  # 4 ON: into the fist
        None,  # 5 OFF
        _pose(I_MCPJ=-90, M_MCPJ=-90, R_MCPJ=-90, L_MCPJ=-90),  # 6 ON: into the square MCP angle
        None,  # 7 OFF
        wedges(1, 0, 0),
        wedges(1, 1, 0),
        wedges(1, 1, 1),
        wedges(0, 1, 1),
        wedges(0, 0, 1),
        wedges(0, 0, 0),
        _pose(T_MCPJ=-45, I_MCPJ=-45),
        _pose(I_MCPJ=-45, M_MCPJ=-45),
        _pose(M_MCPJ=-45, R_MCPJ=-45),
        _pose(R_MCPJ=-45, L_MCPJ=-45),
        unknown(),  # 18 ON: thumb to fingertips
        unknown(),  # 19 OFF: thumb to middle phalanges
    ]
    if extra_press:
        targets.append(unknown())
    frames: list[np.ndarray] = []
    switch: list[bool] = []
    previous = unknown()
    for k, target in enumerate(targets):
        if target is None:
            segment = [previous] * (move + hold)
        else:
            segment = [previous + (target - previous) * (i + 1) / move for i in range(move)] + [target] * hold
            previous = target
        frames += segment
        switch += [k % 2 == 0] * len(segment)
    angles = np.array(frames)
    raw = offsets + angles / np.where(gains == 0.0, 1.0, gains) + rng.normal(0.0, noise, angles.shape)
    raw = np.clip(np.round(raw), 0, 255)
    for name in UNMEASURED:
        raw[:, IDX[name]] = 0.0
    return raw, np.array(switch), gains, offsets


def _write_raw(path: Path, counts: np.ndarray, switch: np.ndarray) -> Path:
    start = datetime(2014, 9, 12, 8, 49, 21, 712000)
    lines = []
    for k, (row, sw) in enumerate(zip(counts, switch, strict=True)):
        d = start + timedelta(milliseconds=16 * k)
        stamp = f"{d:%Y %m %d %H %M} {d.second + d.microsecond / 1e6:08.5f}"
        lines.append(f"{stamp} {int(sw)} {' '.join(str(int(c)) for c in row)} ")
    path.write_text("\n".join(lines) + "\n")
    return path


def _calibration(**kwargs: object) -> GloveCalibration:
    gains = tuple(0.01 * (i + 1) * (-1) ** i for i in range(23))
    offsets = tuple(100.0 + i for i in range(23))
    return GloveCalibration(gains=gains, offsets=offsets, **kwargs)  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------------------
# The model


def test_apply_calibration_is_gain_times_counts_minus_offset() -> None:
    cal = _calibration()
    raw = np.array([[110.0] * 23, [100.0 + i for i in range(23)]])
    angles = apply_calibration(raw, cal)
    expected = np.array(cal.gains) * (raw - np.array(cal.offsets))
    np.testing.assert_allclose(angles, expected, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(angles[1], 0.0)


def test_apply_calibration_accepts_a_single_sample() -> None:
    cal = _calibration()
    raw = np.full(23, 120.0)
    np.testing.assert_array_equal(apply_calibration(raw, cal), apply_calibration(raw[None], cal)[0])


def test_abduction_coupling_subtracts_k_times_mean_neighbour_flexion() -> None:
    coupling = tuple(
        AbductionCoupling(c.sensor, c.flexions, 0.5 if c.sensor == "MI-AA" else 0.0) for c in DEFAULT_COUPLING
    )
    plain, coupled = _calibration(), _calibration(coupling=coupling)
    raw = np.random.default_rng(3).uniform(0, 255, size=(5, 23))
    a, b = apply_calibration(raw, plain), apply_calibration(raw, coupled)
    mi, i_mcp, m_mcp = IDX["MI-AA"], IDX["I-MCPJ"], IDX["M-MCPJ"]
    np.testing.assert_allclose(b[:, mi], a[:, mi] - 0.5 * (a[:, i_mcp] + a[:, m_mcp]) / 2, atol=1e-15)
    others = [i for i in range(23) if i != mi]
    np.testing.assert_array_equal(b[:, others], a[:, others])


def test_default_coupling_pairs_each_abduction_sensor_with_its_neighbouring_mcps_at_zero() -> None:
    assert [(c.sensor, c.flexions, c.k) for c in DEFAULT_COUPLING] == [
        ("TI-AA", ("T-MCPJ", "I-MCPJ"), 0.0),
        ("MI-AA", ("I-MCPJ", "M-MCPJ"), 0.0),
        ("RM-AA", ("M-MCPJ", "R-MCPJ"), 0.0),
        ("LR-AA", ("R-MCPJ", "L-MCPJ"), 0.0),
    ]


def test_default_gains_are_the_graspdb14_glove_software_steps() -> None:
    cal = GloveCalibration.default()
    assert cal.gain("I-PIPJ") == -0.01459
    assert cal.gain("W-AA") == 0.00392
    assert cal.gain("I-AA") == 0.0
    assert cal.offsets == (0.0,) * 23
    assert cal.unfitted == SENSOR_NAMES


@pytest.mark.parametrize(
    ("shape", "message"),
    [((5, 22), r"raw counts must have shape \(T, 23\), got \(5, 22\)"), ((2, 3, 23), r".*got \(2, 3, 23\)")],
)
def test_apply_calibration_rejects_wrong_shapes(shape: tuple[int, ...], message: str) -> None:
    with pytest.raises(CalibrationError, match=rf"^{message}$"):
        apply_calibration(np.zeros(shape), _calibration())


def test_apply_calibration_rejects_non_finite_counts() -> None:
    raw = np.zeros((2, 23))
    raw[1, 4] = np.nan
    with pytest.raises(CalibrationError, match=r"^raw counts must be finite$"):
        apply_calibration(raw, _calibration())


def test_calibration_with_wrong_number_of_gains_is_an_error() -> None:
    with pytest.raises(CalibrationError, match=r"^gains must hold 23 values \(one per sensor\), got 22$"):
        GloveCalibration(gains=(0.01,) * 22, offsets=(0.0,) * 23)


def test_calibration_with_non_finite_offset_is_an_error() -> None:
    offsets = (0.0,) * 21 + (math.inf, 0.0)
    with pytest.raises(CalibrationError, match=r"^offsets must be finite; not finite for \['W-FE'\]$"):
        GloveCalibration(gains=(0.01,) * 23, offsets=offsets)


def test_unknown_sensor_lookup_lists_the_sensors() -> None:
    with pytest.raises(CalibrationError, match=r"^unknown sensor 'I-XYZ'; sensors are \['T-TMCJ', 'T-MCPJ'"):
        _calibration().gain("I-XYZ")


@settings(max_examples=50, deadline=None)
@given(
    gains=st.lists(
        st.floats(min_value=1e-4, max_value=0.05) | st.floats(min_value=-0.05, max_value=-1e-4),
        min_size=23,
        max_size=23,
    ),
    offsets=st.lists(st.floats(min_value=0, max_value=255), min_size=23, max_size=23),
    angles=st.lists(st.floats(min_value=-1.5, max_value=1.5), min_size=23, max_size=23),
)
def test_counts_made_from_angles_calibrate_back_to_them(
    gains: list[float], offsets: list[float], angles: list[float]
) -> None:
    cal = GloveCalibration(gains=tuple(gains), offsets=tuple(offsets))
    raw = np.array(offsets) + np.array(angles) / np.array(gains)
    np.testing.assert_allclose(apply_calibration(raw, cal), angles, rtol=0, atol=1e-9)


# --------------------------------------------------------------------------------------------------
# JSON file


def test_json_round_trip_is_exact(tmp_path: Path) -> None:
    raw, switch, _, _ = _synthetic_sequence()
    cal = estimate_calibration(raw, switch, provenance="synthetic su04")
    path = save_calibration(cal, tmp_path / "su04.calib.json")
    assert load_calibration(path) == cal


def test_json_file_follows_the_documented_schema(tmp_path: Path) -> None:
    cal = _calibration(
        provenance="by hand", fitted=("MI-AA",), residuals=(None,) * 11 + (0.002,) + (None,) * 11
    )
    doc = json.loads(save_calibration(cal, tmp_path / "c.json").read_text())
    assert doc["format"] == "handsim-glove-calibration" == FORMAT
    assert doc["version"] == 1 == VERSION
    assert doc["units"] == {"gain": "rad/count", "offset": "count", "residual": "rad", "k": "1"}
    assert doc["provenance"] == "by hand"
    assert [s["name"] for s in doc["sensors"]] == list(SENSOR_NAMES)
    assert doc["sensors"][11] == {
        "name": "MI-AA",
        "gain": -0.12,
        "offset": 111.0,
        "fitted": True,
        "residual": 0.002,
    }
    assert doc["sensors"][0] == {
        "name": "T-TMCJ",
        "gain": 0.01,
        "offset": 100.0,
        "fitted": False,
        "residual": None,
    }
    assert doc["abduction_coupling"][1] == {"sensor": "MI-AA", "flexions": ["I-MCPJ", "M-MCPJ"], "k": 0.0}


def test_minimal_json_without_optional_keys_loads_with_defaults(tmp_path: Path) -> None:
    doc = {
        "format": FORMAT,
        "version": 1,
        "sensors": [{"name": n, "gain": -0.015, "offset": 120} for n in reversed(SENSOR_NAMES)],
    }
    path = tmp_path / "c.json"
    path.write_text(json.dumps(doc))
    cal = load_calibration(path)
    assert cal.gains == (-0.015,) * 23
    assert cal.offsets == (120.0,) * 23
    assert cal.coupling == DEFAULT_COUPLING
    assert cal.residuals is None
    assert cal.fitted == ()
    assert cal.provenance == ""


def _doc() -> dict:
    return _calibration().to_dict()


def _set(path: list[object], value: object) -> dict:
    doc = _doc()
    target = doc
    for key in path[:-1]:
        target = target[key]  # type: ignore[index]
    if value is _DELETE:
        del target[path[-1]]  # type: ignore[arg-type]
    else:
        target[path[-1]] = value  # type: ignore[index]
    return doc


_DELETE = object()


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (["format"], "glove", r"\[format\]: expected 'handsim-glove-calibration', got 'glove'"),
        (["version"], 2, r"\[version\]: unsupported schema version 2; this handsim reads version 1"),
        (["version"], "1", r"\[version\]: unsupported schema version '1'; this handsim reads version 1"),
        (["version"], _DELETE, r"\[version\]: missing"),
        (["sensors"], {}, r"\[sensors\]: expected a list of 23 sensor objects"),
        (["sensors", 3, "gain"], "abc", r"\[sensors\[3\]\.gain\]: expected a finite number, got 'abc'"),
        (["sensors", 3, "gain"], True, r"\[sensors\[3\]\.gain\]: expected a finite number, got True"),
        (["sensors", 22, "offset"], _DELETE, r"\[sensors\[22\]\.offset\]: missing"),
        (
            ["sensors", 5, "name"],
            "I-PIP",
            r"\[sensors\[5\]\.name\]: unknown sensor 'I-PIP'; sensors are \['T-TMCJ', .*'W-AA'\]",
        ),
        (["sensors", 5, "name"], "T-TMCJ", r"\[sensors\[5\]\.name\]: sensor 'T-TMCJ' is listed twice"),
        (["sensors", 2, "fitted"], "yes", r"\[sensors\[2\]\.fitted\]: expected true or false, got 'yes'"),
        (["sensors", 2, "residual"], -0.1, r"\[sensors\[2\]\.residual\]: expected a number >= 0, got -0.1"),
        (
            ["sensors", 2, "gian"],
            1.0,
            r"\[sensors\[2\]\]: unknown keys \['gian'\]; known keys are "
            r"\['fitted', 'gain', 'name', 'offset', 'residual'\]",
        ),
        (["sensors", 4], [1, 2], r"\[sensors\[4\]\]: expected a JSON object, got list"),
        (
            ["abduction_coupling", 1, "flexions"],
            ["I-MCPJ"],
            r"\[abduction_coupling\[1\]\.flexions\]: expected a list of two sensor names, got \['I-MCPJ'\]",
        ),
        (
            ["abduction_coupling", 0, "k"],
            None,
            r"\[abduction_coupling\[0\]\.k\]: expected a finite number, got None",
        ),
        (
            ["abduction_coupling", 2, "sensor"],
            "X",
            r"\[abduction_coupling\[2\]\.sensor\]: unknown sensor 'X'",
        ),
        (["provenance"], 3, r"\[provenance\]: expected a string, got 3"),
        (["notes"], "n", r"\[notes\]: expected a list of strings"),
    ],
)
def test_bad_json_field_is_named_in_the_error(
    tmp_path: Path, path: list[object], value: object, message: str
) -> None:
    file = tmp_path / "bad.json"
    file.write_text(json.dumps(_set(path, value)))
    with pytest.raises(FormatError, match=rf"^{file}\s?{message}"):
        load_calibration(file)


def test_missing_sensor_entries_are_listed(tmp_path: Path) -> None:
    doc = _doc()
    doc["sensors"] = [s for s in doc["sensors"] if s["name"] not in ("I-AA", "W-AA")]
    file = tmp_path / "bad.json"
    file.write_text(json.dumps(doc))
    with pytest.raises(
        FormatError, match=rf"^{file} \[sensors\]: missing sensors \['I-AA', 'W-AA'\]; all 23 must be listed$"
    ):
        load_calibration(file)


def test_unknown_top_level_key_is_an_error(tmp_path: Path) -> None:
    doc = _doc()
    doc["gains"] = []
    file = tmp_path / "bad.json"
    file.write_text(json.dumps(doc))
    with pytest.raises(
        FormatError, match=rf"^{file}: unknown keys \['gains'\]; known keys are \['abduction_coupling'"
    ):
        load_calibration(file)


def test_invalid_json_names_the_line(tmp_path: Path) -> None:
    file = tmp_path / "bad.json"
    file.write_text('{\n  "format": "handsim-glove-calibration",\n  "version": 1,,\n}')
    with pytest.raises(
        FormatError,
        match=rf"^{file}:3: invalid JSON: Expecting property name enclosed in double quotes \(column 16\)$",
    ):
        load_calibration(file)


def test_json_that_is_not_an_object_is_an_error(tmp_path: Path) -> None:
    file = tmp_path / "bad.json"
    file.write_text("[1, 2]")
    with pytest.raises(FormatError, match=rf"^{file}: expected a JSON object, got list$"):
        load_calibration(file)


def test_missing_calibration_file_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputFileError, match=r"file not found$"):
        load_calibration(tmp_path / "none.json")


def test_calibration_from_dict_names_its_source_in_errors() -> None:
    with pytest.raises(FormatError, match=r"^given \[format\]: missing$"):
        calibration_from_dict({"version": 1, "sensors": []}, "given")


# --------------------------------------------------------------------------------------------------
# Estimation


def test_protocol_covers_the_spec_poses_with_known_angles() -> None:
    names = [(p.segment, p.hold, p.name) for p in CALIBRATION_PROTOCOL]
    assert names == [
        (1, "segment", "flat unspread hand"),
        (7, "segment", "square angle in the MCP joints"),
        (8, "end", "25° wedges index-middle"),
        (9, "end", "25° wedges index-middle, middle-ring"),
        (10, "end", "25° wedges index-middle, middle-ring, ring-little"),
        (11, "end", "25° wedges middle-ring, ring-little"),
        (12, "end", "25° wedges ring-little"),
        (13, "end", "wedges removed"),
        (14, "end", "45° MCP flexion, thumb and index"),
        (15, "end", "45° MCP flexion, index and middle"),
        (16, "end", "45° MCP flexion, middle and ring"),
        (17, "end", "45° MCP flexion, ring and little"),
    ]
    flat = dict(CALIBRATION_PROTOCOL[0].angles)
    assert flat == dict.fromkeys(SENSOR_NAMES, 0.0)
    assert dict(CALIBRATION_PROTOCOL[4].angles) == {"MI-AA": 25.0, "RM-AA": 25.0, "LR-AA": 25.0}


@pytest.mark.parametrize(("seed", "extra_press"), [(0, False), (1, True), (2, False)])
def test_estimation_recovers_synthetic_gains_and_offsets_within_one_percent(
    seed: int, extra_press: bool
) -> None:
    raw, switch, gains, offsets = _synthetic_sequence(seed=seed, extra_press=extra_press)
    cal = estimate_calibration(raw, switch)
    assert cal.fitted == FITTED
    for name in FITTED:
        i = IDX[name]
        assert cal.gains[i] == pytest.approx(gains[i], rel=0.01), name
    for name in SENSOR_NAMES:  # the flat hand fixes every offset
        i = IDX[name]
        assert cal.offsets[i] == pytest.approx(offsets[i], rel=0.01, abs=1e-9), name
    assert cal.residuals is not None
    assert all(r is not None and r < 0.01 for r in cal.residuals)


def test_estimation_keeps_default_gains_for_sensors_the_protocol_does_not_excite() -> None:
    raw, switch, _, _ = _synthetic_sequence()
    cal = estimate_calibration(raw, switch, provenance="synthetic")
    kept = [n for n in SENSOR_NAMES if n not in FITTED]
    assert list(cal.unfitted) == kept
    for name in kept:
        assert cal.gain(name) == DEFAULT_GAINS[IDX[name]]
    assert cal.provenance == "synthetic"
    assert cal.notes[0] == f"switch segments: 20, of {[45] * 20} frames"
    assert cal.notes[2].startswith(
        f"gains kept from the base calibration (handsim default gains, zero offsets) for {kept}"
    )


def test_estimation_takes_unexcited_gains_and_coupling_from_the_base() -> None:
    raw, switch, _, _ = _synthetic_sequence()
    coupling = tuple(AbductionCoupling(c.sensor, c.flexions, 0.2) for c in DEFAULT_COUPLING)
    base = GloveCalibration(gains=(0.02,) * 23, offsets=(0.0,) * 23, coupling=coupling, provenance="mine")
    cal = estimate_calibration(raw, switch, base=base)
    assert cal.gain("I-PIPJ") == 0.02
    assert cal.coupling == coupling


def test_estimation_from_a_written_calibration_file_matches_the_arrays(tmp_path: Path) -> None:
    raw, switch, _, _ = _synthetic_sequence()
    path = _write_raw(tmp_path / "su04_calib-.txt", raw, switch)
    recording = read_graspdb_raw(path)
    np.testing.assert_array_equal(recording.counts, raw)
    assert recording.switch.tolist() == switch.tolist()
    assert estimate_calibration(recording.counts, recording.switch) == estimate_calibration(raw, switch)


def test_sequence_with_wrong_segment_count_lists_the_segments() -> None:
    raw, switch, _, _ = _synthetic_sequence()
    n = 45 * 18
    with pytest.raises(
        CalibrationError,
        match=r"^a calibration sequence has 20 or 21 switch segments \(spec §3\.5\); this one has 18, of "
        r"\[45, 45, .*, 45\] frames$",
    ):
        estimate_calibration(raw[:n], switch[:n])


def test_sequence_starting_with_switch_off_is_an_error() -> None:
    raw, switch, _, _ = _synthetic_sequence()
    with pytest.raises(
        CalibrationError,
        match=r"^a calibration sequence starts with the switch ON \(spec §3\.5\); this one starts OFF$",
    ):
        estimate_calibration(raw, ~switch)


def test_sensor_that_does_not_respond_is_named() -> None:
    raw, switch, _, _ = _synthetic_sequence()
    raw[:, IDX["RM-AA"]] = 130.0
    with pytest.raises(
        CalibrationError,
        match=r"^sensor RM-AA does not respond to the calibration poses: its mean counts at the reference "
        r"angles differ by less than 1 count \(0°: 130\.00, 25°: 130\.00\)$",
    ):
        estimate_calibration(raw, switch)


def test_estimation_rejects_mismatched_switch() -> None:
    raw, switch, _, _ = _synthetic_sequence()
    with pytest.raises(CalibrationError, match=r"^switch must have shape \(900,\), got \(899,\)$"):
        estimate_calibration(raw, switch[:-1])


def test_estimation_rejects_wrong_raw_shape() -> None:
    with pytest.raises(CalibrationError, match=r"^raw sequence must have shape \(T, 23\), got \(10, 18\)$"):
        estimate_calibration(np.zeros((10, 18)), np.ones(10, dtype=bool))


def test_pose_naming_a_missing_segment_is_an_error() -> None:
    raw, switch, _, _ = _synthetic_sequence()
    bad = (*CALIBRATION_PROTOCOL[:1], CALIBRATION_PROTOCOL[1].__class__("late", 25, "end", (("W-FE", 10.0),)))
    with pytest.raises(CalibrationError, match=r"^pose 'late' names segment 25; there are 20$"):
        estimate_calibration(raw, switch, protocol=bad)


def test_estimation_rejects_an_empty_hold_window() -> None:
    raw, switch, _, _ = _synthetic_sequence()
    with pytest.raises(
        CalibrationError, match=r"^hold_frames must be >= 1 and trim_frames >= 0, got 0 and 3$"
    ):
        estimate_calibration(raw, switch, hold_frames=0)


def test_calibration_sequence_whose_switch_is_never_on_is_an_error(tmp_path: Path) -> None:

    raw, switch, _, _ = _synthetic_sequence()
    path = _write_raw(tmp_path / "01_calib-raw-001-su01.txt", raw, np.zeros_like(switch))
    recording = read_graspdb_raw(path)
    with pytest.raises(
        CalibrationError,
        match=rf"^{re.escape(str(path))}: the switch is never ON in its {len(raw)} samples, so the "
        r"calibration poses cannot be told apart \(spec §3\.5: the actor presses the switch at each "
        r"pose\); is this a calibration sequence\?$",
    ):
        estimate_calibration(recording.counts, recording.switch, provenance=str(path))


def test_calibration_file_for_another_sensor_count_is_an_error(tmp_path: Path) -> None:
    path = save_calibration(GloveCalibration.default(), tmp_path / "glove.json")
    doc = json.loads(path.read_text())
    doc["sensors"] = doc["sensors"][:18]
    path.write_text(json.dumps(doc))
    with pytest.raises(
        FormatError,
        match=rf"^{re.escape(str(path))} \[sensors\]: missing sensors \['L-DIPJ', 'LR-AA', 'P-Arch', 'W-FE', "
        r"'W-AA'\]; all 23 must be listed$",
    ):
        load_calibration(path)
