"""Occupancy grids from laser scans with known poses (thesis sec. 3.2).

Every beam is ray-cast (Bresenham, :func:`crfmap.raycast.bresenham_step`) from the laser's cell to its end point's
cell: the cells passed are *empty hits*, the end cell an *occupied hit* unless the beam returned nothing. Two ways to
turn hits into P(occupied):

- ``model="arctan"`` (the thesis, eq. 16): with x = occupied hits - empty hits over all beams, ``P = 0.5 + atan(x) /
  pi``. Cells never passed stay 0.5 (unknown).
- ``model="logodds"`` (the baseline of Probabilistic Robotics, ch. 9, Table 9.1): per scan, every cell the scan
  observes gets ``l += log(p/(1-p))`` once, with ``p = p_hit`` if a beam ended in it (occupied takes precedence, as
  in OctoMap) and ``p = p_miss`` otherwise; ``l`` is clamped to ``[-logodds_limit, logodds_limit]`` after each
  update; ``P = 1 - 1 / (1 + exp(l))``.

Readings follow REP 117: NaN (invalid) and -Inf (too close) are dropped, finite readings outside [range_min,
range_max] are dropped, +Inf (and a finite reading equal to range_max, the legacy max-range code) means "no return":
it clears free space up to ``free_on_no_return`` metres when asked, and is dropped otherwise."""
from __future__ import annotations

import math

import numpy as np

from crfmap.mapping._beam_kernels import _count_hits, _logodds_update
from crfmap.checks import check_positive as _positive
from crfmap.errors import InputError
from crfmap.grid import UNKNOWN, OccupancyGrid
from crfmap.recording import ScanSet

BOUNDS_PADDING = 0.5  # [m] margin around poses and end points when the bounds come from the data
MAX_CELLS = 100_000_000  # a bigger grid is almost surely a unit mistake (and would not fit in memory)
PROGRESS_CHUNK = 64  # scans per kernel call when a progress bar is shown
_NO_STAMP = np.zeros((0, 0), np.int32)  # the hit kernel lists no touched cells
_NO_CELLS = np.zeros((0, 2), np.int64)


def _check_scans(scans):
    source = getattr(scans, "source", "") or "scans"
    try:
        ranges = np.asarray(scans.ranges)
        poses = np.asarray(scans.laser_poses, dtype=np.float64)
    except AttributeError:
        raise InputError("scans", f"expected a crfmap.recording.ScanSet, got {type(scans).__name__}") from None
    if ranges.ndim != 2 or ranges.shape[0] == 0 or ranges.shape[1] == 0:
        raise InputError(source, f"ranges must be a non-empty (n_scans, n_beams) array, got shape {ranges.shape}")
    if not np.issubdtype(ranges.dtype, np.floating):
        raise InputError(source, f"ranges must be floating point, got dtype {ranges.dtype}")
    if poses.shape != (ranges.shape[0], 3):
        raise InputError(source, f"laser_poses must have shape ({ranges.shape[0]}, 3), got {poses.shape}")
    if not np.all(np.isfinite(poses)):
        bad = int(np.argmax(~np.all(np.isfinite(poses), axis=1)))
        raise InputError(source, f"laser pose of scan {bad} is not finite")
    for name in ("angle_min", "angle_increment"):
        if not math.isfinite(float(getattr(scans, name))):
            raise InputError(source, f"{name} is not finite")
    range_min, range_max = float(scans.range_min), float(scans.range_max)
    if not (range_min >= 0 and range_max > range_min):
        raise InputError(source, f"need 0 <= range_min < range_max, got [{range_min:g}, {range_max:g}]")
    return source, ranges.astype(np.float32, copy=False), poses


def _free_range(free_on_no_return, range_max, source):
    if free_on_no_return is None or free_on_no_return is False:
        return 0.0
    if free_on_no_return is True:
        if not math.isfinite(range_max):
            raise InputError("free_on_no_return", f"True means range_max, but range_max of {source} is infinite; give metres")
        return float(range_max)
    return _positive("free_on_no_return", free_on_no_return)


def scan_bounds(scans, free_on_no_return=False, max_range_is_no_return=True, padding=BOUNDS_PADDING):
    """(xmin, ymin, xmax, ymax) [m] holding every laser position and used beam end, padded.

    >>> from crfmap.recording import ScanSet
    >>> s = ScanSet(np.array([[1.0]], np.float32), 0.0, 0.0, 0.1, 5.0, np.zeros((1, 3)), np.zeros(1))
    >>> scan_bounds(s, padding=0.0)
    (0.0, 0.0, 1.0, 0.0)
    """
    source, ranges, poses = _check_scans(scans)
    free_range = _free_range(free_on_no_return, float(scans.range_max), source)
    r = ranges.astype(np.float64)
    range_min, range_max = float(np.float32(scans.range_min)), float(np.float32(scans.range_max))
    with np.errstate(invalid="ignore"):
        no_return = np.isposinf(r) | (max_range_is_no_return & (r == range_max))
        hit = np.isfinite(r) & (r >= range_min) & (r <= range_max) & ~no_return
    length = np.where(hit, r, np.where(no_return & (free_range > 0), free_range, np.nan))
    angles = poses[:, 2:3] + scans.angle_min + scans.angle_increment * np.arange(r.shape[1])
    ex = poses[:, 0:1] + length * np.cos(angles)
    ey = poses[:, 1:2] + length * np.sin(angles)
    xs = np.concatenate([poses[:, 0], ex[np.isfinite(ex)]])
    ys = np.concatenate([poses[:, 1], ey[np.isfinite(ey)]])
    return (float(xs.min() - padding), float(ys.min() - padding), float(xs.max() + padding), float(ys.max() + padding))


def _geometry(scans, resolution, bounds, free_on_no_return, max_range_is_no_return):
    """Checked inputs plus the grid's origin and shape."""
    source, ranges, poses = _check_scans(scans)
    resolution = _positive("resolution", resolution)
    if bounds is None:
        xmin, ymin, xmax, ymax = scan_bounds(scans, free_on_no_return, max_range_is_no_return)
        # snapped to multiples of the resolution so grids of one data set line up; rounded to 1e-9 m to print cleanly
        xmin = round(math.floor(xmin / resolution) * resolution, 9)
        ymin = round(math.floor(ymin / resolution) * resolution, 9)
    else:
        try:
            xmin, ymin, xmax, ymax = (float(v) for v in bounds)
        except (TypeError, ValueError):
            raise InputError("bounds", f"expected (xmin, ymin, xmax, ymax) in metres, got {bounds!r}") from None
        if not all(math.isfinite(v) for v in (xmin, ymin, xmax, ymax)) or xmax <= xmin or ymax <= ymin:
            raise InputError("bounds", f"need finite xmin < xmax and ymin < ymax, got {bounds!r}")
    width = max(1, int(math.ceil((xmax - xmin) / resolution - 1e-9)))
    height = max(1, int(math.ceil((ymax - ymin) / resolution - 1e-9)))
    if width * height > MAX_CELLS:
        raise InputError(
            "resolution",
            f"a {width} x {height} grid ({width * height:,} cells) at {resolution:g} m is too large; "
            f"use a coarser resolution or a smaller area",
        )
    u = (poses[:, 0] - xmin) / resolution
    v = (poses[:, 1] - ymin) / resolution
    outside = (u < 0) | (u >= width) | (v < 0) | (v >= height)
    if outside.any():
        i = int(np.argmax(outside))
        raise InputError(
            "bounds" if bounds is not None else source,
            f"laser pose of scan {i} at ({poses[i, 0]:.3f}, {poses[i, 1]:.3f}) m lies outside the grid "
            f"x [{xmin:g}, {xmin + width * resolution:g}], y [{ymin:g}, {ymin + height * resolution:g}]",
        )
    free_range = _free_range(free_on_no_return, float(scans.range_max), source)
    angles = (float(scans.angle_min) + float(scans.angle_increment) * np.arange(ranges.shape[1])).astype(np.float64)
    return dict(source=source, ranges=ranges, poses=poses, angles=angles, resolution=resolution,
                origin_x=float(xmin), origin_y=float(ymin), width=width, height=height,
                range_min=np.float32(scans.range_min), range_max=np.float32(scans.range_max),
                max_is_no_return=bool(max_range_is_no_return), free_range=float(free_range))


def _chunks(n_scans, progress, desc):
    """Scan index ranges to hand the kernel, with a tqdm bar when asked."""
    if not progress:
        yield 0, n_scans
        return
    from tqdm.auto import tqdm

    with tqdm(total=n_scans, desc=desc, unit="scan") as bar:
        for start in range(0, n_scans, PROGRESS_CHUNK):
            stop = min(start + PROGRESS_CHUNK, n_scans)
            yield start, stop
            bar.update(stop - start)


def _ray_buffer(g):
    return np.empty((g["width"] + g["height"] + 2, 2), dtype=np.int64)


def _hits(g, progress):
    occupied = np.zeros((g["height"], g["width"]), dtype=np.int32)
    empty = np.zeros_like(occupied)
    buf = _ray_buffer(g)
    used = 0
    for a, b in _chunks(len(g["ranges"]), progress, "ray casting"):
        n, _ = _count_hits(g["ranges"][a:b], g["angles"], g["poses"][a:b], g["range_min"], g["range_max"],
                           g["max_is_no_return"], g["free_range"], g["origin_x"], g["origin_y"],
                           g["resolution"], occupied, empty, buf, _NO_STAMP, 0, _NO_CELLS)
        used += n
    return occupied, empty, used


def count_hits(scans, resolution, bounds=None, free_on_no_return=False, max_range_is_no_return=True,
               progress=False):
    """Occupied and empty hit counts per cell, ``[y, x]`` int32 arrays, on :func:`build_grid`'s grid.

    >>> from crfmap.recording import ScanSet
    >>> s = ScanSet(np.array([[0.36]], np.float32), 0.0, 0.0, 0.1, 5.0, np.array([[0.05, 0.05, 0.0]]), np.zeros(1))
    >>> occ, emp = count_hits(s, 0.1, bounds=(0, 0, 0.5, 0.1))
    >>> occ.tolist(), emp.tolist()
    ([[0, 0, 0, 0, 1]], [[1, 1, 1, 1, 0]])
    """
    g = _geometry(scans, resolution, bounds, free_on_no_return, max_range_is_no_return)
    occupied, empty, _ = _hits(g, progress)
    return occupied, empty


def sensor_probe(bounds, angle_min, angle_increment, n_beams, range_min, range_max, frame_id="map"):
    """A one-scan ScanSet of a laser's geometry at the centre of ``bounds`` (xmin, ymin, xmax, ymax) [m], no readings:
    what a grid for that sensor is made from before any scan arrives."""
    try:
        xmin, ymin, xmax, ymax = (float(v) for v in bounds)
    except (TypeError, ValueError):
        raise InputError("bounds", f"expected (xmin, ymin, xmax, ymax) in metres, got {bounds!r}") from None
    if not (isinstance(n_beams, (int, np.integer)) and n_beams >= 1):
        raise InputError("n_beams", f"must be a positive integer, got {n_beams!r}")
    centre = np.array([[(xmin + xmax) / 2, (ymin + ymax) / 2, 0.0]])
    return ScanSet(np.full((1, int(n_beams)), np.nan, np.float32), angle_min, angle_increment, range_min,
                   range_max, centre, np.zeros(1), frame_id=frame_id, source="sensor")


class HitCounter:
    """The hit counts of :func:`count_hits`, filled one scan at a time (online mapping).

    After :meth:`add_scan` of every scan of a recording, in any order, ``occupied`` and ``empty`` equal
    :func:`count_hits` of it and :meth:`grid` equals :func:`build_grid` with the arctan model.

    >>> from crfmap.recording import ScanSet
    >>> s = ScanSet(np.array([[0.36]], np.float32), 0.0, 0.0, 0.1, 5.0, np.array([[0.05, 0.05, 0.0]]), np.zeros(1))
    >>> counter = HitCounter.for_scans(s, 0.1, bounds=(0, 0, 0.5, 0.1))
    >>> counter.add_scan(s.ranges[0], s.laser_poses[0]).tolist()  # the cells it touched, (x, y)
    [[0, 0], [1, 0], [2, 0], [3, 0], [4, 0]]
    >>> counter.occupied.tolist(), counter.empty.tolist()
    ([[0, 0, 0, 0, 1]], [[1, 1, 1, 1, 0]])
    """

    def __init__(self, geometry):
        g = dict(geometry)
        self.width, self.height = int(g["width"]), int(g["height"])
        self.resolution = float(g["resolution"])
        self.origin = (float(g["origin_x"]), float(g["origin_y"]), 0.0)
        self.frame_id = g.get("frame_id", "map")
        self.angles = np.asarray(g["angles"], np.float64)
        self._sensor = (g["range_min"], g["range_max"], g["max_is_no_return"], g["free_range"])
        self.occupied = np.zeros((self.height, self.width), np.int32)
        self.empty = np.zeros_like(self.occupied)
        self.scans = 0
        self._buf = np.empty((self.width + self.height + 2, 2), np.int64)
        self._stamp = np.full((self.height, self.width), -1, np.int32)
        # a scan touches at most every cell, or every beam's whole line (pages are used lazily)
        self._touched = np.empty((min(self.width * self.height, len(self.angles) * len(self._buf)), 2), np.int64)

    @classmethod
    def for_scans(cls, scans, resolution, bounds=None, free_on_no_return=False,
                  max_range_is_no_return=True) -> "HitCounter":
        """A counter for a recording's sensor, on the grid :func:`build_grid` would make of it."""
        g = _geometry(scans, resolution, bounds, free_on_no_return, max_range_is_no_return)
        g["frame_id"] = getattr(scans, "frame_id", "map") or "map"
        return cls(g)

    @classmethod
    def for_sensor(cls, bounds, resolution, angle_min, angle_increment, n_beams, range_min, range_max,
                   free_on_no_return=False, max_range_is_no_return=True, frame_id="map") -> "HitCounter":
        """A counter for a grid over ``bounds`` (xmin, ymin, xmax, ymax) [m] and a laser's geometry."""
        probe = sensor_probe(bounds, angle_min, angle_increment, n_beams, range_min, range_max, frame_id)
        return cls.for_scans(probe, resolution, bounds, free_on_no_return, max_range_is_no_return)

    def add_scan(self, ranges, laser_pose) -> np.ndarray:
        """Count one scan's hits (``ranges`` [m], REP 117, at ``laser_pose`` (x, y, yaw) in the map); returns the
        cells whose counts changed, once each, as (n, 2) (x, y)."""
        r = np.asarray(ranges)
        if r.shape != (len(self.angles),) or not np.issubdtype(r.dtype, np.floating):
            raise InputError("ranges", f"expected {len(self.angles)} floating-point readings, got shape {r.shape} "
                             f"dtype {r.dtype}")
        try:  # a string, a (3, 1) column or a ragged list is no pose: refused, not reshaped
            pose = np.asarray(laser_pose, dtype=np.float64)
        except (TypeError, ValueError):
            pose = None
        if pose is None or pose.shape != (3,) or not np.all(np.isfinite(pose)):
            raise InputError("laser_pose", f"expected finite (x, y, yaw), got {laser_pose!r}")
        u = (pose[0] - self.origin[0]) / self.resolution
        v = (pose[1] - self.origin[1]) / self.resolution
        if not (0 <= u < self.width and 0 <= v < self.height):
            raise InputError("laser_pose", f"({pose[0]:.3f}, {pose[1]:.3f}) m lies outside the grid")
        if self.scans >= np.iinfo(np.int32).max:  # pragma: no cover - 2 billion scans
            self._stamp.fill(-1)
            self.scans = 0
        range_min, range_max, max_is_no_return, free_range = self._sensor
        _, n = _count_hits(r.astype(np.float32, copy=False)[None, :], self.angles, pose[None, :], range_min,
                           range_max, max_is_no_return, free_range, self.origin[0], self.origin[1], self.resolution,
                           self.occupied, self.empty, self._buf, self._stamp, self.scans, self._touched)
        self.scans += 1
        return self._touched[:n].copy()

    def grid(self) -> OccupancyGrid:
        """The arctan grid of the scans so far (:func:`build_grid` with ``model="arctan"``)."""
        p = arctan_probability(self.occupied, self.empty)
        p[(self.occupied == 0) & (self.empty == 0)] = UNKNOWN
        return OccupancyGrid(p, resolution=self.resolution, origin=self.origin, frame_id=self.frame_id,
                             meta={"model": "arctan", "scans": self.scans})


def arctan_probability(occupied_hits, empty_hits):
    """Thesis eq. 16: ``P = 0.5 + atan(occupied - empty) / pi``.

    >>> arctan_probability(np.array([0, 1, 0]), np.array([0, 0, 1])).round(3).tolist()
    [0.5, 0.75, 0.25]
    """
    x = np.asarray(occupied_hits, np.float64) - np.asarray(empty_hits, np.float64)
    return 0.5 + np.arctan(x) / np.pi


def logit(p, name) -> float:
    """``log(p / (1 - p))`` of a probability ``p`` strictly between 0 and 1 (InputError naming ``name``)."""
    if not (isinstance(p, (int, float, np.floating)) and 0.0 < float(p) < 1.0):
        raise InputError(name, f"must be a probability strictly between 0 and 1, got {p!r}")
    return math.log(float(p) / (1.0 - float(p)))


def hit_miss_logodds(p_hit, p_miss) -> tuple:
    """The log-odds a hit and a pass add, checked: probabilities with ``p_hit > 0.5 > p_miss``."""
    l_hit, l_miss = logit(p_hit, "p_hit"), logit(p_miss, "p_miss")
    if not (l_hit > 0 > l_miss):
        raise InputError("p_hit/p_miss", f"need p_hit > 0.5 > p_miss, got {p_hit!r} and {p_miss!r}")
    return l_hit, l_miss


def logodds_to_probability(logodds):
    """``P = 1 - 1 / (1 + exp(l))`` (Probabilistic Robotics eq. 9.8), without overflow."""
    return 0.5 * (1.0 + np.tanh(0.5 * np.asarray(logodds, np.float64)))


def build_grid(scans, resolution, model="arctan", bounds=None, free_on_no_return=False,
               max_range_is_no_return=True, p_hit=0.7, p_miss=0.4, logodds_limit=5.0,
               progress=False) -> OccupancyGrid:
    """Occupancy grid [y, x] from scans with known laser poses (x, y, yaw per scan, in ``scans.frame_id``).

    ``resolution``: the cell size [m]. ``model``: ``"arctan"`` or ``"logodds"`` (see the module doc). ``bounds`` (xmin,
    ymin, xmax, ymax) [m]: the area to map, by default the data's bounding box plus ``BOUNDS_PADDING``; beams leaving
    it are cut at its edge (no occupied hit there). ``free_on_no_return``: the range [m] up to which a no-return beam
    (+Inf, or range_max when ``max_range_is_no_return``) marks cells free (True: ``range_max``). The grid's origin is
    its lower-left corner, its ``meta`` the model and counts.

    >>> from crfmap.recording import ScanSet
    >>> s = ScanSet(np.array([[0.36]], np.float32), 0.0, 0.0, 0.1, 5.0, np.array([[0.05, 0.05, 0.0]]), np.zeros(1))
    >>> build_grid(s, 0.1, bounds=(0, 0, 0.5, 0.1)).probability.round(2).tolist()
    [[0.25, 0.25, 0.25, 0.25, 0.75]]
    """
    if model not in ("arctan", "logodds"):
        raise InputError("model", f"expected 'arctan' or 'logodds', got {model!r}")
    g = _geometry(scans, resolution, bounds, free_on_no_return, max_range_is_no_return)
    meta = {"model": model, "scans": len(g["ranges"]), "source": g["source"],
            "free_on_no_return": g["free_range"] or None}
    if model == "arctan":
        occupied, empty, used = _hits(g, progress)
        probability = arctan_probability(occupied, empty)
        probability[(occupied == 0) & (empty == 0)] = UNKNOWN
    else:
        l_hit, l_miss = hit_miss_logodds(p_hit, p_miss)
        limit = float(logodds_limit)
        if not limit > 0:
            raise InputError("logodds_limit", f"must be positive (inf for no clamping), got {logodds_limit!r}")
        shape = (g["height"], g["width"])
        logodds = np.zeros(shape)
        hit_stamp = np.full(shape, -1, dtype=np.int64)
        miss_stamp = np.full(shape, -1, dtype=np.int64)
        buf = _ray_buffer(g)
        used = 0
        for a, b in _chunks(len(g["ranges"]), progress, "log-odds update"):
            used += _logodds_update(g["ranges"][a:b], g["angles"], g["poses"][a:b], g["range_min"], g["range_max"],
                                    g["max_is_no_return"], g["free_range"], g["origin_x"], g["origin_y"],
                                    g["resolution"], l_hit, l_miss, limit, logodds, hit_stamp, miss_stamp, a, buf)
        probability = logodds_to_probability(logodds)
        probability[(hit_stamp < 0) & (miss_stamp < 0)] = UNKNOWN
        meta.update(p_hit=float(p_hit), p_miss=float(p_miss), logodds_limit=limit)
    meta["beams_used"] = int(used)
    return OccupancyGrid(probability, resolution=g["resolution"], origin=(g["origin_x"], g["origin_y"], 0.0),
                         frame_id=getattr(scans, "frame_id", "map") or "map", meta=meta)
