"""The closed loop: planner and inflation against brute force, frontiers, determinism, a tiny room explored."""
import math
from collections import deque

import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfstudy.closed_loop.exploration import ExploreSettings, explore, map_scores, navigation_task, reachable_free_space
from crfstudy.closed_loop.frontiers import costmap, frontiers, inflate, path_cost, plan_path, shortest_paths
from crfmap.sim.laser import Laser
from crfstudy.closed_loop.onboard import ONBOARD_MAPS, make_onboard
from crfmap.world.scene import Scene

MOVES = [(dx, dy) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dx or dy]


def _naive_reachable(blocked, start):
    """BFS over 8-connected moves without corner cutting: the cells a path can reach."""
    h, w = blocked.shape
    seen = {start}
    queue = deque([start])
    while queue:
        x, y = queue.popleft()
        for dx, dy in MOVES:
            nx, ny = x + dx, y + dy
            if not (0 <= nx < w and 0 <= ny < h) or blocked[ny, nx] or (nx, ny) in seen:
                continue
            if dx and dy and (blocked[y, nx] or blocked[ny, x]):
                continue
            seen.add((nx, ny))
            queue.append((nx, ny))
    return seen


def _naive_costs(blocked, factor, start):
    """Bellman-Ford relaxation until nothing changes: the least cost of every cell, slow and obvious."""
    h, w = blocked.shape
    cost = np.full((h, w), np.inf)
    cost[start[1], start[0]] = 0.0
    changed = True
    while changed:
        changed = False
        for y in range(h):
            for x in range(w):
                if not np.isfinite(cost[y, x]):
                    continue
                for dx, dy in MOVES:
                    nx, ny = x + dx, y + dy
                    if not (0 <= nx < w and 0 <= ny < h) or blocked[ny, nx]:
                        continue
                    if dx and dy and (blocked[y, nx] or blocked[ny, x]):
                        continue
                    new = cost[y, x] + math.hypot(dx, dy) * factor[ny, nx]
                    if new < cost[ny, nx] - 1e-12:
                        cost[ny, nx] = new
                        changed = True
    return cost


@pytest.mark.parametrize("seed", range(8))
def test_planner_against_brute_force(seed):
    rng = np.random.default_rng(seed)
    h, w = rng.integers(3, 8, 2)
    p = np.where(rng.random((h, w)) < 0.3, 0.9, 0.1)
    start = (int(rng.integers(w)), int(rng.integers(h)))
    p[start[1], start[0]] = 0.1
    c = costmap(p, 0.1, 0.0)
    c.factor[:] = rng.uniform(1.0, 3.0, c.factor.shape)  # uneven step costs, as inflation gives
    cost, parent = shortest_paths(c, start)
    reach = _naive_reachable(c.blocked, start)
    assert {(x, y) for y, x in np.argwhere(np.isfinite(cost))} == reach
    np.testing.assert_allclose(cost, _naive_costs(c.blocked, c.factor, start), rtol=1e-12)
    for goal in [(x, y) for y in range(h) for x in range(w)]:
        path = plan_path(c, start, goal)  # A*: the same least cost, a connected path of passable cells
        if goal not in reach:
            assert len(path) == 0
            continue
        assert tuple(path[0]) == start and tuple(path[-1]) == goal
        assert not c.blocked[path[1:, 1], path[1:, 0]].any()
        assert np.all(np.abs(np.diff(path, axis=0)).max(axis=1) == 1)
        assert path_cost(c, path) == pytest.approx(cost[goal[1], goal[0]], rel=1e-12)


@pytest.mark.parametrize("radius", [0.0, 0.05, 0.1, 0.14, 0.2, 0.31])
def test_inflation_against_brute_force_distances(radius):
    rng = np.random.default_rng(int(radius * 100))
    lethal = rng.random((9, 11)) < 0.08
    blocked, factor = inflate(lethal, 0.1, radius, inflation_radius=0.4, cost_scaling=3.0, cost_weight=2.0)
    walls = np.argwhere(lethal)  # (y, x)
    for y in range(9):
        for x in range(11):
            # the gap from this cell's centre to each lethal cell's square, and to its centre [m]
            gaps = [math.hypot(max(abs(x - wx) - 0.5, 0), max(abs(y - wy) - 0.5, 0)) * 0.1 for wy, wx in walls]
            centres = [math.hypot(x - wx, y - wy) * 0.1 for wy, wx in walls]
            near = lethal[y, x] or min(gaps) < radius
            assert blocked[y, x] == near, (x, y)
            d = min(centres)
            expected = 1.0 if near or d > 0.4 else 1.0 + 2.0 * math.exp(-3.0 * (d - radius))
            assert factor[y, x] == pytest.approx(expected, rel=1e-12), (x, y)


def test_costmap_reads_maps_as_nav2_and_unknown_per_flag():
    p = np.array([[0.65, 0.649, 0.197, 0.196, 0.5]])
    c = costmap(p, 0.1, 0.0)
    assert c.lethal.tolist() == [[True, False, False, False, False]]
    assert c.free.tolist() == [[False, False, False, True, False]]
    assert c.blocked.tolist() == [[True, False, False, False, False]]
    assert costmap(p, 0.1, 0.0, unknown="lethal").blocked.tolist() == [[True, True, True, False, True]]


def test_frontiers_are_free_cells_beside_unknown():
    p = np.full((6, 6), 0.5)
    p[1:5, 1:5] = 0.1
    p[1:5, 4] = 0.9  # a wall on the right: no frontier through it
    f = frontiers(costmap(p, 0.1, 0.0))
    expected = np.zeros((6, 6), bool)
    expected[1, 1:4] = expected[4, 1:4] = expected[1:5, 1] = True
    np.testing.assert_array_equal(f, expected)


def _room(size=20, resolution=0.1):
    cells = np.zeros((size, size))
    cells[0, :] = cells[-1, :] = cells[:, 0] = cells[:, -1] = 1.0
    return Scene("room", OccupancyGrid(cells, resolution), (size * resolution / 2, size * resolution / 2, 0.0))


@pytest.mark.parametrize("kind", list(ONBOARD_MAPS))
def test_a_tiny_empty_room_is_covered_without_collisions(kind):
    scene = _room()
    run = explore(scene, kind, ExploreSettings(robot_radius=0.15, max_scans=80), seed=1)
    assert run.stop == "coverage"
    assert run.coverage >= 0.95 and run.scans_to_goal == run.scans
    assert run.collisions == 0 and run.plans_into_walls == 0
    assert run.target.sum() == reachable_free_space(scene, 0.15).sum() > 0


def test_a_run_is_deterministic_and_the_seed_matters():
    from crfmap.world.office import office_floor

    scene = office_floor(8.0, 6.0, 0.1, seed=2)
    settings = ExploreSettings(max_scans=40, range_noise=0.05)
    a, b = (explore(scene, "online-crf", settings, seed=3) for _ in range(2))
    for key, value in a.summary().items():
        if not key.endswith("seconds"):
            assert getattr(b, key) == value, key
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_array_equal(a.probability, b.probability)
    other = explore(scene, "online-crf", settings, seed=4)
    assert not np.array_equal(other.probability, a.probability)


def test_a_map_that_hides_walls_leads_into_them():
    # the truth has a wall across the room with a door at its right end; an onboard map that reads every
    # wall it sees as free plans through it: the referee counts those plans and the refused steps
    scene = _room(20)
    scene.truth.probability[10, 1:15] = 1.0
    scene.start = (0.55, 0.55, 0.0)

    class Wallless:
        def __init__(self, bounds, resolution, laser):
            self.inner = make_onboard("raw", bounds, resolution, laser)

        def integrate(self, ranges, pose):
            self.inner.integrate(ranges, pose)

        def probability(self):
            p = self.inner.probability()
            return np.where(p >= 0.65, 0.0, p)

    ONBOARD_MAPS["wallless"] = Wallless
    try:
        run = explore(scene, "wallless", ExploreSettings(robot_radius=0.0, max_scans=60), seed=0)
        honest = explore(scene, "raw", ExploreSettings(robot_radius=0.0, max_scans=60), seed=0)
    finally:
        del ONBOARD_MAPS["wallless"]
    assert run.collisions > 0 and run.plans_through_free_walls > 0
    assert honest.collisions == 0 and honest.plans_through_free_walls == 0 and honest.stop == "coverage"
    blind = np.full(scene.truth.shape, 0.1)  # all free: the navigation task plans through the wall
    nav = navigation_task(blind, scene, 0.0, n_pairs=30, seed=0)
    truth_nav = navigation_task(scene.truth.probability, scene, 0.0, n_pairs=30, seed=0)
    assert nav["into_walls"] > 0 and nav["pairs"] == 30
    assert {k: truth_nav[k] for k in ("pairs", "succeeded", "into_walls", "failed")} == {
        "pairs": 30, "succeeded": 30, "into_walls": 0, "failed": 0}
    assert truth_nav["length_ratio"] >= 1.0  # the inflation cost keeps paths off the walls: never shorter
    unexplored = navigation_task(np.full(scene.truth.shape, 0.5), scene, 0.0, n_pairs=30, unknown="lethal", seed=0)
    assert unexplored["failed"] == 30  # nothing known and unknown blocked: every plan fails


def test_map_scores_count_misses_ghosts_and_iou():
    scene = _room(10)
    target = reachable_free_space(scene, 0.0)
    truth = scene.truth.probability
    assert map_scores(truth, scene, target) == {"dangerous_misses": 0, "dangerous_miss_rate": 0.0, "wall_iou": 1.0,
                                                "ghosts": 0}
    p = truth.copy()
    p[0, 3] = 0.1  # a wall cell called free
    p[5, 5] = 0.9  # a ghost
    s = map_scores(p, scene, target)
    walls = 36  # the border ring: every cell of it is an 8-neighbour of the free space
    assert s["dangerous_misses"] == 1 and s["dangerous_miss_rate"] == pytest.approx(1 / walls)
    assert s["ghosts"] == 1 and s["wall_iou"] == pytest.approx((walls - 1) / (walls + 1))


def test_bad_input_is_refused():
    scene = _room()
    with pytest.raises(InputError, match="onboard"):
        explore(scene, "nope")
    with pytest.raises(InputError, match="cells_per_scan"):
        ExploreSettings(cells_per_scan=0)
    with pytest.raises(InputError, match="coverage_goal"):
        ExploreSettings(coverage_goal=1.5)
    with pytest.raises(InputError, match="unknown"):
        ExploreSettings(unknown="maybe")
    with pytest.raises(InputError, match="scene"):
        explore("room")
    with pytest.raises(InputError, match="laser"):
        explore(scene, laser="sick")
    with pytest.raises(InputError, match="start"):
        explore(Scene("s", scene.truth, (0.05, 0.05, 0.0)))  # the start cell is a wall
    with pytest.raises(InputError, match="probability"):
        costmap(np.array([[1.5]]), 0.1, 0.0)
    with pytest.raises(InputError, match="goal"):
        plan_path(costmap(np.zeros((3, 3)), 0.1, 0.0), (0, 0), (5, 0))
    with pytest.raises(InputError, match="probability"):
        map_scores(np.zeros((3, 3)), scene, np.zeros((3, 3), bool))
    with pytest.raises(InputError, match="n_pairs"):
        navigation_task(scene.truth.probability, scene, 0.0, n_pairs=0)
    with pytest.raises(InputError, match="every"):
        make_onboard("refined-on-arrival", (0, 0, 1, 1), 0.1, Laser(), every=0)
