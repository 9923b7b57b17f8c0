"""OctoMap's occupancy update (Hornung et al. 2013) on a 2-D grid: the ``octomap`` peer.

What OctoMap does with one scan (``OccupancyOcTreeBase::insertPointCloud`` with its defaults, ``computeUpdate``; read
from OctoMap's source, OctoMap/octomap):

1. every returned beam's end point marks its cell *occupied*; the cells the beam crosses on the way, from the sensor's
   cell up to but excluding the end cell, are *free*: those of Amanatides & Woo's voxel traversal
   (``computeRayKeys``), every cell the segment enters, 4-connected in 2-D (Bresenham's line skips corner cells);
2. the free and occupied sets are sets: a cell many beams pass is updated once per scan; a cell both free and occupied
   in the same scan counts as occupied only;
3. each free cell gets ``l += logit(p_miss)``, each occupied one ``l += logit(p_hit)``, then ``l`` is clamped to
   ``[logit(clamp_min), logit(clamp_max)]`` (``updateNodeLogOdds``), in float32 like OctoMap's nodes. Never-updated
   cells stay unknown (P = 0.5).

This is this project's implementation of OctoMap's update, not the OctoMap library: the tests check it against the
library (through octomap-python) on the same rays, cell by cell. Defaults are OctoMap's; the ``octomap`` peer row
uses :data:`crfmap.assess.peers.OCTOMAP_INTEL`. The octree is only OctoMap's storage: at one fixed resolution its
leaves are this grid's cells. Readings follow REP 117 as in :mod:`crfmap.mapping.builder` (no-returns dropped unless
``free_on_no_return``, which clears up to that range like OctoMap's ``maxrange``); a beam leaving the grid clears
cells up to the edge and marks nothing occupied.

>>> from crfmap.recording import ScanSet
>>> s = ScanSet(np.array([[0.36]], np.float32), 0.0, 0.0, 0.1, 5.0, np.array([[0.05, 0.05, 0.0]]), np.zeros(1))
>>> octomap_grid(s, 0.1, bounds=(0, 0, 0.5, 0.1)).probability.round(2).tolist()
[[0.4, 0.4, 0.4, 0.4, 0.7]]
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from crfmap.errors import InputError
from crfmap.grid import UNKNOWN, OccupancyGrid
from crfmap.mapping._beam_kernels import _HIT, _SKIP, _classify
from crfmap.mapping.builder import _geometry, hit_miss_logodds, logit, sensor_probe

# OctoMap's defaults (octomap/src/AbstractOccupancyOcTree.cpp)
P_HIT = 0.7
P_MISS = 0.4
CLAMP_MIN = 0.1192  # log-odds -2.0
CLAMP_MAX = 0.971  # log-odds +3.5


@njit(cache=True, nogil=True)
def _ray_cells(u0, v0, u1, v1, width, height, out):
    """Cells (x, y) OctoMap's ``computeRayKeys`` lists from (u0, v0) to (u1, v1) [cell units]; returns the count.

    The start cell and every cell the segment then enters, excluding the end cell; the walk also stops on leaving the
    grid or when it overshoots the segment's length (OctoMap's guard against rounding). Ties (a corner) step in y, as
    OctoMap's minimum over (x, y, z) does."""
    x, y = int(math.floor(u0)), int(math.floor(v0))
    xe, ye = int(math.floor(u1)), int(math.floor(v1))
    if x == xe and y == ye:
        return 0
    n = 0
    out[n, 0], out[n, 1] = x, y
    n += 1
    du, dv = u1 - u0, v1 - v0
    length = math.sqrt(du * du + dv * dv)
    du, dv = du / length, dv / length
    big = 1.7976931348623157e308  # OctoMap's numeric_limits<double>::max()
    sx = 1 if du > 0 else (-1 if du < 0 else 0)
    sy = 1 if dv > 0 else (-1 if dv < 0 else 0)
    tx = ((x + 0.5 + 0.5 * sx) - u0) / du if sx != 0 else big
    ty = ((y + 0.5 + 0.5 * sy) - v0) / dv if sy != 0 else big
    dtx = 1.0 / abs(du) if sx != 0 else big
    dty = 1.0 / abs(dv) if sy != 0 else big
    while True:
        if tx < ty:
            x += sx
            tx += dtx
        else:
            y += sy
            ty += dty
        if x == xe and y == ye:
            break
        if min(tx, ty) > length:
            break
        if x < 0 or x >= width or y < 0 or y >= height:
            break
        out[n, 0], out[n, 1] = x, y
        n += 1
    return n


@njit(cache=True, nogil=True)
def _octomap_update(ranges, angles, poses, range_min, range_max, max_is_no_return, free_range,
                    origin_x, origin_y, resolution, l_hit, l_miss, l_min, l_max, logodds, hit_stamp, miss_stamp,
                    scan_offset, buf):  # pragma: no cover - compiled; tested against a hand-worked case and OctoMap
    """Apply every scan's update to ``logodds[y, x]`` (float32, in place); returns beams used."""
    height, width = logodds.shape
    n_beams = ranges.shape[1]
    kinds = np.zeros(n_beams, np.int64)
    ends = np.empty((n_beams, 2), np.float64)
    used = 0
    for i in range(ranges.shape[0]):
        scan_id = scan_offset + i
        u0 = (poses[i, 0] - origin_x) / resolution
        v0 = (poses[i, 1] - origin_y) / resolution
        # the occupied set: end cells of returned beams inside the grid
        for k in range(n_beams):
            kind, length = _classify(ranges[i, k], range_min, range_max, max_is_no_return, free_range)
            kinds[k] = kind
            if kind == _SKIP:
                continue
            used += 1
            a = poses[i, 2] + angles[k]
            u1 = u0 + length * math.cos(a) / resolution
            v1 = v0 + length * math.sin(a) / resolution
            ends[k, 0], ends[k, 1] = u1, v1
            xe, ye = int(math.floor(u1)), int(math.floor(v1))
            inside = 0 <= xe < width and 0 <= ye < height
            if kind == _HIT and inside:
                if hit_stamp[ye, xe] != scan_id:
                    hit_stamp[ye, xe] = scan_id
                    l = logodds[ye, xe] + l_hit
                    logodds[ye, xe] = min(max(l, l_min), l_max)
            elif kind == _HIT:
                kinds[k] = -1  # a hit outside the grid: free cells up to the edge only
        # the free set minus the occupied set, each cell once
        for k in range(n_beams):
            if kinds[k] == _SKIP:
                continue
            n = _ray_cells(u0, v0, ends[k, 0], ends[k, 1], width, height, buf)
            for j in range(n):
                x, y = buf[j, 0], buf[j, 1]
                if hit_stamp[y, x] != scan_id and miss_stamp[y, x] != scan_id:
                    miss_stamp[y, x] = scan_id
                    l = logodds[y, x] + l_miss
                    logodds[y, x] = min(max(l, l_min), l_max)
    return used


def _logodds_params(p_hit, p_miss, clamp_min, clamp_max) -> tuple:
    """The float32 log-odds (hit, miss, lower clamp, upper clamp) of the four probabilities, checked."""
    l_hit, l_miss = hit_miss_logodds(p_hit, p_miss)
    l_min, l_max = logit(clamp_min, "clamp_min"), logit(clamp_max, "clamp_max")
    if not (l_min < 0 < l_max):
        raise InputError("clamp_min/clamp_max", f"need clamp_min < 0.5 < clamp_max, got {clamp_min!r} and {clamp_max!r}")
    return tuple(np.float32(v) for v in (l_hit, l_miss, l_min, l_max))


def octomap_grid(scans, resolution, bounds=None, p_hit=P_HIT, p_miss=P_MISS, clamp_min=CLAMP_MIN,
                 clamp_max=CLAMP_MAX, free_on_no_return=False, max_range_is_no_return=True) -> OccupancyGrid:
    """Occupancy grid of OctoMap's clamped log-odds update on :func:`crfmap.mapping.build_grid`'s grid: ``sigmoid(l)``
    where a cell was updated, 0.5 elsewhere."""
    g = _geometry(scans, resolution, bounds, free_on_no_return, max_range_is_no_return)
    octomap = OctoMapUpdater(g, p_hit, p_miss, clamp_min, clamp_max)
    used = octomap.update(g["ranges"], g["poses"])
    meta = {"model": "octomap", "scans": octomap.scans, "beams_used": int(used), "p_hit": float(p_hit),
            "p_miss": float(p_miss), "clamp_min": float(clamp_min), "clamp_max": float(clamp_max)}
    return OccupancyGrid(octomap.probability(), resolution=octomap.resolution, origin=octomap.origin,
                         frame_id=getattr(scans, "frame_id", "map") or "map", meta=meta)


class OctoMapUpdater:
    """OctoMap's update one scan at a time (a robot mapping as it drives): after :meth:`add_scan` of every scan of a
    recording, in order, :meth:`grid` equals :func:`octomap_grid` of it on the same grid with the same parameters.

    >>> up = OctoMapUpdater.for_sensor((0, 0, 0.5, 0.1), 0.1, 0.0, 0.1, 1, 0.05, 5.0)
    >>> up.add_scan(np.array([0.36], np.float32), (0.05, 0.05, 0.0))
    >>> up.grid().probability.round(2).tolist()
    [[0.4, 0.4, 0.4, 0.4, 0.7]]
    """

    def __init__(self, geometry, p_hit=P_HIT, p_miss=P_MISS, clamp_min=CLAMP_MIN, clamp_max=CLAMP_MAX):
        self._logodds_params = _logodds_params(p_hit, p_miss, clamp_min, clamp_max)
        g = dict(geometry)
        self.width, self.height, self.resolution = int(g["width"]), int(g["height"]), float(g["resolution"])
        self.origin = (float(g["origin_x"]), float(g["origin_y"]), 0.0)
        self.angles = np.asarray(g["angles"], np.float64)
        self._sensor = (g["range_min"], g["range_max"], g["max_is_no_return"], g["free_range"])
        self.logodds = np.zeros((self.height, self.width), np.float32)
        self._hit_stamp = np.full((self.height, self.width), -1, np.int64)
        self._miss_stamp = np.full((self.height, self.width), -1, np.int64)
        self._buf = np.empty((2 * (self.width + self.height) + 4, 2), np.int64)
        self.scans = 0

    @classmethod
    def for_sensor(cls, bounds, resolution, angle_min, angle_increment, n_beams, range_min, range_max,
                   free_on_no_return=False, max_range_is_no_return=True, **params) -> "OctoMapUpdater":
        """An updater for a grid over ``bounds`` (xmin, ymin, xmax, ymax) [m] and a laser's geometry."""
        probe = sensor_probe(bounds, angle_min, angle_increment, n_beams, range_min, range_max)
        return cls(_geometry(probe, resolution, bounds, free_on_no_return, max_range_is_no_return), **params)

    def add_scan(self, ranges, laser_pose) -> None:
        """Update with one scan (``ranges`` [m], REP 117, at ``laser_pose`` (x, y, yaw) in the map)."""
        r = np.asarray(ranges)
        if r.shape != (len(self.angles),) or not np.issubdtype(r.dtype, np.floating):
            raise InputError("ranges", f"expected {len(self.angles)} floating-point readings, got shape {r.shape}")
        pose = np.asarray(laser_pose, dtype=np.float64).ravel()
        if pose.shape != (3,) or not np.all(np.isfinite(pose)):
            raise InputError("laser_pose", f"expected finite (x, y, yaw), got {laser_pose!r}")
        u, v = (pose[0] - self.origin[0]) / self.resolution, (pose[1] - self.origin[1]) / self.resolution
        if not (0 <= u < self.width and 0 <= v < self.height):
            raise InputError("laser_pose", f"({pose[0]:.3f}, {pose[1]:.3f}) m lies outside the grid")
        self.update(r.astype(np.float32, copy=False)[None, :], pose[None, :])

    def update(self, ranges, laser_poses) -> int:
        """Update with scans ``ranges`` [scan, beam] (float32) at ``laser_poses`` [scan, (x, y, yaw)], checked by the
        caller; returns the beams used."""
        range_min, range_max, max_is_no_return, free_range = self._sensor
        used = _octomap_update(ranges, self.angles, laser_poses, range_min, range_max, max_is_no_return, free_range,
                               self.origin[0], self.origin[1], self.resolution, *self._logodds_params, self.logodds,
                               self._hit_stamp, self._miss_stamp, self.scans, self._buf)
        self.scans += len(ranges)
        return used

    def probability(self) -> np.ndarray:
        """P(occupied) [y, x]: ``sigmoid(l)`` where a cell was updated, 0.5 elsewhere."""
        p = 1.0 / (1.0 + np.exp(-self.logodds.astype(np.float64)))
        p[(self._hit_stamp < 0) & (self._miss_stamp < 0)] = UNKNOWN
        return p

    def grid(self) -> OccupancyGrid:
        """The map so far, as :func:`octomap_grid` returns it."""
        return OccupancyGrid(self.probability(), resolution=self.resolution, origin=self.origin,
                             meta={"model": "octomap", "scans": self.scans})
