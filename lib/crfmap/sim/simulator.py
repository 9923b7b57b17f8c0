"""A robot with a laser scanner in a ground-truth grid (thesis sec. 3.1), recorded as a bag would hold it.

Sensing: each beam is ray-cast with Bresenham's line (:func:`crfmap.raycast.first_hit_kernel`, thesis Listing 1) from
the laser's cell to the cell of the beam's end point at ``range_max``; a hit reads the Euclidean distance from the
laser to the hit cell's centre (so axis-aligned beams from a cell centre read whole cells). Beyond ``range_max`` is no
return (``+inf``, REP 117; the thesis wrote -1, :data:`LEGACY_NO_RETURN`), nearer than ``range_min`` is ``-inf``;
outside the grid is empty space. Range noise (:func:`add_range_noise`) may take a return out of ``[range_min,
range_max]``; readers then discard it, as REP 117 asks.

Motion: a drive (:mod:`crfmap.sim.drives`) moves the robot (:mod:`crfmap.sim.motion`). Odometry integrates what the
wheels report: every executed translation ``d`` reads ``d +- C_lin``, every executed turn ``a`` reads ``a +- C_yaw``
(the thesis's noise "at each interval of movement", Fig. 16); wheels that do not turn add no error. Odometry starts at
(0, 0, 0) in ``odom``; ``map -> odom`` is the start pose (``recording.meta["map_to_odom"]``).

>>> from crfmap.world.scenes import enclosed_boxes
>>> rec = simulate(enclosed_boxes("train"), Laser.with_fov(360, 90), "look", progress=False)
>>> rec.scans.ranges.shape
(1, 90)
>>> simulate(enclosed_boxes("train"), Laser.with_fov(360, 90), Look(turns=2), progress=False).scans.ranges.shape
(2, 90)
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from crfmap.errors import InputError
from crfmap.frames import compose
from crfmap.grid import OccupancyGrid
from crfmap.checks import check_number
from crfmap.sim.drives import DRIVE_SETTINGS, Look, drive_for
from crfmap.sim.motion import _integrate
from crfmap.raycast import first_hit_kernel
from crfmap.sim.laser import Laser
from crfmap.recording import Recording, ScanSet, Trajectory
from crfmap.world.scene import Scene

SCAN_CHUNK = 512  # scans per progress-bar tick
DEFAULT_LINEAR_SPEED = 0.5  # [m/s]
PROGRESS_BEAMS = 2_000_000  # beams in a run above which simulate() shows a progress bar (below, it is too quick)


# --- ray casting --------------------------------------------------------------------------
@njit(cache=True)
def _cast_scans(occupied, lx, ly, lyaw, angles, reach, out):
    """Distances [cells] from laser positions (lx, ly) [cells, continuous] to the first occupied cell's centre
    (``out[i, j]`` = inf where beam j of scan i meets nothing before ``reach`` cells)."""
    for i in range(lx.shape[0]):
        cx = int(math.floor(lx[i]))
        cy = int(math.floor(ly[i]))
        for j in range(angles.shape[0]):
            a = lyaw[i] + angles[j]
            ex = int(math.floor(lx[i] + reach * math.cos(a)))
            ey = int(math.floor(ly[i] + reach * math.sin(a)))
            hx, hy, hit = first_hit_kernel(occupied, cx, cy, ex, ey)
            if hit:
                out[i, j] = math.hypot(hx + 0.5 - lx[i], hy + 0.5 - ly[i])
            else:
                out[i, j] = math.inf


def cast_rays(truth: OccupancyGrid, laser: Laser, laser_poses, progress=False) -> np.ndarray:
    """Noiseless ranges [m] (n_poses, n_beams) of every beam from every laser pose (x [m], y [m], yaw [rad] in the
    grid's frame); ``+inf`` / ``-inf`` as in the module doc. ``truth`` is occupied where P > 0.5.

    >>> from crfmap.world.scenes import enclosed_boxes
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
    """The thesis's ``d +- C`` on every finite range: ``d + s * c``, ``s`` = +-1, ``c`` ~ U[0, bound], plus N(0, sigma),
    floored at 0. Numbers are drawn for every beam (returns or not), so the stream does not depend on the scene.

    >>> r = add_range_noise(np.array([[1.0, np.inf]]), 0.1, rng=np.random.default_rng(0))
    >>> bool(abs(r[0, 0] - 1.0) <= 0.1), float(r[0, 1])
    (True, inf)
    """
    bound = check_number("range_noise", bound, low=0.0)
    sigma = check_number("range_sigma", sigma, low=0.0)
    rng = np.random.default_rng(rng)
    ranges = np.array(ranges, dtype=np.float64)
    sign = rng.choice(np.array([-1.0, 1.0]), size=ranges.shape)
    magnitude = rng.uniform(0.0, bound, size=ranges.shape)
    gauss = rng.normal(0.0, sigma, size=ranges.shape) if sigma > 0 else 0.0
    finite = np.isfinite(ranges)
    ranges[finite] = np.maximum((ranges + sign * magnitude + gauss)[finite], 0.0)
    return ranges


# --- putting it together ---------------------------------------------------------------
def _odometry_noise(value):
    if isinstance(value, (tuple, list, np.ndarray)):
        if len(value) != 2:
            raise InputError("odometry_noise", f"expected C or (C_lin [m], C_yaw [rad]), got {value!r}")
        return check_number("odometry_noise", value[0], low=0.0), check_number("odometry_noise", value[1], low=0.0)
    c = check_number("odometry_noise", value, low=0.0)
    return c, 0.0


START_TIME = 1_700_000_000.0  # [s] 2023-11-14 UTC, fixed: wall-clock-like stamps, as ROS expects (0 means "no time")


def simulate(scene: Scene, laser: Laser | None = None, drive=None, *, seed=0, range_noise=0.0, range_sigma=0.0,
             odometry_noise=0.0, laser_mount=(0.0, 0.0, 0.0), start=None, dt=0.1, linear_speed=None,
             angular_speed=1.5, t0=START_TIME, progress=True, **misplaced) -> Recording:
    """Simulate a robot scanning ``scene``: a :class:`~crfmap.recording.Recording` (what a bag would hold).

    ``drive``: a drive of :mod:`crfmap.sim.drives` or a mode name (default ``scene.default_mode``); a drive's settings
    (``stride``, ``turns``, ``waypoints``, ``scan_period``, ``robot_radius``) given here are an InputError. All noise
    comes from ``np.random.default_rng(seed)``: ``range_noise`` C [m] and ``range_sigma`` [m] (:func:`add_range_noise`),
    ``odometry_noise`` C [m] or (C_lin [m], C_yaw [rad]) per step (0: perfect). ``laser_mount``: (x, y, yaw) in
    base_link; ``start``: (x, y, yaw) [m, rad], None for ``scene.start``. ``dt`` [s] per Twist command; limits
    ``linear_speed`` [m/s] (default 0.5; not for :class:`Look`, which only turns) and ``angular_speed`` [rad/s].
    ``t0`` [s]: the first pose's stamp (a ROS bag refuses 0).

    Returns ``scans`` (true laser poses in map), ``odometry`` (base_link in odom, noisy, twists = measured),
    ``true_poses`` (base_link in map), ``cmd_vel`` (twists = commanded), ``laser_mount``, ``ground_truth =
    scene.truth`` and ``meta`` (all settings, ``map_to_odom``). Identical for identical arguments."""
    for name in misplaced:
        if name in DRIVE_SETTINGS:
            raise InputError(name, f"belongs to the drive: pass drive={DRIVE_SETTINGS[name]}({name}=...)")
        raise TypeError(f"simulate() got an unexpected keyword argument {name!r}")
    if not isinstance(scene, Scene):
        raise InputError("scene", f"expected a crfmap.world.scene.Scene, got {type(scene).__name__}")
    laser = Laser() if laser is None else laser
    if not isinstance(laser, Laser):
        raise InputError("laser", f"expected a crfmap.sim.simulator.Laser, got {type(laser).__name__}")
    drive = drive_for(scene.default_mode if drive is None else drive)
    if linear_speed is not None and isinstance(drive, Look):
        raise InputError("linear_speed", "does not apply to the look drive: the robot only turns in place")
    linear_speed = DEFAULT_LINEAR_SPEED if linear_speed is None else linear_speed
    c_lin, c_yaw = _odometry_noise(odometry_noise)
    t0 = check_number("t0", t0)
    mount = np.array([check_number("laser_mount", v) for v in laser_mount], dtype=np.float64)
    if mount.shape != (3,):
        raise InputError("laser_mount", f"expected (x, y, yaw), got {laser_mount!r}")
    start = tuple(float(v) for v in (scene.start if start is None else start))
    if len(start) != 3:
        raise InputError("start", f"expected (x, y, yaw), got {start!r}")
    motion = drive.motion(scene, laser, start=start, dt=dt, linear_speed=linear_speed, angular_speed=angular_speed)

    rng = np.random.default_rng(seed)
    n = len(motion)
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
        "simulator": "crfmap.sim.simulator",
        "scene": scene.name,
        "scene_description": scene.description,
        "mode": drive.mode,
        "seed": seed,
        "range_noise": float(range_noise),
        "range_sigma": float(range_sigma),
        "odometry_noise": (c_lin, c_yaw),
        "no_return": laser.no_return,
        "angle_max": laser.angle_max,
        "dt": motion.dt,
        "map_to_odom": start,
        "robot_radius": scene.robot_radius if getattr(drive, "robot_radius", None) is None else drive.robot_radius,
    }
    return Recording(scans=scans, laser_mount=tuple(float(v) for v in mount), odometry=odometry,
                     true_poses=true_poses, cmd_vel=cmd_vel, ground_truth=scene.truth, meta=meta)
