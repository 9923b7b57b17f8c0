"""What a navigating robot makes of its own map: nav2's costmap reading, inflation, frontiers, shortest paths.

A map's P(occupied) is read the way nav2 reads a map_saver map: lethal where P >= 0.65, free where
P <= 0.196, unknown in between (:data:`LETHAL`, :data:`FREE`). Around lethal cells the costmap inflates
as nav2's inflation layer does for a round robot: a cell whose centre is within the robot's radius of
a lethal cell's square (the robot centred there would touch it, the rule of
:func:`crfmap.world.reachability.traversable`) is blocked, and beyond that a cost decaying as
``exp(-cost_scaling * (d - radius))`` up to ``inflation_radius`` keeps paths off the walls. Unknown
cells are either passable (nav2's ``allow_unknown: true``, the default) or blocked, never inflated.

Frontiers are free cells with an unknown side neighbour. Paths are 8-connected without cutting
corners; :func:`shortest_paths` is Dijkstra from one cell (the nearest frontier), :func:`plan_path`
A* between two cells with the octile distance as its heuristic (admissible: a step costs at least its
length).

>>> p = np.full((5, 7), 0.5); p[1:4, 1:6] = 0.1; p[:, 6] = 0.9
>>> c = costmap(p, 0.1, robot_radius=0.0)
>>> int(c.lethal.sum()), int(frontiers(c).sum())
(5, 11)
>>> plan_path(c, (1, 2), (4, 2)).tolist()
[[1, 2], [2, 2], [3, 2], [4, 2]]
"""
from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy import ndimage

from crfmap.checks import check_int, check_number, check_positive
from crfmap.errors import InputError
from crfmap.io.map_server import FREE_THRESH_DEFAULT, OCCUPIED_THRESH_DEFAULT
from crfmap.world.reachability import footprint_offsets

LETHAL = OCCUPIED_THRESH_DEFAULT  # P >= 0.65: nav2's lethal obstacle (map_saver's occupied_thresh)
FREE = FREE_THRESH_DEFAULT  # P <= 0.196: free (map_saver's free_thresh since Jazzy)
INFLATION_RADIUS = 0.55  # [m] nav2's inflation layer default
COST_SCALING = 3.0  # [1/m] nav2's cost_scaling_factor default
COST_WEIGHT = 2.0  # a step next to the inscribed radius costs 1 + COST_WEIGHT times its length
UNKNOWN_READINGS = ("free", "lethal")  # how a planner may read unknown cells


@dataclass(frozen=True)
class Costmap:
    """A map as the planner sees it: [y, x] masks and the cost factor of entering each cell."""

    lethal: np.ndarray  # bool, P >= LETHAL
    free: np.ndarray  # bool, P <= FREE
    unknown: np.ndarray  # bool, neither
    blocked: np.ndarray  # bool, lethal or within the robot's radius of one (or unknown, when read as lethal)
    factor: np.ndarray  # float64 >= 1: a step into the cell costs its length times this
    resolution: float  # [m/cell]


def inflate(lethal, resolution, robot_radius, inflation_radius=INFLATION_RADIUS, cost_scaling=COST_SCALING,
            cost_weight=COST_WEIGHT):
    """(blocked, factor) of nav2's inflation around the ``lethal`` [y, x] cells.

    ``blocked``: cells whose centre lies within ``robot_radius`` [m] of a lethal cell's square
    (:func:`~crfmap.world.reachability.footprint_offsets`), lethal cells included. ``factor``: 1 +
    ``cost_weight * exp(-cost_scaling * (d - robot_radius))`` for the other cells whose centre is within
    ``inflation_radius`` of a lethal cell's centre (distance d [m]), else 1.

    >>> lethal = np.zeros((1, 6), bool); lethal[0, 0] = True
    >>> blocked, factor = inflate(lethal, 0.1, 0.1)
    >>> blocked.astype(int).tolist(), factor.round(2).tolist()
    ([[1, 1, 0, 0, 0, 0]], [[1.0, 1.0, 2.48, 2.1, 1.81, 1.6]])
    """
    lethal = np.asarray(lethal, dtype=bool)
    if lethal.ndim != 2:
        raise InputError("lethal", f"expected a 2-D mask, got shape {lethal.shape}")
    resolution = check_positive("resolution", resolution)
    robot_radius = check_number("robot_radius", robot_radius, low=0.0)
    inflation_radius = check_number("inflation_radius", inflation_radius, low=0.0)
    cost_scaling = check_number("cost_scaling", cost_scaling, low=0.0)
    cost_weight = check_number("cost_weight", cost_weight, low=0.0)
    offsets = footprint_offsets(robot_radius, resolution)
    k = int(np.abs(offsets).max())
    structure = np.zeros((2 * k + 1, 2 * k + 1), bool)
    structure[offsets[:, 1] + k, offsets[:, 0] + k] = True
    blocked = ndimage.binary_dilation(lethal, structure) if lethal.any() else lethal.copy()
    factor = np.ones(lethal.shape)
    if lethal.any():
        d = ndimage.distance_transform_edt(~lethal) * resolution
        near = ~blocked & (d <= inflation_radius)
        factor[near] += cost_weight * np.exp(-cost_scaling * (d[near] - robot_radius))
    return blocked, factor


def costmap(probability, resolution, robot_radius, unknown="free", **inflation) -> Costmap:
    """The :class:`Costmap` of a map's P(occupied) [y, x] for a round robot (``inflation``: see :func:`inflate`).

    ``unknown="free"`` lets paths through unknown cells (nav2's ``allow_unknown``), ``"lethal"``
    blocks them (not inflated, as nav2's NO_INFORMATION).
    """
    p = np.asarray(probability, dtype=np.float64)
    if p.ndim != 2 or not np.all((p >= 0) & (p <= 1)):
        raise InputError("probability", f"expected a 2-D grid of probabilities in [0, 1], got shape {p.shape}")
    if unknown not in UNKNOWN_READINGS:
        raise InputError("unknown", f"must be one of {', '.join(UNKNOWN_READINGS)}, got {unknown!r}")
    lethal, free = p >= LETHAL, p <= FREE
    unknown_cells = ~lethal & ~free
    blocked, factor = inflate(lethal, resolution, robot_radius, **inflation)
    if unknown == "lethal":
        blocked = blocked | unknown_cells
    return Costmap(lethal, free, unknown_cells, blocked, factor, float(resolution))


def frontiers(costmap: Costmap, min_size=1) -> np.ndarray:
    """Boolean [y, x] mask of frontier cells: free cells with an unknown side neighbour, in 8-connected
    groups of at least ``min_size`` cells (smaller groups are single unobserved cells, not unexplored space).

    >>> c = costmap(np.array([[0.1, 0.1, 0.5], [0.1, 0.1, 0.1]]), 0.1, 0.0)
    >>> frontiers(c).astype(int).tolist(), int(frontiers(c, min_size=3).sum())
    ([[0, 1, 0], [0, 0, 1]], 0)
    """
    min_size = check_int("min_size", min_size, low=1)
    u = costmap.unknown
    beside = np.zeros_like(u)
    beside[1:, :] |= u[:-1, :]
    beside[:-1, :] |= u[1:, :]
    beside[:, 1:] |= u[:, :-1]
    beside[:, :-1] |= u[:, 1:]
    mask = costmap.free & beside
    if min_size > 1 and mask.any():
        labels, n = ndimage.label(mask, structure=np.ones((3, 3), bool))
        sizes = np.bincount(labels.ravel(), minlength=n + 1)
        mask = (sizes >= min_size)[labels] & mask
    return mask


@njit(cache=True)
def _search(blocked, factor, sx, sy, gx, gy):
    """Dijkstra (gx < 0) or A* to (gx, gy) from (sx, sy): (cost [cells], parent index) per cell, inf / -1 unreached.

    8-connected, no corner cutting; a step into cell c costs its length times ``factor[c]``. The start
    is allowed even if blocked (the robot is where it is). A* stops when the goal is settled.
    """
    h, w = blocked.shape
    cost = np.full((h, w), np.inf)
    parent = np.full((h, w), -1, np.int64)
    done = np.zeros((h, w), np.bool_)
    cost[sy, sx] = 0.0
    parent[sy, sx] = sy * w + sx
    diag = math.sqrt(2.0)
    heap = [(0.0, sy * w + sx)]
    while len(heap) > 0:
        _, c = heapq.heappop(heap)
        x, y = c % w, c // w
        if done[y, x]:
            continue
        done[y, x] = True
        if x == gx and y == gy:
            break
        for dy in range(-1, 2):
            for dx in range(-1, 2):
                nx, ny = x + dx, y + dy
                if (dx == 0 and dy == 0) or nx < 0 or ny < 0 or nx >= w or ny >= h or blocked[ny, nx]:
                    continue
                if dx != 0 and dy != 0 and (blocked[y, nx] or blocked[ny, x]):
                    continue
                new = cost[y, x] + (diag if dx != 0 and dy != 0 else 1.0) * factor[ny, nx]
                if new < cost[ny, nx]:
                    cost[ny, nx] = new
                    parent[ny, nx] = c
                    guess = new
                    if gx >= 0:  # octile distance to the goal: a lower bound of the rest
                        ax, ay = abs(gx - nx), abs(gy - ny)
                        guess += max(ax, ay) + (diag - 1.0) * min(ax, ay)
                    heapq.heappush(heap, (guess, ny * w + nx))
    return cost, parent


def _check_cell(name, cell, shape):
    try:
        x, y = (int(v) for v in cell)
    except (TypeError, ValueError):
        raise InputError(name, f"expected a cell (x, y), got {cell!r}") from None
    if not (0 <= x < shape[1] and 0 <= y < shape[0]):
        raise InputError(name, f"cell ({x}, {y}) lies outside the {shape[1]} x {shape[0]} grid")
    return x, y


def shortest_paths(costmap: Costmap, start):
    """Dijkstra from cell ``start`` (x, y): (cost [cells, inf unreachable], parent) arrays [y, x] (see :func:`path_to`)."""
    sx, sy = _check_cell("start", start, costmap.blocked.shape)
    return _search(costmap.blocked, costmap.factor, sx, sy, -1, -1)


def path_to(parent, goal) -> np.ndarray:
    """The cells (n, 2) of (x, y) from the search's start to ``goal`` along ``parent``; (0, 2) if unreached."""
    gx, gy = _check_cell("goal", goal, parent.shape)
    w = parent.shape[1]
    if parent[gy, gx] < 0:
        return np.empty((0, 2), np.int64)
    cells = [(gx, gy)]
    c = gy * w + gx
    while parent[c // w, c % w] != c:
        c = int(parent[c // w, c % w])
        cells.append((c % w, c // w))
    return np.array(cells[::-1], np.int64)


def plan_path(costmap: Costmap, start, goal) -> np.ndarray:
    """A* path (n, 2) of cells (x, y) from ``start`` to ``goal`` on ``costmap``; (0, 2) if there is none."""
    sx, sy = _check_cell("start", start, costmap.blocked.shape)
    gx, gy = _check_cell("goal", goal, costmap.blocked.shape)
    _, parent = _search(costmap.blocked, costmap.factor, sx, sy, gx, gy)
    return path_to(parent, (gx, gy))


def path_cost(costmap: Costmap, path) -> float:
    """The cost [cells] :func:`plan_path` gives ``path``: each step's length times the entered cell's factor."""
    p = np.asarray(path, np.int64)
    if len(p) < 2:
        return 0.0
    steps = np.hypot(*np.diff(p, axis=0).T)
    return float(np.sum(steps * costmap.factor[p[1:, 1], p[1:, 0]]))
