"""Slow, obviously correct references for crfmap.mapping.builder: plain Python loops, no numba."""
import math

import numpy as np

from naive_raycast import exact_line  # the exact rational line, independent of the Bresenham kernel


def beams(scans, origin, resolution, free_on_no_return=0.0, max_range_is_no_return=True):
    """Per scan, a list of (cells on the ray, ends_in_hit) under REP 117; no clipping (the bounds must hold all)."""
    ox, oy = origin
    range_min, range_max = float(np.float32(scans.range_min)), float(np.float32(scans.range_max))
    out = []
    for i in range(scans.ranges.shape[0]):
        px, py, pyaw = (float(v) for v in scans.laser_poses[i])
        x0 = math.floor((px - ox) / resolution)
        y0 = math.floor((py - oy) / resolution)
        rays = []
        for k in range(scans.ranges.shape[1]):
            r = float(scans.ranges[i, k])
            if math.isnan(r) or r == -math.inf:
                continue
            if r == math.inf or (max_range_is_no_return and r == range_max):
                if not free_on_no_return:
                    continue
                length, hit = free_on_no_return, False
            elif r < range_min or r > range_max:
                continue
            else:
                length, hit = r, True
            a = pyaw + scans.angle_min + k * scans.angle_increment
            u = (px - ox) / resolution + length * math.cos(a) / resolution
            v = (py - oy) / resolution + length * math.sin(a) / resolution
            rays.append((exact_line(x0, y0, math.floor(u), math.floor(v)), hit))
        out.append(rays)
    return out


def count_hits(scans, shape, origin, resolution, **kw):
    """Thesis sec. 3.2 counts: every beam adds an empty hit to each cell it passes, an occupied hit to its end."""
    occupied = np.zeros(shape, int)
    empty = np.zeros(shape, int)
    for rays in beams(scans, origin, resolution, **kw):
        for cells, hit in rays:
            for x, y in cells[:-1]:
                empty[y, x] += 1
            x, y = cells[-1]
            if hit:
                occupied[y, x] += 1
            else:
                empty[y, x] += 1
    return occupied, empty


def logodds(scans, shape, origin, resolution, p_hit, p_miss, limit, **kw):
    """Probabilistic Robotics Table 9.1, one update per cell and scan, occupied first; clamped."""
    l_hit, l_miss = math.log(p_hit / (1 - p_hit)), math.log(p_miss / (1 - p_miss))
    l = np.zeros(shape)
    seen = np.zeros(shape, bool)
    for rays in beams(scans, origin, resolution, **kw):
        hit_cells = {cells[-1] for cells, hit in rays if hit}
        miss_cells = set()
        for cells, hit in rays:
            miss_cells.update(cells[:-1] if hit else cells)
        for x, y in hit_cells:
            l[y, x] = min(max(l[y, x] + l_hit, -limit), limit)
            seen[y, x] = True
        for x, y in miss_cells - hit_cells:
            l[y, x] = min(max(l[y, x] + l_miss, -limit), limit)
            seen[y, x] = True
    p = 1.0 - 1.0 / (1.0 + np.exp(l))
    p[~seen] = 0.5
    return p
