"""Drawing grids and curves the same way everywhere (ROS orientation: row 0 at the bottom).

Occupancy is drawn with a perceptual colour map (:data:`OCCUPANCY_CMAP`, matplotlib's
``magma_r``): free is pale, occupied black, and the in-between values the arctan grid is
made of (0.25, 0.5 unknown, 0.75) get clearly different hues instead of three close greys.
Every grid gets a labelled colour bar unless ``colorbar=False``.
"""
from __future__ import annotations

import numpy as np

from crfmap.grid import OccupancyGrid

OCCUPANCY_CMAP = "magma_r"  # perceptually uniform, monotone in lightness: pale = free, black = occupied
OCCUPANCY_TICKS = (0.0, 0.25, 0.5, 0.75, 1.0)
# Above this many cells on a side a page-size figure shows fewer pixels than cells: nearest-neighbour
# sampling would drop one-cell walls, so the image is averaged in colour space instead.
_DOWNSAMPLE_CELLS = 400


def show_grid(ax, grid, title: str = "", cells: bool = False, colorbar: bool = True, **kwargs):
    """Draw P(occupied) (free pale, occupied black, unknown 0.5 magenta); y up, as in rviz.

    ``cells=True`` labels axes in cells instead of metres; in metres the axis labels give the
    cell size, so a length in cells can be read off either way. ``colorbar=True`` (default)
    adds a colour bar labelled P(occupied) with ticks at 0, 0.25, 0.5, 0.75 and 1.

    >>> import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots()
    >>> im = show_grid(ax, OccupancyGrid(np.array([[0.0, 0.25], [0.5, 1.0]]), 0.1))
    >>> ax.get_xlabel(), len(fig.axes)
    ('x [m] (cells of 0.1 m)', 2)
    """
    if isinstance(grid, OccupancyGrid):
        data = grid.probability
        extent = None if cells else grid.extent()
        resolution = grid.resolution
    else:
        data = np.asarray(grid)
        extent = None
        resolution = None
    if max(data.shape) > _DOWNSAMPLE_CELLS:
        kwargs.setdefault("interpolation", "antialiased")
        kwargs.setdefault("interpolation_stage", "rgba")
    kwargs.setdefault("interpolation", "nearest")
    im = ax.imshow(data, cmap=kwargs.pop("cmap", OCCUPANCY_CMAP), vmin=0.0, vmax=1.0, origin="lower",
                   extent=extent, **kwargs)
    if title:
        ax.set_title(title)
    if extent is None:
        ax.set_xlabel("x [cells]")
        ax.set_ylabel("y [cells]")
    else:
        ax.set_xlabel(f"x [m] (cells of {resolution:g} m)")
        ax.set_ylabel("y [m]")
    if colorbar:
        bar = ax.figure.colorbar(im, ax=ax, fraction=0.046, pad=0.04, ticks=OCCUPANCY_TICKS)
        bar.set_label("P(occupied)")
        bar.ax.set_yticklabels(["0 free", "0.25", "0.5 unknown", "0.75", "1 occupied"])
    return im


def plot_roc(ax, curves: dict, title: str = "ROC"):
    """``curves``: label -> (fpr, tpr[, auc]). Draws them with the chance diagonal."""
    for label, curve in curves.items():
        fpr, tpr = curve[0], curve[1]
        text = f"{label} (AUC {curve[2]:.3f})" if len(curve) > 2 else label
        ax.plot(fpr, tpr, label=text)
    ax.plot([0, 1], [0, 1], color="0.7", linestyle=":", linewidth=1)
    ax.set_xlabel("false positive rate")
    ax.set_ylabel("true positive rate")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.01)
    ax.set_title(title)
    ax.legend(loc="lower right", fontsize="small")
