"""One trial's section of the HTML report: its numbers, curves, frames, warnings, notes and error."""

from __future__ import annotations

import json
from collections.abc import Sequence

from handsim.report import fmt
from handsim.report.aggregate import number
from handsim.report.frames import FrameImage
from handsim.report.html_curves import curves_block
from handsim.report.markup import badge, esc, numbers, simple_table

SUMMARY_FIELDS: tuple[tuple[str, str, int | None], ...] = (
    # key, label, decimals (None: whole number / boolean / text)
    ("frames", "frames", None),
    ("duration_s", "duration s", 2),
    ("max_penetration_mm", "max penetration mm", 2),
    ("p95_penetration_mm", "p95 penetration mm", 2),
    ("frames_penetrating_over_1mm", "frames > 1 mm deep", None),
    ("contact_frames", "frames in contact", None),
    ("max_contact_links", "max links in contact", None),
    ("max_total_normal_force_n", "max normal force N", 2),
    ("truncated_contact_pairs", "truncated contact pairs", None),
    ("mean_tracking_error_deg", "mean tracking error °", 2),
    ("max_tracking_error_deg", "max tracking error °", 2),
    ("mean_tip_error_mm", "mean fingertip error mm", 1),
    ("max_tip_error_mm", "max fingertip error mm", 1),
    ("max_self_penetration_mm", "max self-penetration mm (hand through itself)", 2),
    ("p95_self_penetration_mm", "p95 self-penetration mm", 2),
    ("frames_self_penetrating_over_1mm", "frames self-penetrating > 1 mm", None),
    ("self_penetration_links", "deepest self-penetration between", None),
    ("self_penetration_at_s", "deepest self-penetration at s", 2),
    ("max_target_self_penetration_mm", "max self-penetration at the recorded targets mm", 2),
    ("target_self_penetration_links", "… between", None),
    ("target_self_penetration_at_s", "… at s", 2),
    ("hold_reason", "hold", None),
    ("drift_reason", "drift", None),
    ("held", "held", None),
    ("time_held_s", "time held s", 2),
    ("max_slip_mm", "max slip mm", 1),
    ("drop_mm", "drop mm", 1),
    ("mean_drift_mm", "mean drift mm", 1),
    ("max_drift_mm", "max drift mm", 1),
    ("final_drift_mm", "final drift mm", 1),
    ("within_tolerance", "frames on track %", None),
    ("mean_rotation_drift_deg", "mean rotation drift °", 1),
    ("max_rotation_drift_deg", "max rotation drift °", 1),
    ("max_articulation_drift_deg", "max hinge drift °", 1),
    ("mean_articulation_drift_deg", "mean hinge drift °", 1),
    ("final_articulation_drift_deg", "final hinge drift °", 1),
    ("stable", "stable (6 directions)", None),
    ("simulation_displacement_mm", "simulation displacement mm", 1),
    ("diverged", "diverged", None),
    ("warnings", "MuJoCo warnings", None),
)
_PER_HAND = (
    "max_penetration_mm", "frames_penetrating_over_1mm", "contact_frames", "max_contact_links",
    "max_total_normal_force_n", "mean_tracking_error_deg", "max_tracking_error_deg", "mean_tip_error_mm",
    "max_tip_error_mm",
)  # fmt: skip
SUMMARY_FIELDS += tuple(
    (f"{hand}/{key}", f"{hand}: {label}", decimals)
    for hand in ("right", "left")
    for key, label, decimals in SUMMARY_FIELDS
    if key in _PER_HAND
)
"""… and a two-hand trial's per-hand numbers, ``<hand>/<key>``, labelled ``<hand>: <label>``."""
_QUALITY_FIELDS = (
    ("frames", "frames", None),
    ("duration_s", "duration s", 2),
    ("limit_violations", "limit violations", None),
    ("limit_violation_max_deg", "worst limit violation °", 2),
    ("gaps_filled", "gaps filled", None),
    ("filled_fraction", "samples filled %", None),
    ("invalid_samples", "invalid samples left", None),
)


def _value(key: str, value: object, decimals: int | None) -> str:
    if isinstance(value, bool) or value is None:
        return fmt.yes_no(value)
    if isinstance(value, list):
        return fmt.text(" | ".join(map(str, value)))
    if key in ("within_tolerance", "filled_fraction"):
        x = number(value)
        return fmt.MISSING if x is None else f"{100 * x:.1f}"
    if isinstance(value, (int, float)):
        return fmt.integer(number(value)) if decimals is None else fmt.num(number(value), decimals)
    return fmt.text(value)


def _fields(values: dict, fields: Sequence[tuple[str, str, int | None]]) -> list[tuple[str, str]]:
    known = {k for k, _, _ in fields}
    items = [(label, _value(key, values[key], d)) for key, label, d in fields if key in values]
    items += [
        (k.replace("_", " "), _value(k, values[k], None if isinstance(values[k], int) else 3))
        for k in sorted(values)
        if k not in known
    ]
    return items


def _recording(quality: dict | None) -> str:
    """The recording's quality, and a glove recording's checks (annotation, phase source, spikes) if any.

    Those keys are None in the record of a recording that is not checked (Tzionas, ARCTIC): a row of dashes
    for each would only say that they do not apply.
    """
    if not quality:
        return ""
    known = {key for key, _, _ in _QUALITY_FIELDS}
    if all(value is None for key, value in quality.items() if key not in known):
        quality = {key: value for key, value in quality.items() if key in known}
    return "<h4>Recording</h4>" + numbers(_fields(quality, _QUALITY_FIELDS))


def _frames(images: Sequence[FrameImage]) -> str:
    if not images:
        return ""
    figures = []
    for image in images:
        caption = f"frame {fmt.text(image.frame)} · {fmt.num(number(image.time_s), 2)} s"
        if image.data_uri:
            body = f'<img src="{image.data_uri}" alt="{esc(caption)}">'
        else:
            body = f'<a href="{esc(image.path)}">{esc(image.path)}</a>'
        problem = f'<div class="problem">{esc(image.problem)}</div>' if image.problem else ""
        figures.append(f"<figure>{body}<figcaption>{esc(caption)}</figcaption>{problem}</figure>")
    return "<h4>Rendered frames</h4>" + '<div class="frames">' + "".join(figures) + "</div>"


def _warnings(record: dict) -> str:
    warnings = record.get("warnings") or []
    if not warnings:
        return ""
    rows = [
        [
            fmt.text(w.get("name")),
            fmt.text(w.get("step")),
            fmt.text(w.get("frame")),
            fmt.text(w.get("count")),
            fmt.yes_no(w.get("diverged")),
            fmt.text(w.get("message") or w.get("info")),
        ]
        for w in warnings
    ]
    return "<h4>MuJoCo warnings</h4>" + simple_table(
        ["warning", "step", "frame", "count", "diverged", "message"], rows, [False, True, True, True]
    )


def _hold(record: dict) -> str:
    hold = record.get("hold")
    if not hold:
        return ""
    window = hold.get("window") or [None, None]
    items = [
        ("released at s", fmt.num(number(hold.get("released_at")), 3)),
        ("hold window s", f"{fmt.num(number(window[0]), 2)} – {fmt.num(number(window[1]), 2)}"),
        ("held", "not judged" if hold.get("held") is None else fmt.yes_no(hold.get("held"))),
        ("lost at s", fmt.num(number(hold.get("lost_at")), 3)),
        ("why lost" if hold.get("held") is False else "why not judged", fmt.text(hold.get("reason"))),
        ("robustness", fmt.num(number((record.get("summary") or {}).get("hold_robustness")))),
        (
            "gravity directions held at release",
            fmt.integer(number((record.get("summary") or {}).get("release_directions_held"))),
        ),
    ]
    summary = record.get("summary") or {}
    factors = summary.get("hold_robustness_factors") or {}
    if factors:
        items.insert(
            6,
            (
                "robustness by factor (held of judged)",
                "; ".join(f"{name} {f.get('held')} of {f.get('judged')}" for name, f in factors.items()),
            ),
        )
    return (
        "<h4>Hold outcome</h4>"
        + _episode(record.get("episode"))
        + numbers(items)
        + _grip(record.get("grip"))
        + _closure(summary)
    )


def _episode(episode: dict | None) -> str:
    """Which grasp episode of its recording a glove trial replays (frames of the recording)."""
    if not episode:
        return ""
    phases = ", ".join(
        f"{name} {start}–{stop - 1}" for name, (start, stop) in (episode.get("phases") or {}).items()
    )
    source = "the annotated grasp phase" if episode.get("source") == "annotation" else "the finger flexion"
    span = f"{episode.get('start')}–{episode.get('stop', 1) - 1}"
    text = (
        f"Grasp episode {episode.get('index')}: frames {span} of the recording ({phases}), found from "
        f"{source}; times are the episode's own."
    )
    return f'<p class="note">{esc(text)}</p>'


def _grip(grip: dict | None) -> str:
    """The grip check beside the verdict: what touched, what opposed, the deepest link, the forces."""
    if not grip:
        return ""
    pair = grip.get("opposing_links")
    window = grip.get("window") or [None, None]
    items = [
        ("links touching", ", ".join(grip.get("links") or []) or "none"),
        ("opposition (share of frames in force closure)", fmt.num(number(grip.get("opposition")))),
        ("opposing links", " against ".join(pair) if pair else "none"),
        ("examined", f"{fmt.integer(number(grip.get('frames')))} frames, {fmt.num(number(window[0]), 2)} – "
         f"{fmt.num(number(window[1]), 2)} s"),
        ("deepest link", fmt.text(grip.get("deepest_link"))),
        ("its depth mm (limit)", f"{fmt.num(number(grip.get('max_depth_mm')), 1)} "
         f"({fmt.num(number(grip.get('depth_limit_mm')), 1)})"),
        ("grip force N (what the servos can press with)", f"{fmt.num(number(grip.get('grip_force')), 1)} "
         f"({fmt.num(number(grip.get('force_limit')), 1)} + weight {fmt.num(number(grip.get('weight')))})"),
    ]  # fmt: skip
    return "<h4>Grip check</h4>" + numbers(items)


def _track(record: dict) -> str:
    """The verdict on a recorded object's track, and what the checks before the run found."""
    summary = record.get("summary") or {}
    if summary.get("track") is None:
        return ""
    starts = {
        k.removesuffix("start_penetration_mm").rstrip("/") or "hand": v
        for k, v in summary.items()
        if k.endswith("start_penetration_mm")
    }
    untouched = summary.get("track_untouched_hands") or []
    items = [
        ("verdict", fmt.text(summary.get("track"))),
        ("reason", fmt.text(summary.get("track_reason"))),
        ("lost at s", fmt.num(number(summary.get("track_lost_at_s")), 2)),
        ("where it went", fmt.text(summary.get("track_lost_how"))),
        ("manipulated frames", fmt.integer(number(summary.get("track_manipulated_frames")))),
        ("of them within tolerance", fmt.num(number(summary.get("track_followed_fraction")))),
        ("hands that never touch it", ", ".join(h or "hand" for h in untouched) or "none"),
        ("ends on the floor", ", ".join(summary.get("track_on_floor") or []) or "no"),
        *((f"{hand} starts inside the object mm", fmt.num(number(v), 1)) for hand, v in starts.items()),
    ]
    return "<h4>Object track</h4>" + numbers(items)


def _closure(summary: dict) -> str:
    """How far the recorded closing passes the object: recording-quality numbers of a glove trial."""
    items = [
        ("flexion fraction where the object fits", fmt.num(number(summary.get("fit_fraction")))),
        ("grip normal force N", fmt.num(number(summary.get("grip_normal_force_n")), 1)),
        ("grip servo torque N·m", fmt.num(number(summary.get("grip_servo_torque_nm")))),
        ("gravity directions the grip resists", fmt.integer(number(summary.get("grip_directions_held")))),
        (
            "hand self-penetration at closure mm",
            fmt.num(number(summary.get("self_penetration_at_closure_mm")), 1),
        ),
    ]
    if all(value == fmt.MISSING for _, value in items):
        return ""
    return "<h4>Recorded closure</h4>" + numbers(items)


def _stability(record: dict) -> str:
    stability = record.get("stability")
    if not stability:
        return ""
    rows = [
        [
            fmt.text(d.get("direction")),
            fmt.yes_no(d.get("success")),
            fmt.num(
                None if number(d.get("displacement")) is None else 1000 * number(d.get("displacement")), 1
            ),
            fmt.num(number(d.get("rotation_deg")), 1),
            fmt.text(d.get("failure")),
        ]
        for d in stability.get("directions") or []
    ]
    displacement = number(stability.get("simulation_displacement"))
    head = numbers(
        [
            ("all directions held", fmt.yes_no(stability.get("success"))),
            ("simulation displacement mm", fmt.num(None if displacement is None else 1000 * displacement, 1)),
        ]
    )
    return (
        "<h4>Grasp stability</h4>"
        + head
        + (
            simple_table(
                ["gravity", "held", "displacement mm", "rotation °", "failure"],
                rows,
                [False, False, True, True],
            )
            if rows
            else ""
        )
    )


def _flags(record: dict) -> str:
    flags = [f for f in record.get("flags") or [] if isinstance(f, dict)]
    if not flags:
        return ""
    items = "".join(
        f"<li><strong>{esc(fmt.text(f.get('code')))}</strong> "
        f"({'not valid' if f.get('invalid') else 'a note'}): {esc(fmt.text(f.get('reason')))}</li>"
        for f in flags
    )
    return f'<h4>Plausibility flags</h4><ul class="plain">{items}</ul>'


def _error(record: dict) -> str:
    error = record.get("error")
    if not error:
        return ""
    trace = error.get("traceback")
    details = f"<details><summary>traceback</summary><pre>{esc(trace)}</pre></details>" if trace else ""
    return (
        f'<div class="reason error"><strong>{esc(fmt.text(error.get("type")))}</strong>: '
        f"{esc(fmt.text(error.get('message')))}</div>{details}"
    )


def _provenance(record: dict) -> str:
    inputs = [
        [fmt.text(i.get("role")), fmt.text(i.get("path")), fmt.text(i.get("sha256"))]
        for i in record.get("inputs") or []
    ]
    timing = record.get("timing") or {}
    items = [("model sha256", fmt.text(record.get("model_sha256")))]
    items += [(f"{k} s", fmt.num(number(v), 2)) for k, v in sorted(timing.items())]
    trial = json.dumps(record.get("trial"), indent=1, sort_keys=True)
    return (
        "<details><summary>inputs, model hash, timing and trial definition</summary>"
        + simple_table(["role", "path", "sha256"], inputs)
        + numbers(items)
        + f"<pre>{esc(trial)}</pre></details>"
    )


def trial_section(record: dict, row: dict, images: Sequence[FrameImage], trials: int) -> str:
    """The section of one trial.

    Args:
        record: The trial's record.
        row: Its entry in the summary's ``trials`` (anchor, rank, reason, outcome).
        images: Its rendered frames (:func:`~handsim.report.frames.load_frames`).
        trials: How many trials the report has (for "rank k of n").

    Returns:
        A ``<section id="trial-…">`` element.
    """
    meta = record.get("meta") or {}
    first = ("object", "grasp", "grasp_id", "action", "scenario", "actor", "sequence")
    order = [k for k in first if k in meta] + sorted(set(meta) - set(first))
    facts = [f"kind {record.get('kind')}"] + [
        f"{k.replace('_', ' ')} {', '.join(map(str, v)) if isinstance(v, list) else v}"
        for k in order
        if (v := meta[k]) is not None
    ]
    tier_class = {"error": "error", "diverged": "diverged"}.get(record["status"], "")
    reason = (
        f'<div class="reason {tier_class}">{esc(row["reason"])}</div>'
        if row["outcome"] in ("not held", "lost", "not judged", "flagged", "diverged")
        else ""
    )
    diverged = record.get("diverged") or {}
    if diverged.get("message"):
        reason += f'<p class="note">{esc(diverged["message"])}</p>'
    summary = record.get("summary")
    quality = record.get("trajectory_quality")
    notes = record.get("notes") or []
    parts = [
        f'<section class="trial" id="{esc(row["anchor"])}">',
        '<a class="top" href="#trials">↑ all trials</a>',
        f"<h3>{esc(record['id'])} {badge(row['outcome'])}"
        f'<span class="rank">rank {row["rank"]} of {trials} (1 = worst)</span></h3>',
        f'<div class="meta">{esc(" · ".join(facts))}</div>',
        reason,
        _error(record),
        _flags(record),
        numbers(_fields(summary, SUMMARY_FIELDS)) if summary else "",
        _recording(quality),
        curves_block(record),
        _frames(images),
        _hold(record),
        _track(record),
        _stability(record),
        _warnings(record),
        ('<h4>Notes</h4><ul class="plain">' + "".join(f"<li>{esc(n)}</li>" for n in notes) + "</ul>")
        if notes
        else "",
        _provenance(record),
        "</section>",
    ]
    return "".join(parts)
