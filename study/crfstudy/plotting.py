"""Drawing grids and curves the same way everywhere (ROS orientation: row 0 at the bottom).

Occupancy is drawn with :data:`OCCUPANCY_CMAP`: free is near white, unknown (0.5) a mid grey as in
rviz, occupied black, and lightness falls monotonically from free to occupied (it prints in grey).
The levels the arctan grid is made of get distinct hues: 0.25 (a cell passed once) light blue,
0.5 grey, 0.75 (a wall hit once) dark red -- far from the unknown grey in both hue and lightness,
so single-hit walls stand out against unseen space.
Every grid gets a compact colour bar unless ``colorbar=False`` (:func:`occupancy_colorbar`); a
figure of several grids can share one (:func:`shared_colorbar`). Both keep their labels short, so
they do not run into a neighbouring panel's axis label.
"""
from __future__ import annotations

import numpy as np
from matplotlib.colors import LinearSegmentedColormap

from crfmap.grid import OccupancyGrid

# P(occupied) -> colour; lightness (CIELAB L*) about 99, 86, 58, 33, 0 at the five nodes.
OCCUPANCY_CMAP = LinearSegmentedColormap.from_list("crfmap_occupancy", [
    (0.0, "#fcfcf5"), (0.25, "#bdd7ee"), (0.5, "#8c8c8c"), (0.75, "#a50f15"), (1.0, "#000000")])
OCCUPANCY_TICKS = (0.0, 0.25, 0.5, 0.75, 1.0)
OCCUPANCY_TICK_LABELS = ("0", ".25", ".5", ".75", "1")
COLORBAR_LABEL = "P(occupied)"
# Above this many cells on a side a page-size figure shows fewer pixels than cells: sampling would drop
# one-cell walls, so the grid is pooled for display (display_pool), walls kept.
_DOWNSAMPLE_CELLS = 400


def imshow_extent(grid: OccupancyGrid) -> tuple:
    """(left, right, bottom, top) [m] of ``grid``, matplotlib's ``imshow(..., extent=..., origin='lower')`` (yaw 0).

    >>> imshow_extent(OccupancyGrid(np.zeros((2, 3)), 0.5, origin=(1.0, 2.0, 0.0)))
    (1.0, 2.5, 2.0, 3.0)
    """
    xmin, ymin, xmax, ymax = grid.bounds()
    return (xmin, xmax, ymin, ymax)


def display_pool(p, k: int) -> np.ndarray:
    """Shrink a grid k-fold for display only, so thin walls survive at page size.

    Each k x k block shows its largest P if that is above 0.5 (a wall anywhere in the block stays
    visible), else its mean.

    >>> display_pool(np.array([[0.0, 1.0], [0.0, 0.0]]), 2).tolist()
    [[1.0]]
    """
    p = np.asarray(p, dtype=float)
    h, w = -(-p.shape[0] // k) * k, -(-p.shape[1] // k) * k
    padded = np.full((h, w), np.nan)
    padded[:p.shape[0], :p.shape[1]] = p
    blocks = padded.reshape(h // k, k, w // k, k)
    top = np.nanmax(blocks, axis=(1, 3))
    return np.where(top > 0.5, top, np.nanmean(blocks, axis=(1, 3)))


def show_grid(ax, grid, title: str = "", cells: bool = False, colorbar: bool = True, **kwargs):
    """Draw P(occupied) (free near white, unknown 0.5 grey, occupied black); y up, as in rviz.

    ``cells=True`` labels axes in cells instead of metres; in metres the axis labels give the
    cell size, so a length in cells can be read off either way. ``colorbar=True`` (default)
    adds a slim colour bar labelled P(occupied) with ticks at 0, 0.25, 0.5, 0.75 and 1.

    >>> import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> im = show_grid(ax, OccupancyGrid(np.array([[0.0, 0.25], [0.5, 1.0]]), 0.1))
    >>> ax.get_xlabel(), len(ax.child_axes)
    ('x [m] (cells of 0.1 m)', 1)
    """
    if isinstance(grid, OccupancyGrid):
        data = grid.probability
        extent = None if cells else imshow_extent(grid)
        resolution = grid.resolution
    else:
        data = np.asarray(grid)
        extent = None
        resolution = None
    if max(data.shape) > _DOWNSAMPLE_CELLS:
        if extent is None:  # keep the axes in cells of the full grid
            extent = (-0.5, data.shape[1] - 0.5, -0.5, data.shape[0] - 0.5)
            cells = True
        data = display_pool(data, -(-max(data.shape) // _DOWNSAMPLE_CELLS))
    kwargs.setdefault("interpolation", "nearest")
    im = ax.imshow(data, cmap=kwargs.pop("cmap", OCCUPANCY_CMAP), vmin=0.0, vmax=1.0, origin="lower",
                   extent=extent, **kwargs)
    if title:
        ax.set_title(title)
    if extent is None or cells:
        ax.set_xlabel("x [cells]")
        ax.set_ylabel("y [cells]")
    else:
        ax.set_xlabel(f"x [m] (cells of {resolution:g} m)")
        ax.set_ylabel("y [m]")
    if colorbar:
        occupancy_colorbar(im, ax)
    return im


def _label_bar(bar):
    bar.set_ticks(OCCUPANCY_TICKS, labels=OCCUPANCY_TICK_LABELS)
    bar.ax.tick_params(labelsize="small", length=2, pad=1)
    bar.set_label(COLORBAR_LABEL, fontsize="small", labelpad=1)
    return bar


def occupancy_colorbar(im, ax):
    """A slim colour bar beside one grid: short tick labels (0 .25 .5 .75 1) and "P(occupied)".

    Short labels keep the bar inside the gap to the next panel of a grid of subplots; the bar is as tall
    as the grid itself, so it never reaches up beside the panel's title.

    >>> import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> bar = occupancy_colorbar(ax.imshow(np.eye(2), cmap=OCCUPANCY_CMAP, vmin=0, vmax=1), ax)
    >>> [t.get_text() for t in bar.ax.get_yticklabels()], bar.ax.get_ylabel()
    (['0', '.25', '.5', '.75', '1'], 'P(occupied)')
    """
    # The bar lives in the panel's own coordinates: exactly as tall as the drawn grid (an equal-aspect grid is
    # shorter than its slot, where a slot-high bar would reach up beside the title), and the layout engines
    # count it as part of the panel.
    bar_axes = ax.inset_axes([1.03, 0.0, 0.045, 1.0])
    return _label_bar(ax.figure.colorbar(im, cax=bar_axes))


def shared_colorbar(fig, im, axes, orientation: str = "vertical"):
    """One colour bar for several grid panels (pass ``colorbar=False`` to :func:`show_grid` for each).

    With several panels in a row a shared bar at the right (or, ``orientation="horizontal"``, below)
    leaves every panel its full width and no label between panels.
    """
    bar = fig.colorbar(im, ax=list(np.ravel(axes)), orientation=orientation, fraction=0.03, pad=0.02, aspect=40)
    if orientation == "horizontal":
        bar.set_ticks(OCCUPANCY_TICKS, labels=OCCUPANCY_TICK_LABELS)
        bar.ax.tick_params(labelsize="small", length=2, pad=1)
        bar.set_label(COLORBAR_LABEL, fontsize="small", labelpad=1)
        return bar
    return _label_bar(bar)


def plot_roc(ax, curves: dict, title: str = "ROC"):
    """``curves``: label -> (fpr, tpr[, auc]). Draws them with the chance diagonal.

    Curves that coincide would hide each other: each gets its own dash pattern, and later curves are
    drawn thinner on top of earlier ones, so every curve stays visible.

    >>> import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> plot_roc(ax, {"a": ([0, 1], [0, 1]), "b": ([0, 1], [0, 1], 0.5)})
    >>> [(l.get_linestyle(), l.get_linewidth()) for l in ax.get_lines()[:2]]
    [('-', 2.6), ('--', 2.0)]
    """
    styles = ("-", "--", "-.", ":")
    for k, (label, curve) in enumerate(curves.items()):
        fpr, tpr = curve[0], curve[1]
        text = f"{label} (AUC {curve[2]:.3f})" if len(curve) > 2 else label
        ax.plot(fpr, tpr, label=text, linestyle=styles[k % len(styles)], linewidth=max(2.6 - 0.6 * k, 1.0),
                zorder=2 + k)
    ax.plot([0, 1], [0, 1], color="0.7", linestyle=":", linewidth=1)
    ax.set_xlabel("false positive rate")
    ax.set_ylabel("true positive rate")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.01)
    ax.set_title(title)
    ax.legend(loc="lower right", fontsize="small")
