"""Plots of trajectories (matplotlib, optional: ``pip install "handsim[plot]"``), written to image files.

:func:`plot_trajectory` draws one panel per DoF; given a glove recording's grasp segmentation
(:func:`handsim.glove.segmentation.segment_grasps`) it adds a wide panel on top with the summed finger
flexion and the episodes shaded (:func:`draw_episodes`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import HandsimError
from handsim.glove.segmentation import GraspSegmentation

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

PHASE_COLOURS = ("#e8eef7", "#f7eee8", "#eef7e8", "#f3e8f7", "#f7f5e8")

EPISODE_COLOURS = {"approach": "#eef3e2", "closure": "#f8dfb8", "hold": "#f0a848", "release": "#d9e4f2"}
"""Shading of an episode's phases in :func:`draw_episodes` (a truncated episode's are hatched grey)."""


def pyplot():
    """Matplotlib's ``pyplot`` on the file-only Agg backend (imported on first use: an optional extra).

    Raises:
        HandsimError: matplotlib is not installed (the message says how to install it).
    """
    try:
        import matplotlib  # lazy: optional extra handsim[plot]
    except ImportError as exc:
        raise HandsimError('plots need matplotlib: pip install "handsim[plot]"') from exc
    matplotlib.use("Agg")  # files only; never a window
    import matplotlib.pyplot as plt  # lazy: after choosing the Agg backend above

    return plt


def plot_trajectory(
    trajectory: Trajectory,
    path: str | Path,
    skeleton: Skeleton | None = None,
    segmentation: GraspSegmentation | None = None,
) -> Path:
    """One small panel per DoF: the target angle over time, phases shaded, invalid samples marked.

    Args:
        trajectory: The trajectory.
        path: Image file to write (``.png``, ``.svg``, ``.pdf``).
        skeleton: When given, each panel shows the DoF's limits as dashed lines.
        segmentation: The recording's grasp episodes: a wide panel above the DoFs shows the summed finger
            flexion with them shaded (:func:`draw_episodes`).

    Returns:
        The path written.

    Raises:
        HandsimError: matplotlib is not installed.
    """
    plt = pyplot()
    n = len(trajectory.dof_names)
    cols = min(5, n)
    rows = math.ceil(n / cols)
    top = 0 if segmentation is None else 2
    fig = plt.figure(figsize=(3.2 * cols, 1.9 * (rows + top)))
    grid = fig.add_gridspec(rows + top, cols)
    if segmentation is not None:
        draw_episodes(fig.add_subplot(grid[:top, :]), segmentation)
    axes = [[fig.add_subplot(grid[top + r, c]) for c in range(cols)] for r in range(rows)]
    t = trajectory.times
    invalid = ~np.asarray(trajectory.valid, bool) | ~np.isfinite(trajectory.targets)
    for i, name in enumerate(trajectory.dof_names):
        ax = axes[i // cols][i % cols]
        for k, phase in enumerate(trajectory.phases):
            ax.axvspan(t[phase.start], t[phase.stop - 1], color=PHASE_COLOURS[k % len(PHASE_COLOURS)], lw=0)
        y = np.degrees(trajectory.targets[:, i])
        ax.plot(t, np.where(invalid[:, i], np.nan, y), lw=1.0, color="#1f4e8c")
        if invalid[:, i].any():
            ax.plot(t[invalid[:, i]], np.zeros(int(invalid[:, i].sum())), "|", color="#c0392b", ms=6)
        if trajectory.filled is not None and trajectory.filled[:, i].any():
            f = trajectory.filled[:, i]
            ax.plot(t[f], y[f], ".", color="#e67e22", ms=2)
        if skeleton is not None and name in skeleton.dof_names:
            dof = skeleton.dofs[skeleton.dof_index(name)]
            for limit in (dof.lower, dof.upper):
                ax.axhline(math.degrees(limit), ls="--", lw=0.7, color="#7f8c8d")
        computed = " (computed)" if name in trajectory.computed else ""
        ax.set_title(name + computed, fontsize=8)
        ax.tick_params(labelsize=7)
        if ax is not axes[0][0]:
            ax.sharex(axes[0][0])
    for j in range(n, rows * cols):
        axes[j // cols][j % cols].axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("time (s)", fontsize=7)
    title = Path(trajectory.source).name if trajectory.source else "trajectory"
    phases = ", ".join(p.name for p in trajectory.phases)
    fig.suptitle(f"{title} — joint targets (degrees)" + (f"; phases: {phases}" if phases else ""), fontsize=9)
    return save_figure(fig, path)


def draw_episodes(ax: Axes, segmentation: GraspSegmentation) -> None:
    """The summed finger flexion over time with each grasp episode's phases shaded and numbered.

    Approach, closure, hold and release take :data:`EPISODE_COLOURS`; a truncated episode is hatched grey
    (never judged). An automatic segmentation also shows the open and closed flexion its thresholds are
    scaled by (dashed); a calibration sequence says so in the title.

    Args:
        ax: The axes to draw into.
        segmentation: The recording's segmentation (times and summed flexion included).
    """
    t, flexion = segmentation.times, segmentation.flexion
    for episode in segmentation.episodes:
        for phase in episode.phases:
            span = (t[phase.start], t[min(phase.stop, t.shape[0] - 1)])
            if episode.truncated:
                ax.axvspan(*span, facecolor="#eeeeee", edgecolor="#999999", hatch="///", lw=0)
            else:
                ax.axvspan(*span, color=EPISODE_COLOURS[phase.name], lw=0)
        middle = (t[episode.hold.start] + t[episode.hold.stop - 1]) / 2
        colour = "#555555" if episode.truncated else "#8a4b00"
        ax.text(middle, 1.0, str(episode.index), transform=ax.get_xaxis_transform(), ha="center", va="bottom",
                fontsize=6, color=colour)  # fmt: skip
    if segmentation.open_closed is not None:
        for level, label in zip(segmentation.open_closed, ("open", "closed"), strict=True):
            ax.axhline(level, ls="--", lw=0.7, color="#7f8c8d")
            ax.text(t[0], level, f" {label}", va="bottom", fontsize=6, color="#7f8c8d")
    ax.plot(t, flexion, lw=0.8, color="#1f4e8c")
    ax.set_xlim(t[0], t[-1])
    ax.set_ylabel("summed finger flexion (rad)", fontsize=7)
    ax.tick_params(labelsize=7)
    n, k = len(segmentation.episodes), len(segmentation.complete)
    what = (
        segmentation.calibration.text().split(":")[0]
        if segmentation.calibration is not None
        else f"{n} grasp episodes ({k} complete, {n - k} truncated), {segmentation.source}"
    )
    ax.set_title(f"{what}; shaded: approach, closure, hold (dark), release", fontsize=8)


def save_figure(fig: Figure, path: str | Path) -> Path:
    """Lay out ``fig``, write it to ``path`` (PNG/SVG/PDF by suffix, folders created), close it."""
    plt = pyplot()
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
