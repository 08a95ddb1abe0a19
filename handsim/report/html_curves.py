"""A trial's curves in the HTML report: penetration, contacts per finger, object drift and tracking error.

Every chart shares the trial's time axis and its markers: the hold window as a band, the release, the loss
of the object and a divergence as vertical lines. A curve whose length does not match the times is left
out with a note instead of being drawn against the wrong times.
"""

from __future__ import annotations

from handsim.datatypes.fingers import groups_by_hand
from handsim.report.aggregate import number
from handsim.report.charts import Markers, Series, area_chart, line_chart
from handsim.report.markup import esc

_TIME = "time (s)"
"""Every chart's x label."""


def _checked_curves(curves: dict) -> tuple[dict, list[str]]:
    """The curves whose length matches ``time_s`` (others left out, with a note)."""
    n = len(curves.get("time_s") or [])
    kept, problems = {"time_s": curves.get("time_s") or []}, []
    for key in ("penetration_mm", "drift_mm", "tracking_error_deg", "self_penetration_mm"):
        values = curves.get(key)
        if values is not None and len(values) != n:
            problems.append(f"{key} has {len(values)} values for {n} times: not drawn")
            values = None
        kept[key] = values
    fingers = {}
    for name, values in (curves.get("contacts_per_finger") or {}).items():
        if len(values) == n:
            fingers[name] = values
        else:
            problems.append(f"contacts of {name} have {len(values)} values for {n} times: not drawn")
    kept["contacts_per_finger"] = fingers
    kept["stride"] = curves.get("stride")
    return kept, problems


def _markers(record: dict, curves: dict) -> Markers:
    """The hold window (a band) and the release, loss and divergence times (lines) of a trial's charts."""
    t = curves["time_s"]
    hold = record.get("hold") or {}
    spans, events = [], []
    window = hold.get("window")
    if isinstance(window, (list, tuple)) and len(window) == 2 and None not in window:
        spans.append((float(window[0]), float(window[1]), "hold window"))
    if number(hold.get("released_at")) is not None:
        events.append((float(hold["released_at"]), "release"))
    if number(hold.get("lost_at")) is not None:
        events.append((float(hold["lost_at"]), "lost"))
    track_lost = number((record.get("summary") or {}).get("track_lost_at_s"))
    if track_lost is not None:
        events.append((track_lost, "object lost"))
    diverged_at = number((record.get("diverged") or {}).get("frame"))
    if diverged_at is not None and t:
        stride = max(1, int(number(curves.get("stride")) or 1))  # curves keep every stride-th frame
        events.append((float(t[min(int(diverged_at) // stride, len(t) - 1)]), "diverged"))
    return Markers(vlines=events, vspans=spans)


def _depth_chart(curves: dict, marks: Markers) -> str:
    """Hand–object penetration, or a hand-only trial's self-penetration, with the 1 mm line."""
    t = curves["time_s"]
    self_penetration = curves.get("self_penetration_mm")  # a hand-only trial: no hand–object penetration
    depth, title = (
        (Series("self-penetration", t, self_penetration), "The hand through itself (deepest, simulated)")
        if self_penetration
        else (
            Series("penetration", t, curves.get("penetration_mm") or [None] * len(t)),
            "Deepest hand–object penetration",
        )
    )
    return line_chart(
        [depth],
        title=title,
        x_label=_TIME,
        y_label="mm",
        y_min=0.0,
        markers=Markers(hlines=[(1.0, "1 mm")], vlines=marks.vlines, vspans=marks.vspans),
    )


def _contact_charts(curves: dict, marks: Markers) -> list[str]:
    """Contacts per finger, stacked: one chart per hand (none for a hand-only trial without contacts)."""
    t = curves["time_s"]
    per_finger = curves.get("contacts_per_finger") or {}
    charts = []
    for hand, names in (groups_by_hand(per_finger) or {"": []}).items():
        if names or not curves.get("self_penetration_mm"):
            charts.append(
                area_chart(
                    t,
                    [(name[len(hand) + 1 :] if hand else name, per_finger[name]) for name in names],
                    title="Contacts per finger (stacked)" + (f", {hand} hand" if hand else ""),
                    x_label=_TIME,
                    y_label="contacts",
                    markers=marks,
                )
            )
    return charts


def _drift_chart(record: dict, curves: dict, marks: Markers) -> str:
    """The object's drift from its recorded track, with the run's tolerance; ``""`` without a track."""
    drift = curves.get("drift_mm")
    if not drift:
        return ""
    metrics = ((record.get("parameters") or {}).get("replay") or {}).get("metrics") or {}
    tolerance = number(metrics.get("drift_tolerance"))
    hlines = [(tolerance * 1000.0, "tolerance")] if tolerance is not None else []
    return line_chart(
        [Series("drift", curves["time_s"], drift)],
        title="Object drift from the recording",
        x_label=_TIME,
        y_label="mm",
        y_min=0.0,
        markers=Markers(hlines=hlines, vlines=marks.vlines, vspans=marks.vspans),
    )


def _tracking_chart(curves: dict, marks: Markers) -> str:
    """The joints' RMS tracking error."""
    t = curves["time_s"]
    return line_chart(
        [Series("tracking error", t, curves.get("tracking_error_deg") or [None] * len(t))],
        title="Joint tracking error (RMS over the joints)",
        x_label=_TIME,
        y_label="degrees",
        y_min=0.0,
        markers=marks,
    )


def curves_block(record: dict) -> str:
    """A trial's charts in a two-column grid, with why a chart is missing.

    Args:
        record: The trial's record (its ``curves``, ``hold``, ``summary``, ``diverged``, ``parameters``).

    Returns:
        The charts' ``<div class="grid2">`` and notes, or a note that the trial did not run.
    """
    curves, problems = _checked_curves(record.get("curves") or {})
    if not curves["time_s"]:
        return '<p class="note">No curves: the trial did not run.</p>'
    marks = _markers(record, curves)
    drift = _drift_chart(record, curves, marks)
    charts = [_depth_chart(curves, marks), *_contact_charts(curves, marks), *([drift] if drift else [])]
    charts.append(_tracking_chart(curves, marks))
    if curves.get("self_penetration_mm"):
        reason = (record.get("summary") or {}).get("hold_reason") or "not judged: no object"
        note = f'<p class="note">Hand–object penetration, contacts, hold and drift: {esc(reason)}.</p>'
    else:
        note = "" if drift else '<p class="note">No object track to drift from (glove scenario).</p>'
    note += "".join(f'<p class="problem">{esc(p)}</p>' for p in problems)
    return '<div class="grid2">' + "".join(f"<div>{c}</div>" for c in charts) + "</div>" + note
