"""Ray casting on a grid: Bresenham's line with an error term (thesis Listing 1). Cells are integer (x, y) indices of a
``[y, x]`` array. The ``@njit`` kernels take plain integers and a preallocated buffer, so other kernels (the simulator,
the grid builder) call them in their own loops; :func:`line_cells` and :func:`first_hit` check their input.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from crfmap.errors import InputError


@njit(cache=True, nogil=True)
def _line_length(x0, y0, x1, y1):
    """Number of cells on the Bresenham line from (x0, y0) to (x1, y1), both ends included."""
    return max(abs(x1 - x0), abs(y1 - y0)) + 1


@njit(inline="always", cache=True, nogil=True)
def _step(x, y, err, dx, dy, sx, sy):
    """One step along the line: Listing 1's error term decides which coordinates move."""
    e2 = 2 * err
    if e2 > -dy:
        err -= dy
        x += sx
    if e2 < dx:
        err += dx
        y += sy
    return x, y, err


@njit(cache=True, nogil=True)
def bresenham_step(x0, y0, x1, y1, out):
    """Write the cells of the line (x0, y0) -> (x1, y1) into ``out[:, 0:2]`` (at least ``_line_length(...)`` rows) as
    (x, y); return the count. At a tie (thesis Fig. 15) the minor coordinate stays nearer the start, as in Listing 1.
    """
    dx = abs(x1 - x0)
    dy = abs(y1 - y0)
    sx = 1 if x1 > x0 else -1
    sy = 1 if y1 > y0 else -1
    err = dx - dy
    x, y = x0, y0
    n = 0
    while True:
        out[n, 0] = x
        out[n, 1] = y
        n += 1
        if x == x1 and y == y1:
            break
        x, y, err = _step(x, y, err, dx, dy, sx, sy)
    return n


@njit(cache=True, nogil=True)
def first_hit_kernel(occupied, x0, y0, x1, y1):
    """(x, y, True) of the first cell after (x0, y0) towards (x1, y1) with ``occupied[y, x]`` (the start cell, where
    the robot stands, is not tested), or (x, y, False) of the last in-grid cell (leaving the grid ends the ray)."""
    h, w = occupied.shape
    dx = abs(x1 - x0)
    dy = abs(y1 - y0)
    sx = 1 if x1 > x0 else -1
    sy = 1 if y1 > y0 else -1
    err = dx - dy
    x, y = x0, y0
    lx, ly = x0, y0
    while not (x == x1 and y == y1):
        x, y, err = _step(x, y, err, dx, dy, sx, sy)
        if x < 0 or y < 0 or x >= w or y >= h:
            return lx, ly, False
        if occupied[y, x]:
            return x, y, True
        lx, ly = x, y
    return lx, ly, False


def line_cells(x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
    """Cells (x, y) of the Bresenham line between two cells, both ends included.

    >>> line_cells(0, 0, 3, 1).tolist()
    [[0, 0], [1, 0], [2, 1], [3, 1]]
    """
    ints = []
    for name, v in zip(("x0", "y0", "x1", "y1"), (x0, y0, x1, y1)):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
            raise InputError(name, f"cell coordinates must be integers, got {v!r}")
        ints.append(int(v))
    x0, y0, x1, y1 = ints
    out = np.empty((_line_length(x0, y0, x1, y1), 2), dtype=np.int64)
    n = bresenham_step(x0, y0, x1, y1, out)
    return out[:n]


def first_hit(occupied, start, end):
    """(x, y) of the first occupied cell of ``occupied`` ([y, x] bool) seen from cell ``start`` (x, y) towards cell
    ``end``, or None if the ray reaches ``end`` (or leaves the grid) unblocked.

    >>> occ = np.zeros((1, 5), bool); occ[0, 3] = True
    >>> first_hit(occ, (0, 0), (4, 0))
    (3, 0)
    """
    occ = np.asarray(occupied)
    if occ.ndim != 2 or occ.size == 0:
        raise InputError("occupied", f"expected a non-empty 2-D [y, x] array, got shape {occ.shape}")
    x0, y0 = (int(v) for v in start)
    x1, y1 = (int(v) for v in end)
    x, y, hit = first_hit_kernel(occ.astype(np.bool_), x0, y0, x1, y1)
    return (int(x), int(y)) if hit else None
