"""The replay plot's contacts-per-link raster: readable inside the hold window, and a colour scale that
says something."""

from __future__ import annotations

import numpy as np
import pytest

from handsim.viz.replay_plots import ReplayCurves, _mark, contacts_label, draw_contacts

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
from matplotlib import pyplot as plt  # noqa: E402  the backend first


def _curves(contacts: np.ndarray, window: tuple[float, float] | None) -> ReplayCurves:
    n, links = contacts.shape
    nan = np.full(n, np.nan)
    return ReplayCurves(
        times=np.arange(n) * 0.01,
        penetration=nan,
        links=tuple(f"link{i}" for i in range(links)),
        link_contacts=contacts,
        tracking_error=nan,
        tips=(),
        tip_error=np.zeros((n, 0)),
        objects=("obj",),
        drift=None,
        rotation_drift=None,
        slip=None,
        release=None,
        hold_window=window,
        lost_at=None,
        diverged_at=None,
    )


@pytest.mark.parametrize(("most", "scale"), [(0, "(none)"), (1, "(1 per cell)"), (4, "(dark 1 … bright 4)")])
def test_contacts_label_names_a_scale_that_means_something(most, scale):
    assert contacts_label(most) == f"contacts per link\n{scale}"


def test_contacts_raster_stays_visible_inside_the_hold_window(tmp_path):
    rng = np.random.default_rng(0)
    contacts = rng.integers(0, 4, size=(100, 6))  # 1 s, counts 0 … 3 in varied cells
    curves = _curves(contacts, window=(0.3, 0.8))
    fig, ax = plt.subplots(figsize=(6, 2), dpi=100)
    draw_contacts(ax, curves)
    _mark(ax, curves)  # as plot_replay does: the window's shade after the raster
    assert ax.get_ylabel() == "contacts per link\n(dark 1 … bright 3)"
    ax.set_axis_off()
    fig.subplots_adjust(0, 0, 1, 1)  # the axes fill the image: x in pixels is linear in time
    path = tmp_path / "raster.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    image = plt.imread(path)[..., :3]
    width = image.shape[1]
    x0, x1 = ax.get_xlim()
    inside = slice(int((0.4 - x0) / (x1 - x0) * width), int((0.7 - x0) / (x1 - x0) * width))
    window = image[:, inside].reshape(-1, 3)
    assert len(np.unique(window, axis=0)) >= 4  # the counts' colours, not one flat shade
