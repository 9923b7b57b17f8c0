"""crfstudy.experiments.beyond_figures: a metric (J, K) diagram and before/after maps with a colour bar and zoom."""
import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

from crfstudy.experiments.beyond_figures import before_after_figure, phase_diagram_figure  # noqa: E402


def test_phase_diagram_draws_unevenly_spaced_couplings_where_they_lie():
    couplings, strengths = [0.0, 0.1, 0.44, 1.15], [0.5, 2.0]
    d = {"intel": {"brier": np.arange(8.0).reshape(4, 2), "wall_recall": np.ones((4, 2))}}
    fig = phase_diagram_figure(d, couplings, strengths, critical=0.4407)
    ax = fig.axes[0]
    assert [t for t in ax.get_xticks()] == couplings  # ticks at the values, not at their indices
    assert np.allclose(ax.get_xlim(), (-0.05, 1.505))  # half a step beyond the first and last samples
    (line,) = ax.get_lines()
    assert line.get_xdata()[0] == 0.4407
    mesh = ax.collections[0]
    assert np.array_equal(np.asarray(mesh.get_array()).reshape(2, 4), d["intel"]["brier"].T)


def test_before_after_has_one_colour_bar_and_the_zoomed_square_below_each_map():
    p = np.full((500, 600), 0.5)
    p[200, 100:500] = 0.9
    fig = before_after_figure({"raw": p, "refined": p}, "intel", (150, 250, 200, 300))
    maps = [ax for ax in fig.axes if ax.get_title().startswith("intel: ")]
    zooms = [ax for ax in fig.axes if ax.get_title() == "the outlined square, every cell"]
    assert len(maps) == 2 and len(zooms) == 2
    assert len([ax for ax in fig.axes if ax.get_xlabel() == "P(occupied)"]) == 1
    for ax, zoom in zip(maps, zooms):
        (outline,) = ax.patches
        assert outline.get_xy() == (199.5, 149.5) and (outline.get_width(), outline.get_height()) == (100, 100)
        (image,) = zoom.get_images()
        assert image.get_array().shape == (100, 100)  # every cell of the window, not pooled
        assert image.get_extent() == [199.5, 299.5, 149.5, 249.5]


def test_densest_window_finds_the_walls():
    from crfstudy.experiments.beyond_figures import densest_window

    walls = np.zeros((300, 400), bool)
    walls[250:260, 330:390] = True
    y0, y1, x0, x1 = densest_window(walls, 80)
    assert y0 <= 250 and y1 >= 260 and x0 <= 330 and x1 >= 390 and (y1 - y0, x1 - x0) == (80, 80)
