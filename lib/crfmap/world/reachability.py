"""Where a robot can be and go in a ground-truth grid: its cell, its footprint, the cells it reaches.

The robot is a disc of ``robot_radius`` metres (0 = the thesis's point robot, one cell). A cell is traversable when
the disc centred in it overlaps no occupied cell (P > 0.5; outside the grid counts as occupied); the robot moves
between side neighbours, so it never slips through a diagonal gap. Functions take an
:class:`~crfmap.grid.OccupancyGrid` or a :class:`~crfmap.world.scene.Scene` (its ``truth``).

>>> occ = np.zeros((5, 5)); occ[:, 2] = 1  # a wall down the middle
>>> reachable(OccupancyGrid(occ, 0.1), (0.05, 0.05)).sum(axis=0).tolist()
[5, 5, 0, 0, 0]
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from crfmap.checks import check_number
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid


def _grid_of(truth):
    """The grid of a Scene (its ``truth``), else ``truth`` itself."""
    inner = getattr(truth, "truth", None)
    return inner if isinstance(inner, OccupancyGrid) else truth


def pose_cell(grid: OccupancyGrid, pose) -> tuple:
    """Integer cell (ix, iy) containing the point ``pose[:2]`` [m], or InputError if outside the grid."""
    fx, fy = grid.world_to_cell(pose[0], pose[1])
    ix, iy = int(math.floor(float(fx))), int(math.floor(float(fy)))
    if not (0 <= ix < grid.width and 0 <= iy < grid.height):
        raise InputError("start", f"position ({pose[0]:g}, {pose[1]:g}) m lies outside the "
                                  f"{grid.width}x{grid.height} grid")
    return ix, iy



def footprint_offsets(robot_radius, resolution) -> np.ndarray:
    """Offsets (dx, dy) [cells] of the cells a disc of ``robot_radius`` [m] centred in cell (0, 0) overlaps (the
    nearest point of the cell's square is nearer than the radius), always including (0, 0).

    >>> footprint_offsets(0.0, 0.1).tolist()
    [[0, 0]]
    >>> len(footprint_offsets(0.06, 0.1))  # the 4 side neighbours (0.05 m away) join, corners (0.07 m) do not
    5
    """
    r = float(robot_radius) / float(resolution)
    k = int(math.ceil(r + 0.5))
    d = np.arange(-k, k + 1)
    dx, dy = np.meshgrid(d, d)
    gap = np.hypot(np.maximum(np.abs(dx) - 0.5, 0.0), np.maximum(np.abs(dy) - 0.5, 0.0))
    keep = (gap < r) | ((dx == 0) & (dy == 0))
    return np.stack([dx[keep], dy[keep]], axis=1)


def traversable(truth, robot_radius=0.0) -> np.ndarray:
    """Boolean [y, x] mask of cells where a disc robot of ``robot_radius`` [m] fits (see the module doc).

    >>> occ = np.zeros((7, 7)); occ[3, 3] = 1
    >>> int(traversable(OccupancyGrid(occ, 0.1), 0.06).sum())  # not: the border ring, the wall, its 4 neighbours
    20
    """
    grid = _grid_of(truth)
    if not isinstance(grid, OccupancyGrid):
        grid = OccupancyGrid(np.asarray(truth, dtype=float))
    robot_radius = check_number("robot_radius", robot_radius, low=0.0)
    occ = grid.probability > 0.5
    offsets = footprint_offsets(robot_radius, grid.resolution)
    k = int(np.abs(offsets).max())
    if k == 0:
        return ~occ
    h, w = occ.shape
    padded = np.ones((h + 2 * k, w + 2 * k), dtype=bool)
    padded[k : k + h, k : k + w] = occ
    blocked = np.zeros_like(occ)
    for dx, dy in offsets:
        blocked |= padded[k + dy : k + dy + h, k + dx : k + dx + w]
    return ~blocked


@njit(cache=True)
def _flood_fill(free, sx, sy):
    """Cells 4-connected to (sx, sy) through ``free`` cells (the start must be free)."""
    h, w = free.shape
    seen = np.zeros((h, w), dtype=np.bool_)
    stack = np.empty((h * w, 2), dtype=np.int64)
    seen[sy, sx] = True
    stack[0, 0] = sx
    stack[0, 1] = sy
    top = 1
    while top > 0:
        top -= 1
        x = stack[top, 0]
        y = stack[top, 1]
        for k in range(4):
            nx = x + (1 if k == 0 else (-1 if k == 1 else 0))
            ny = y + (1 if k == 2 else (-1 if k == 3 else 0))
            if 0 <= nx < w and 0 <= ny < h and free[ny, nx] and not seen[ny, nx]:
                seen[ny, nx] = True
                stack[top, 0] = nx
                stack[top, 1] = ny
                top += 1
    return seen


def reachable(truth, start, robot_radius=0.0) -> np.ndarray:
    """Boolean [y, x] mask of the cells a disc robot can reach from ``start`` (x [m], y [m][, yaw]) by moving between
    side neighbours through :func:`traversable` cells.

    >>> from crfmap.world.scenes import enclosed_boxes
    >>> s = enclosed_boxes("train")
    >>> m = reachable(s.truth, s.start)
    >>> bool(m[7, 7]), bool(m[s.start_cell()[1], s.start_cell()[0]])
    (False, True)
    """
    grid = _grid_of(truth)
    free = traversable(grid, robot_radius)
    sx, sy = pose_cell(grid, start)
    if not free[sy, sx]:
        raise InputError("start", f"cell ({sx}, {sy}) is occupied or too close to a wall for a robot of radius "
                                  f"{robot_radius} m")
    return _flood_fill(free, sx, sy)

