"""A procedurally generated office floor, any size: a floor plan a mobile robot would map, beside the thesis's rooms.

>>> s = office_floor(8.0, 6.0, 0.1, seed=0)
>>> s.name, s.default_mode, s.truth.shape
('office', 'waypoints', (60, 80))
"""
from __future__ import annotations


import numpy as np

from crfmap.checks import check_positive
from crfmap.errors import InputError
from crfmap.world.reachability import pose_cell, reachable
from crfmap.world.scene import Scene, scene_grid



def _split(rng, total, lo, hi, wall):
    """Split ``total`` cells into parts of lo..hi cells separated by ``wall`` cells; the last absorbs the rest."""
    parts = []
    left = total
    while left > 0:
        if left <= hi or left - wall < 2 * lo:
            size = left
        else:
            size = int(rng.integers(lo, min(hi, left - wall - lo) + 1))
        parts.append(size)
        left -= size + wall
    if len(parts) > 1 and parts[-1] < lo:  # too thin: give it to its neighbour (the wall goes too)
        last = parts.pop()
        parts[-1] += wall + last
    return parts


def office_floor(width_m=20.0, height_m=15.0, resolution=0.05, seed=0, robot_radius=0.15) -> Scene:
    """A ``width_m`` x ``height_m`` [m] office floor (at least about 6 x 5 m), everything random from ``seed``.

    Layout (y up): a vertical corridor along the left wall joins horizontal corridors, each with a row of rooms below
    and above it. Rooms are 2.5-4.5 m wide and deep; each has a 0.9 m door onto its corridor, some a door to the next
    room, most a desk against the back wall. Walls are 0.15 m. The robot starts where the first corridor meets the
    left one, facing +x; the waypoints visit every room centre a robot of ``robot_radius`` [m] can reach, corridor by
    corridor (``default_mode="waypoints"``).

    >>> s = office_floor(12.0, 10.0, 0.1, seed=3)
    >>> s.truth.shape, len(s.waypoints) >= 2
    ((100, 120), True)
    """
    res = check_positive("resolution", resolution)
    check_positive("width_m", width_m), check_positive("height_m", height_m)
    rng = np.random.default_rng(seed)
    cells_of = lambda metres, least=1: max(least, int(round(metres / res)))  # noqa: E731
    t = cells_of(0.15)  # wall
    cw = cells_of(1.6, 3)  # corridor width
    door = cells_of(0.9, 2)
    room_lo, room_hi = cells_of(2.5, 4), cells_of(4.5, 5)
    desk_w, desk_d = cells_of(1.4, 2), cells_of(0.7, 1)
    W, H = int(round(width_m / res)), int(round(height_m / res))
    min_w, min_h = 3 * t + cw + room_lo, 3 * t + cw + room_lo
    if W < min_w:
        raise InputError("width_m", f"an office needs at least {min_w * res:.2f} m at {res} m/cell, got {width_m}")
    if H < min_h:
        raise InputError("height_m", f"an office needs at least {min_h * res:.2f} m at {res} m/cell, got {height_m}")
    cells = np.ones((H, W), np.uint8)  # carve free space out of solid
    spine = (t, t + cw - 1)  # x range of the left corridor
    cells[t : H - t, spine[0] : spine[1] + 1] = 0
    x_rooms = spine[1] + 1 + t  # first room column
    # Horizontal bands: blocks of [rooms, wall, corridor, wall, rooms] separated by walls.
    inner = H - 2 * t
    block = 2 * (room_lo + room_hi) // 2 + cw + 3 * t
    n_blocks = max(1, int(round(inner / block)))
    while n_blocks > 1 and inner - n_blocks * (cw + 3 * t) + t < 2 * n_blocks * room_lo:
        n_blocks -= 1
    depth_total = inner - n_blocks * (cw + 2 * t) - (n_blocks - 1) * t
    two_rows = depth_total >= 2 * n_blocks * room_lo
    n_rows = 2 * n_blocks if two_rows else 1
    depths = np.full(n_rows, depth_total // n_rows)
    depths[: depth_total - depths.sum()] += 1
    rooms = []  # (x0, y0, x1, y1, corridor index, door side: +1 corridor above, -1 below)
    corridors = []
    y = t
    for b in range(n_blocks):
        rows_here = [(depths[2 * b], +1), (depths[2 * b + 1], -1)] if two_rows else [(depths[0], +1)]
        # row below the corridor
        d, side = rows_here[0]
        row_below = (y, y + d - 1)
        y += d + t
        corridor = (y, y + cw - 1)
        corridors.append(corridor)
        cells[corridor[0] : corridor[1] + 1, spine[0] : W - t] = 0
        y += cw + t
        rows = [(row_below, +1)]
        if two_rows:
            d, _ = rows_here[1]
            rows.append(((y, y + d - 1), -1))
            y += d + t
        for (ya, yb), side in rows:
            x = x_rooms
            for wdt in _split(rng, W - t - x_rooms, room_lo, room_hi, t):
                rooms.append((x, ya, x + wdt - 1, yb, b, side))
                x += wdt + t
    if not two_rows:  # one row of rooms below the corridor; the rest above it is open floor
        cells[corridors[0][1] + 1 : H - t, spine[0] : W - t] = 0
    for i, (x0, y0, x1, y1, b, side) in enumerate(rooms):
        cells[y0 : y1 + 1, x0 : x1 + 1] = 0
        width = x1 - x0 + 1
        dw = min(door, width - 2)
        dx = int(rng.integers(x0 + 1, x1 - dw + 2)) if width - dw > 2 else x0 + 1
        wall_rows = range(y1 + 1, y1 + 1 + t) if side > 0 else range(y0 - t, y0)
        for wy in wall_rows:
            cells[wy, dx : dx + dw] = 0
        nxt = rooms[i + 1] if i + 1 < len(rooms) else None
        if nxt is not None and nxt[1] == y0 and rng.random() < 0.3:  # a door to the next room in the row
            dy = y0 + (y1 - y0) // 2 - door // 2
            cells[max(y0 + 1, dy) : min(y1, dy + door), x1 + 1 : x1 + 1 + t] = 0
        if rng.random() < 0.7 and width > desk_w + 2 and (y1 - y0 + 1) > 3 * desk_d:
            desk_x = int(rng.integers(x0 + 1, x1 - desk_w + 1))
            if side > 0:  # corridor above: the back wall is below
                cells[y0 : y0 + desk_d, desk_x : desk_x + desk_w] = 1
            else:
                cells[y1 - desk_d + 1 : y1 + 1, desk_x : desk_x + desk_w] = 1
    truth = scene_grid(cells, res, scene="office", seed=seed, width_m=width_m, height_m=height_m)
    start = ((spine[0] + spine[1] + 1) / 2 * res, (corridors[0][0] + corridors[0][1] + 1) / 2 * res, 0.0)
    ordered = []
    for b in range(len(corridors)):
        here = sorted((r for r in rooms if r[4] == b), key=lambda r: (r[0], r[1]), reverse=bool(b % 2))
        ordered += [((r[0] + r[2] + 1) / 2 * res, (r[1] + r[3] + 1) / 2 * res) for r in here]
    can_reach = reachable(truth, start, robot_radius)
    waypoints = [p for p in ordered if can_reach[pose_cell(truth, p)[::-1]]]
    return Scene(
        name="office",
        truth=truth,
        start=start,
        description=f"{width_m:g} m x {height_m:g} m office floor (seed {seed}): {len(rooms)} rooms, "
        f"{len(corridors)} corridor(s)",
        default_mode="waypoints",
        waypoints=np.asarray(waypoints, dtype=np.float64).reshape(-1, 2),
        robot_radius=float(robot_radius),
    )

