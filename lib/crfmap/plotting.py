"""Drawing grids and curves the same way everywhere (ROS orientation: row 0 at the bottom)."""
from __future__ import annotations

import numpy as np

from crfmap.grid import OccupancyGrid


def show_grid(ax, grid, title: str = "", cells: bool = False, colorbar: bool = False, **kwargs):
    """Draw P(occupied) with occupied black, empty white, unknown grey; y up, as in rviz.

    ``cells=True`` labels axes in cells instead of metres.
    """
    if isinstance(grid, OccupancyGrid):
        data = grid.probability
        extent = None if cells else grid.imshow_extent()
    else:
        data = np.asarray(grid)
        extent = None
    im = ax.imshow(data, cmap=kwargs.pop("cmap", "gray_r"), vmin=0.0, vmax=1.0, origin="lower",
                   extent=extent, interpolation="nearest", **kwargs)
    if title:
        ax.set_title(title)
    ax.set_xlabel("x [cells]" if extent is None else "x [m]")
    ax.set_ylabel("y [cells]" if extent is None else "y [m]")
    if colorbar:
        ax.figure.colorbar(im, ax=ax, fraction=0.046, pad=0.04, label="P(occupied)")
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
