"""Regions of a grid that LBP updates (``infer(region=...)``): a disc around the robot (the thesis's
bounded LBP, sec. 3.4.4) and the cells near observations (so never-seen space stays unknown)."""
from __future__ import annotations

import numpy as np

from crfmap.errors import InputError
from crfmap.grid import as_grid
from crfmap.checks import check_mask


def disc_region(grid, center, radius) -> np.ndarray:
    """Boolean [y, x] mask of cells whose centres lie within ``radius`` [m] of ``center`` (x, y) [m].

    >>> from crfmap.grid import OccupancyGrid
    >>> g = OccupancyGrid(np.full((5, 5), 0.5))
    >>> int(disc_region(g, (2.5, 2.5), 1.0).sum())
    5
    """
    g = as_grid(grid)
    ys, xs = np.mgrid[0 : g.height, 0 : g.width]
    wx, wy = g.cell_to_world(xs, ys)
    return (wx - center[0]) ** 2 + (wy - center[1]) ** 2 <= radius * radius


def near_known(grid, margin: int) -> np.ndarray:
    """Boolean [y, x] mask of cells within ``margin`` cells (Chebyshev distance) of an observed cell.

    As ``region`` (keeping the input outside it) it fills gaps up to ``margin`` cells deep and leaves the unexplored
    outside unknown, which in the ordered phase would otherwise take the state of its border.

    >>> m = near_known(np.array([[0.5, 0.5, 0.5, 0.9]]), 1)
    >>> m.astype(int).tolist()
    [[0, 0, 1, 1]]
    """
    return near_cells(as_grid(grid).known(), margin)


def near_cells(mask, margin: int) -> np.ndarray:
    """Boolean [y, x] mask of cells within ``margin`` cells (Chebyshev distance) of a True cell of ``mask``.

    >>> near_cells(np.array([[False, False, False, True]]), 2).astype(int).tolist()
    [[0, 1, 1, 1]]
    """
    if not (isinstance(margin, (int, np.integer)) and not isinstance(margin, bool) and margin >= 0):
        raise InputError("margin", f"must be a non-negative whole number of cells, got {margin!r}")

    mask = check_mask("mask", mask)
    # a separable max-filter: dilate rows, then columns, by margin cells
    for axis in (0, 1):
        out = mask.copy()
        for shift in range(1, int(margin) + 1):
            if shift >= mask.shape[axis]:
                break
            sl_a = [slice(None)] * 2
            sl_b = [slice(None)] * 2
            sl_a[axis], sl_b[axis] = slice(shift, None), slice(None, -shift)
            out[tuple(sl_a)] |= mask[tuple(sl_b)]
            out[tuple(sl_b)] |= mask[tuple(sl_a)]
        mask = out
    return mask
