"""crfmap.world.reachability: the robot's footprint and the cells it reaches, against brute-force references."""
from collections import deque

import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.world.reachability import footprint_offsets, pose_cell, reachable, traversable
from crfmap.world.scenes import enclosed_boxes


def naive_traversable(occ, radius_cells):
    """Cell i is free when no occupied cell's square, nor the outside of the grid, comes nearer than the radius."""
    h, w = occ.shape
    ys, xs = np.nonzero(occ)
    out = np.zeros((h, w), bool)
    for y in range(h):
        for x in range(w):
            if occ[y, x]:
                continue
            gaps = np.hypot(np.maximum(np.abs(xs - x) - 0.5, 0), np.maximum(np.abs(ys - y) - 0.5, 0))
            border = min(x + 0.5, w - x - 0.5, y + 0.5, h - y - 0.5)
            out[y, x] = gaps.min(initial=np.inf) >= radius_cells and (radius_cells == 0 or border >= radius_cells)
    return out


def naive_flood(free, start):
    h, w = free.shape
    seen = np.zeros_like(free)
    seen[start[1], start[0]] = True
    queue = deque([start])
    while queue:
        x, y = queue.popleft()
        for nx, ny in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
            if 0 <= nx < w and 0 <= ny < h and free[ny, nx] and not seen[ny, nx]:
                seen[ny, nx] = True
                queue.append((nx, ny))
    return seen


@pytest.mark.parametrize("radius", [0.0, 0.05, 0.1, 0.149, 0.15, 0.23, 0.4])
def test_reachable_matches_brute_force_with_footprint(radius):
    rng = np.random.default_rng(7)
    for _ in range(6):
        occ = rng.random((17, 23)) < 0.12
        grid = OccupancyGrid(occ.astype(float), resolution=0.1)
        free = naive_traversable(occ, radius / 0.1)
        assert np.array_equal(traversable(grid, radius), free)
        starts = np.argwhere(free)
        if len(starts) == 0:
            continue
        iy, ix = starts[rng.integers(len(starts))]
        got = reachable(grid, ((ix + 0.5) * 0.1, (iy + 0.5) * 0.1, 0.0), radius)
        assert np.array_equal(got, naive_flood(free, (ix, iy)))


def test_reachable_footprint_closes_narrow_gaps():
    cells = np.zeros((9, 15))
    cells[:, 7] = 1
    cells[4, 7] = 0  # a one-cell door in a wall
    grid = OccupancyGrid(cells, resolution=0.1)
    start = (0.25, 0.45, 0.0)
    assert reachable(grid, start, 0.0)[4, 12]  # a point robot passes
    assert not reachable(grid, start, 0.08)[4, 12]  # a 16 cm robot does not fit a 10 cm door
    with pytest.raises(InputError):
        reachable(grid, (0.75, 0.15, 0.0))  # start inside the wall
    with pytest.raises(InputError):
        reachable(grid, (5.0, 0.15, 0.0))  # outside the grid


def test_footprint_is_symmetric_and_grows_with_the_radius():
    previous = 0
    for radius in (0.0, 0.03, 0.05, 0.051, 0.1, 0.17, 0.3):
        offsets = footprint_offsets(radius, 0.1)
        cells = {tuple(o) for o in offsets.tolist()}
        assert (0, 0) in cells and len(cells) == len(offsets) >= previous
        assert cells == {(-dx, dy) for dx, dy in cells} == {(dy, dx) for dx, dy in cells}  # mirror and swap axes
        previous = len(cells)
    assert len(footprint_offsets(0.051, 0.1)) == 5  # the side neighbours' edges are 0.05 m away


def test_a_scene_stands_for_its_grid_and_pose_cell_names_the_outside():
    scene = enclosed_boxes("train")
    assert np.array_equal(traversable(scene, 0.1), traversable(scene.truth, 0.1))
    assert np.array_equal(reachable(scene, scene.start), reachable(scene.truth, scene.start))
    assert pose_cell(scene.truth, (0.05, 0.15)) == (0, 1)
    with pytest.raises(InputError, match="outside"):
        pose_cell(scene.truth, (-0.01, 0.5))
