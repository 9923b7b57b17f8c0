"""The thesis's closed loop (sec. 4.3): a robot explores with its own onboard map, then navigates on it.

A round robot stands in a ground-truth scene with the project's laser (:func:`crfmap.sim.simulator.cast_rays`,
range noise :func:`crfmap.sim.simulator.add_range_noise`). It repeats: scan, add the scan to its onboard
map (:mod:`crfstudy.closed_loop.onboard`), read the map as nav2 does (:func:`crfstudy.closed_loop.frontiers.costmap`), pick
the nearest reachable frontier by Dijkstra over the inflated map, and drive ``cells_per_scan`` cells of
that path. Every step is checked against the *truth*: a step whose footprint would touch a true wall is
a collision; the robot stays, scans and replans. A plan whose path touches a true wall is counted
whether or not the robot drives into it. The run ends when the scans have observed ``coverage_goal``
of the reachable free space (true free cells under the robot's footprint at some reachable pose), at
the scan budget, when no frontier is reachable, or after ``max_collisions`` collisions in a row.

Coverage is the referee's, the same for every onboard map: a cell counts once a beam has passed or
ended in it (the arctan builder's cells). A frontier the robot stands next to after scanning, still a
frontier, is given up (its neighbourhood is blacklisted, as explore_lite does), so a cell no beam can
resolve does not hold the robot forever.

>>> from crfmap.world.scenes import enclosed_boxes
>>> run = explore(enclosed_boxes("train"), "raw", ExploreSettings(robot_radius=None, max_scans=40), seed=0)
>>> run.stop, run.collisions, bool(run.coverage >= 0.95)
('coverage', 0, True)
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, fields

import numpy as np

from crfmap.checks import check_int, check_number
from crfmap.errors import InputError
from crfmap.mapping.builder import HitCounter
from crfstudy.closed_loop.frontiers import FREE, LETHAL, UNKNOWN_READINGS, costmap, frontiers, path_to, plan_path, shortest_paths
from crfmap.sim.laser import Laser
from crfstudy.closed_loop.onboard import make_onboard
from crfmap.sim.simulator import add_range_noise, cast_rays
from crfmap.world.reachability import footprint_offsets, pose_cell, reachable, traversable
from crfmap.world.scene import Scene


@dataclass(frozen=True)
class ExploreSettings:
    """How the robot explores (every field checked; see the module docstring)."""

    robot_radius: float | None = 0.2  # [m]; None: the scene's own (the thesis's scenes: 0, a point robot)
    cells_per_scan: int = 3  # cells driven along the plan between two scans
    max_scans: int = 600  # budget
    coverage_goal: float = 0.95  # fraction of the reachable free space observed
    range_noise: float = 0.02  # [m] the thesis's +-C on every range
    unknown: str = "free"  # planner reads unknown cells as free (nav2 allow_unknown) or lethal
    min_frontier: int = 3  # [cells] smaller frontier groups are ignored
    giveup_radius: int = 2  # [cells] around a frontier reached and still unresolved, frontiers are dropped
    max_collisions: int = 5  # in a row: the robot is stuck
    max_stalls: int = 5  # plannings in a row that find no frontier (the robot scans again where it stands)
    onboard_options: dict = field(default_factory=dict)  # passed to the onboard map's constructor

    def __post_init__(self):
        if self.robot_radius is not None:
            object.__setattr__(self, "robot_radius", check_number("robot_radius", self.robot_radius, low=0.0))
        for name in ("cells_per_scan", "max_scans", "min_frontier", "max_collisions", "max_stalls"):
            object.__setattr__(self, name, check_int(name, getattr(self, name), low=1))
        object.__setattr__(self, "giveup_radius", check_int("giveup_radius", self.giveup_radius, low=0))
        object.__setattr__(self, "coverage_goal", check_number("coverage_goal", self.coverage_goal, 0.0, True, 1.0))
        object.__setattr__(self, "range_noise", check_number("range_noise", self.range_noise, low=0.0))
        if self.unknown not in UNKNOWN_READINGS:
            raise InputError("unknown", f"must be one of {', '.join(UNKNOWN_READINGS)}, got {self.unknown!r}")
        if not isinstance(self.onboard_options, dict):
            raise InputError("onboard_options", f"expected a dict, got {type(self.onboard_options).__name__}")

    def as_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass
class ExplorationRun:
    """One exploration: what it cost, what went wrong, and the map it ended with."""

    scene: str
    onboard: str
    seed: int
    stop: str  # "coverage", "budget", "no frontier" or "stuck"
    scans: int  # scans taken
    scans_to_goal: int | None  # scans when coverage first reached the goal (None: never)
    distance: float  # [m] driven
    distance_to_goal: float | None  # [m] driven when coverage first reached the goal
    collisions: int  # steps refused because the footprint would touch a true wall
    plans: int  # frontier plans made
    failed_plans: int  # plannings that found no reachable frontier before the goal
    plans_into_walls: int  # plans whose path touches a true wall
    plans_through_free_walls: int  # ... where a touched true wall cell is mapped free (not merely unknown)
    map_seconds: float  # integrating scans and reading the map
    plan_seconds: float  # costmap, frontiers, Dijkstra
    coverage: float  # final fraction of the reachable free space observed
    coverage_trace: np.ndarray  # after each scan
    path: np.ndarray  # (n, 2) robot positions [m], one per step driven (the start first)
    probability: np.ndarray  # the onboard map at the end, [y, x]
    target: np.ndarray = field(repr=False)  # the reachable free space (the coverage's denominator)

    def summary(self) -> dict:
        """The scalar results, for a table row."""
        keep = ("scene", "onboard", "seed", "stop", "scans", "scans_to_goal", "distance", "distance_to_goal",
                "collisions", "plans", "failed_plans", "plans_into_walls", "plans_through_free_walls", "map_seconds", "plan_seconds", "coverage")
        return {k: getattr(self, k) for k in keep}


def reachable_free_space(scene: Scene, robot_radius) -> np.ndarray:
    """Boolean [y, x]: true free cells a round robot reachable from the start can cover with its footprint.

    >>> from crfmap.world.scenes import enclosed_boxes
    >>> s = enclosed_boxes("train")
    >>> int(reachable_free_space(s, 0.0).sum()) == int(reachable(s.truth, s.start).sum())
    True
    """
    truth = scene.truth
    centres = reachable(truth, scene.start, robot_radius)
    covered = np.zeros_like(centres)
    h, w = centres.shape
    ys, xs = np.nonzero(centres)
    for dx, dy in footprint_offsets(robot_radius, truth.resolution):
        x, y = xs + dx, ys + dy
        inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
        covered[y[inside], x[inside]] = True
    return covered & (truth.probability <= 0.5)


class _Robot:
    """The robot's true state and the referee's counts while it explores."""

    def __init__(self, scene, laser, settings, rng):
        self.scene, self.laser, self.settings, self.rng = scene, laser, settings, rng
        truth = scene.truth
        self.radius = scene.robot_radius if settings.robot_radius is None else settings.robot_radius
        self.fits = traversable(truth, self.radius)  # where the footprint touches no true wall
        self.target = reachable_free_space(scene, self.radius)
        self.cell = pose_cell(truth, scene.start)
        self.yaw = float(scene.start[2])
        self.referee = HitCounter.for_sensor(truth.bounds(), truth.resolution, laser.angle_min, laser.angle_increment,
                                             laser.n_beams, laser.range_min, laser.range_max)
        self.path = [self.position()]
        self.distance = 0.0

    def position(self):
        x, y = self.scene.truth.cell_to_world(*self.cell)
        return float(x), float(y)

    def scan(self):
        pose = (*self.position(), self.yaw)
        ranges = cast_rays(self.scene.truth, self.laser, [pose])
        ranges = add_range_noise(ranges, self.settings.range_noise, rng=self.rng)[0]
        ranges[ranges == math.inf] = self.laser.no_return
        self.referee.add_scan(ranges.astype(np.float32), pose)
        return ranges, pose

    def coverage(self) -> float:
        seen = (self.referee.occupied > 0) | (self.referee.empty > 0)
        return float((seen & self.target).sum() / max(int(self.target.sum()), 1))

    def touches_free_wall(self, cells, free) -> bool:
        """Whether the footprint at any of ``cells`` (x, y) touches a true wall cell that ``free`` calls free."""
        h, w = free.shape
        opened = (self.scene.truth.probability > 0.5) & free
        for dx, dy in footprint_offsets(self.radius, self.scene.truth.resolution):
            x, y = cells[:, 0] + dx, cells[:, 1] + dy
            inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
            if opened[y[inside], x[inside]].any():
                return True
        return False

    def step_to(self, cell) -> bool:
        """Move to a neighbouring cell unless the footprint would touch a true wall there (a collision)."""
        x, y = int(cell[0]), int(cell[1])
        if not self.fits[y, x]:
            return False
        dx, dy = x - self.cell[0], y - self.cell[1]
        self.distance += math.hypot(dx, dy) * self.scene.truth.resolution
        self.yaw = math.atan2(dy, dx)
        self.cell = (x, y)
        self.path.append(self.position())
        return True


def _nearest_frontier(cost, mask):
    """Cell (x, y) of the least-cost frontier (ties: lowest row, then column), or None."""
    c = np.where(mask, cost, np.inf)
    i = int(np.argmin(c))
    return None if not np.isfinite(c.flat[i]) else (i % c.shape[1], i // c.shape[1])


def explore(scene: Scene, onboard="raw", settings: ExploreSettings | None = None, laser: Laser | None = None,
            seed=0) -> ExplorationRun:
    """Explore ``scene`` with an ``onboard`` map (a key of :data:`crfstudy.closed_loop.onboard.ONBOARD_MAPS`).

    Deterministic: the range noise comes from ``np.random.default_rng(seed)``; ties between frontiers
    break by position. Returns an :class:`ExplorationRun`.
    """
    if not isinstance(scene, Scene):
        raise InputError("scene", f"expected a crfmap.world.scene.Scene, got {type(scene).__name__}")
    settings = ExploreSettings() if settings is None else settings
    if not isinstance(settings, ExploreSettings):
        raise InputError("settings", f"expected an ExploreSettings, got {type(settings).__name__}")
    laser = Laser() if laser is None else laser
    if not isinstance(laser, Laser):
        raise InputError("laser", f"expected a crfmap.sim.laser.Laser, got {type(laser).__name__}")
    seed = check_int("seed", seed, low=0)
    truth = scene.truth
    robot = _Robot(scene, laser, settings, np.random.default_rng(seed))
    onboard_map = make_onboard(onboard, truth.bounds(), truth.resolution, laser, **settings.onboard_options)
    given_up = np.zeros(truth.shape, bool)
    counts = dict(collisions=0, plans=0, failed_plans=0, plans_into_walls=0, plans_through_free_walls=0)
    map_seconds = plan_seconds = 0.0
    trace, goal_at, stop, in_a_row, stalls = [], None, "budget", 0, 0
    g = settings.giveup_radius
    for _ in range(settings.max_scans):
        ranges, pose = robot.scan()
        t0 = time.perf_counter()
        onboard_map.integrate(ranges, pose)
        probability = onboard_map.probability()
        t1 = time.perf_counter()
        map_seconds += t1 - t0
        trace.append(robot.coverage())
        if goal_at is None and trace[-1] >= settings.coverage_goal:
            goal_at = (len(trace), robot.distance)
            stop = "coverage"
            break
        cmap = costmap(probability, truth.resolution, robot.radius, settings.unknown)
        cost, parent = shortest_paths(cmap, robot.cell)
        candidates = frontiers(cmap, settings.min_frontier) & ~given_up
        goal = _nearest_frontier(cost, candidates)
        while goal is not None and max(abs(goal[0] - robot.cell[0]), abs(goal[1] - robot.cell[1])) <= 1:
            given_up[max(goal[1] - g, 0): goal[1] + g + 1, max(goal[0] - g, 0): goal[0] + g + 1] = True
            goal = _nearest_frontier(cost, candidates & ~given_up)
        plan_seconds += time.perf_counter() - t1
        if goal is None:
            counts["failed_plans"] += 1
            stalls += 1
            if stalls >= settings.max_stalls:
                stop = "no frontier"
                break
            continue
        stalls = 0
        path = path_to(parent, goal)
        counts["plans"] += 1
        into = path[~robot.fits[path[:, 1], path[:, 0]]]
        if len(into):
            counts["plans_into_walls"] += 1
            counts["plans_through_free_walls"] += int(robot.touches_free_wall(into, cmap.free))
        for cell in path[1 : settings.cells_per_scan + 1]:
            if not robot.step_to(cell):
                counts["collisions"] += 1
                in_a_row += 1
                break
            in_a_row = 0
        if in_a_row >= settings.max_collisions:
            stop = "stuck"
            break
    return ExplorationRun(
        scene=scene.name, onboard=onboard, seed=seed, stop=stop, scans=len(trace),
        scans_to_goal=None if goal_at is None else goal_at[0], distance=robot.distance,
        distance_to_goal=None if goal_at is None else goal_at[1], map_seconds=map_seconds, plan_seconds=plan_seconds,
        coverage=trace[-1] if trace else 0.0, coverage_trace=np.asarray(trace), path=np.asarray(robot.path),
        probability=np.asarray(onboard_map.probability(), np.float64).copy(), target=robot.target, **counts)


def map_scores(probability, scene: Scene, target) -> dict:
    """The final map against the truth, on the reachable free space ``target`` and its 8 neighbours.

    ``dangerous_misses``: true wall cells there the map calls free (P <= 0.196), and their fraction of the
    true wall cells there; ``wall_iou``: lethal (P >= 0.65) against true walls there; ``ghosts``: true free
    cells of ``target`` the map calls lethal.
    """
    p = np.asarray(probability, np.float64)
    truth = scene.truth.probability > 0.5
    target = np.asarray(target, bool)
    if p.shape != truth.shape or target.shape != truth.shape:
        raise InputError("probability", f"shape {p.shape} (target {target.shape}) does not match the truth's "
                                        f"{truth.shape}")
    near = target.copy()
    near[1:, :] |= target[:-1, :]
    near[:-1, :] |= target[1:, :]
    near[:, 1:] |= near[:, :-1].copy()
    near[:, :-1] |= near[:, 1:].copy()
    walls = truth & near
    lethal = (p >= LETHAL) & near
    union = int((walls | lethal).sum())
    misses = int((walls & (p <= FREE)).sum())
    return {"dangerous_misses": misses, "dangerous_miss_rate": misses / max(int(walls.sum()), 1),
            "wall_iou": int((walls & lethal).sum()) / union if union else 1.0,
            "ghosts": int(((p >= LETHAL) & target & ~truth).sum())}


def navigation_task(probability, scene: Scene, robot_radius, n_pairs=20, unknown="free", seed=0) -> dict:
    """Plan between ``n_pairs`` random pairs of truly reachable cells (seeded) on a finished map.

    Every pair is connected in the truth; a plan either ``succeeded`` (its footprint touches no true
    wall), went ``into_walls``, or ``failed`` (the map shows no path). ``length_ratio``: mean of the
    successful paths' length over the true map's shortest path (same planner, no inflation cost).
    """
    n_pairs = check_int("n_pairs", n_pairs, low=1)
    robot_radius = check_number("robot_radius", robot_radius, low=0.0)
    truth = scene.truth
    fits = traversable(truth, robot_radius)
    centres = np.argwhere(reachable(truth, scene.start, robot_radius))  # (y, x)
    rng = np.random.default_rng(seed)
    pairs = centres[rng.integers(0, len(centres), (n_pairs, 2))]
    cmap = costmap(probability, truth.resolution, robot_radius, unknown)
    exact = costmap(truth.probability, truth.resolution, robot_radius, "lethal", cost_weight=0.0)
    out = {"pairs": n_pairs, "succeeded": 0, "into_walls": 0, "failed": 0}
    ratios = []
    for (ay, ax), (by, bx) in pairs:
        path = plan_path(cmap, (ax, ay), (bx, by))
        if len(path) == 0:
            out["failed"] += 1
        elif not fits[path[:, 1], path[:, 0]].all():
            out["into_walls"] += 1
        else:
            out["succeeded"] += 1
            best = plan_path(exact, (ax, ay), (bx, by))
            ratios.append(_length(path) / max(_length(best), 1e-9) if len(best) > 1 else 1.0)
    out["length_ratio"] = float(np.mean(ratios)) if ratios else float("nan")
    return out


def _length(path) -> float:
    return float(np.hypot(*np.diff(np.asarray(path, float), axis=0).T).sum()) if len(path) > 1 else 0.0
