"""Beam kernels of the grid builder (:mod:`crfmap.mapping.builder`, private): classify readings, clip rays, count hits.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from crfmap.raycast import bresenham_step

_SKIP, _HIT, _FREE = 0, 1, 2  # beam kinds


@njit(cache=True, nogil=True)
def _classify(r, range_min, range_max, max_is_no_return, free_range):
    """(kind, length [m]) of one reading under REP 117."""
    if math.isnan(r) or r == -math.inf:
        return _SKIP, 0.0
    if r == math.inf or (max_is_no_return and r == range_max):
        if free_range > 0.0:
            return _FREE, free_range
        return _SKIP, 0.0
    if r < range_min or r > range_max:
        return _SKIP, 0.0
    return _HIT, r


@njit(cache=True, nogil=True)
def _end_cell(u0, v0, u1, v1, width, height):
    """End cell of the ray (u0, v0) -> (u1, v1) in cell units, clipped to the grid; (x, y, clipped)."""
    t = 1.0
    du, dv = u1 - u0, v1 - v0
    edge = 1e-9  # stay inside the last cell when clipping to the far edge
    if u1 < 0.0:
        t = min(t, (0.0 - u0) / du)
    elif u1 >= width:
        t = min(t, (width - edge - u0) / du)
    if v1 < 0.0:
        t = min(t, (0.0 - v0) / dv)
    elif v1 >= height:
        t = min(t, (height - edge - v0) / dv)
    clipped = t < 1.0
    x = min(max(int(math.floor(u0 + t * du)), 0), width - 1)
    y = min(max(int(math.floor(v0 + t * dv)), 0), height - 1)
    return x, y, clipped


@njit(cache=True, nogil=True)
def _count_hits(ranges, angles, poses, range_min, range_max, max_is_no_return, free_range,
                origin_x, origin_y, resolution, occupied, empty, buf, stamp, scan_id, touched):
    """Add every beam's hits to ``occupied[y, x]`` / ``empty[y, x]`` (in place); returns (beams used, n_touched).

    With a ``stamp`` array the size of the grid (else a 0 x 0 one), every cell a beam passes or ends in is listed once
    in ``touched[:n_touched]`` as (x, y) and stamped with ``scan_id`` (stamps must be below it beforehand)."""
    height, width = occupied.shape
    record = stamp.shape[0] > 0
    used = 0
    n_touched = 0
    for i in range(ranges.shape[0]):
        px, py, pyaw = poses[i, 0], poses[i, 1], poses[i, 2]
        u0 = (px - origin_x) / resolution
        v0 = (py - origin_y) / resolution
        x0 = int(math.floor(u0))
        y0 = int(math.floor(v0))
        for k in range(ranges.shape[1]):
            kind, length = _classify(ranges[i, k], range_min, range_max, max_is_no_return, free_range)
            if kind == _SKIP:
                continue
            used += 1
            a = pyaw + angles[k]
            u1 = u0 + length * math.cos(a) / resolution
            v1 = v0 + length * math.sin(a) / resolution
            x1, y1, clipped = _end_cell(u0, v0, u1, v1, width, height)
            n = bresenham_step(x0, y0, x1, y1, buf)
            for j in range(n - 1):
                empty[buf[j, 1], buf[j, 0]] += 1
            if kind == _HIT and not clipped:
                occupied[y1, x1] += 1
            else:
                empty[y1, x1] += 1
            if record:
                for j in range(n):
                    x, y = buf[j, 0], buf[j, 1]
                    if stamp[y, x] != scan_id:
                        stamp[y, x] = scan_id
                        touched[n_touched, 0] = x
                        touched[n_touched, 1] = y
                        n_touched += 1
    return used, n_touched


@njit(cache=True, nogil=True)
def _logodds_update(ranges, angles, poses, range_min, range_max, max_is_no_return, free_range,
                    origin_x, origin_y, resolution, l_hit, l_miss, limit, logodds,
                    hit_stamp, miss_stamp, scan_offset, buf):
    """Per-scan log-odds update of ``logodds[y, x]`` (in place); each cell changes once per scan."""
    height, width = logodds.shape
    n_beams = ranges.shape[1]
    end_x = np.empty(n_beams, np.int64)
    end_y = np.empty(n_beams, np.int64)
    kinds = np.zeros(n_beams, np.int64)
    used = 0
    for i in range(ranges.shape[0]):
        scan_id = scan_offset + i
        px, py, pyaw = poses[i, 0], poses[i, 1], poses[i, 2]
        u0 = (px - origin_x) / resolution
        v0 = (py - origin_y) / resolution
        x0 = int(math.floor(u0))
        y0 = int(math.floor(v0))
        # Pass 1: end cells; cells where a beam ended are occupied for this scan.
        for k in range(n_beams):
            kind, length = _classify(ranges[i, k], range_min, range_max, max_is_no_return, free_range)
            kinds[k] = kind
            if kind == _SKIP:
                continue
            used += 1
            a = pyaw + angles[k]
            x1, y1, clipped = _end_cell(u0, v0, u0 + length * math.cos(a) / resolution,
                                        v0 + length * math.sin(a) / resolution, width, height)
            end_x[k], end_y[k] = x1, y1
            if kind == _HIT and clipped:
                kinds[k] = _FREE
            if kinds[k] == _HIT and hit_stamp[y1, x1] != scan_id:
                hit_stamp[y1, x1] = scan_id
                logodds[y1, x1] = min(max(logodds[y1, x1] + l_hit, -limit), limit)
        # Pass 2: every other cell the beams pass (or end in, for no-returns) is a miss, once.
        for k in range(n_beams):
            if kinds[k] == _SKIP:
                continue
            n = bresenham_step(x0, y0, end_x[k], end_y[k], buf)
            last = n - 1 if kinds[k] == _HIT else n
            for j in range(last):
                x, y = buf[j, 0], buf[j, 1]
                if hit_stamp[y, x] != scan_id and miss_stamp[y, x] != scan_id:
                    miss_stamp[y, x] = scan_id
                    logodds[y, x] = min(max(logodds[y, x] + l_miss, -limit), limit)
    return used
