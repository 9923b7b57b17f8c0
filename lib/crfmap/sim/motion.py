"""How the simulated robot moves: Twist commands, the true motion they cause, and the three drives.

The robot follows Twist commands (v [m/s], w [rad/s]) at a fixed ``dt``; each step turns by ``w * dt`` and moves
``v * dt`` along the step's mean heading, but does not translate if its straight path would put the robot on an
occupied cell (or too near one for its radius). The drives, :func:`explore_reachable` (the thesis's "the robot has
moved to every cell ... it can physically access"), :func:`look_around` (Fig. 28) and :func:`follow_waypoints`,
return a :class:`Motion`, which :func:`crfmap.sim.simulator.simulate` turns into odometry and scans. Of the laser a
drive needs only how many scans cover a full turn (:meth:`crfmap.sim.laser.Laser.headings_per_turn`).

>>> from crfmap.world.scenes import enclosed_boxes
>>> from crfmap.sim.laser import Laser
>>> m = look_around(enclosed_boxes("train"), Laser.with_fov(180, 9))
>>> len(m.scan_at), len(m.poses) == len(m) + 1
(2, True)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from crfmap.sim.planning import coverage_tour, grid_path, segment_clear, simplify
from crfmap.checks import check_int, check_number, check_positive
from crfmap.errors import InputError
from crfmap.frames import TWO_PI, wrap_angle
from crfmap.world.reachability import pose_cell, reachable, traversable
from crfmap.world.scene import Scene

if TYPE_CHECKING:
    from crfmap.sim.laser import Laser

ALIGNED = 0.05  # [rad] heading error under which the waypoint controller drives instead of turning in place


# --- a drive: steps, poses, scans ---------------------------------------------------------
@njit(cache=True)
def _integrate(x, y, yaw, moves):
    """Poses (n+1, 3) from a start and per-step (distance [m], turn [rad]): turn half, move, turn half."""
    n = moves.shape[0]
    out = np.empty((n + 1, 3))
    out[0, 0] = x
    out[0, 1] = y
    out[0, 2] = yaw
    for k in range(n):
        d = moves[k, 0]
        a = moves[k, 1]
        mid = yaw + 0.5 * a
        x += d * math.cos(mid)
        y += d * math.sin(mid)
        yaw += a
        yaw = (yaw + math.pi) % (2.0 * math.pi) - math.pi
        out[k + 1, 0] = x
        out[k + 1, 1] = y
        out[k + 1, 2] = yaw
    return out


@dataclass
class Motion:
    """A driven run: the commands, what the robot actually did, and when it scanned."""

    poses: np.ndarray  # (n + 1, 3) true base_link pose in map after k steps
    moves: np.ndarray  # (n, 2) (distance [m], turn [rad]) executed in step k
    commands: np.ndarray  # (n, 2) the Twist (v [m/s], w [rad/s]) sent for step k
    scan_at: np.ndarray  # (m,) int, indices into poses
    dt: float  # [s]

    def __len__(self):
        return len(self.moves)


class _Planner:
    """Accumulates turn / drive / scan steps of a robot with speed limits (used by explore and look)."""

    def __init__(self, pose, dt, linear_speed, angular_speed):
        self.x, self.y, self.yaw = (float(v) for v in pose)
        self.dt, self.v_max, self.w_max = dt, linear_speed, angular_speed
        self.moves, self.scans = [], []

    def turn(self, angle):
        if abs(angle) < 1e-12:
            return
        n = int(math.ceil(abs(angle) / (self.w_max * self.dt) - 1e-9))
        self.moves += [(0.0, angle / n)] * n
        self.yaw = float(wrap_angle(self.yaw + angle))

    def turn_to(self, heading):
        self.turn(float(wrap_angle(heading - self.yaw)))

    def drive(self, distance):
        n = int(math.ceil(distance / (self.v_max * self.dt) - 1e-9))
        self.moves += [(distance / n, 0.0)] * n

    def look(self, laser):
        """Scan, then turn by 2 pi / k and scan again, k times in all (one scan for a 360 deg laser)."""
        k = laser.headings_per_turn()
        for i in range(k):
            if i:
                self.turn(TWO_PI / k)
            self.scans.append(len(self.moves))

    def motion(self, start):
        moves = np.asarray(self.moves, dtype=np.float64).reshape(-1, 2)
        poses = _integrate(float(start[0]), float(start[1]), float(start[2]), moves)
        return Motion(poses, moves, moves / self.dt, np.asarray(self.scans, dtype=np.int64), self.dt)


def _check_speeds(dt, linear_speed, angular_speed):
    return (check_positive("dt", dt), check_positive("linear_speed", linear_speed),
            check_positive("angular_speed", angular_speed))


def explore_reachable(scene: Scene, laser: Laser, *, start=None, robot_radius=None, stride=1, dt=0.1,
                      linear_speed=0.5, angular_speed=1.5) -> Motion:
    """Drive through every reachable cell (depth-first, centre to centre, from the start cell's centre) and look
    around at each newly visited cell not within ``stride - 1`` cells (Chebyshev) of an earlier look-around.

    >>> from crfmap.world.scenes import enclosed_boxes
    >>> from crfmap.sim.laser import Laser
    >>> m = explore_reachable(enclosed_boxes("train"), Laser(), stride=4)
    >>> len(m.scan_at) < len(m.poses)
    True
    """
    dt, linear_speed, angular_speed = _check_speeds(dt, linear_speed, angular_speed)
    stride = check_int("stride", stride, low=1)
    grid = scene.truth
    start = tuple(float(v) for v in (scene.start if start is None else start))
    radius = scene.robot_radius if robot_radius is None else check_number("robot_radius", robot_radius, low=0.0)
    can_reach = reachable(grid, start, radius)
    sx, sy = pose_cell(grid, start)
    tour = coverage_tour(can_reach, sx, sy)
    cx, cy = grid.cell_to_world(tour[:, 0], tour[:, 1])
    plan = _Planner(start, dt, linear_speed, angular_speed)
    covered = np.zeros(grid.shape, dtype=bool)
    visited = np.zeros(grid.shape, dtype=bool)
    r = int(stride) - 1
    for i in range(len(tour)):
        dx, dy = cx[i] - plan.x, cy[i] - plan.y
        distance = math.hypot(dx, dy)
        if distance > 1e-9:
            plan.turn_to(math.atan2(dy, dx))
            plan.drive(distance)
            plan.x, plan.y = float(cx[i]), float(cy[i])
        ix, iy = tour[i]
        if not visited[iy, ix]:
            visited[iy, ix] = True
            if not covered[iy, ix]:
                plan.look(laser)
                covered[max(0, iy - r) : iy + r + 1, max(0, ix - r) : ix + r + 1] = True
    return plan.motion(start)


def look_around(scene: Scene, laser: Laser, *, start=None, dt=0.1, angular_speed=1.5, turns=1) -> Motion:
    """Stand at the start and turn in place, scanning: ``turns`` full circles of look-arounds (thesis Fig. 28).

    >>> from crfmap.grid import OccupancyGrid
    >>> from crfmap.sim.laser import Laser
    >>> m = look_around(Scene("s", OccupancyGrid(np.zeros((3, 3))), (1.5, 1.5, 0.0)), Laser.with_fov(90, 10))
    >>> len(m.scan_at), round(float(np.degrees(m.poses[m.scan_at[-1], 2])), 6)
    (4, -90.0)
    """
    dt, _, angular_speed = _check_speeds(dt, 1.0, angular_speed)
    turns = check_int("turns", turns, low=1)
    start = tuple(float(v) for v in (scene.start if start is None else start))
    pose_cell(scene.truth, start)
    plan = _Planner(start, dt, 1.0, angular_speed)
    for t in range(int(turns)):
        if t:
            plan.turn(TWO_PI / laser.headings_per_turn())
        plan.look(laser)
    return plan.motion(start)


# --- waypoints ----------------------------------------------------------------------------
@njit(cache=True)
def _step(x, y, yaw, v, w, dt, free, ox, oy, c, s, res):
    """One step: turn ``w*dt``, translate ``v*dt`` unless that runs into a non-free cell of the grid at (ox, oy) with
    yaw cosine / sine (c, s) and cell size ``res``."""
    d = v * dt
    a = w * dt
    mid = yaw + 0.5 * a
    nx = x + d * math.cos(mid)
    ny = y + d * math.sin(mid)
    if d != 0.0:
        x0, y0 = (c * (x - ox) + s * (y - oy)) / res, (-s * (x - ox) + c * (y - oy)) / res
        x1, y1 = (c * (nx - ox) + s * (ny - oy)) / res, (-s * (nx - ox) + c * (ny - oy)) / res
        if not segment_clear(free, x0, y0, x1, y1):
            d = 0.0
    return d, a


def follow_waypoints(scene: Scene, laser: Laser, waypoints=None, *, start=None, robot_radius=None, dt=0.1,
                     linear_speed=0.5, angular_speed=1.5, scan_period=0.2, max_steps=1_000_000) -> Motion:
    """Drive through ``waypoints`` (x, y) [m] in order, scanning every ``scan_period`` seconds, along the shortest grid
    path (8-connected, footprint respected) shortened to straight free segments. The controller sees the true pose: it
    turns in place towards the next point when off by more than ``ALIGNED`` rad, else drives at up to ``linear_speed``
    while steering (``w = heading error / dt``).

    >>> from crfmap.world.scenes import office_floor
    >>> from crfmap.sim.laser import Laser
    >>> s = office_floor(8.0, 6.0, 0.1, seed=0)
    >>> m = follow_waypoints(s, Laser(), s.waypoints[:1])
    >>> bool(np.hypot(*(m.poses[-1, :2] - s.waypoints[0])) < 0.05)
    True
    """
    dt, linear_speed, angular_speed = _check_speeds(dt, linear_speed, angular_speed)
    scan_period = check_positive("scan_period", scan_period)
    grid = scene.truth
    start = tuple(float(v) for v in (scene.start if start is None else start))
    radius = scene.robot_radius if robot_radius is None else check_number("robot_radius", robot_radius, low=0.0)
    if waypoints is None:
        waypoints = scene.waypoints
    if waypoints is None:
        raise InputError("waypoints", f"scene {scene.name!r} has no waypoints; give some")
    wps = np.asarray(waypoints, dtype=np.float64)
    if wps.ndim != 2 or wps.shape[1] < 2 or len(wps) == 0 or not np.isfinite(wps).all():
        raise InputError("waypoints", f"expected finite (k, 2) x, y rows, got shape {wps.shape}")
    can_reach = reachable(grid, start, radius)
    free = traversable(grid, radius)
    cell = pose_cell(grid, start)
    # Targets: the simplified grid path's cell centres, then the waypoint, from its cell's centre: no leg cuts a corner
    targets = [tuple(float(v) for v in grid.cell_to_world(*cell))]
    for k, (wx, wy) in enumerate(wps[:, :2]):
        try:
            goal = pose_cell(grid, (wx, wy))
        except InputError:
            raise InputError("waypoints", f"waypoint {k} ({wx:g}, {wy:g}) m lies outside the grid") from None
        if not can_reach[goal[1], goal[0]]:
            raise InputError("waypoints", f"waypoint {k} ({wx:g}, {wy:g}) m is not reachable from the start")
        path = simplify(free, grid_path(free, cell[0], cell[1], goal[0], goal[1]))
        px, py = grid.cell_to_world(path[1:, 0], path[1:, 1])
        targets += [(float(a), float(b)) for a, b in zip(px, py)]
        targets.append((float(wx), float(wy)))
        cell = goal
    ox, oy, oyaw = grid.origin
    frame = (ox, oy, math.cos(oyaw), math.sin(oyaw), grid.resolution)
    scan_every = max(1, int(round(scan_period / dt)))
    x, y, yaw = start
    poses, moves, commands, scans = [start], [], [], [0]
    tol = max(1e-3, 0.02 * grid.resolution)
    blocked = 0
    for tx, ty in targets:
        while True:
            dx, dy = tx - x, ty - y
            dist = math.hypot(dx, dy)
            if dist < tol:
                break
            err = float(wrap_angle(math.atan2(dy, dx) - yaw))
            w = max(-angular_speed, min(angular_speed, err / dt))
            v = 0.0 if abs(err) > ALIGNED else min(linear_speed, dist / dt)
            d, a = _step(x, y, yaw, v, w, dt, free, *frame)
            blocked = blocked + 1 if (v > 0 and d == 0) else 0
            if blocked > 20 or len(moves) >= max_steps:
                raise InputError("waypoints", f"the robot got stuck at ({x:.2f}, {y:.2f}) m on its way to "
                                              f"({tx:.2f}, {ty:.2f}) m; add waypoints around the obstacle")
            mid = yaw + 0.5 * a
            x, y, yaw = x + d * math.cos(mid), y + d * math.sin(mid), float(wrap_angle(yaw + a))
            poses.append((x, y, yaw))
            moves.append((d, a))
            commands.append((v, w))
            if len(moves) % scan_every == 0:
                scans.append(len(moves))
    if scans[-1] != len(moves):
        scans.append(len(moves))
    moves = np.asarray(moves, dtype=np.float64).reshape(-1, 2)
    return Motion(_integrate(start[0], start[1], start[2], moves), moves,
                  np.asarray(commands, dtype=np.float64).reshape(-1, 2), np.asarray(scans, dtype=np.int64), dt)

