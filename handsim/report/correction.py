"""The report of a correction run (``handsim correct DATASET -o OUT``): ``OUT/correction.html``, from records.

One self-contained page: the trials ranked by the size of their correction (against its plausibility
bounds: above 1 the correction is large and the recording implausible, said in those words with the
numbers), each with its before/after plot embedded as a small PNG (matplotlib, ``handsim[plot]``): the
object's distance from its goal (its recorded track, or for a glove grasp where the grasp placed it, over
the hold) in pure replay and in the corrected replay, and the correction's size over time. Trials that
cannot be corrected are listed with their reason; failed ones with their error. Rendered from
``OUT/records.jsonl`` alone (the records of :mod:`handsim.runner.correction_job`).
"""

from __future__ import annotations

import base64
import io
import math
from pathlib import Path

from handsim.errors import HandsimError
from handsim.files import write_atomic
from handsim.report.fmt import num
from handsim.report.markup import esc, simple_table
from handsim.report.style import CSS
from handsim.runner.records import read_records
from handsim.viz.plotting import pyplot

REPORT_FILE = "correction.html"
"""The page, in the run's output folder."""
PLOT_DPI = 72
"""Resolution of the embedded plots: 6.4 × 3.6 inches at 72 dpi, ~25 kB a trial."""

_BEFORE, _AFTER, _FINGER, _WRIST = "#8c96a3", "#1f5fa8", "#d4862a", "#b45fc4"


def _nan(values: list) -> list[float]:
    return [math.nan if v is None else float(v) for v in values]


def correction_plot(record: dict) -> bytes:
    """The before/after plot of a corrected trial's record, PNG bytes.

    Raises:
        HandsimError: matplotlib is not installed.
    """
    plt = pyplot()
    curves, c = record["curves"], record["correction"]
    t = _nan(curves["time_s"])
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 3.6), sharex=True, constrained_layout=True)
    goal = "placed pose" if c.get("objective") == "hold" else "recorded track"
    top.plot(t, _nan(curves["before_mm"]), color=_BEFORE, lw=1.2, label=f"before ({c['before']['track']})")
    top.plot(t, _nan(curves["after_mm"]), color=_AFTER, lw=1.4, label=f"after ({c['after']['track']})")
    top.set_ylabel(f"from {goal}, mm", fontsize=8)
    window = curves.get("hold_window_s")
    for axis in (top, bottom):
        if window:
            axis.axvspan(window[0], window[1], color="#f0a848", alpha=0.15, lw=0)
        axis.tick_params(labelsize=7)
        axis.grid(alpha=0.3, lw=0.5)
    top.legend(fontsize=7, loc="upper left", frameon=False)
    bottom.plot(t, _nan(curves["finger_rms_deg"]), color=_FINGER, lw=1.2, label="fingers RMS, °")
    bottom.plot(t, _nan(curves["finger_max_deg"]), color=_FINGER, lw=0.8, ls=":", label="fingers max, °")
    if any(v is not None for v in curves["wrist_mm"]):
        bottom.plot(t, _nan(curves["wrist_mm"]), color=_WRIST, lw=1.0, label="wrist, mm")
    bottom.set_ylabel("correction", fontsize=8)
    bottom.set_xlabel("time, s", fontsize=8)
    bottom.legend(fontsize=7, loc="upper left", frameon=False, ncol=3)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=PLOT_DPI, metadata={"Software": None})
    plt.close(fig)
    return buffer.getvalue()


def ranked(records: list[dict]) -> list[dict]:
    """The corrected trials' records, largest correction first (ties by id)."""
    done = [r for r in records if r["status"] == "ok" and "size" in (r.get("correction") or {})]
    return sorted(done, key=lambda r: (-float(r["correction"]["size"] or 0.0), r["id"]))


def _tracking(t: dict) -> str:
    return f"{t['track']}; {num(t['within_1cm'] * 100 if t['within_1cm'] is not None else None, 1)} % ≤ 1 cm"


def _row(rank: int, record: dict) -> list[str]:
    c = record["correction"]
    wrist = "—"
    if c.get("wrist_position_rms_mm") is not None:
        wrist = f"{num(c['wrist_position_rms_mm'], 1)} mm, {num(c['wrist_rotation_rms_deg'])}°"
    return [
        str(rank),
        record["id"],
        c["status"],
        num(c["size"]),
        f"{num(c['finger_rms_deg'])}° ({num(c['finger_max_deg'])}° max)",
        f"{num(c['finger_vs_replay_tracking'])}×",
        wrist,
        _tracking(c["before"]),
        _tracking(c["after"]),
        f"implausible: {c['implausible']}" if c.get("implausible") else "",
    ]


def _trial_section(rank: int, record: dict, plot: str) -> str:
    c = record["correction"]
    lines = [
        f"<h3 id='t{rank}'>{rank}. {esc(record['id'])}</h3>",
        f"<p>{esc(c['status'])}: {esc(c['reason'])}</p>",
    ]
    if c.get("implausible"):
        lines.append(f"<p><b>implausible</b>: {esc(c['implausible'])}</p>")
    lines.extend(f"<p><b>in the air</b>: {esc(u['text'])}</p>" for u in c.get("unsupported") or ())
    lines.append(plot)
    return "\n".join(lines)


def correction_html(records: list[dict], plots: bool = True) -> str:
    """The page of a correction run's records (plots embedded when ``plots`` and matplotlib allow)."""
    order = ranked(records)
    headers = ["#", "trial", "verdict", "size", "fingers RMS", "× replay", "wrist RMS", "before", "after", ""]
    table = simple_table(
        headers, [_row(i, r) for i, r in enumerate(order, 1)], numeric=[True, False, False, True]
    )
    sections, note = [], ""
    for i, record in enumerate(order, 1):
        image = ""
        if plots:
            try:
                data = base64.b64encode(correction_plot(record)).decode("ascii")
                image = f"<img alt='before/after' src='data:image/png;base64,{data}'>"
            except HandsimError as exc:
                plots, note = False, f"<p class='note'>no plots: {esc(exc)}</p>"
        sections.append(_trial_section(i, record, image))
    other = [r for r in records if r not in order]
    rest = simple_table(
        ["trial", "why not corrected"],
        [[r["id"], _why_not(r)] for r in sorted(other, key=lambda r: r["id"])],
    )
    large = sum(bool(r["correction"].get("implausible")) for r in order)
    return (
        "<!doctype html><html lang='en'><head><meta charset='utf-8'><title>handsim correct</title>"
        f"<style>{CSS}</style></head><body><header class='top'><h1>handsim correct</h1>"
        f"<div class='sub'>{len(order)} trials corrected, {large} implausible (a large correction), "
        f"{len(other)} not corrected · terms: handsim's docs/concepts.md</div></header><main>"
        "<section class='block'><h2>Trials by correction size</h2><p class='note'>size: the correction "
        "against its plausibility bounds (finger RMS over twice pure replay's joint tracking error, wrist "
        f"RMS over 10 mm and 5°); above 1 it is large.</p>{table}</section>"
        f"<section class='block'><h2>Before and after</h2>{note}{''.join(sections)}</section>"
        f"<section class='block'><h2>Not corrected</h2>{rest}</section></main></body></html>\n"
    )


def _why_not(record: dict) -> str:
    if record["status"] == "error":
        error = record.get("error") or {}
        return f"failed: {error.get('type')}: {error.get('message')}"
    c = record.get("correction") or {}
    return f"{c.get('status')}: {c.get('reason')}"


def write_correction_report(out_dir: str | Path) -> Path:
    """Write ``OUT/correction.html`` from ``OUT/records.jsonl`` and return its path.

    Plots need matplotlib; without it the page says so and has the table alone.
    """
    out = Path(out_dir)
    return write_atomic(out / REPORT_FILE, correction_html(read_records(out)).encode("utf-8"))
