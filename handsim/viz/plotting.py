"""Plots of trajectories (matplotlib, optional: ``pip install "handsim[plot]"``), written to image files."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from handsim.datatypes.skeleton import Skeleton
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import HandsimError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PHASE_COLOURS = ("#e8eef7", "#f7eee8", "#eef7e8", "#f3e8f7", "#f7f5e8")


def _pyplot():
    try:
        import matplotlib  # lazy: optional extra handsim[plot]
    except ImportError as exc:
        raise HandsimError('plots need matplotlib: pip install "handsim[plot]"') from exc
    matplotlib.use("Agg")  # files only; never a window
    import matplotlib.pyplot as plt  # lazy: after choosing the Agg backend above

    return plt


def plot_trajectory(trajectory: Trajectory, path: str | Path, skeleton: Skeleton | None = None) -> Path:
    """One small panel per DoF: the target angle over time, phases shaded, invalid samples marked.

    Args:
        trajectory: The trajectory.
        path: Image file to write (``.png``, ``.svg``, ``.pdf``).
        skeleton: When given, each panel shows the DoF's limits as dashed lines.

    Returns:
        The path written.

    Raises:
        HandsimError: matplotlib is not installed.
    """
    plt = _pyplot()
    n = len(trajectory.dof_names)
    cols = min(5, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 1.9 * rows), sharex=True, squeeze=False)
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
    for j in range(n, rows * cols):
        axes[j // cols][j % cols].axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("time (s)", fontsize=7)
    title = Path(trajectory.source).name if trajectory.source else "trajectory"
    phases = ", ".join(p.name for p in trajectory.phases)
    fig.suptitle(f"{title} — joint targets (degrees)" + (f"; phases: {phases}" if phases else ""), fontsize=9)
    return save_figure(fig, path)


def save_figure(fig: Figure, path: str | Path) -> Path:
    """Lay out ``fig``, write it to ``path`` (PNG/SVG/PDF by suffix, folders created), close it."""
    plt = _pyplot()
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
