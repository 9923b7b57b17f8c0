"""Grids drawn for the paper: colour bars stay out of the neighbouring panels, single-hit walls stand out."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from crfmap.grid import OccupancyGrid  # noqa: E402
from crfstudy.plotting import OCCUPANCY_CMAP, imshow_extent, plot_roc, shared_colorbar, show_grid  # noqa: E402


def _boxes_overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


@pytest.mark.parametrize("layout", ["constrained", "tight"])
def test_colour_bars_do_not_run_into_the_next_panel(layout):
    grid = OccupancyGrid(np.linspace(0, 1, 400).reshape(20, 20), 0.1)
    fig, axes = plt.subplots(1, 3, figsize=(9, 2.8), layout=layout)
    for k, ax in enumerate(axes):
        show_grid(ax, grid, f"panel {k} with a title")
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    bars = [child for ax in axes for child in ax.child_axes]  # each panel's bar lives in its own coordinates
    assert len(bars) == 3
    for bar, right_neighbour in zip(bars[:2], axes[1:]):
        assert not _boxes_overlap(bar.get_tightbbox(renderer), right_neighbour.get_tightbbox(renderer))
    for ax, bar in zip(axes, bars):  # the bar does not reach its own panel's title, and is as tall as the grid
        assert not _boxes_overlap(bar.get_tightbbox(renderer), ax.title.get_window_extent(renderer))
        assert bar.get_position().height == pytest.approx(ax.get_position().height)
    plt.close(fig)


def test_a_shared_colour_bar_serves_a_row_of_panels():
    fig, axes = plt.subplots(1, 4, figsize=(10, 2.8), layout="constrained")
    images = [show_grid(ax, np.eye(8) * 0.75, colorbar=False, cells=True) for ax in axes]
    bar = shared_colorbar(fig, images[0], axes)
    assert len(fig.axes) == 5 and bar.ax.get_ylabel() == "P(occupied)"
    plt.close(fig)


def _lightness(rgb) -> float:
    """CIELAB L* of an sRGB colour."""
    linear = [c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in rgb[:3]]
    y = 0.2126 * linear[0] + 0.7152 * linear[1] + 0.0722 * linear[2]
    return 116 * y ** (1 / 3) - 16 if y > 0.008856 else 903.3 * y


def test_the_occupancy_colours_fall_in_lightness_and_separate_the_arctan_levels():
    levels = [_lightness(OCCUPANCY_CMAP(v)) for v in (0.0, 0.25, 0.5, 0.75, 1.0)]
    assert levels == sorted(levels, reverse=True)  # prints in grey: free light, occupied dark
    assert levels[2] - levels[3] >= 20  # a wall hit once (0.75) stands out against unknown (0.5)
    assert min(np.diff(levels[::-1])) >= 10


def test_coinciding_roc_curves_stay_visible():
    fig, ax = plt.subplots()
    plot_roc(ax, {"before": ([0, 0.5, 1], [0, 0.9, 1]), "after": ([0, 0.5, 1], [0, 0.9, 1])})
    first, second = ax.get_lines()[:2]
    assert first.get_linestyle() != second.get_linestyle() and second.get_linewidth() < first.get_linewidth()
    assert second.get_zorder() > first.get_zorder()
    plt.close(fig)


def test_imshow_extent_is_the_grids_bounds_in_matplotlibs_order():
    g = OccupancyGrid(np.full((3, 4), 0.5), resolution=0.25, origin=(-1.0, 2.0, 0.0))
    assert g.bounds() == (-1.0, 2.0, 0.0, 2.75)  # xmin, ymin, xmax, ymax
    assert imshow_extent(g) == (-1.0, 0.0, 2.0, 2.75)  # left, right, bottom, top
