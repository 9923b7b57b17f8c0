"""Paths on a grid for the simulated robot: a coverage tour of the reachable cells, shortest grid paths,
and straight-line shortcuts where the way is clear. Cells are (x, y) indices of a boolean ``free`` [y, x] mask."""
from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def segment_clear(free, x0, y0, x1, y1):
    """Whether every cell the straight segment (x0, y0) -> (x1, y1) [cells, continuous] passes is free."""
    h, w = free.shape
    n = int(math.ceil(max(abs(x1 - x0), abs(y1 - y0)) * 4.0)) + 1  # a sample every quarter cell
    for k in range(n + 1):
        t = k / n
        cx = int(math.floor(x0 + t * (x1 - x0)))
        cy = int(math.floor(y0 + t * (y1 - y0)))
        if cx < 0 or cy < 0 or cx >= w or cy >= h or not free[cy, cx]:
            return False
    return True


@njit(cache=True)
def coverage_tour(free, sx, sy):
    """Depth-first tour of the cells 4-connected to (sx, sy): (m, 2) cells, each a side neighbour of the last
    (backtracking included, m < 2 * cells, no walk back after the last new cell); neighbours tried +x, +y, -x, -y."""
    h, w = free.shape
    seen = np.zeros((h, w), dtype=np.bool_)
    stack = np.empty((h * w, 3), dtype=np.int64)  # x, y, next neighbour to try
    tour = np.empty((2 * h * w, 2), dtype=np.int64)
    seen[sy, sx] = True
    stack[0, 0], stack[0, 1], stack[0, 2] = sx, sy, 0
    top = 1
    tour[0, 0], tour[0, 1] = sx, sy
    m = 1
    while top > 0:
        x, y, k = stack[top - 1, 0], stack[top - 1, 1], stack[top - 1, 2]
        moved = False
        while k < 4:
            nx = x + (1 if k == 0 else (-1 if k == 2 else 0))
            ny = y + (1 if k == 1 else (-1 if k == 3 else 0))
            k += 1
            if 0 <= nx < w and 0 <= ny < h and free[ny, nx] and not seen[ny, nx]:
                stack[top - 1, 2] = k
                seen[ny, nx] = True
                stack[top, 0], stack[top, 1], stack[top, 2] = nx, ny, 0
                top += 1
                tour[m, 0], tour[m, 1] = nx, ny
                m += 1
                moved = True
                break
        if not moved:
            top -= 1
            if top > 0:
                tour[m, 0], tour[m, 1] = stack[top - 1, 0], stack[top - 1, 1]
                m += 1
    # drop the final walk back to the start: nothing new is seen on it
    last_new = 0
    mark = np.zeros((h, w), dtype=np.bool_)
    for i in range(m):
        if not mark[tour[i, 1], tour[i, 0]]:
            mark[tour[i, 1], tour[i, 0]] = True
            last_new = i
    return tour[: last_new + 1].copy()


@njit(cache=True)
def grid_path(free, sx, sy, gx, gy):
    """Shortest 8-connected path of free cells (no corner cutting) from (sx, sy) to (gx, gy); (0, 2) if none."""
    h, w = free.shape
    parent = np.full((h, w), -1, dtype=np.int64)
    queue = np.empty(h * w, dtype=np.int64)
    parent[sy, sx] = sy * w + sx
    queue[0] = sy * w + sx
    head, tail = 0, 1
    while head < tail:
        c = queue[head]
        head += 1
        x, y = c % w, c // w
        if x == gx and y == gy:
            break
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                if dx == 0 and dy == 0:
                    continue
                nx, ny = x + dx, y + dy
                if not (0 <= nx < w and 0 <= ny < h) or not free[ny, nx] or parent[ny, nx] >= 0:
                    continue
                if dx != 0 and dy != 0 and not (free[y, nx] and free[ny, x]):
                    continue
                parent[ny, nx] = c
                queue[tail] = ny * w + nx
                tail += 1
    if parent[gy, gx] < 0:
        return np.empty((0, 2), dtype=np.int64)
    n = 1
    c = gy * w + gx
    while c != sy * w + sx:
        c = parent[c // w, c % w]
        n += 1
    out = np.empty((n, 2), dtype=np.int64)
    c = gy * w + gx
    for i in range(n - 1, -1, -1):
        out[i, 0], out[i, 1] = c % w, c // w
        c = parent[c // w, c % w]
    return out


def in_sight(free, a, b, margin=0.25):
    """Whether the straight leg between cell centres a and b, widened by ``margin`` cells each side, is free."""
    (x0, y0), (x1, y1) = a + 0.5, b + 0.5
    length = math.hypot(x1 - x0, y1 - y0)
    nx, ny = (-(y1 - y0) / length, (x1 - x0) / length) if length else (0.0, 0.0)
    return all(segment_clear(free, x0 + o * nx, y0 + o * ny, x1 + o * nx, y1 + o * ny) for o in (-margin, 0.0, margin))


def simplify(free, cells):
    """Keep the path cells from which the next kept one is in straight, free sight (see :func:`in_sight`)."""
    keep = [0]
    i = 0
    while i < len(cells) - 1:
        j = len(cells) - 1
        while j > i + 1 and not in_sight(free, cells[i], cells[j]):
            j -= 1
        keep.append(j)
        i = j
    return cells[keep]
