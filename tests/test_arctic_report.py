"""``handsim report`` on an ARCTIC root as a user runs it: what the report leaves out, what its frames show.

A synthetic MANO pair and a synthetic ARCTIC root in the real layout (``tests/mano_fixtures.py``,
``tests/arctic_fixtures.py``) with the companions a real root has beside its sequences: egocentric camera
poses and SMPL-X bodies per sequence, subject templates, ``misc.json``, the object templates' other files and
templates no sequence uses. Three sequences (30 frames at 30 Hz, a regular clock; in one the hands reach in
from afar) of block-shaped templates (no convex decomposition: fast), run once for the module.
"""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from handsim.cli import main
from handsim.io.arctic.sequence import HANDS
from handsim.report.files import group_files
from handsim.sim.replay import ReplayConfig, replay
from handsim.trials import load_trial
from handsim.viz.headless import offscreen_renderer
from handsim.viz.render import TRACK_CAMERA, _camera, frame_camera
from tests.arctic_fixtures import recording, template_parts, write_template
from tests.mano_fixtures import mano_hand_params, write_arctic_mano_npy, write_arctic_object_npy
from tests.mano_fixtures import write_synthetic_mano_pkl as write_mano

FRAMES = 30
SEQUENCES = {"laptop_grab_01": "s01", "phone_use_01": "s02", "notebook_use_02": "s01"}
"""The sequences and their subjects (the laptop's template is mesh.obj + parts.json, the others' two OBJs)."""
APART = {"notebook_use_02": 0.3}
"""Sequences whose wrists are this much further out to each side (m): hands that reach in from afar, as
ARCTIC's do before they take the object (the track camera, 0.45 m from the right wrist, misses the left)."""
TEMPLATE_EXTRAS = ("mesh_tex.obj", "material.mtl", "top_keypoints_300.json", "bottom_keypoints_300.json")
"""Files of a real template folder that handsim does not read."""


def _root(tmp_path):
    """An ARCTIC root (every template of ``template_parts``, two sequences, real companions) and MANO."""
    mano = tmp_path / "mano"
    mano.mkdir()
    for side in HANDS:
        write_mano(mano / f"MANO_{side.upper()}.pkl", side=side)
    root = tmp_path / "arctic"
    templates = root / "meta" / "object_vtemplates"
    for name in template_parts():
        folder = write_template(templates, name)
        for extra in TEMPLATE_EXTRAS:
            (folder / extra).write_text("not read\n")
    subjects = root / "meta" / "subject_vtemplates"
    subjects.mkdir()
    for k in range(1, 11):
        (subjects / f"s{k:02d}.obj").write_text("v 0 0 0\n")
    (root / "meta" / "misc.json").write_text("{}\n")
    for k, (seq, subject) in enumerate(SEQUENCES.items()):
        raw = root / "raw_seqs" / subject
        raw.mkdir(parents=True, exist_ok=True)
        right, left = mano_hand_params(FRAMES, 10 + k), mano_hand_params(FRAMES, 20 + k, side="left")
        right["trans"] += np.float32([APART.get(seq, 0.0), 0.0, 0.0])
        left["trans"] -= np.float32([APART.get(seq, 0.0), 0.0, 0.0])
        write_arctic_mano_npy(raw / f"{seq}.mano.npy", right, left)
        write_arctic_object_npy(raw / f"{seq}.object.npy", recording(seq.split("_")[0], FRAMES))
        for companion in (".egocam.dist.npy", ".smplx.npy"):
            (raw / f"{seq}{companion}").write_bytes(b"not read")
    stray = root / "raw_seqs" / "s02"
    for n in range(3):
        (stray / f"box_use_0{n + 1}.object.npy").write_bytes(b"no .mano.npy beside it")
    return root, mano


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """The root, its MANO folder, the run's output folder and what ``handsim report`` printed."""
    tmp = tmp_path_factory.mktemp("arctic_report")
    root, mano = _root(tmp)
    out = tmp / "out"
    args = ["report", str(root), "-o", str(out), "--mano-dir", str(mano), "--workers", "1", "--frames", "2"]
    capture = pytest.MonkeyPatch()
    printed = []
    capture.setattr("builtins.print", lambda *a, **k: printed.append(" ".join(map(str, a))))
    try:
        code = main(args)
    finally:
        capture.undo()
    assert code == 0
    return root, mano, out, printed


def test_companion_files_of_an_arctic_root_are_grouped_one_line_per_kind(report):
    root, _, out, printed = report
    markdown = (out / "report.md").read_text()
    listed = markdown[markdown.index("Companion files:") : markdown.index("## Groups")]
    template_reason = (
        "ARCTIC object template file not read (handsim reads top.obj + bottom.obj, else mesh.obj + "
        "parts.json), or a template no sequence here uses"
    )
    assert listed.splitlines() == [
        "Companion files: 47.",
        "",
        "- `meta/misc.json` — ARCTIC camera parameters, sync offsets and image sizes (not read)",
        "- `meta/object_vtemplates/` (30 files: box/, ketchup/, laptop/, notebook/ and 2 more) — "
        + template_reason,
        "- `meta/subject_vtemplates/` (10 files: s01.obj, s02.obj, s03.obj, s04.obj and 6 more) — ARCTIC "
        "personalised subject template (not read)",
        "- `raw_seqs/` (3 files: s01/, s02/) — ARCTIC egocentric camera poses (not read)",
        "- `raw_seqs/` (3 files: s01/, s02/) — ARCTIC SMPL-X body parameters (not read: handsim replays the "
        "hands)",
        "",
        "Unknown files (not used): 3.",
        "",
        "- `raw_seqs/s02/` (3 files: box_use_01.object.npy, box_use_02.object.npy, box_use_03.object.npy) — "
        "an ARCTIC object motion without its .mano.npy beside it: not a trial",
        "",
    ]
    html = (out / "report.html").read_text()
    assert "<h3>Companion files (read with a trial) (47)</h3>" in html
    assert (
        html.count("meta/object_vtemplates/ (30 files: box/, ketchup/, laptop/, notebook/ and 2 more)") == 1
    )
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["overview"]["companion"]) == 47  # summary.json keeps every file
    assert printed[0] == (
        "unknown     raw_seqs/s02/ (3 files: box_use_01.object.npy, box_use_02.object.npy, "
        "box_use_03.object.npy): an ARCTIC object motion without its .mano.npy beside it: not a trial"
    )
    assert printed[1] == f"dataset     {root}: 3 trials, 47 companion and 3 unknown files; running 3"


def test_group_files_keeps_a_reason_one_file_has_as_that_files_row():
    groups = group_files(
        [
            {"path": "01_11_ex03-rad-004-grasp-su04_annot-.txt", "reason": "annotation of the trial"},
            {"path": "a/x/1.png", "reason": "image"},
            {"path": "a/y/2.png", "reason": "image"},
            {"path": "3.png", "reason": "loose image"},
            {"path": "4.png", "reason": "loose image"},
        ]
    )
    assert [(g.what(), g.reason) for g in groups] == [
        ("01_11_ex03-rad-004-grasp-su04_annot-.txt", "annotation of the trial"),
        ("./ (2 files: 3.png, 4.png)", "loose image"),
        ("a/ (2 files: x/, y/)", "image"),
    ]


def test_an_arctic_report_has_no_glove_columns_grasp_table_or_glove_notes(report):
    _, _, out, _ = report
    markdown = (out / "report.md").read_text()
    header = next(line for line in markdown.splitlines() if line.startswith("| trial | kind |"))
    assert header == (
        "| trial | kind | outcome | on track | object | actor | pen. max mm | pen. p95 mm | drift max mm | "
        "track. mean ° | limit viol. | gaps filled | warnings |"
    )
    group_header = next(line for line in markdown.splitlines() if line.startswith("| object | trials |"))
    for glove in ("hold rate", "robust holds", "slip p50 mm", "slip max mm"):
        assert f"| {glove} |" not in group_header and f"**{glove}**" not in markdown
    assert "| follow rate |" in group_header and "| drift mean mm |" in group_header
    assert "By grasp type" not in markdown and "No trial has" not in markdown
    html = (out / "report.html").read_text()
    assert "By grasp type" not in html and "No trial has" not in html
    assert "Max slip per glove trial" not in html and "Max object drift per recorded trial" in html
    assert "Hold rate:" not in html and "Follow rate:" in html
    assert '<div class="k">hold rate</div>' not in html and '<div class="k">follow rate</div>' in html
    assert "<dt>annotation</dt>" not in html and "<dt>spikes</dt>" not in html
    for line in (out / "records.jsonl").read_text().splitlines():
        record = json.loads(line)
        assert record["status"] == "ok", record["error"]
        notes = " ".join(record["notes"])
        assert "stability tests" not in notes  # no hold window: by its nature, not a failure to note
        assert "largest gap between input samples" not in notes  # a regular 30 Hz clock has none
        assert "30.00 Hz mean, regular" in notes


def test_rendered_frames_show_both_hands_and_the_object(report):
    _, _, out, _ = report
    for line in (out / "records.jsonl").read_text().splitlines():
        record = json.loads(line)
        assert len(record["renders"]) == 2, record["notes"]
        for render in record["renders"]:
            assert (out / render["path"]).is_file()


def _visible_geoms(model: mujoco.MjModel, data: mujoco.MjData, camera: mujoco.MjvCamera) -> set[int]:
    """The geoms that cover at least one pixel of a 320 × 240 image from ``camera`` (segmentation)."""
    renderer = offscreen_renderer(model, 320, 240)
    try:
        renderer.enable_segmentation_rendering()
        renderer.update_scene(data, camera=camera)
        ids, types = np.moveaxis(renderer.render(), -1, 0)
    finally:
        renderer.close()
    return set(ids[types == int(mujoco.mjtObj.mjOBJ_GEOM)].tolist())


@pytest.mark.parametrize("seq", SEQUENCES)
def test_the_frame_camera_shows_every_hand_and_the_object_in_every_frame(report, seq):
    root, mano, _, _ = report
    path = next(root.glob(f"raw_seqs/*/{seq}.mano.npy"))
    loaded = load_trial(path, mano_dir=mano)
    result = replay(loaded.scene, loaded.trajectory, ReplayConfig(keep_states=True))
    model, data = loaded.scene.model, mujoco.MjData(loaded.scene.model)
    owner = {
        **{b: hand.name for hand in loaded.scene.layout.hands for b in range(model.nbody)
           if model.body_rootid[b] == model.body_rootid[hand.root_body]},
        **{b: "object" for o in loaded.scene.layout.objects for b in o.part_bodies},
    }  # fmt: skip
    tracked = []
    for frame in np.linspace(0, len(result.states) - 1, 5).astype(int):
        data.qpos[:] = result.states[frame]
        mujoco.mj_forward(model, data)
        seen = _visible_geoms(model, data, frame_camera(loaded.scene, data, 320 / 240))
        shown = {owner.get(int(model.geom_bodyid[g])) for g in seen}
        assert {"right", "left", "object"} <= shown, f"frame {frame}: {shown}"
        seen = _visible_geoms(model, data, _camera(loaded.scene, TRACK_CAMERA))
        tracked.append({"right", "left", "object"} <= {owner.get(int(model.geom_bodyid[g])) for g in seen})
    assert all(tracked) != (seq in APART)  # hands apart: the track camera misses one, the frame camera not
