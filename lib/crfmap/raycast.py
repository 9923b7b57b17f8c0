"""Ray casting on a grid: Bresenham's line with an error term (thesis Listing 1). Cells are integer (x, y) indices of a
``[y, x]`` array. The ``@njit`` kernels take plain integers and a preallocated buffer, so other kernels (the simulator,
the grid builder) call them in their own loops.
"""
from __future__ import annotations

from numba import njit


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
    """Write the cells of the line (x0, y0) -> (x1, y1) into ``out[:, 0:2]`` (at least max(|x1 - x0|, |y1 - y0|) + 1
    rows) as (x, y), return the count. Ties (thesis Fig. 15) keep the minor coordinate nearer the start (Listing 1)."""
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
