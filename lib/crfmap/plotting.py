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
# Above this many cells on a side a page-size figure shows fewer pixels than cells: sampling would drop
# one-cell walls, so the grid is pooled for display (display_pool), walls kept.
_DOWNSAMPLE_CELLS = 400


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
        extent = None if cells else grid.imshow_extent()
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
