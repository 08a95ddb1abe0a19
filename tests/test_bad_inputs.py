"""The bad-input catalogue of issue 14 as a test: every row runs the command line as a user would.

Each case runs ``handsim.cli.main`` in-process and asserts the exit code and the exact first line of
stderr. A usage error (exit 2) prints argparse's usage first: its first line is pinned as far as the
command (``usage: handsim build object ``; the option list after it follows the terminal width), and
its last line, the error, exactly. A row whose input must now be accepted (a byte-order mark) asserts
exit 0, no stderr and the first line of stdout.

Inputs are made here or copied from the bundled Tzionas sample, so only the row that needs the
GraspDB14 skeleton (``../shared/data``) can skip.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest
import trimesh

from handsim.assets import TZIONAS_DIR
from handsim.cli import main
from tests.text_samples import glove_rows

REC = "01_ex01-rad-001-grasp-su01.txt"  # object id 1 (tennis ball) in the name, as replay needs


@dataclass(frozen=True)
class Outcome:
    """What a user sees: the exit code, stderr's lines and stdout's lines."""

    code: int
    err: list[str]
    out: list[str]

    @property
    def first(self) -> str:
        return self.err[0] if self.err else ""


def run(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> Outcome:
    """``handsim ARGV`` in-process (a usage error's SystemExit becomes its code)."""
    capsys.readouterr()
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exit_:
        code = exit_.code if isinstance(exit_.code, int) else 1
    captured = capsys.readouterr()
    return Outcome(code, captured.err.splitlines(), captured.out.splitlines())


def write(path: Path, data: str | bytes) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(data, bytes):
        path.write_bytes(data)
    else:
        path.write_text(data)
    return path


def tzionas_copy(tmp_path: Path) -> Path:
    """A copy of the bundled Tzionas sample (Models/NN, Configs/NN) to edit."""
    root = tmp_path / "tzionas_ijcv16"
    shutil.copytree(TZIONAS_DIR, root)
    return root


def box_text(file_type: str, size: tuple[float, float, float] = (50.0, 40.0, 30.0)) -> str:
    text = trimesh.creation.box(size).export(file_type=file_type)
    return "".join(line + "\n" for line in text.splitlines() if not line.startswith("#"))


# readers and inputs
# --------------------------------------------------------------------------------------------------
# Rows of issue 14's catalogue: silent meaningless results, now refused or noted


def test_row_targets_beyond_the_joint_limits_on_the_glove_path_get_a_per_dof_note(
    capsys, tmp_path, graspdb_dir
):
    rows = [line.split() for line in glove_rows(4).splitlines()]
    for row in rows:
        row[7:] = ["0.0"] * 23
        row[7 + 4] = "-3.0"  # I-MCPJ: if_mcp_flex = 172°, the skeleton allows 0..90°
    path = write(tmp_path / REC, "".join(" ".join(r) + " \n" for r in rows))
    result = run(capsys, "inspect", path, "--skeleton", graspdb_dir / "default.xmlskel")
    assert (result.code, result.err) == (0, [])
    notes = [line for line in result.out if "outside the DoF limits" in line]
    assert notes == [
        "note       targets outside the DoF limits of 'default' in 4 samples (position actuators clamp them "
        "to the joint range): if_mcp_flex 4/4 (up to 81.9° beyond)"
    ]


@pytest.mark.parametrize("rows", [1, 2])
def test_row_recording_of_one_or_two_rows_is_refused(capsys, tmp_path, rows):
    path = write(tmp_path / REC, glove_rows(rows))
    result = run(capsys, "replay", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: {rows} row{'s' if rows == 2 else ''}: a recording needs at least 3 (two "
        "sample intervals) to describe a motion",
    )


def test_row_samples_10_microseconds_apart_are_refused(capsys, tmp_path):
    lines = glove_rows(5).splitlines()
    for i, line in enumerate(lines):
        tokens = line.split()
        tokens[5] = f"{9.024 + 1e-5 * i:08.5f}"
        lines[i] = " ".join(tokens)
    path = write(tmp_path / REC, "\n".join(lines) + "\n")
    result = run(capsys, "replay", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:2 [timestamp]: time stamp '2014 09 15 08 02 09.02401' is 1e-05 s after the "
        "previous row's (line 1): closer than 6.67 ms, a sampling rate above 150 Hz, faster than any "
        "CyberGlove records (at most 120 records/s); are the time stamps right?",
    )


def test_row_a_one_hour_jump_is_refused_before_any_resampling(capsys, tmp_path):
    lines = glove_rows(6).splitlines()
    lines[3:] = [line.replace(" 08 02 ", " 09 02 ", 1) for line in lines[3:]]
    path = write(tmp_path / REC, "\n".join(lines) + "\n")
    result = run(capsys, "replay", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:4 [timestamp]: time stamp '2014 09 15 09 02 09.07200' is 3600.02 s after "
        "the previous row's (line 3): more than the 1 s a recording may skip (the replay would invent the "
        "hand's motion over the hole); cut the recording there into two files",
    )


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        (
            "--mass",
            "1e-9",
            "mass 1e-09 kg is outside the plausible 0.001 to 23 kg (household objects a hand grasps)",
        ),
        (
            "--mass",
            "1e9",
            "mass 1e+09 kg is outside the plausible 0.001 to 23 kg (household objects a hand grasps)",
        ),
        (
            "--density",
            "1e-6",
            "density 1e-06 kg/m³ is outside the plausible 10 to 11400 kg/m³ (expanded polystyrene foam to "
            "lead)",
        ),
        (
            "--density",
            "1e9",
            "density 1e+09 kg/m³ is outside the plausible 10 to 11400 kg/m³ (expanded polystyrene foam to "
            "lead)",
        ),
    ],
)
@pytest.mark.parametrize("command", [("build", "object", "mug"), ("build", "scene", "--object", "mug")])
def test_row_implausible_mass_or_density_is_a_usage_error(capsys, command, option, value, message):
    result = run(capsys, *command, option, value)
    assert result.code == 2
    assert result.first.startswith(f"usage: handsim {command[0]} {command[1]} ")
    assert result.err[-1] == (
        f"handsim {command[0]} {command[1]}: error: argument {option}: {message}, see docs/objects.md; give "
        "--force to use it anyway"
    )


def test_row_a_3_micrometre_thick_mesh_is_refused_not_built_at_0_grams(capsys, tmp_path):
    path = write(tmp_path / "foil.obj", box_text("obj", (50.0, 50.0, 0.003)))
    result = run(capsys, "build", "object", path, "--units", "mm")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: the object is 0.003 mm thick (its smallest extent along its principal "
        "axes), thinner than the 0.1 mm handsim accepts (a sheet of paper); a surface this thin has no "
        "usable volume, mass or contact",
    )


def test_row_off_header_promising_more_faces_than_present_is_refused(capsys, tmp_path):
    path = write(tmp_path / "box.off", box_text("off").replace("8 12 0", "8 13 0", 1))
    result = run(capsys, "build", "object", path, "--units", "mm")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:2 [counts]: the header promises 8 vertices and 13 faces, but the file ends "
        "after 8 vertex and 12 face lines (line 22)",
    )


# --------------------------------------------------------------------------------------------------
# Rows of issue 14's catalogue: vague or wrong messages, now naming the real cause


def test_row_degree_values_are_called_degrees_not_a_raw_count_file(capsys, tmp_path):
    rows = [line.split() for line in glove_rows(4).splitlines()]
    for row in rows:
        row[7:] = [f"{-30.0 + 4.5 * k:.4f}" for k in range(23)]
    path = write(tmp_path / REC, "".join(" ".join(r) + " \n" for r in rows))
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:1 [sensor T-TMCJ]: value -30.0000 exceeds 7 in magnitude: the sensor values "
        "reach 69 and 87% of them exceed 7, so they look like angles in degrees; GraspDB14 'rad' files hold "
        "radians (|x| <= 2*pi): convert the file's sensor values to radians",
    )


def test_row_motion_row_whose_first_token_is_not_a_number_names_that_token(capsys, tmp_path):
    motion = tzionas_copy(tmp_path) / "Models" / "20" / "Model_Hand_R.MOTION"
    lines = motion.read_text().splitlines()
    assert len(lines[2].split()) == 12  # the first bone's row 1
    lines[2] = "x" + lines[2].lstrip()  # a stray letter glued to R[0][0]
    bad = lines[2].split()[0]
    motion.write_text("\n".join(lines) + "\n")
    result = run(capsys, "inspect", motion)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {motion}:3 [R[0][0]]: expected a number, got {bad!r}",
    )


def test_row_obj_without_faces_says_no_faces_not_0_vertices(capsys, tmp_path):
    path = write(
        tmp_path / "cloud.obj",
        "".join(line + "\n" for line in box_text("obj").splitlines() if line[:2] == "v "),
    )
    result = run(capsys, "build", "object", path, "--units", "mm")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: the file holds 8 vertices but no faces; a mesh needs triangles or polygons "
        "(OBJ 'f' lines) that close its surface, not a point cloud",
    )


def test_row_unsupported_mesh_extension_is_not_looked_up_in_the_catalogue(capsys):
    result = run(capsys, "build", "object", "foo.xyz")
    assert (result.code, result.first) == (
        1,
        "handsim: error: foo.xyz: unsupported mesh extension '.xyz'; handsim reads meshes .obj, .off, .stl, "
        ".ply (give their units), Tzionas object .SKEL files, ARCTIC template folders and catalogue names "
        "(see `handsim catalog`)",
    )


def test_row_a_directory_named_like_a_motion_is_called_a_directory(capsys, tmp_path):
    folder = tmp_path / "x.MOTION"
    folder.mkdir()
    result = run(capsys, "inspect", folder)
    assert (result.code, result.first) == (1, f"handsim: error: {folder}: is a directory, expected a file")


# --------------------------------------------------------------------------------------------------
# Rows of issue 14's catalogue: wrong rejections, now read


def test_row_a_byte_order_mark_before_a_graspdb14_recording_is_read(capsys, tmp_path):
    path = write(tmp_path / REC, b"\xef\xbb\xbf" + glove_rows(4).replace("\n", "\r\n").encode())
    result = run(capsys, "inspect", path)
    assert (result.code, result.err, result.out[0]) == (0, [], f"file       {path}")


def test_row_a_byte_order_mark_before_every_tzionas_file_is_read(capsys, tmp_path):
    root = tzionas_copy(tmp_path)
    for path in (root / "Models" / "20").iterdir():
        path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    for path in (root / "Configs" / "20").iterdir():
        path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    motion = root / "Models" / "20" / "Model_Hand_R.MOTION"
    result = run(capsys, "inspect", motion)
    assert (result.code, result.err, result.out[0]) == (0, [], f"file       {motion}")


# --------------------------------------------------------------------------------------------------
# Earlier rows (readers and inputs) that already gave a clear error, kept as they are


def test_earlier_row_a_missing_recording_is_file_not_found(capsys, tmp_path):
    result = run(capsys, "inspect", tmp_path / REC)
    assert (result.code, result.first) == (1, f"handsim: error: {tmp_path / REC}: file not found")


def test_earlier_row_an_empty_recording_says_what_a_row_holds(capsys, tmp_path):
    path = write(tmp_path / REC, "\n")
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: empty file: expected rows of 30 blank-separated entries (YYYY MM DD HH mm "
        "ss.sssss switch, then 23 sensor values in radians)",
    )


def test_earlier_row_a_raw_file_without_calibration_says_how_to_calibrate(capsys, tmp_path):
    path = write(tmp_path / REC.replace("-rad-", "-raw-"), glove_rows(4, counts=True))
    result = run(capsys, "inspect", path)
    assert result.code == 1
    assert result.first.startswith(
        f"handsim: error: {path}: this is a raw-count file ('-raw-' in its name); "
    )


def test_earlier_row_nan_in_a_recording_names_line_and_sensor(capsys, tmp_path):
    rows = glove_rows(4).splitlines()
    rows[1] = rows[1].replace("0.01000", "nan", 1)
    path = write(tmp_path / REC, "\n".join(rows) + "\n")
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:2 [sensor T-TMCJ]: expected a finite number, got 'nan'",
    )


def test_earlier_row_time_stamps_that_go_back_name_both_lines(capsys, tmp_path):
    rows = glove_rows(4).splitlines()
    rows[1], rows[2] = rows[2], rows[1]
    path = write(tmp_path / REC, "\n".join(rows) + "\n")
    result = run(capsys, "inspect", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}:3 [timestamp]: time stamp '2014 09 15 08 02 09.04000' is not after the "
        "previous row's '2014 09 15 08 02 09.05600' (line 2); time stamps must strictly increase",
    )


def test_earlier_row_a_mesh_without_units_asks_for_them(capsys, tmp_path):
    path = write(tmp_path / "box.obj", box_text("obj"))
    result = run(capsys, "build", "object", path)
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: give the mesh's units ('m' or 'mm'); a wrong guess scales it 1000×",
    )


def test_earlier_row_a_mesh_in_mm_read_as_metres_suggests_mm(capsys, tmp_path):
    path = write(tmp_path / "box.obj", box_text("obj"))
    result = run(capsys, "build", "object", path, "--units", "m")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {path}: the object is 50 m across in units='m', outside the plausible 5 mm – "
        "0.6 m; are the coordinates in mm? (pass units='mm')",
    )


def test_earlier_row_an_unknown_catalogue_name_lists_the_catalogue(capsys):
    result = run(capsys, "build", "object", "teapot")
    assert result.code == 1
    assert result.first.startswith("handsim: error: unknown object 'teapot'; catalogue objects are: bottle, ")


def test_earlier_row_a_skel_without_its_limits_names_the_missing_file(capsys, tmp_path):
    models = tmp_path / "Models" / "20"
    models.mkdir(parents=True)
    shutil.copy(TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.SKEL", models)
    result = run(capsys, "build", "hand", models / "Model_Hand_R.SKEL")
    assert (result.code, result.first) == (
        1,
        f"handsim: error: {models / 'Model_Hand_R.LIMITS'}: file not found; a .SKEL needs its .LIMITS beside "
        "it (same stem)",
    )
