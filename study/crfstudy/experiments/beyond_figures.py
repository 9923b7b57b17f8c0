"""Notebook 10's figures that need more than a few lines: the (J, K) phase diagram and the before/after maps.

>>> import matplotlib; matplotlib.use("Agg")
>>> d = {"intel": {"brier": np.ones((3, 2)), "wall_recall": np.ones((3, 2))}}
>>> fig = phase_diagram_figure(d, [0.1, 0.2, 0.6], [0.5, 2.0], critical=0.44)
>>> [round(float(t), 2) for t in fig.axes[0].get_xlim()]
[0.05, 0.8]
"""
from __future__ import annotations

import numpy as np

from crfstudy.plotting import OCCUPANCY_CMAP, shared_colorbar, show_grid


def _edges(values) -> np.ndarray:
    """Cell edges around sampled values on a metric axis: midpoints inside, half a step beyond the ends.

    >>> np.round(_edges([0.1, 0.2, 0.6]), 6).tolist()
    [0.05, 0.15, 0.4, 0.8]
    """
    v = np.asarray(values, dtype=float)
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = (v[1:] + v[:-1]) / 2
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def spaced_labels(values, span: float, min_gap: float = 0.06) -> list:
    """Tick labels for sampled ``values`` on an axis ``span`` long: a value closer than ``min_gap`` of the span to
    the last labelled one gets a tick without a label (the labels of 0.3, 0.35 and 0.44 ran into each other).

    >>> spaced_labels([0, 0.1, 0.2, 0.3, 0.35, 0.44, 0.6, 1.15], span=1.55)
    ['0', '0.1', '0.2', '0.3', '', '0.44', '0.6', '1.15']
    """
    labels, last = [], None
    for v in values:
        keep = last is None or v - last >= min_gap * span
        labels.append(f"{v:g}" if keep else "")
        last = v if keep else last
    return labels


def phase_diagram_figure(diagrams, couplings, link_strengths, critical):
    """Brier score and wall recall over the sampled (coupling J, link strength K), one column per recording.

    Both axes are metric (each sample a cell around its value, so unevenly spaced samples are drawn
    where they lie) and the critical coupling is a dashed line at its value.
    """
    import matplotlib.pyplot as plt

    # a smaller canvas for the same page width: its text prints larger (at four by seven inches a column it came
    # out at four points)
    fig, axes = plt.subplots(2, len(diagrams), figsize=(3.2 * len(diagrams), 6), squeeze=False, layout="constrained")
    jx, ky = _edges(couplings), _edges(link_strengths)
    for col, (name, d) in enumerate(diagrams.items()):
        for row, key in enumerate(("brier", "wall_recall")):
            ax = axes[row, col]
            mesh = ax.pcolormesh(jx, ky, np.asarray(d[key]).T, cmap="viridis_r" if key == "brier" else "viridis")
            ax.axvline(critical, color="w", ls="--", lw=1)
            ax.set_xticks(couplings, spaced_labels(couplings, jx[-1] - jx[0]), rotation=90, fontsize=9)
            ax.set_yticks(link_strengths, spaced_labels(link_strengths, ky[-1] - ky[0]), fontsize=9)
            ax.set_title(f"{name}: {'Brier' if key == 'brier' else 'wall recall'}")
            ax.set_xlabel("coupling J")
            ax.set_ylabel("link strength K")
            fig.colorbar(mesh, ax=ax, shrink=0.9)
    return fig


def densest_window(mask, side):
    """The (y0, y1, x0, x1) square of ``side`` cells (clipped to the grid) holding the most True cells of ``mask``.

    A coarse search (steps of side / 8) over a summed-area table.

    >>> m = np.zeros((40, 40), bool); m[30:34, 5:9] = True
    >>> densest_window(m, 8)
    (26, 34, 1, 9)
    """
    mask = np.asarray(mask, bool)
    h, w = mask.shape
    side_y, side_x = min(side, h), min(side, w)
    c = np.pad(mask.astype(np.int64).cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    best, where = -1, (0, side_y, 0, side_x)
    for y in range(0, h - side_y + 1, max(1, side_y // 8)):
        for x in range(0, w - side_x + 1, max(1, side_x // 8)):
            n = c[y + side_y, x + side_x] - c[y, x + side_x] - c[y + side_y, x] + c[y, x]
            if n > best:
                best, where = n, (y, y + side_y, x, x + side_x)
    return where


def before_after_figure(maps, name, window):
    """The same map raw and refined, side by side, one shared P(occupied) colour bar; below each, the ``window``
    (y0, y1, x0, x1 cells, outlined in the map above) enlarged, every cell drawn.
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    y0, y1, x0, x1 = window
    fig, axes = plt.subplots(2, len(maps), figsize=(5 * len(maps), 10), squeeze=False, layout="constrained",
                             height_ratios=(1, 1))
    im = None
    for col, (title, p) in enumerate(maps.items()):
        p = np.asarray(p)
        im = show_grid(axes[0, col], p, title=f"{name}: {title}", colorbar=False)
        axes[0, col].add_patch(Rectangle((x0 - 0.5, y0 - 0.5), x1 - x0, y1 - y0, fill=False, edgecolor="tab:blue",
                                         linewidth=1.5))
        zoom = axes[1, col]
        zoom.imshow(p[y0:y1, x0:x1], cmap=OCCUPANCY_CMAP, vmin=0.0, vmax=1.0, origin="lower", interpolation="nearest",
                    extent=(x0 - 0.5, x1 - 0.5, y0 - 0.5, y1 - 0.5))
        zoom.set_title("the outlined square, every cell", fontsize="small")
        zoom.set_xlabel("x [cells]")
        zoom.set_ylabel("y [cells]")
    shared_colorbar(fig, im, axes, orientation="horizontal")
    return fig
