"""The dataset report (handsim.report): aggregation, determinism, well-formed HTML, and headless Chromium.

Fixture runs are written here in the records schema 1 the runner writes (see ``_make_run``): glove trials
held and not held, a recorded trial with drift, a diverged one and one that failed.
"""

from __future__ import annotations

import base64
import fcntl
import hashlib
import json
import math
import os
import select
import shutil
import signal
import statistics
import struct
import subprocess
import sys
import time
import zlib
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from handsim.errors import InputFileError
from handsim.report import build_summary, read_run, render_report
from handsim.report.aggregate import group_stats, group_table, overview, rank
from handsim.report.charts import (
    Series,
    area_chart,
    decimate,
    histogram,
    line_chart,
    nice_step,
    stacked_bars,
    ticks,
)
from handsim.report.frames import FrameBudget, load_frames
from handsim.runner.records import RecordsError
from tests.conftest import GRASPDB, TZIONAS, _require

# --------------------------------------------------------------------------------------------- fixtures

FINGERS = ("thumb", "index", "middle", "ring", "little", "palm")
VERSIONS = {
    "handsim": "0.1.0",
    "mujoco": "3.3.7",
    "numpy": "2.4.6",
    "python": "3.11.2",
    "platform": "Linux-x86_64",
}
METRICS = {
    "version": "1",
    "drift_tolerance": 0.01,
    "release_delay": 0.1,
    "slip_limit": 0.02,
    "contact_gap": 0.1,
    "placement_penetration": 0.002,
    "placement_touch": 0.002,
    "stability": {"version": "1", "duration": 1.0},
}


def _png(width: int, height: int, shade: int) -> bytes:
    """A small valid RGB PNG with a gradient and a disc (filter type 0 on every row)."""
    rows = []
    for y in range(height):
        row = bytearray([0])
        for x in range(width):
            inside = (x - width / 2) ** 2 + (y - height / 2) ** 2 < (height / 3) ** 2
            row += bytes((shade, 40 + 3 * x % 200, 200 - 2 * y % 180) if inside else (230, 232, 236))
        rows.append(bytes(row))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(b"".join(rows)))
        + chunk(b"IEND", b"")
    )


def _curves(frames: int, dt: float, peak_mm: float, drift_mm: float | None, seed: int) -> dict:
    t = [round(k * dt, 6) for k in range(frames)]
    penetration = [peak_mm * math.sin(math.pi * k / (frames - 1)) ** 2 for k in range(frames)]
    contacts = {
        f: [int(max(0.0, 3 * math.sin(math.pi * k / frames + i + seed))) for k in range(frames)]
        for i, f in enumerate(FINGERS)
    }
    drift = None if drift_mm is None else [drift_mm * k / (frames - 1) for k in range(frames)]
    tracking = [0.5 + 0.4 * math.sin(0.3 * k + seed) for k in range(frames)]
    tracking[frames // 3] = None  # a frame without a value
    return {
        "time_s": t,
        "penetration_mm": penetration,
        "contacts_per_finger": contacts,
        "drift_mm": drift,
        "tracking_error_deg": tracking,
    }


def _record(trial_id: str, kind: str, status: str, meta: dict, *, seed: int, **fields) -> dict:
    frames = fields.pop("frames", 120)
    summary = fields.pop("summary", {})
    has_summary = status != "error"
    curves = (
        _curves(frames, 0.01, summary.get("max_penetration_mm", 1.0), fields.pop("drift", None), seed)
        if has_summary
        else None
    )
    base_summary = {
        "frames": frames,
        "duration_s": (frames - 1) * 0.01,
        "p95_penetration_mm": 0.8 * summary.get("max_penetration_mm", 0.0),
        "frames_penetrating_over_1mm": 3,
        "contact_frames": 80,
        "max_contact_links": 5,
        "max_total_normal_force_n": 4.5 + seed,
        "truncated_contact_pairs": 0,
        "mean_tracking_error_deg": 0.4 + 0.1 * seed,
        "max_tracking_error_deg": 2.5 + seed,
        "mean_tip_error_mm": 3.1,
        "max_tip_error_mm": 9.0,
        "diverged": status == "diverged",
        "warnings": 1 if status == "diverged" else 0,
    }
    record = {
        "schema": 1,
        "id": trial_id,
        "kind": kind,
        "status": status,
        "meta": {
            "object": None,
            "grasp": None,
            "grasp_id": None,
            "action": None,
            "scenario": None,
            "actor": None,
            "sequence": None,
            **meta,
        },
        "trial": {"kind": kind, "trajectory_path": f"/data/{trial_id}", "skeleton_path": None, "objects": []},
        "inputs": [
            {
                "role": "trajectory",
                "path": f"/data/{trial_id}",
                "sha256": hashlib.sha256(trial_id.encode()).hexdigest(),
            }
        ],
        "parameters": {
            "replay": {"control_rate": 100.0, "metrics": METRICS, "keep_states": False, "stability_at": None},
            "render_frames": 2,
        },
        "metric_spec_version": "1",
        "versions": VERSIONS,
        "model_sha256": None if not has_summary else hashlib.sha256(f"model {trial_id}".encode()).hexdigest(),
        "summary": {**base_summary, **summary} if has_summary else None,
        "hold": fields.pop("hold", None),
        "stability": None,
        "warnings": fields.pop("warnings", []),
        "diverged": fields.pop("diverged", None),
        "notes": fields.pop("notes", []),
        "trajectory_quality": {
            "frames": frames,
            "duration_s": (frames - 1) * 0.01,
            "limit_violations": fields.pop("limit_violations", 0),
            "limit_violation_max_deg": 1.5,
            "gaps_filled": fields.pop("gaps_filled", 0),
            "filled_fraction": 0.01,
        },
        "curves": curves,
        "renders": fields.pop("renders", []),
        "error": fields.pop("error", None),
        "timing": {"load_s": 0.2, "replay_s": 1.5, "render_s": 0.3, "total_s": 2.0},
    }
    assert not fields, fields
    return record


def _hold(held: bool, reason: str | None = None) -> dict:
    return {
        "released_at": 0.5,
        "window": [0.5, 1.1],
        "held": held,
        "time_held": 0.6 if held else 0.2,
        "lost_at": None if held else 0.7,
        "reason": reason,
        "max_slip": 0.004 if held else 0.025,
        "drop": 0.001,
    }


def _renders(out: Path, trial_id: str, shade: int) -> list[dict]:
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in trial_id)
    renders = []
    for k, frame in enumerate((0, 60)):
        data = _png(48, 32, (shade + 40 * k) % 256)
        path = out / "frames" / safe / f"{frame:05d}.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        renders.append(
            {
                "frame": frame,
                "time_s": frame * 0.01,
                "path": path.relative_to(out).as_posix(),
                "sha256": hashlib.sha256(data).hexdigest(),
            }
        )
    return renders


def _records(out: Path) -> list[dict]:
    glove = {"action": "grasp", "scenario": "ex01"}
    return [
        _record(
            "r_01_11_ex03-rad-004-grasp-su04.txt",
            "graspdb",
            "ok",
            {**glove, "object": "tennis_ball", "grasp": "power sphere", "grasp_id": 11, "actor": "su04"},
            seed=1,
            summary={
                "max_penetration_mm": 1.8,
                "held": True,
                "time_held_s": 0.6,
                "max_slip_mm": 4.0,
                "drop_mm": 1.0,
                "fit_fraction": 0.71,
                "grip_normal_force_n": 19.4,
                "grip_servo_torque_nm": 1.94,
                "grip_directions_held": 6,
                "self_penetration_at_closure_mm": 4.9,
            },
            hold=_hold(True),
            renders=_renders(out, "r_01_11_ex03-rad-004-grasp-su04.txt", 10),
            limit_violations=4,
            gaps_filled=12,
        ),
        _record(
            "01_ex01-rad-002-grasp-su01.txt",
            "graspdb",
            "ok",
            {**glove, "object": "tennis_ball", "grasp": "precision disk", "grasp_id": 2, "actor": "su01"},
            seed=2,
            summary={
                "max_penetration_mm": 0.9,
                "held": False,
                "time_held_s": 0.2,
                "max_slip_mm": 25.0,
                "drop_mm": 30.0,
            },
            hold=_hold(False, "slipped 2.5 cm relative to the hand"),
            renders=_renders(out, "01_ex01-rad-002-grasp-su01.txt", 90),
            limit_violations=1,
        ),
        _record(
            "04_ex01-rad-045-grasp-su03.txt",
            "graspdb",
            "ok",
            {**glove, "object": "mug", "grasp": "power sphere", "grasp_id": 11, "actor": "su03"},
            seed=3,
            summary={
                "max_penetration_mm": 2.6,
                "held": True,
                "time_held_s": 0.6,
                "max_slip_mm": 7.5,
                "drop_mm": 0.5,
            },
            hold=_hold(True),
            gaps_filled=3,
            notes=["grasp frame from the annotation"],
        ),
        _record(
            "Models/20",
            "tzionas",
            "ok",
            {"object": "cube", "sequence": "20", "scenario": "recorded"},
            seed=4,
            drift=33.9,
            summary={
                "max_penetration_mm": 0.68,
                "mean_drift_mm": 10.6,
                "max_drift_mm": 33.9,
                "final_drift_mm": 30.6,
                "within_tolerance": 0.742,
                "mean_rotation_drift_deg": 4.2,
                "max_rotation_drift_deg": 12.4,
                "max_articulation_drift_deg": None,
            },
            renders=_renders(out, "Models/20", 170),
        ),
        _record(
            "Models/17",
            "tzionas",
            "diverged",
            {"object": "pipe", "sequence": "17", "scenario": "recorded"},
            seed=5,
            drift=80.0,
            frames=40,
            summary={"max_penetration_mm": 4.2, "mean_drift_mm": 20.0, "max_drift_mm": 80.0},
            diverged={
                "name": "mjWARN_BADQACC",
                "step": 196,
                "frame": 39,
                "count": 1,
                "info": 12,
                "diverged": True,
                "message": "MuJoCo reported mjWARN_BADQACC at step 196 (frame 39)",
            },
            warnings=[
                {
                    "name": "mjWARN_BADQACC",
                    "step": 196,
                    "frame": 39,
                    "count": 1,
                    "info": 12,
                    "diverged": True,
                    "message": "MuJoCo reported mjWARN_BADQACC at step 196 (frame 39)",
                }
            ],
        ),
        _record(
            "05_ex02-rad-010-grasp-su04.txt",
            "graspdb",
            "error",
            {**glove, "object": "mug", "grasp": "precision disk", "grasp_id": 2, "actor": "su04"},
            seed=6,
            error={
                "type": "FormatError",
                "message": 'line 3: bad <value> & "quotes" in <script>alert(1)</script>',
                "traceback": 'Traceback (most recent call last):\n  File "x.py", line 1\nFormatError: <bad>',
            },
            gaps_filled=None,
        ),
    ]


def _make_run(out: Path, order: list[int] | None = None) -> list[dict]:
    """Write a fixture run folder (records in ``order`` of the list above) and return its records."""
    out.mkdir(parents=True, exist_ok=True)
    records = _records(out)
    ordered = [records[i] for i in order] if order else records
    (out / "records.jsonl").write_text("".join(json.dumps(r) + "\n" for r in ordered), encoding="utf-8")
    run = {
        "command": ["handsim", "report", "/data/graspdb14", "-o", str(out)],
        "dataset": "/data/graspdb14",
        "versions": VERSIONS,
        "discovery": {
            "trials": len(records),
            "companion": [{"path": "01_11_ex03-rad-004-grasp-su04_annot-.txt", "reason": "annotation"}],
            "unknown": [{"path": "notes & <todo>.txt", "reason": "not a recording"}],
        },
        "parameters": {"workers": 2, "render_frames": 2},
    }
    (out / "run.json").write_text(json.dumps(run), encoding="utf-8")
    return records


@pytest.fixture
def run_dir(tmp_path: Path) -> Path:
    out = tmp_path / "out"
    _make_run(out)
    return out


def _by_id(records: list[dict]) -> dict[str, dict]:
    return {r["id"]: r for r in records}


# ------------------------------------------------------------------------------------------- records


def test_records_are_ordered_by_natural_id_whatever_the_file_order(tmp_path):
    _make_run(tmp_path, order=[5, 3, 1, 4, 0, 2])
    ids = [r["id"] for r in read_run(tmp_path).records]
    assert ids == [
        "01_ex01-rad-002-grasp-su01.txt",
        "04_ex01-rad-045-grasp-su03.txt",
        "05_ex02-rad-010-grasp-su04.txt",
        "Models/17",
        "Models/20",
        "r_01_11_ex03-rad-004-grasp-su04.txt",
    ]


def test_cut_off_last_line_is_skipped_and_noted(run_dir):
    with open(run_dir / "records.jsonl", "a", encoding="utf-8") as f:
        f.write('{"schema": 1, "id": "Models/9", "sta')
    run = read_run(run_dir)
    assert len(run.records) == 6
    assert (
        len(run.notes) == 1 and "records.jsonl: the last line" in run.notes[0] and "truncated" in run.notes[0]
    )


def test_bad_line_in_the_middle_raises_records_error_with_its_line(run_dir):
    lines = (run_dir / "records.jsonl").read_text().splitlines()
    lines.insert(2, "{not json")
    (run_dir / "records.jsonl").write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordsError, match=r"records\.jsonl:3: not a JSON record"):
        read_run(run_dir)


def test_unsupported_schema_raises_records_error(run_dir):
    (run_dir / "records.jsonl").write_text(json.dumps({"schema": 2, "id": "x", "status": "ok"}) + "\n")
    with pytest.raises(RecordsError, match=r":1: field 'schema' is 2; this handsim reads schema 1"):
        read_run(run_dir)


def test_unknown_status_raises_records_error(run_dir):
    (run_dir / "records.jsonl").write_text(json.dumps({"schema": 1, "id": "x", "status": "done"}) + "\n")
    with pytest.raises(
        RecordsError, match=r"field 'status' is 'done'; expected one of \['ok', 'diverged', 'error'\]"
    ):
        read_run(run_dir)


def test_missing_records_file_raises_input_file_error(tmp_path):
    with pytest.raises(InputFileError, match=r"records\.jsonl does not exist"):
        render_report(tmp_path)


def test_repeated_id_keeps_the_first_record_and_says_so(run_dir):
    records = [json.loads(line) for line in (run_dir / "records.jsonl").read_text().splitlines()]
    again = dict(
        records[0], status="error", summary=None, error={"type": "X", "message": "m", "traceback": ""}
    )
    with open(run_dir / "records.jsonl", "a", encoding="utf-8") as f:
        f.write(json.dumps(again) + "\n")
    run = read_run(run_dir)
    assert len(run.records) == 6
    assert _by_id(list(run.records))[records[0]["id"]]["status"] == records[0]["status"]
    assert len(run.notes) == 1
    assert f"repeats the record of {records[0]['id']!r}; the first is kept" in run.notes[0]


def test_missing_run_json_is_noted_and_the_report_still_renders(run_dir):
    (run_dir / "run.json").unlink()
    files = render_report(run_dir)
    summary = json.loads(files.json.read_text())
    assert summary["command"] is None
    assert summary["notes"] == ["run.json is absent: no command line, discovery or run parameters to show"]


# --------------------------------------------------------------------------------------- aggregation


def _linear_percentile(values: list[float], q: float) -> float:
    """Percentile by linear interpolation between order statistics, written out."""
    s = sorted(values)
    h = (len(s) - 1) * q / 100
    lo = math.floor(h)
    return s[lo] + (h - lo) * (s[min(lo + 1, len(s) - 1)] - s[lo])


def test_group_table_by_object_matches_independent_computation(tmp_path):
    records = _make_run(tmp_path)
    rows = {row["group"]: row for row in group_table(read_run(tmp_path).records, "object")}
    assert list(rows) == ["cube", "mug", "pipe", "tennis_ball"]
    for name, row in rows.items():
        group = [r for r in records if r["meta"]["object"] == name]
        summaries = [r["summary"] for r in group if r["summary"]]
        holds = [s["held"] for s in summaries if "held" in s]
        slips = [s["max_slip_mm"] for s in summaries if "max_slip_mm" in s]
        penetration = [s["max_penetration_mm"] for s in summaries]
        assert row["trials"] == len(group)
        assert row["errors"] == sum(r["status"] == "error" for r in group)
        assert row["diverged"] == sum(r["status"] == "diverged" for r in group)
        assert row["hold_judged"] == len(holds) and row["held"] == sum(holds)
        assert row["hold_rate"] == (sum(holds) / len(holds) if holds else None)
        assert row["slip_max_mm"] == (max(slips) if slips else None)
        assert row["slip_median_mm"] == (pytest.approx(statistics.median(slips)) if slips else None)
        for q, key in ((50, "penetration_p50_mm"), (95, "penetration_p95_mm")):
            assert row[key] == (pytest.approx(_linear_percentile(penetration, q)) if penetration else None)
        gaps = [
            r["trajectory_quality"]["gaps_filled"]
            for r in group
            if r["trajectory_quality"]["gaps_filled"] is not None
        ]
        assert row["gaps_filled"] == (sum(gaps) if gaps else None)
    tennis = rows["tennis_ball"]
    assert (tennis["hold_rate"], tennis["slip_median_mm"], tennis["slip_max_mm"]) == (0.5, 14.5, 25.0)
    assert tennis["limit_violations"] == 5 and tennis["gaps_filled"] == 12
    assert rows["cube"]["drift_mean_mm"] == 10.6 and rows["cube"]["drift_max_mm"] == 33.9
    assert rows["cube"]["hold_rate"] is None and rows["cube"]["slip_max_mm"] is None


def test_group_stats_over_every_trial(tmp_path):
    records = _make_run(tmp_path)
    stats = group_stats(read_run(tmp_path).records)
    penetration = [r["summary"]["max_penetration_mm"] for r in records if r["summary"]]
    assert (stats["trials"], stats["ok"], stats["diverged"], stats["errors"]) == (6, 4, 1, 1)
    assert (stats["held"], stats["hold_judged"]) == (2, 3)
    assert stats["penetration_max_mm"] == max(penetration) == 4.2
    assert stats["penetration_p50_mm"] == pytest.approx(_linear_percentile(penetration, 50))
    assert stats["penetration_p95_mm"] == pytest.approx(_linear_percentile(penetration, 95))
    assert stats["drift_mean_mm"] == pytest.approx((10.6 + 20.0) / 2)
    assert stats["limit_violations"] == 5 and stats["gaps_filled"] == 15


def test_group_tables_by_grasp_and_actor_put_trials_without_a_value_last(tmp_path):
    _make_run(tmp_path)
    records = read_run(tmp_path).records
    grasp = group_table(records, "grasp")
    assert [(r["group"], r["trials"]) for r in grasp] == [
        ("power sphere", 2),
        ("precision disk", 2),
        (None, 2),
    ]
    actor = group_table(records, "actor")
    assert [(r["group"], r["trials"]) for r in actor] == [("su01", 1), ("su03", 1), ("su04", 2), (None, 2)]
    assert group_table(records, "sequence") != [] and group_table(records, "nothing") == []


def test_overview_counts_trials_by_status_and_kind(tmp_path):
    _make_run(tmp_path)
    run = read_run(tmp_path)
    o = overview(run.records, run.run)
    assert o["by_status"] == {"ok": 4, "diverged": 1, "error": 1}
    assert o["by_kind"] == {
        "graspdb": {"ok": 3, "diverged": 0, "error": 1},
        "tzionas": {"ok": 1, "diverged": 1, "error": 0},
    }
    assert o["discovered_trials"] == 6
    assert [e["path"] for e in o["unknown"]] == ["notes & <todo>.txt"]


def test_ranking_puts_errors_then_diverged_then_not_held_then_deepest_penetration_first(tmp_path):
    _make_run(tmp_path)
    ranking = rank(read_run(tmp_path).records)
    assert [(r["rank"], r["id"], r["tier"]) for r in ranking] == [
        (1, "05_ex02-rad-010-grasp-su04.txt", "error"),
        (2, "Models/17", "diverged"),
        (3, "01_ex01-rad-002-grasp-su01.txt", "not held"),
        (4, "04_ex01-rad-045-grasp-su03.txt", "ok"),  # 2.6 mm
        (5, "r_01_11_ex03-rad-004-grasp-su04.txt", "ok"),  # 1.8 mm
        (6, "Models/20", "ok"),  # 0.68 mm
    ]
    assert ranking[0]["reason"] == 'FormatError: line 3: bad <value> & "quotes" in <script>alert(1)</script>'
    assert ranking[1]["reason"] == "MuJoCo mjWARN_BADQACC at step 196"
    assert ranking[2]["reason"] == "object lost: slipped 2.5 cm relative to the hand; max penetration 0.90 mm"


def test_summary_json_lists_every_trial_with_its_key_metrics(run_dir):
    records = _by_id(_records(run_dir))
    files = render_report(run_dir)
    summary = json.loads(files.json.read_text())
    assert summary["schema"] == 1 and summary["metric_spec_version"] == "1"
    assert summary["versions"] == [{"value": VERSIONS, "trials": 6}]
    assert summary["metric_specs"] == [{"value": METRICS, "trials": 6}]
    assert sorted(t["id"] for t in summary["trials"]) == sorted(records)
    for trial in summary["trials"]:
        record = records[trial["id"]]
        assert trial["status"] == record["status"]
        s = record["summary"] or {}
        assert trial["max_penetration_mm"] == s.get("max_penetration_mm")
        assert trial["max_slip_mm"] == s.get("max_slip_mm")
        assert trial["max_drift_mm"] == s.get("max_drift_mm")
        assert trial["held"] == s.get("held")
        assert trial["renders"] == [r["path"] for r in record["renders"]]
    assert [w["id"] for w in summary["worst"]][:3] == [
        "05_ex02-rad-010-grasp-su04.txt",
        "Models/17",
        "01_ex01-rad-002-grasp-su01.txt",
    ]
    assert set(summary["groups"]) == {"object", "grasp", "actor"}


def test_trial_anchors_are_unique_slugs(tmp_path):
    _make_run(tmp_path)
    run = read_run(tmp_path)
    extra = dict(run.records[0], id="Models-20")
    summary = build_summary(type(run)(run.out_dir, (*run.records, extra), run.run, ()))
    anchors = {t["id"]: t["anchor"] for t in summary["trials"]}
    assert anchors["r_01_11_ex03-rad-004-grasp-su04.txt"] == "trial-r-01-11-ex03-rad-004-grasp-su04-txt"
    assert anchors["Models/20"].startswith("trial-models-20-") and anchors["Models-20"].startswith(
        "trial-models-20-"
    )
    assert len(set(anchors.values())) == len(anchors)


# --------------------------------------------------------------------------------------------- files


def test_rendering_twice_or_from_a_reordered_file_gives_identical_bytes(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    _make_run(a)
    first = render_report(a)
    blobs = [p.read_bytes() for p in (first.html, first.markdown, first.json)]
    again = render_report(a)
    assert [p.read_bytes() for p in (again.html, again.markdown, again.json)] == blobs
    _make_run(b, order=[3, 5, 0, 4, 2, 1])
    other = render_report(b)
    # the folders differ only in the run.json command line (-o a / -o b)
    swap = [
        p.read_bytes().replace(str(b).encode(), str(a).encode())
        for p in (other.html, other.markdown, other.json)
    ]
    assert swap == blobs


class _Checker(HTMLParser):
    """Tag nesting, ids, links and resource URLs of a page."""

    VOID = frozenset("meta img br hr link input source wbr col area base embed track".split())
    SVG_SELF = frozenset({"line", "rect", "path", "circle", "polyline"})

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.ids: list[str] = []
        self.hrefs: list[str] = []
        self.srcs: list[str] = []
        self.tags: set[str] = set()
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        self._attrs(tag, attrs)
        if tag not in self.VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self._attrs(tag, attrs)
        if tag not in self.VOID | self.SVG_SELF:
            self.errors.append(f"self-closed <{tag}/>")

    def _attrs(self, tag, attrs):
        self.tags.add(tag)
        a = dict(attrs)
        if "id" in a:
            self.ids.append(a["id"])
        if "href" in a:
            self.hrefs.append(a["href"])
        if "src" in a:
            self.srcs.append(a["src"])
        for name, value in attrs:
            if name.startswith("on"):
                self.errors.append(f"event handler {name} on <{tag}>")
            if value and "url(" in value:
                self.errors.append(f"url() in {name} of <{tag}>")

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1] if self.stack else None}>")
            return
        self.stack.pop()

    def handle_data(self, data):
        self.text.append(data)


def _check_html(path: Path) -> _Checker:
    checker = _Checker()
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    checker.feed(text)
    checker.close()
    assert checker.errors == []
    assert checker.stack == []
    assert len(checker.ids) == len(set(checker.ids)), "duplicate ids"
    assert "script" not in checker.tags and "link" not in checker.tags and "iframe" not in checker.tags
    ids = set(checker.ids)
    for href in checker.hrefs:
        assert not href.startswith(("http:", "https:", "//", "javascript:")), href
        if href.startswith("#"):
            assert href[1:] in ids, f"anchor {href} does not resolve"
    for src in checker.srcs:
        assert src.startswith("data:image/png;base64,"), src[:40]
    style = text[text.index("<style>") : text.index("</style>")]
    assert "url(" not in style and "@import" not in style
    return checker


def test_html_is_well_formed_self_contained_and_every_anchor_resolves(run_dir):
    files = render_report(run_dir)
    checker = _check_html(files.html)
    summary = json.loads(files.json.read_text())
    for trial in summary["trials"]:
        assert trial["anchor"] in checker.ids
        assert f"#{trial['anchor']}" in checker.hrefs  # reachable from the trials table
    for section in ("overview", "groups", "distributions", "worst", "trials", "reproducibility"):
        assert section in checker.ids
    assert len(checker.srcs) == 6  # 3 trials × 2 frames, embedded


def test_html_escapes_text_from_the_records(run_dir):
    html = render_report(run_dir).html.read_text()
    assert "<script>" not in html and "<bad>" not in html and "<todo>" not in html
    assert "bad &lt;value&gt; &amp; &quot;quotes&quot; in &lt;script&gt;alert(1)&lt;/script&gt;" in html
    assert "notes &amp; &lt;todo&gt;.txt" in html


def test_html_shows_curves_frames_traceback_and_reproducibility(run_dir):
    html = render_report(run_dir).html.read_text()
    # 3 glove trials × 3 curves, 2 recorded × 4 (with drift), 4 histograms, 2 outcome bar charts
    assert html.count("<svg") == 3 * 3 + 2 * 4 + 4 + 2
    assert "Object drift from the recording" in html and "Contacts per finger" in html
    assert "<details><summary>traceback</summary><pre>Traceback (most recent call last):" in html
    assert "handsim report /data/graspdb14 -o" in html  # the command line
    assert hashlib.sha256(b"Models/20").hexdigest() in html  # an input hash
    assert hashlib.sha256(b"model Models/20").hexdigest() in html  # a model hash
    assert "&quot;slip_limit&quot;: 0.02" in html  # the metric spec


def test_glove_trial_shows_how_far_the_recorded_closure_passes_the_object(run_dir):
    html = render_report(run_dir).html.read_text()
    assert html.count("<h4>Recorded closure</h4>") == 1  # only the trial whose record has the numbers
    closure = html.split("<h4>Recorded closure</h4>", 1)[1].split("</table>", 1)[0]
    for label, value in [
        ("flexion fraction where the object fits", "0.71"),
        ("grip normal force N", "19.4"),
        ("grip servo torque N·m", "1.94"),
        ("gravity directions the grip resists", "6"),
        ("hand self-penetration at closure mm", "4.9"),
    ]:
        assert label in closure and f">{value}<" in closure, label
    md = render_report(run_dir).markdown.read_text()
    header = next(line for line in md.splitlines() if "| fit at |" in line)
    row = next(line for line in md.splitlines() if "r_01_11_ex03" in line and "| 0.71 |" in line)
    column = header.split(" | ").index("fit at")
    assert row.split(" | ")[column] == "0.71"
    assert row.split(" | ")[header.split(" | ").index("closure self-pen. mm")] == "4.9"


def test_missing_values_show_as_a_dash(run_dir):
    md = render_report(run_dir).markdown.read_text()
    cube = next(line for line in md.splitlines() if line.startswith("| cube |"))
    assert cube.split(" | ")[6] == "—"  # hold rate of a recorded-only group


def test_changed_or_missing_frames_are_reported_not_raised(run_dir):
    records = _by_id(_records(run_dir))
    record = records["Models/20"]
    (run_dir / record["renders"][0]["path"]).write_bytes(_png(8, 8, 1))
    (run_dir / record["renders"][1]["path"]).unlink()
    images = load_frames(record, run_dir, FrameBudget())
    assert images[0].data_uri is not None
    assert images[
        0
    ].problem == f"{record['renders'][0]['path']} does not match the SHA-256 recorded for it " + (
        "(changed after the run)"
    )
    assert (
        images[1].data_uri is None and images[1].problem == f"file {record['renders'][1]['path']} is missing"
    )
    html = render_report(run_dir).html.read_text()
    assert "does not match the SHA-256 recorded for it" in html


def test_curves_of_the_wrong_length_are_left_out_with_a_note(run_dir):
    records = [json.loads(line) for line in (run_dir / "records.jsonl").read_text().splitlines()]
    records[0]["curves"]["penetration_mm"] = records[0]["curves"]["penetration_mm"][:-1]
    records[0]["curves"]["time_s"][5] = None
    (run_dir / "records.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    html = render_report(run_dir).html.read_text()
    assert "penetration_mm has 119 values for 120 times: not drawn" in html


def test_frames_past_the_embedding_budget_are_linked(run_dir):
    files = render_report(run_dir, embed_budget=0)
    checker = _check_html(files.html)
    assert checker.srcs == []
    assert "frames/Models_20/00000.png" in checker.hrefs


def test_markdown_has_the_tables_and_links_the_frames(run_dir):
    md = render_report(run_dir).markdown.read_text()
    for heading in (
        "## Dataset overview",
        "### By object",
        "### By grasp type",
        "### By actor",
        "## Worst trials first",
    ):
        assert heading in md
    tables: list[list[str]] = []
    previous = False
    for line in md.splitlines():
        is_row = line.startswith("|")
        if is_row and not previous:
            tables.append([])
        if is_row:
            tables[-1].append(line)
        previous = is_row
    assert len(tables) == 5  # kinds, object, grasp, actor, all trials
    for table in tables:
        widths = {len(line.replace("\\|", "").split("|")) for line in table}
        assert len(widths) == 1, table[0]
    assert "[00000.png](frames/Models_20/00000.png)" in md
    assert (
        "1. [05_ex02-rad-010-grasp-su04.txt](report.html#trial-05-ex02-rad-010-grasp-su04-txt) — **error**"
        in md
    )


# ---------------------------------------------------------------------------------------------- svg


def test_nice_ticks_cover_the_range_with_round_steps():
    assert ticks(0, 4.2) == [0, 1, 2, 3, 4, 5]
    assert ticks(0.3, 0.68) == [0.3, 0.4, 0.5, 0.6, 0.7]
    assert ticks(2, 2) == [1.8, 1.9, 2.0, 2.1, 2.2]
    assert nice_step(10, 4) == 2.5


def test_decimation_keeps_each_buckets_extremes_and_gaps():
    x = list(range(10_000))
    y = [math.sin(k / 100) for k in x]
    y[5000] = 7.0
    y[7000] = None
    kept = decimate(x, y, 400)
    assert len(kept) <= 600
    assert (5000.0, 7.0) in kept and any(v is None for _, v in kept)
    assert max(v for _, v in kept if v is not None) == 7.0


def test_line_chart_breaks_lines_at_missing_values_and_labels_axes():
    svg = line_chart(
        [Series("a", [0, 1, 2, 3], [1.0, None, 2.0, 3.0]), Series("b", [0, 1, 2, 3], [0, 0, 1, 1])],
        title="T <1>",
        x_label="time (s)",
        y_label="mm",
    )
    first_path = svg[svg.index('d="') + 3 :].split('"')[0]
    assert first_path.count("M") == 2
    assert "T &lt;1&gt;" in svg and ">time (s)<" in svg and ">mm<" in svg
    assert svg.count('class="legend"') == 2
    assert (
        line_chart([Series("a", [0, 1], [None, None])], title="t", x_label="x", y_label="y").count("no data")
        == 1
    )


def test_stacked_area_draws_each_nonzero_layer_on_the_ones_below():
    svg = area_chart(
        [0, 1, 2],
        [("a", [1, 1, 1]), ("b", [0, 0, 0]), ("c", [2, None, 1])],
        title="t",
        x_label="s",
        y_label="n",
    )
    assert svg.count('class="area"') == 2  # "b" is all zero
    assert svg.count('class="legend"') == 3
    top_of_c = svg.split('class="area" d="M')[2].split("L")[:3]
    bottom = svg.split('class="area" d="M')[1].split("L")[:3]
    assert [p.split()[1] for p in top_of_c] != [p.split()[1] for p in bottom]
    assert "no data" in area_chart([], [], title="t", x_label="s", y_label="n")


def test_histogram_counts_every_value_once():
    values = [0.1, 0.2, 0.2, 0.9, 1.4, 3.3, 3.4]
    svg = histogram(values, title="h", x_label="mm")
    counts = [int(t.split("</title>")[0].rsplit(": ", 1)[1]) for t in svg.split("<title>")[2:]]
    assert sum(counts) == len(values)
    assert "median 0.9" in svg and "n = 7" in svg
    assert "no values" in histogram([], title="h", x_label="mm")


def test_stacked_bars_total_each_category():
    svg = stacked_bars(
        ["mug", "ball"], [("ok", [2, 1], "#0a0"), ("error", [1, 0], "#a00")], title="t", x_label="n"
    )
    assert ">3</text>" in svg and ">1</text>" in svg
    assert "mug: 2 ok" in svg and "mug: 1 error" in svg


# ------------------------------------------------------------------------------------------ chromium


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        found = shutil.which(name)
        if found:
            return found
    return None


class _DevTools:
    """A minimal Chrome DevTools Protocol client over ``--remote-debugging-pipe``.

    Chromium reads commands from its fd 3 and writes replies and events to its fd 4, each message a JSON
    object ended by a NUL byte. The browser is started with ``os.posix_spawn`` so that exactly these two
    descriptors are set up; its stderr goes to ``log``.
    """

    def __init__(self, exe: str, profile: Path, log: Path) -> None:
        to_child_r, self._w = (self._high(fd) for fd in os.pipe())
        self._r, from_child_w = (self._high(fd) for fd in os.pipe())
        args = [
            exe,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-extensions",
            "--hide-scrollbars",
            "--remote-debugging-pipe",
            f"--user-data-dir={profile}",
            "about:blank",
        ]
        self.pid = os.posix_spawn(
            exe,
            args,
            os.environ,
            file_actions=[
                (os.POSIX_SPAWN_OPEN, 0, os.devnull, os.O_RDONLY, 0),
                (os.POSIX_SPAWN_OPEN, 1, os.devnull, os.O_WRONLY, 0),
                (os.POSIX_SPAWN_OPEN, 2, str(log), os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644),
                (os.POSIX_SPAWN_DUP2, to_child_r, 3),
                (os.POSIX_SPAWN_DUP2, from_child_w, 4),
            ],
        )
        os.close(to_child_r)
        os.close(from_child_w)
        self._next, self._buffer, self.events = 0, b"", []

    @staticmethod
    def _high(fd: int) -> int:
        """The same pipe end on a descriptor ≥ 10 (clear of the 3 and 4 it is duplicated to)."""
        new = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10)
        os.close(fd)
        return new

    def _read(self, deadline: float) -> dict | None:
        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._r], [], [], left)[0]:
                return None
            chunk = os.read(self._r, 1 << 20)
            if not chunk:
                raise RuntimeError("chromium closed the DevTools pipe")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def send(
        self, method: str, params: dict | None = None, session: str | None = None, timeout: float = 60
    ) -> dict:
        self._next += 1
        message = {"id": self._next, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self._w, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            reply = self._read(deadline)
            if reply is None:
                raise TimeoutError(f"no reply to {method}")
            if reply.get("id") == self._next:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def wait_for(self, method: str, after: int = 0, timeout: float = 60) -> None:
        """Read until an event ``method`` arrives past the first ``after`` events."""
        deadline = time.monotonic() + timeout
        while not any(e.get("method") == method for e in self.events[after:]):
            event = self._read(deadline)
            if event is None:
                raise TimeoutError(f"no {method} event")
            self.events.append(event)

    def drain(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while (event := self._read(deadline)) is not None:
            self.events.append(event)

    def close(self) -> None:
        try:
            self.send("Browser.close", timeout=10)
        except (RuntimeError, TimeoutError, OSError):
            pass
        os.close(self._w)
        deadline = time.monotonic() + 20
        while os.waitpid(self.pid, os.WNOHANG) == (0, 0):
            if time.monotonic() > deadline:
                os.kill(self.pid, signal.SIGKILL)
                os.waitpid(self.pid, 0)
                break
            time.sleep(0.05)
        os.close(self._r)


def _open_in_chromium(html: Path, screenshot: Path, profile: Path) -> tuple[list[str], list[dict]]:
    """Load ``html``, save a 1280 × 2000 screenshot; return the page's [URL, title] and the events seen."""
    exe = _chromium()
    assert exe is not None
    tools = _DevTools(exe, profile, profile.with_suffix(".log"))
    try:
        target = tools.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = tools.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log", "Network"):
            tools.send(f"{domain}.enable", session=session)
        tools.send(
            "Emulation.setDeviceMetricsOverride",
            {"width": 1280, "height": 2000, "deviceScaleFactor": 1, "mobile": False},
            session=session,
        )
        seen = len(tools.events)
        tools.send("Page.navigate", {"url": html.resolve().as_uri()}, session=session)
        tools.wait_for("Page.loadEventFired", after=seen)
        tools.drain(1.0)
        shot = tools.send("Page.captureScreenshot", {"format": "png"}, session=session)
        screenshot.write_bytes(base64.b64decode(shot["data"]))
        page = tools.send(
            "Runtime.evaluate",
            {"expression": "JSON.stringify([location.href, document.title])", "returnByValue": True},
            session=session,
        )
    finally:
        tools.close()
    return json.loads(page["result"]["value"]), tools.events


def _console_problems(events: list[dict]) -> list[str]:
    problems = []
    for event in events:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.exceptionThrown":
            problems.append(f"uncaught: {params['exceptionDetails'].get('text')}")
        elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert", "warning"):
            problems.append(f"console.{params['type']}: {params.get('args')}")
        elif method == "Log.entryAdded" and params["entry"].get("level") in ("error", "warning"):
            problems.append(f"log {params['entry']['level']}: {params['entry'].get('text')}")
        elif method == "Network.loadingFailed":
            problems.append(f"load failed: {params.get('errorText')}")
        elif method == "Network.requestWillBeSent":
            url = params["request"]["url"]
            if not url.startswith(("file:", "data:", "about:")):
                problems.append(f"request to {url}")
    return problems


def _png_pixels(data: bytes) -> np.ndarray:
    """Decode an 8-bit RGB/RGBA non-interlaced PNG (what Chromium writes) with zlib and numpy."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    assert depth == 8 and colour in (2, 6) and interlace == 0, header
    bpp = 3 if colour == 2 else 4
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(height, 1 + width * bpp)
    out = np.zeros((height, width * bpp), dtype=np.uint8)
    prev = np.zeros(width * bpp, dtype=np.int32)
    for y in range(height):
        kind, line = raw[y, 0], raw[y, 1:].astype(np.int32)
        if kind == 0:
            row = line
        elif kind == 1:  # Sub: running sum per channel
            row = np.cumsum(line.reshape(width, bpp), axis=0).reshape(-1) % 256
        elif kind == 2:  # Up
            row = (line + prev) % 256
        else:  # Average, Paeth: sequential
            row = np.zeros_like(line)
            for i in range(line.size):
                a = row[i - bpp] if i >= bpp else 0
                b, c = prev[i], prev[i - bpp] if i >= bpp else 0
                if kind == 3:
                    row[i] = (line[i] + (a + b) // 2) % 256
                else:
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                    row[i] = (line[i] + pred) % 256
        out[y] = row
        prev = row.astype(np.int32)
    return out.reshape(height, width, bpp)[..., :3]


def test_png_decoder_reads_a_known_image():
    pixels = _png_pixels(_png(6, 4, 77))
    assert pixels.shape == (4, 6, 3)
    assert tuple(pixels[0, 0]) == (230, 232, 236)
    assert tuple(pixels[2, 3]) == (77, (40 + 3 * 3) % 200, 200 - 2 * 2 % 180)


SCREENSHOT = "report-screenshot.png"


def test_report_opens_in_headless_chromium_without_console_errors(run_dir, tmp_path):
    if _chromium() is None:
        pytest.skip("chromium is not installed (CI installs Debian's chromium package: see .ci/run)")
    files = render_report(run_dir)
    screenshot = run_dir / SCREENSHOT
    (url, title), events = _open_in_chromium(files.html, screenshot, tmp_path / "profile")
    assert url == files.html.resolve().as_uri()  # not Chromium's error page
    assert title == "handsim report — /data/graspdb14"
    assert _console_problems(events) == []
    requests = [
        e["params"]["request"]["url"] for e in events if e.get("method") == "Network.requestWillBeSent"
    ]
    assert [u for u in requests if not u.startswith("data:image/png;base64,")] == [
        files.html.resolve().as_uri()
    ]
    pixels = _png_pixels(screenshot.read_bytes())
    assert pixels.shape == (2000, 1280, 3)
    assert pixels.std() > 20 and len(np.unique(pixels.reshape(-1, 3), axis=0)) > 50  # not blank


@pytest.mark.slow
@pytest.mark.parametrize("dataset", ["graspdb14", "tzionas_ijcv16"])
def test_real_dataset_run_reports_every_trial_and_opens_in_chromium(dataset, tmp_path):
    data = TZIONAS if dataset == "tzionas_ijcv16" else _require(GRASPDB)  # the Tzionas sample is bundled
    out = tmp_path / "out"
    command = [sys.executable, "-m", "handsim.cli", "report", str(data), "-o", str(out)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=900, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    records = [json.loads(line) for line in (out / "records.jsonl").read_text().splitlines() if line.strip()]
    discovered = json.loads((out / "run.json").read_text())["discovery"]["trials"]
    summary = json.loads((out / "summary.json").read_text())
    assert len(records) == discovered == len(summary["trials"])
    assert sorted(t["id"] for t in summary["trials"]) == sorted(r["id"] for r in records)
    assert summary["metric_spec_version"] == records[0]["metric_spec_version"]
    written = [p.read_bytes() for p in (out / "report.html", out / "report.md", out / "summary.json")]
    files = render_report(out)  # what --render-only does: the same bytes from the same records
    assert [p.read_bytes() for p in (files.html, files.markdown, files.json)] == written
    checker = _check_html(files.html)
    assert len(checker.srcs) == sum(len(r["renders"]) for r in records)  # every rendered frame embedded
    if _chromium() is None:
        pytest.skip("chromium is not installed (CI installs Debian's chromium package: see .ci/run)")
    (url, _), events = _open_in_chromium(files.html, out / SCREENSHOT, tmp_path / "profile")
    assert url == files.html.resolve().as_uri()
    assert _console_problems(events) == []
    pixels = _png_pixels((out / SCREENSHOT).read_bytes())
    assert pixels.std() > 20


def test_a_trial_flagged_not_valid_is_its_own_outcome_and_left_out_of_every_rate(tmp_path):
    from handsim.report.aggregate import distributions, outcome

    records = _records(tmp_path)
    flagged = records[0]  # a glove trial that "held", 1.8 mm deep
    reason = "the hand is 37.6 mm inside the object at the start, more than 5 mm"
    flagged["summary"]["valid"] = False
    flagged["flags"] = [
        {"code": "initial_penetration", "invalid": True, "reason": reason, "values": {"depth_mm": 37.6}},
        {"code": "joint_limits", "invalid": False, "reason": "4 target samples beyond", "values": {}},
    ]
    for record in records[1:]:
        if record["summary"] is not None:
            record["summary"]["valid"] = True
    (tmp_path / "records.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    run = read_run(tmp_path)
    assert [outcome(r) for r in run.records if r["id"] == flagged["id"]] == ["flagged"]
    stats = group_stats(run.records)
    assert (stats["flagged"], stats["held"], stats["hold_judged"]) == (1, 1, 2)
    penetration = [r["summary"]["max_penetration_mm"] for r in records[1:] if r["summary"]]
    assert stats["penetration_p50_mm"] == pytest.approx(_linear_percentile(penetration, 50))
    assert 1.8 not in distributions(run.records)["max_penetration_mm"]
    ranking = rank(run.records)
    assert [(r["id"], r["tier"], r["reason"]) for r in ranking[2:3]] == [
        (flagged["id"], "flagged", f"not valid: {reason}")
    ]
    files = render_report(tmp_path)
    html = files.html.read_text()
    assert "Plausibility flags" in html and "37.6 mm inside the object" in html
    assert "1 flagged not valid (left out of every rate and statistic)" in files.markdown.read_text()
