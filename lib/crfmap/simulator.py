"""A robot with a laser scanner in a ground-truth grid (thesis sec. 3.1), recorded as a bag would hold it.

Sensing. Each beam is ray-cast with Bresenham's line (:func:`crfmap.raycast._first_hit`,
thesis Listing 1) from the laser's cell to the cell of the beam's end point at
``range_max``; the range of a hit is the Euclidean distance from the laser's position to
the centre of the hit cell (so axis-aligned beams from a cell centre read whole cells).
Hits farther than ``range_max`` are no return (``+inf``, REP 117; the thesis wrote -1,
:data:`LEGACY_NO_RETURN`); hits nearer than ``range_min`` are ``-inf`` (too close). Outside
the grid is empty space. Range noise is the thesis's ``d +- C``: ``d + s * c`` with ``s`` a
random sign and ``c`` uniform in ``[0, C]`` (optionally plus Gaussian noise), applied to
returns only and floored at 0; a noisy value may leave ``[range_min, range_max]``, and
readers discard it then, as REP 117 asks.

Motion. The robot follows Twist commands (v [m/s], w [rad/s]) at a fixed ``dt``; each
step it turns by ``w * dt`` and moves ``v * dt`` along the mean heading of the step. The
true motion is the commanded one, except that a step whose straight path would put the
robot on an occupied cell (or too near one for its radius) does not translate. Odometry
integrates what the wheels report: every executed translation ``d`` reads ``d +- C_lin``
and every executed turn ``a`` reads ``a +- C_yaw`` (the thesis's noise "at each interval
of movement", Fig. 16); wheels that do not turn add no error. Odometry starts at (0, 0, 0)
in ``odom``; ``map -> odom`` is the start pose (``recording.meta["map_to_odom"]``).

Modes (:func:`simulate`):

- ``"explore"`` (:func:`explore_reachable`): drive cell to cell along a depth-first tour of
  every reachable cell and look around (a full turn in place, or one scan for a 360 deg
  laser) at each newly visited cell, or at fewer with ``stride``; the thesis's "the robot
  has moved to every cell ... it can physically access".
- ``"look"`` (:func:`look_around`): stand at the start and turn in place (Fig. 28).
- ``"waypoints"`` (:func:`follow_waypoints`): plan a grid path through the waypoints and
  drive it with a turn-then-go controller on the true pose, scanning at a fixed rate.

>>> from crfmap.scenes import enclosed_boxes
>>> rec = simulate(enclosed_boxes("train"), Laser.with_fov(360, 90), mode="look", progress=False)
>>> rec.scans.ranges.shape
(1, 90)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .errors import InputError
from .grid import OccupancyGrid
from .raycast import _first_hit
from .recording import Recording, ScanSet, Trajectory
from .scenes import MODES, Scene, pose_cell, reachable, traversable

LEGACY_NO_RETURN = -1.0  # the thesis's "nothing within range" code (sec. 3.1.1)
SCAN_CHUNK = 512  # scans per progress-bar tick
PROGRESS_BEAMS = 2_000_000  # beams in a run above which simulate() shows a progress bar (below, it is too quick)
TWO_PI = 2.0 * math.pi
ALIGNED = 0.05  # [rad] heading error under which the waypoint controller drives instead of turning in place


def _number(name, value, low=None, low_open=False):
    numeric = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
    if not numeric or not math.isfinite(value):
        raise InputError(name, f"expected a finite number, got {value!r}")
    value = float(value)
    if low is not None and (value < low or (low_open and value == low)):
        raise InputError(name, f"must be {'>' if low_open else '>='} {low:g}, got {value:g}")
    return value


def wrap_angle(a):
    """Angles folded into [-pi, pi)."""
    return (np.asarray(a) + math.pi) % TWO_PI - math.pi


def compose(a, b) -> np.ndarray:
    """Planar pose composition ``a (+) b`` of (x, y, yaw) rows: pose ``b`` (given in frame ``a``) in ``a``'s parent.

    >>> compose([1.0, 0.0, math.pi / 2], [1.0, 0.0, 0.0]).round(6).tolist()
    [1.0, 1.0, 1.570796]
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    y = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    return np.stack([x, y, wrap_angle(a[..., 2] + b[..., 2])], axis=-1)


# --- the laser --------------------------------------------------------------------------
@dataclass
class Laser:
    """A planar laser scanner, as a sensor_msgs/LaserScan describes it.

    Beam i points at ``angle_min + i * angle_increment`` (CCW, laser frame) for
    ``angle_min <= angle <= angle_max``. ``no_return`` is what a beam that hits nothing
    reports: ``inf`` (REP 117) or :data:`LEGACY_NO_RETURN` (-1, the thesis).

    >>> Laser.with_fov(180, 5).angles.round(3).tolist()
    [-1.571, -0.785, 0.0, 0.785, 1.571]
    """

    angle_min: float = -math.pi  # [rad]
    angle_max: float = math.pi - TWO_PI / 360  # [rad]
    angle_increment: float = TWO_PI / 360  # [rad]
    range_min: float = 0.05  # [m]
    range_max: float = 5.0  # [m]
    no_return: float = math.inf  # reported for beams that hit nothing within range_max

    def __post_init__(self):
        for name in ("angle_min", "angle_max", "angle_increment", "range_min", "range_max"):
            setattr(self, name, _number(f"laser.{name}", getattr(self, name)))
        if self.angle_increment <= 0:
            raise InputError("laser.angle_increment", f"must be > 0, got {self.angle_increment:g}")
        if self.angle_max < self.angle_min:
            raise InputError("laser.angle_max", f"must be >= angle_min ({self.angle_min:g}), got {self.angle_max:g}")
        if self.fov > TWO_PI + 1e-9:
            raise InputError("laser", f"the beams span {math.degrees(self.fov):g} deg, more than a full turn")
        if not 0 <= self.range_min < self.range_max:
            raise InputError("laser.range_min",
                             f"need 0 <= range_min < range_max, got {self.range_min:g}, {self.range_max:g}")
        nr = float(self.no_return)
        if not (nr == math.inf or nr < 0):
            raise InputError("laser.no_return", f"must be inf (REP 117) or negative (legacy -1), got {nr:g}")
        self.no_return = nr

    @classmethod
    def with_fov(cls, fov_deg=360.0, n_beams=360, range_max=5.0, range_min=0.05, no_return=math.inf) -> "Laser":
        """A laser of ``n_beams`` beams centred on +x. A 360 deg one spreads them evenly over the circle from -pi.

        >>> Laser.with_fov(360, 4).angles.round(3).tolist()
        [-3.142, -1.571, 0.0, 1.571]
        """
        fov_deg = _number("fov", fov_deg, 0.0, low_open=True)
        if fov_deg > 360:
            raise InputError("fov", f"must be at most 360 deg, got {fov_deg:g}")
        if isinstance(n_beams, bool) or not isinstance(n_beams, (int, np.integer)) or n_beams < 1:
            raise InputError("beams", f"must be a positive integer, got {n_beams!r}")
        if fov_deg == 360:
            inc = TWO_PI / n_beams
            return cls(-math.pi, math.pi - inc, inc, range_min, range_max, no_return)
        fov = math.radians(fov_deg)
        if n_beams == 1:
            return cls(0.0, 0.0, fov, range_min, range_max, no_return)
        return cls(-fov / 2, fov / 2, fov / (n_beams - 1), range_min, range_max, no_return)

    @property
    def n_beams(self) -> int:
        return int(math.floor((self.angle_max - self.angle_min) / self.angle_increment + 1e-6)) + 1

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.n_beams)

    @property
    def fov(self) -> float:
        """Angle [rad] the beams cover, counting half an increment on each side."""
        return self.angle_max - self.angle_min + self.angle_increment

    def headings_per_turn(self) -> int:
        """How many scans, turning by ``2 pi / n`` between them, cover a full circle."""
        return max(1, int(math.ceil(TWO_PI / self.fov - 1e-9)))


# --- ray casting --------------------------------------------------------------------------
@njit(cache=True)
def _cast_scans(occupied, lx, ly, lyaw, angles, reach, out):
    """Distances [cells] from laser positions (lx, ly) [cells, continuous] to the first occupied cell's centre.

    ``out[i, j]`` = inf where beam j of scan i meets nothing before ``reach`` cells.
    """
    for i in range(lx.shape[0]):
        cx = int(math.floor(lx[i]))
        cy = int(math.floor(ly[i]))
        for j in range(angles.shape[0]):
            a = lyaw[i] + angles[j]
            ex = int(math.floor(lx[i] + reach * math.cos(a)))
            ey = int(math.floor(ly[i] + reach * math.sin(a)))
            hx, hy, hit = _first_hit(occupied, cx, cy, ex, ey)
            if hit:
                out[i, j] = math.hypot(hx + 0.5 - lx[i], hy + 0.5 - ly[i])
            else:
                out[i, j] = math.inf


def cast_rays(truth: OccupancyGrid, laser: Laser, laser_poses, progress=False) -> np.ndarray:
    """Noiseless ranges [m] of every beam from every laser pose: (n_poses, n_beams) float64.

    ``+inf`` = nothing within ``range_max``; ``-inf`` = a hit nearer than ``range_min``.

    Parameters
    ----------
    truth : OccupancyGrid, occupied where P > 0.5
    laser : Laser
    laser_poses : (n, 3) x [m], y [m], yaw [rad] of the laser in the grid's frame

    >>> from crfmap.scenes import enclosed_boxes
    >>> s = enclosed_boxes("train")
    >>> cast_rays(s.truth, Laser.with_fov(360, 4), [s.start]).round(2).tolist()  # -x, -y, +x, +y
    [[0.2, 3.7, 3.7, 0.2]]
    """
    from tqdm.auto import tqdm

    poses = np.asarray(laser_poses, dtype=np.float64)
    if poses.ndim != 2 or poses.shape[1] != 3 or not np.isfinite(poses).all():
        raise InputError("laser_poses", f"expected finite (n, 3) x, y, yaw rows, got shape {poses.shape}")
    fx, fy = truth.world_to_cell(poses[:, 0], poses[:, 1])
    outside = (fx < 0) | (fy < 0) | (fx >= truth.width) | (fy >= truth.height)
    if outside.any():
        i = int(np.argmax(outside))
        raise InputError("laser_poses", f"pose {i} ({poses[i, 0]:g}, {poses[i, 1]:g}) m lies outside the grid")
    yaw = poses[:, 2] - truth.origin[2]
    occupied = np.ascontiguousarray(truth.probability > 0.5)
    angles = laser.angles.astype(np.float64)
    reach = laser.range_max / truth.resolution
    out = np.empty((len(poses), len(angles)), dtype=np.float64)
    with tqdm(total=len(poses), desc="laser scans", unit="scan", disable=not progress) as bar:
        for a in range(0, len(poses), SCAN_CHUNK):
            b = min(a + SCAN_CHUNK, len(poses))
            _cast_scans(occupied, np.ascontiguousarray(fx[a:b]), np.ascontiguousarray(fy[a:b]),
                        np.ascontiguousarray(yaw[a:b]), angles, reach, out[a:b])
            bar.update(b - a)
    out *= truth.resolution
    out[out > laser.range_max] = math.inf
    out[out < laser.range_min] = -math.inf
    return out


def add_range_noise(ranges, bound=0.0, sigma=0.0, rng=None) -> np.ndarray:
    """The thesis's ``d +- C`` on every finite range: ``d + s * c``, ``s`` = +-1, ``c`` ~ U[0, bound], plus N(0, sigma).

    Random numbers are drawn for every beam (returns or not) so the stream does not
    depend on the scene. Results are floored at 0.

    >>> r = add_range_noise(np.array([[1.0, np.inf]]), 0.1, rng=np.random.default_rng(0))
    >>> bool(abs(r[0, 0] - 1.0) <= 0.1), float(r[0, 1])
    (True, inf)
    """
    bound = _number("range_noise", bound, 0.0)
    sigma = _number("range_sigma", sigma, 0.0)
    rng = np.random.default_rng(rng)
    ranges = np.array(ranges, dtype=np.float64)
    sign = rng.choice(np.array([-1.0, 1.0]), size=ranges.shape)
    magnitude = rng.uniform(0.0, bound, size=ranges.shape)
    gauss = rng.normal(0.0, sigma, size=ranges.shape) if sigma > 0 else 0.0
    finite = np.isfinite(ranges)
    ranges[finite] = np.maximum((ranges + sign * magnitude + gauss)[finite], 0.0)
    return ranges


# --- motion -----------------------------------------------------------------------------------
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


@njit(cache=True)
def _segment_clear(free, x0, y0, x1, y1):
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


@dataclass
class Motion:
    """A driven run: the commands, what the robot actually did, and when it scanned.

    ``poses[k]`` is the true base_link pose in map after ``k`` steps of ``dt`` seconds;
    ``moves[k]`` = (distance [m], turn [rad]) executed in step k; ``commands[k]`` = the
    Twist (v [m/s], w [rad/s]) sent for step k; ``scan_at`` = indices into ``poses``.
    """

    poses: np.ndarray  # (n + 1, 3)
    moves: np.ndarray  # (n, 2)
    commands: np.ndarray  # (n, 2)
    scan_at: np.ndarray  # (m,) int
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


@njit(cache=True)
def _coverage_tour(free, sx, sy):
    """Depth-first tour of the cells 4-connected to (sx, sy): (m, 2) cells, each a side neighbour of the last.

    Backtracking steps are included, so consecutive cells are always adjacent; every
    reachable cell appears, the tour has at most 2 * cells - 1 entries. Neighbours are
    tried in the order +x, +y, -x, -y.
    """
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


def _check_speeds(dt, linear_speed, angular_speed):
    return (_number("dt", dt, 0.0, low_open=True), _number("linear_speed", linear_speed, 0.0, low_open=True),
            _number("angular_speed", angular_speed, 0.0, low_open=True))


def explore_reachable(scene: Scene, laser: Laser, *, start=None, robot_radius=None, stride=1, dt=0.1,
                      linear_speed=0.5, angular_speed=1.5) -> Motion:
    """Drive through every reachable cell (depth-first, cell centre to cell centre) and look around.

    The robot first moves to the centre of its start cell. At each newly visited cell not
    within ``stride - 1`` cells (Chebyshev) of an earlier look-around it scans all around
    (:meth:`Laser.headings_per_turn` scans); ``stride = 1`` looks around at every cell.

    >>> from crfmap.scenes import enclosed_boxes
    >>> m = explore_reachable(enclosed_boxes("train"), Laser(), stride=4)
    >>> len(m.scan_at) < len(m.poses)
    True
    """
    dt, linear_speed, angular_speed = _check_speeds(dt, linear_speed, angular_speed)
    if isinstance(stride, bool) or not isinstance(stride, (int, np.integer)) or stride < 1:
        raise InputError("stride", f"must be a positive integer, got {stride!r}")
    grid = scene.truth
    start = tuple(float(v) for v in (scene.start if start is None else start))
    radius = scene.robot_radius if robot_radius is None else _number("robot_radius", robot_radius, 0.0)
    can_reach = reachable(grid, start, radius)
    sx, sy = pose_cell(grid, start)
    tour = _coverage_tour(can_reach, sx, sy)
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

    >>> m = look_around(Scene("s", OccupancyGrid(np.zeros((3, 3))), (1.5, 1.5, 0.0)), Laser.with_fov(90, 10))
    >>> len(m.scan_at), round(float(np.degrees(m.poses[m.scan_at[-1], 2])), 6)
    (4, -90.0)
    """
    dt, _, angular_speed = _check_speeds(dt, 1.0, angular_speed)
    if isinstance(turns, bool) or not isinstance(turns, (int, np.integer)) or turns < 1:
        raise InputError("turns", f"must be a positive integer, got {turns!r}")
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
def _grid_path(free, sx, sy, gx, gy):
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


def _in_sight(free, a, b, margin=0.25):
    """Whether the straight leg between cell centres a and b, widened by ``margin`` cells each side, is free."""
    (x0, y0), (x1, y1) = a + 0.5, b + 0.5
    length = math.hypot(x1 - x0, y1 - y0)
    nx, ny = (-(y1 - y0) / length, (x1 - x0) / length) if length else (0.0, 0.0)
    return all(_segment_clear(free, x0 + o * nx, y0 + o * ny, x1 + o * nx, y1 + o * ny) for o in (-margin, 0.0, margin))


def _simplify(free, cells):
    """Keep the path cells from which the next kept one is in straight, free sight (see :func:`_in_sight`)."""
    keep = [0]
    i = 0
    while i < len(cells) - 1:
        j = len(cells) - 1
        while j > i + 1 and not _in_sight(free, cells[i], cells[j]):
            j -= 1
        keep.append(j)
        i = j
    return cells[keep]


@njit(cache=True)
def _step(x, y, yaw, v, w, dt, free, ox, oy, c, s, res):
    """One step of the robot: turn ``w*dt``, translate ``v*dt`` unless that runs into a non-free cell.

    (ox, oy) is the grid origin, (c, s) the cosine and sine of its yaw, ``res`` its cell size.
    """
    d = v * dt
    a = w * dt
    mid = yaw + 0.5 * a
    nx = x + d * math.cos(mid)
    ny = y + d * math.sin(mid)
    if d != 0.0:
        x0, y0 = (c * (x - ox) + s * (y - oy)) / res, (-s * (x - ox) + c * (y - oy)) / res
        x1, y1 = (c * (nx - ox) + s * (ny - oy)) / res, (-s * (nx - ox) + c * (ny - oy)) / res
        if not _segment_clear(free, x0, y0, x1, y1):
            d = 0.0
    return d, a


def follow_waypoints(scene: Scene, laser: Laser, waypoints=None, *, start=None, robot_radius=None, dt=0.1,
                     linear_speed=0.5, angular_speed=1.5, scan_period=0.2, max_steps=1_000_000) -> Motion:
    """Drive through ``waypoints`` (x, y) [m] in order, scanning every ``scan_period`` seconds.

    Between waypoints the robot follows the shortest grid path (8-connected, footprint
    respected), shortened to straight free segments. The controller sees the true pose:
    it turns in place towards the next point when off by more than ``ALIGNED`` rad, else drives
    at up to ``linear_speed`` while steering (``w = heading error / dt``, clipped).

    >>> from crfmap.scenes import office_floor
    >>> s = office_floor(8.0, 6.0, 0.1, seed=0)
    >>> m = follow_waypoints(s, Laser(), s.waypoints[:1])
    >>> bool(np.hypot(*(m.poses[-1, :2] - s.waypoints[0])) < 0.05)
    True
    """
    dt, linear_speed, angular_speed = _check_speeds(dt, linear_speed, angular_speed)
    scan_period = _number("scan_period", scan_period, 0.0, low_open=True)
    grid = scene.truth
    start = tuple(float(v) for v in (scene.start if start is None else start))
    radius = scene.robot_radius if robot_radius is None else _number("robot_radius", robot_radius, 0.0)
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
    # Targets: cell centres along straight free stretches of the grid path, then the waypoint itself
    # (reached from its own cell's centre, so no leg cuts a corner).
    targets = [tuple(float(v) for v in grid.cell_to_world(*cell))]
    for k, (wx, wy) in enumerate(wps[:, :2]):
        try:
            goal = pose_cell(grid, (wx, wy))
        except InputError:
            raise InputError("waypoints", f"waypoint {k} ({wx:g}, {wy:g}) m lies outside the grid") from None
        if not can_reach[goal[1], goal[0]]:
            raise InputError("waypoints", f"waypoint {k} ({wx:g}, {wy:g}) m is not reachable from the start")
        path = _simplify(free, _grid_path(free, cell[0], cell[1], goal[0], goal[1]))
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


# --- putting it together ---------------------------------------------------------------
def _odometry_noise(value):
    if isinstance(value, (tuple, list, np.ndarray)):
        if len(value) != 2:
            raise InputError("odometry_noise", f"expected C or (C_lin [m], C_yaw [rad]), got {value!r}")
        return _number("odometry_noise", value[0], 0.0), _number("odometry_noise", value[1], 0.0)
    c = _number("odometry_noise", value, 0.0)
    return c, 0.0


def simulate(scene: Scene, laser: Laser | None = None, mode: str | None = None, *, seed=0, range_noise=0.0,
             range_sigma=0.0, odometry_noise=0.0, laser_mount=(0.0, 0.0, 0.0), start=None, robot_radius=None,
             stride=1, waypoints=None, dt=0.1, linear_speed=0.5, angular_speed=1.5, scan_period=0.2, turns=1,
             t0=0.0, progress=True) -> Recording:
    """Simulate a robot scanning ``scene``: a :class:`~crfmap.recording.Recording` (what a bag would hold).

    Parameters
    ----------
    scene : Scene
    laser : Laser (default ``Laser()``: 360 beams over 360 deg, 0.05-5 m)
    mode : "explore", "look" or "waypoints" (default ``scene.default_mode``)
    seed : int, all noise comes from ``np.random.default_rng(seed)``
    range_noise : float C [m], ranges read ``d +- c``, ``c`` ~ U[0, C]
    range_sigma : float [m], extra Gaussian range noise
    odometry_noise : C [m] or (C_lin [m], C_yaw [rad]) per step: odometry reads each
        executed translation ``+- c`` (and each executed turn ``+- c_yaw``); 0 = perfect odometry
    laser_mount : (x, y, yaw) of the laser in base_link
    stride : explore: look around only at cells farther than ``stride - 1`` cells from the last
    waypoints : (k, 2) [m], waypoints mode (default ``scene.waypoints``)
    dt : float [s] per Twist command; ``linear_speed`` [m/s], ``angular_speed`` [rad/s] limits
    scan_period : float [s], waypoints mode; ``turns``: look mode
    t0 : float [s], stamp of the first pose
    progress : bool, show a progress bar for the ray casting

    Returns
    -------
    Recording with ``scans`` (true laser poses in map), ``odometry`` (base_link in odom,
    noisy, twists = measured), ``true_poses`` (base_link in map), ``cmd_vel`` (twists =
    commanded), ``laser_mount``, ``ground_truth = scene.truth`` and ``meta`` (all settings,
    ``map_to_odom``). Identical for identical arguments.
    """
    if not isinstance(scene, Scene):
        raise InputError("scene", f"expected a crfmap.scenes.Scene, got {type(scene).__name__}")
    laser = Laser() if laser is None else laser
    if not isinstance(laser, Laser):
        raise InputError("laser", f"expected a crfmap.simulator.Laser, got {type(laser).__name__}")
    mode = scene.default_mode if mode is None else mode
    if mode not in MODES:
        raise InputError("mode", f"must be one of {', '.join(MODES)}, got {mode!r}")
    c_lin, c_yaw = _odometry_noise(odometry_noise)
    t0 = _number("t0", t0)
    mount = np.array([_number("laser_mount", v) for v in laser_mount], dtype=np.float64)
    if mount.shape != (3,):
        raise InputError("laser_mount", f"expected (x, y, yaw), got {laser_mount!r}")
    start = tuple(float(v) for v in (scene.start if start is None else start))
    if len(start) != 3:
        raise InputError("start", f"expected (x, y, yaw), got {start!r}")
    if mode == "explore":
        motion = explore_reachable(scene, laser, start=start, robot_radius=robot_radius, stride=stride, dt=dt,
                                   linear_speed=linear_speed, angular_speed=angular_speed)
    elif mode == "look":
        motion = look_around(scene, laser, start=start, dt=dt, angular_speed=angular_speed, turns=turns)
    else:
        motion = follow_waypoints(scene, laser, waypoints, start=start, robot_radius=robot_radius, dt=dt,
                                  linear_speed=linear_speed, angular_speed=angular_speed, scan_period=scan_period)

    rng = np.random.default_rng(seed)
    n = len(motion)
    # Odometry: each executed translation / turn read with the thesis's +-C.
    measured = motion.moves.copy()
    for col, bound in ((0, c_lin), (1, c_yaw)):
        sign = rng.choice(np.array([-1.0, 1.0]), size=n)
        error = sign * rng.uniform(0.0, bound, size=n)
        moving = motion.moves[:, col] != 0.0
        measured[moving, col] += error[moving]
    odom_poses = _integrate(0.0, 0.0, 0.0, measured)
    stamps = t0 + motion.dt * np.arange(n + 1)
    zero = np.zeros((1, 2))
    odometry = Trajectory(stamps, odom_poses, "odom", "base_link", np.vstack([zero, measured / motion.dt]))
    true_poses = Trajectory(stamps.copy(), motion.poses.copy(), "map", "base_link",
                            np.vstack([zero, motion.moves / motion.dt]))
    cmd_vel = Trajectory(stamps[:-1].copy(), np.zeros((n, 3)), "base_link", "base_link", motion.commands.copy())

    laser_poses = compose(motion.poses[motion.scan_at], mount)
    long_run = laser_poses.shape[0] * laser.n_beams > PROGRESS_BEAMS
    ranges = cast_rays(scene.truth, laser, laser_poses, progress=progress and long_run)
    ranges = add_range_noise(ranges, range_noise, range_sigma, rng)
    ranges[ranges == math.inf] = laser.no_return
    scans = ScanSet(
        ranges=ranges.astype(np.float32),
        angle_min=laser.angle_min,
        angle_increment=laser.angle_increment,
        range_min=laser.range_min,
        range_max=laser.range_max,
        laser_poses=laser_poses,
        stamps=stamps[motion.scan_at].copy(),
        frame_id="map",
        laser_frame_id="laser",
        source=f"simulated {scene.name}",
    )
    meta = {
        "simulator": "crfmap.simulator",
        "scene": scene.name,
        "scene_description": scene.description,
        "mode": mode,
        "seed": seed,
        "range_noise": float(range_noise),
        "range_sigma": float(range_sigma),
        "odometry_noise": (c_lin, c_yaw),
        "no_return": laser.no_return,
        "angle_max": laser.angle_max,
        "dt": motion.dt,
        "map_to_odom": start,
        "robot_radius": scene.robot_radius if robot_radius is None else float(robot_radius),
    }
    return Recording(scans=scans, laser_mount=tuple(float(v) for v in mount), odometry=odometry,
                     true_poses=true_poses, cmd_vel=cmd_vel, ground_truth=scene.truth, meta=meta)
