"""Per-frame curves of a replay, JSON-ready, and their plot (matplotlib: ``pip install "handsim[plot]"``).

:func:`replay_curves` reduces a :class:`~handsim.sim.replay.ReplayResult`'s per-frame metrics to the curves
people look at (penetration, contacts per hand link, tracking and fingertip errors, object drift or slip);
:func:`plot_replay` draws them over time with the hold window and the release marked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handsim.sim.curves import CURVES, DEG, MM, row_max, tracking_error
from handsim.sim.curves import slip as slip_curve
from handsim.sim.replay import ReplayResult
from handsim.viz.plotting import pyplot, save_figure


@dataclass(frozen=True)
class ReplayCurves:
    """Per-frame curves of a replay (N frames; NaN where a value does not exist).

    Attributes:
        times: Trajectory time of each frame, s (N,).
        penetration: Deepest hand–object penetration, m (N,); NaN without objects (not judged).
        links: Hand links with collision geometry (none without objects: no hand–object contact to count).
        link_contacts: Contacts per hand link with any object part (N, links).
        tracking_error: RMS over the hand's DoFs of achieved minus target angle, rad (N,)
            (:func:`handsim.sim.curves.tracking_error`).
        tips: Fingertip sites.
        tip_error: Distance of each fingertip from where the targets put it, m (N, tips).
        objects: Object labels (their scene prefixes without ``/``: ``obj``, ``obj0`` …).
        drift: Recorded scenario: object position error against its track, m (N, objects), else None.
        rotation_drift: Recorded scenario: object rotation error, rad (N, objects), else None.
        slip: Glove scenario: the object's displacement relative to the hand root since release, m (N,);
            NaN before release; None without a hold outcome.
        release: Time the object's support was switched off, s, or None.
        hold_window: The hold window (start, stop), s, or None.
        lost_at: Time the object was lost, s, or None.
        diverged_at: Time of the last frame before the divergence, s, or None.
        self_penetration: Without objects (a hand-only sequence): the simulated hand through itself, m (N,);
            else None.
    """

    times: np.ndarray
    penetration: np.ndarray
    links: tuple[str, ...]
    link_contacts: np.ndarray
    tracking_error: np.ndarray
    tips: tuple[str, ...]
    tip_error: np.ndarray
    objects: tuple[str, ...]
    drift: np.ndarray | None
    rotation_drift: np.ndarray | None
    slip: np.ndarray | None
    release: float | None
    hold_window: tuple[float, float] | None
    lost_at: float | None
    diverged_at: float | None
    self_penetration: np.ndarray | None = None

    def to_dict(self) -> dict:
        """JSON-ready curves in the units their keys name (``_s``, ``_mm``, ``_deg``); NaN is None."""

        def col(x: np.ndarray, scale: float = 1.0) -> list:
            return [None if not math.isfinite(v) else v for v in (np.asarray(x, float) * scale).tolist()]

        out = {
            "times_s": col(self.times),
            "penetration_mm": col(self.penetration, MM),
            "contacts_per_link": {
                n: self.link_contacts[:, i].astype(int).tolist() for i, n in enumerate(self.links)
            },
            "tracking_error_deg": col(self.tracking_error, DEG),
            "tip_error_mm": {n: col(self.tip_error[:, i], MM) for i, n in enumerate(self.tips)},
            "max_tip_error_mm": col(row_max(self.tip_error), MM),
            "drift_mm": None,
            "rotation_drift_deg": None,
            "slip_mm": None if self.slip is None else col(self.slip, MM),
            "release_s": self.release,
            "hold_window_s": None if self.hold_window is None else list(self.hold_window),
            "lost_at_s": self.lost_at,
            "diverged_at_s": self.diverged_at,
            "self_penetration_mm": None if self.self_penetration is None else col(self.self_penetration, MM),
        }
        if self.drift is not None and self.rotation_drift is not None:
            out["drift_mm"] = {n: col(self.drift[:, i], MM) for i, n in enumerate(self.objects)}
            out["rotation_drift_deg"] = {
                n: col(self.rotation_drift[:, i], DEG) for i, n in enumerate(self.objects)
            }
        return out


def _object_labels(parts: list[str], part_object: np.ndarray, count: int) -> tuple[str, ...]:
    labels = []
    for i in range(count):
        first = next((p for p, o in zip(parts, part_object, strict=False) if o == i), f"obj{i}/")
        labels.append(first.split("/", 1)[0])
    return tuple(labels)


def replay_curves(result: ReplayResult) -> ReplayCurves:
    """The per-frame curves of a replay result.

    Args:
        result: A replay's result.

    Returns:
        The curves.
    """
    f = result.frames
    n = f.times.shape[0]
    nobj = f.object_position_error.shape[1]
    recorded = bool(np.isfinite(f.object_position_error).any())
    slip = None
    hold = result.hold
    if hold is not None and nobj:
        slip = slip_curve(f.object_in_hand[:, 0], int(np.searchsorted(f.times, hold.released_at - 1e-9)))
    diverged_at = None
    if result.diverged is not None and n:
        diverged_at = float(f.times[-1])
    touching = nobj and f.contact_count.size
    return ReplayCurves(
        times=f.times,
        penetration=f.penetration if nobj else np.full(n, np.nan),
        links=tuple(result.scene.get("links", ())) if nobj else (),
        link_contacts=f.contact_count.sum(axis=2) if touching else np.zeros((n, 0), int),
        tracking_error=tracking_error(f.tracking_error),
        tips=tuple(result.scene.get("tips", ())),
        tip_error=f.tip_error,
        objects=_object_labels(list(result.scene.get("parts", ())), f.part_object, nobj),
        drift=f.object_position_error if recorded else None,
        rotation_drift=f.object_rotation_error if recorded else None,
        slip=slip,
        release=None if hold is None else hold.released_at,
        hold_window=None if hold is None else tuple(hold.window),
        lost_at=None if hold is None else hold.lost_at,
        diverged_at=diverged_at,
        self_penetration=None if nobj else f.self_penetration,
    )


HOLD_SHADE = "#e8f4e8"
"""Fill of the hold window behind the curves."""
HOLD_EDGE = "#2e7d32"
"""Colour of the hold window's edges on the contacts raster, where the raster covers the shade."""


def _mark(ax, curves: ReplayCurves) -> None:
    """Mark the hold window, the release, the loss and a divergence on one panel.

    The window's shade goes under everything (``zorder=-1``: above only the axes' background), so it never
    hides a curve or the contacts raster; on the raster, cells with contacts cover it, so
    :func:`draw_contacts` draws the window's edges too.
    """
    if curves.hold_window is not None:
        ax.axvspan(*curves.hold_window, color=HOLD_SHADE, lw=0, zorder=-1)
    if curves.release is not None:
        ax.axvline(curves.release, color="#2e7d32", lw=0.9, ls="--")
    if curves.lost_at is not None:
        ax.axvline(curves.lost_at, color="#c0392b", lw=0.9, ls=":")
    if curves.diverged_at is not None:
        ax.axvline(curves.diverged_at, color="#c0392b", lw=1.4)


def contacts_label(most: int) -> str:
    """The contacts raster's axis label, with its colour scale.

    Args:
        most: The largest contact count of any link in any frame.

    Returns:
        ``"contacts per link"`` and, on a second line, the scale: ``"(dark 1 … bright N)"`` when counts
        differ, ``"(1 per cell)"`` when every coloured cell holds one contact, ``"(none)"`` without any (a
        scale from 1 to 1 would say nothing).
    """
    if most <= 0:
        scale = "(none)"
    elif most == 1:
        scale = "(1 per cell)"
    else:
        scale = f"(dark 1 … bright {most})"
    return f"contacts per link\n{scale}"


def draw_contacts(ax, curves: ReplayCurves) -> None:
    """Draw the contacts-per-link raster on ``ax``: one row per link, one column per frame, 0 blank.

    Colours run from 1 (dark) to the largest count (bright). The hold window's shade lies under the raster
    (:func:`_mark`), so the raster stays readable inside it; its edges are drawn over the raster as lines.

    Args:
        ax: A matplotlib axes.
        curves: The replay's curves.
    """
    t, nlinks = curves.times, len(curves.links)
    most = int(curves.link_contacts.max()) if curves.link_contacts.size else 0
    if nlinks and t.size:
        dt = float(t[1] - t[0]) if t.size > 1 else 1.0
        counts = np.ma.masked_equal(curves.link_contacts.T, 0)
        ax.imshow(
            counts, aspect="auto", interpolation="nearest", cmap="viridis", origin="lower",
            extent=(t[0] - dt / 2, t[-1] + dt / 2, -0.5, nlinks - 0.5), vmin=1, vmax=max(most, 1),
        )  # fmt: skip
        ax.set_yticks(range(nlinks), curves.links, fontsize=max(4, 8 - nlinks // 12))
        if curves.hold_window is not None:
            for edge in curves.hold_window:
                ax.axvline(edge, color=HOLD_EDGE, lw=1.0, zorder=3)
    ax.set_ylabel(contacts_label(most), fontsize=8)


def plot_replay(result: ReplayResult, path: str | Path, *, title: str | None = None) -> Path:
    """Plot a replay: penetration, contacts per link, tracking and tip errors, drift (or slip) over time.

    The hold window is shaded green (under the curves and the contacts raster, whose window edges are
    green lines), the release is a dashed green line, the moment the object was lost a
    dotted red line and a divergence a solid red line.

    Args:
        result: A replay's result.
        path: Image file to write (``.png``, ``.svg``, ``.pdf``).
        title: Figure title (default: the trajectory's file name and the scenario).

    Returns:
        The path written.

    Raises:
        HandsimError: matplotlib is not installed.
    """
    plt = pyplot()
    c = replay_curves(result)
    t = c.times
    nlinks = len(c.links)
    heights = [1.0, max(1.2, 0.11 * nlinks), 1.0, 1.0]
    fig, axes = plt.subplots(4, 1, figsize=(9, 2.0 * sum(heights)), sharex=True, height_ratios=heights)
    ax_pen, ax_con, ax_err, ax_obj = axes

    hand_only = c.self_penetration is not None
    ax_pen.plot(t, (c.self_penetration if hand_only else c.penetration) * MM, lw=1.0, color="#1f4e8c")
    ax_pen.axhline(1.0, lw=0.7, ls="--", color="#7f8c8d")
    ax_pen.set_ylabel("hand through\nitself (mm)" if hand_only else "penetration\n(mm)", fontsize=8)

    draw_contacts(ax_con, c)

    ax_err.plot(t, c.tracking_error * DEG, lw=1.0, color="#1f4e8c", label=CURVES["tracking_error"].label)
    ax_err.set_ylabel("tracking\nerror (°)", fontsize=8)
    tips = ax_err.twinx()
    tips.plot(t, row_max(c.tip_error) * MM, lw=1.0, color="#e67e22", label=CURVES["tip_error"].label)
    tips.set_ylabel("tip error\n(mm)", fontsize=8, color="#e67e22")

    metrics = result.config.get("metrics", {})
    if c.drift is not None and c.rotation_drift is not None:
        for i, label in enumerate(c.objects):
            ax_obj.plot(t, c.drift[:, i] * MM, lw=1.0, label=f"{label} position (mm)")
        ax_obj.axhline(metrics.get("drift_tolerance", 0.01) * MM, lw=0.7, ls="--", color="#7f8c8d")
        ax_obj.set_ylabel("object drift\n(mm)", fontsize=8)
        rot = ax_obj.twinx()
        for i, label in enumerate(c.objects):
            rot.plot(t, c.rotation_drift[:, i] * DEG, lw=0.8, ls=":", label=f"{label} rotation (°)")
        rot.set_ylabel("rotation\ndrift (°)", fontsize=8)
        ax_obj.legend(fontsize=7, loc="upper left")
    elif c.slip is not None:
        limit = metrics.get("slip_limit", 0.02) * MM
        ax_obj.plot(t, c.slip * MM, lw=1.0, color="#8e44ad")
        ax_obj.axhline(limit, lw=0.7, ls="--", color="#7f8c8d")
        label = "slip in hand\n(mm)"
        if np.nanmax(c.slip, initial=0.0) * MM > 5 * limit:
            ax_obj.set_ylim(0, 5 * limit)  # the limit stays readable; a lost object slips far beyond it
            label += "\n(clipped)"
        ax_obj.set_ylabel(label, fontsize=8)
    else:
        ax_obj.set_ylabel("(no object\nmeasure)", fontsize=8)
    for ax in axes:
        _mark(ax, c)
        ax.tick_params(labelsize=7)
    ax_obj.set_xlabel("time (s)", fontsize=8)
    if title is None:
        source = Path(result.trajectory.get("source") or "replay").name
        title = f"{source} — {result.scene.get('scenario', '')} replay"
        if result.hold is not None:
            title += f"; held: {'yes' if result.hold.held else 'no'}"
        if result.diverged is not None:
            title += "; DIVERGED"
    fig.suptitle(title, fontsize=9)
    return save_figure(fig, path)
