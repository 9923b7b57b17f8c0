"""Ground-truth scenes for the experiments of thesis sec. 4.1, and where a robot can go in them.

A scene is a 0/1 :class:`~crfmap.grid.OccupancyGrid` (P(occupied) 1.0 for walls, 0.0 for
free space, nothing unknown) plus a start pose of the robot in a free cell it can move
from. Layouts are drawn in cell coordinates with ``x`` to the right and ``y`` up (row 0 is
the lowest ``y``, as in the grid); "upper left" means small ``x``, large ``y``.

The thesis scenes are 40 x 40 cells of ``resolution = 0.1  # [m]`` (a 4 m x 4 m room) by
default; pass ``resolution=1.0`` to work in cell units as the thesis did. The robot of
the thesis is a point that occupies one cell (``robot_radius = 0``).

Scenes, by name (:data:`SCENES`, :func:`make_scene`):

- ``x``: the 32 x 32 "X" of the UGM toolbox's denoising demo (thesis Fig. 20), stroke occupied.
- ``occluded-train`` / ``occluded-test``: walls partly hidden behind small foreground
  walls, robot upper left (Fig. 27 / Fig. 32).
- ``enclosed-train`` / ``enclosed-test``: a room with filled boxes the robot cannot enter
  (Fig. 36 / Fig. 37); ``hollow-train`` / ``hollow-test``: the same with unfilled
  (enclosed, empty-centred) boxes (Fig. 40).
- ``office``: a procedurally generated floor of rooms, doors and corridors, any size.

>>> scene = occluded_walls("train")
>>> scene.truth.shape, scene.truth.resolution
((40, 40), 0.1)
"""
from __future__ import annotations

import inspect
import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .errors import InputError
from .grid import OccupancyGrid

X_IMAGE_FILE = "images/ugm_X_32x32.csv"  # 1 = white background, 0 = X stroke (UGM's X.mat)
THESIS_SIZE = 40  # [cells] side of the thesis-style scenes
THESIS_RESOLUTION = 0.1  # [m/cell]
MODES = ("explore", "look", "waypoints")


@dataclass
class Scene:
    """A ground-truth grid and where the robot starts in it.

    ``default_mode`` says how the thesis scanned such a scene (see
    :func:`crfmap.simulator.simulate`): ``"look"`` = stand at the start and turn in place,
    ``"explore"`` = visit every reachable cell, ``"waypoints"`` = drive through
    ``waypoints``.
    """

    name: str
    truth: OccupancyGrid  # P(occupied) 0.0 / 1.0
    start: tuple  # (x [m], y [m], yaw [rad]) of base_link in map, in a free reachable cell
    description: str = ""
    default_mode: str = "explore"
    waypoints: np.ndarray | None = None  # (k, 2) x [m], y [m] in map, visited in order
    robot_radius: float = 0.0  # [m] footprint used for reachability (0 = the thesis's point robot)

    @property
    def occupied(self) -> np.ndarray:
        """Boolean [y, x] mask of occupied cells (P > 0.5)."""
        return self.truth.probability > 0.5

    def start_cell(self) -> tuple:
        """(ix, iy) of the cell holding the start pose."""
        return pose_cell(self.truth, self.start)


# --- small helpers -------------------------------------------------------------------
def pose_cell(grid: OccupancyGrid, pose) -> tuple:
    """Integer cell (ix, iy) containing the point ``pose[:2]`` [m], or InputError if outside the grid."""
    fx, fy = grid.world_to_cell(pose[0], pose[1])
    ix, iy = int(math.floor(float(fx))), int(math.floor(float(fy)))
    if not (0 <= ix < grid.width and 0 <= iy < grid.height):
        raise InputError("start", f"position ({pose[0]:g}, {pose[1]:g}) m lies outside the "
                                  f"{grid.width}x{grid.height} grid")
    return ix, iy


def _cell_pose(ix, iy, resolution, yaw=0.0) -> tuple:
    """Pose at the centre of cell (ix, iy) of a grid whose origin is (0, 0, 0)."""
    return ((ix + 0.5) * resolution, (iy + 0.5) * resolution, float(yaw))


def _check_resolution(resolution) -> float:
    if not (isinstance(resolution, (int, float, np.floating)) and math.isfinite(resolution) and resolution > 0):
        raise InputError("resolution", f"must be a positive number of metres per cell, got {resolution!r}")
    return float(resolution)


def _check_variant(variant) -> str:
    if variant not in ("train", "test"):
        raise InputError("variant", f"must be 'train' or 'test', got {variant!r}")
    return variant


def _fill(cells, x0, y0, x1, y1, value=1):
    """Set the rectangle x0..x1, y0..y1 (inclusive, clipped to the array) to ``value``."""
    h, w = cells.shape
    xa, xb = max(0, min(x0, x1)), min(w - 1, max(x0, x1))
    ya, yb = max(0, min(y0, y1)), min(h - 1, max(y0, y1))
    if xa <= xb and ya <= yb:
        cells[ya : yb + 1, xa : xb + 1] = value


def _border(cells, thickness=1):
    cells[:thickness, :] = 1
    cells[-thickness:, :] = 1
    cells[:, :thickness] = 1
    cells[:, -thickness:] = 1


def _corner_loop(width, height, resolution, inset=2) -> np.ndarray:
    """Waypoints [m] at the centres of the cells ``inset`` cells in from each corner: top left, top right,
    bottom right, bottom left, top left again (a lap of a walled room)."""
    lo_x, hi_x, lo_y, hi_y = inset, width - 1 - inset, inset, height - 1 - inset
    cells = np.array([(lo_x, hi_y), (hi_x, hi_y), (hi_x, lo_y), (lo_x, lo_y), (lo_x, hi_y)], dtype=np.float64)
    return (cells + 0.5) * resolution


def _grid(cells, resolution, **meta) -> OccupancyGrid:
    return OccupancyGrid(cells.astype(np.float64), resolution=resolution, origin=(0.0, 0.0, 0.0), meta=dict(meta))


# --- the X image (thesis sec. 4.1.1) ---------------------------------------------------
def _procedural_x(h, w) -> np.ndarray:
    """A thick X on a [y, x] 0/1 array (1 = stroke), as wide as the UGM one relative to its size."""
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    u, v = (xx + 0.5) / w, (yy + 0.5) / h  # in (0, 1)
    half = 0.09  # half stroke width, fraction of the side (the UGM X is ~6 px wide of 32)
    margin = 0.13  # no stroke this close to the border
    d1 = np.abs(u - v) / math.sqrt(2.0)
    d2 = np.abs(u + v - 1.0) / math.sqrt(2.0)
    inside = (u > margin) & (u < 1 - margin) & (v > margin) & (v < 1 - margin)
    return (((d1 < half) | (d2 < half)) & inside).astype(np.uint8)


def _resize_nearest(img, h, w):
    ys = np.minimum((np.arange(h) + 0.5) * img.shape[0] / h, img.shape[0] - 1).astype(int)
    xs = np.minimum((np.arange(w) + 0.5) * img.shape[1] / w, img.shape[1] - 1).astype(int)
    return img[np.ix_(ys, xs)]


def x_image(shape=32, resolution=THESIS_RESOLUTION) -> Scene:
    """The "X" denoising image (thesis Fig. 20) as a 0/1 grid: the X stroke is occupied (1).

    Read from ``images/ugm_X_32x32.csv`` under the data folder (UGM's ``X.mat``: 1 = white
    background, 0 = stroke, so the values are inverted here), resized nearest-neighbour
    if ``shape`` is not 32; when the file is absent an X of the same proportions is drawn
    (``truth.meta["source"]`` says which). The CSV's first row is the image's top, so
    the rows are flipped: drawn with ``origin="lower"`` the X looks as in the toolbox.

    >>> x_image().truth.shape
    (32, 32)
    """
    from . import paths

    if isinstance(shape, (int, np.integer)) and not isinstance(shape, bool):
        h = w = int(shape)
    else:
        try:
            h, w = (int(v) for v in shape)
        except (TypeError, ValueError):
            raise InputError("shape", f"expected an int or (height, width), got {shape!r}") from None
    if h < 4 or w < 4:
        raise InputError("shape", f"the X needs at least 4x4 cells, got {h}x{w}")
    resolution = _check_resolution(resolution)
    if paths.have_data(X_IMAGE_FILE):
        path = paths.data_file(X_IMAGE_FILE)
        try:
            raw = np.loadtxt(path, delimiter=",")
        except ValueError as exc:
            raise InputError(path, f"not a CSV of 0/1 values: {exc}") from None
        if raw.ndim != 2 or not np.isin(raw, (0, 1)).all():
            raise InputError(path, "expected a 2-D CSV of 0/1 values (1 = background, 0 = stroke)")
        stroke = np.flipud(1 - raw.astype(np.uint8))
        if stroke.shape != (h, w):
            stroke = _resize_nearest(stroke, h, w)
        source = f"{X_IMAGE_FILE} (UGM X.mat)"
    else:
        stroke = _procedural_x(h, w)
        source = "procedural X (the UGM image was not found)"
    truth = _grid(stroke, resolution, source=source)
    free = np.argwhere(stroke == 0)  # (iy, ix); start in the lowest-left background cell
    iy, ix = free[np.lexsort((free[:, 0], free[:, 1]))][0]
    return Scene(
        name="x",
        truth=truth,
        start=_cell_pose(ix, iy, resolution),
        description=f"{h}x{w} 'X' image, stroke occupied; {source}",
        default_mode="explore",
        waypoints=_corner_loop(w, h, resolution, inset=1),
    )


def noisy_image(truth, noise=0.4, seed=0, model="gaussian") -> OccupancyGrid:
    """The thesis's "noisy scan" of a 0/1 image (sec. 4.1.1): an observed P(occupied) per cell.

    Models:

    - ``"gaussian"`` (default): ``P = clip(truth + N(0, noise**2), 0, 1)``, the noise of the
      UGM denoising demo (``X + randn/2``) clipped to probabilities. ``noise = 0.4`` gives an
      MSE against the truth of about 0.078 (the thesis reports 0.0825 before LBP).
    - ``"flip"``: each cell's 0/1 value is flipped with probability ``noise`` and the observed
      bit ``o`` is reported as the posterior under a flat prior: ``P = 1 - noise`` if
      ``o = 1`` else ``noise``.

    Parameters
    ----------
    truth : OccupancyGrid or (H, W) array of 0/1
    noise : float, sigma (gaussian) or flip probability in [0, 0.5] (flip)
    seed : int, for ``np.random.default_rng``

    >>> g = noisy_image(x_image().truth, 0.4, seed=1)
    >>> bool(((g.probability >= 0) & (g.probability <= 1)).all())
    True
    """
    if isinstance(truth, Scene):
        truth = truth.truth
    grid = truth if isinstance(truth, OccupancyGrid) else OccupancyGrid(np.asarray(truth, dtype=float))
    p = grid.probability
    if not np.isin(p, (0.0, 1.0)).all():
        raise InputError("truth", "expected a 0/1 ground-truth image")
    if not (isinstance(noise, (int, float, np.floating)) and math.isfinite(noise) and noise >= 0):
        raise InputError("noise", f"must be a non-negative number, got {noise!r}")
    rng = np.random.default_rng(seed)
    if model == "gaussian":
        observed = np.clip(p + rng.normal(0.0, float(noise), p.shape), 0.0, 1.0)
    elif model == "flip":
        if noise > 0.5:
            raise InputError("noise", f"a flip probability must be in [0, 0.5], got {noise}")
        flipped = rng.random(p.shape) < noise
        bit = np.where(flipped, 1.0 - p, p)
        observed = np.where(bit > 0.5, 1.0 - noise, float(noise))
    else:
        raise InputError("model", f"must be 'gaussian' or 'flip', got {model!r}")
    meta = dict(grid.meta, noise_model=model, noise=float(noise), seed=seed)
    return OccupancyGrid(observed, resolution=grid.resolution, origin=grid.origin, frame_id=grid.frame_id, meta=meta)


# --- occluded walls (thesis sec. 4.1.2, Fig. 27 and 32) ------------------------------------
# Walls in cell coordinates of a 40 x 40 room: (x0, y0, x1, y1), inclusive.
_OCCLUDED_LAYOUTS = {
    "train": {
        "background": [(6, 7, 31, 7), (33, 10, 33, 33)],  # a long bottom wall, a long right wall
        "foreground": [(13, 20, 16, 20), (22, 27, 22, 30)],  # small walls shading them from the robot
    },
    "test": {
        "background": [(4, 10, 27, 10), (30, 13, 30, 35), (9, 4, 34, 4)],
        "foreground": [(12, 23, 13, 24), (19, 29, 22, 29), (17, 16, 17, 18)],
    },
}


def occluded_walls(variant="train", size=THESIS_SIZE, resolution=THESIS_RESOLUTION, seed=None) -> Scene:
    """A walled room where small foreground walls hide parts of long background walls.

    The robot stands in the upper-left corner (thesis Fig. 27/28); ``variant="test"`` is a
    similar but different layout (three background walls, three small occluders; Fig. 32).
    The thesis scanned these from the corner (``default_mode="look"``): the shadows of the
    small walls and the gaps between far beams are what LBP must fill in.

    Parameters
    ----------
    variant : "train" or "test"
    size : int, side [cells]; the layout is scaled from 40 cells
    resolution : float [m/cell]
    seed : None for the canonical layout, or an int to jitter every wall by up to 2 cells

    >>> s = occluded_walls("test"); s.start_cell()
    (2, 37)
    """
    variant = _check_variant(variant)
    resolution = _check_resolution(resolution)
    if not isinstance(size, (int, np.integer)) or size < 20:
        raise InputError("size", f"must be an integer of at least 20 cells, got {size!r}")
    size = int(size)
    rng = np.random.default_rng(seed) if seed is not None else None
    scale = size / THESIS_SIZE
    cells = np.zeros((size, size), np.uint8)
    _border(cells)
    layout = _OCCLUDED_LAYOUTS[variant]
    for kind in ("background", "foreground"):
        for x0, y0, x1, y1 in layout[kind]:
            if rng is not None:
                dx, dy = rng.integers(-2, 3, size=2)
                x0, x1, y0, y1 = x0 + dx, x1 + dx, y0 + dy, y1 + dy
            sx = lambda v: int(round(v * scale))  # noqa: E731 - scale a coordinate
            _fill(cells, sx(x0), sx(y0), max(sx(x0), sx(x1)), max(sx(y0), sx(y1)))
    start_cell = (2, size - 3)
    _fill(cells, 1, size - 6, 5, size - 2, 0)  # keep the robot's corner free whatever the jitter
    return Scene(
        name=f"occluded-{variant}",
        truth=_grid(cells, resolution, scene=f"occluded-{variant}", seed=seed),
        start=_cell_pose(*start_cell, resolution, yaw=-math.pi / 4),
        description=f"{size}x{size} room, background walls partly hidden behind small walls, robot upper left "
        f"(thesis Fig. {'27' if variant == 'train' else '32'})",
        default_mode="look",
        waypoints=_corner_loop(size, size, resolution),
    )


# --- enclosed boxes (thesis sec. 4.1.2.1, Fig. 36, 37, 40) ----------------------------------
# Boxes (x0, y0, x1, y1) inclusive in a 40 x 40 room, robot start upper left.
_BOX_LAYOUTS = {
    "train": [(5, 5, 10, 10), (16, 5, 21, 10), (27, 5, 33, 10), (5, 17, 10, 23), (16, 17, 21, 23), (27, 17, 33, 23),
              (16, 29, 21, 34), (27, 29, 33, 34)],
    "test": [(4, 4, 12, 8), (18, 4, 22, 13), (28, 4, 35, 9), (5, 15, 12, 21), (27, 15, 31, 25), (16, 19, 22, 25),
             (8, 28, 13, 31), (19, 30, 30, 34)],
}


def _random_boxes(rng, size, n_boxes=8, gap=3):
    """Non-overlapping boxes at least ``gap`` cells apart and from the border, top-left corner kept free."""
    boxes = []
    attempts = 0
    while len(boxes) < n_boxes and attempts < 2000:
        attempts += 1
        bw, bh = rng.integers(4, 10, size=2)
        x0 = int(rng.integers(1 + gap, size - 1 - gap - bw + 1))
        y0 = int(rng.integers(1 + gap, size - 1 - gap - bh + 1))
        box = (x0, y0, x0 + int(bw) - 1, y0 + int(bh) - 1)
        if box[0] < 8 and box[3] > size - 9:
            continue  # the robot's corner
        if all(box[2] + gap < b[0] or b[2] + gap < box[0] or box[3] + gap < b[1] or b[3] + gap < box[1] for b in boxes):
            boxes.append(box)
    return boxes


def enclosed_boxes(variant="train", hollow=False, size=THESIS_SIZE, resolution=THESIS_RESOLUTION, seed=None) -> Scene:
    """An office-like room with boxes (cubicles) the robot cannot enter (thesis Fig. 36, 37).

    ``hollow=False``: the boxes are solid (occupied inside). ``hollow=True``: only their
    one-cell outline is occupied; the centre is empty but enclosed, so no robot sees it
    (Fig. 40, the case where LBP makes the grid worse). The thesis scanned every cell the
    robot can reach (``default_mode="explore"``).

    Parameters
    ----------
    variant : "train" (a regular 3 x 3 arrangement with one gap) or "test" (irregular sizes)
    hollow : bool
    size : int [cells], layout scaled from 40
    resolution : float [m/cell]
    seed : None for the canonical layout, or an int for random boxes (8 boxes, 3-cell corridors)

    >>> s = enclosed_boxes("train", hollow=True)
    >>> bool(s.truth.probability[7, 7] == 0.0)  # inside a hollow box
    True
    """
    variant = _check_variant(variant)
    resolution = _check_resolution(resolution)
    if not isinstance(size, (int, np.integer)) or size < 20:
        raise InputError("size", f"must be an integer of at least 20 cells, got {size!r}")
    size = int(size)
    scale = size / THESIS_SIZE
    if seed is None:
        boxes = [tuple(int(round(v * scale)) for v in b) for b in _BOX_LAYOUTS[variant]]
    else:
        boxes = _random_boxes(np.random.default_rng(seed), size)
    cells = np.zeros((size, size), np.uint8)
    _border(cells)
    for x0, y0, x1, y1 in boxes:
        _fill(cells, x0, y0, x1, y1)
        if hollow and x1 - x0 >= 2 and y1 - y0 >= 2:
            _fill(cells, x0 + 1, y0 + 1, x1 - 1, y1 - 1, 0)
    kind = "hollow" if hollow else "enclosed"
    figure = "40" if hollow else ("36" if variant == "train" else "37")
    return Scene(
        name=f"{kind}-{variant}",
        truth=_grid(cells, resolution, scene=f"{kind}-{variant}", seed=seed, boxes=boxes),
        start=_cell_pose(2, size - 3, resolution),
        description=f"{size}x{size} room with {len(boxes)} {'hollow' if hollow else 'filled'} boxes the robot cannot "
        f"enter (thesis Fig. {figure})",
        default_mode="explore",
        waypoints=_corner_loop(size, size, resolution),
    )


# --- a procedural office floor -----------------------------------------------------------
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
    """A procedurally generated office floor: rooms with doors and desks along corridors.

    Layout (y up): a vertical corridor along the left wall joins horizontal corridors;
    each horizontal corridor has a row of rooms below and above it. Rooms are 2.5-4.5 m
    wide and 2.5-4.5 m deep; every room has a 0.9 m door onto its corridor, some have a
    door to the next room, and most have a desk against the back wall. Walls are 0.15 m.
    The robot starts where the first corridor meets the left corridor, facing +x; the
    waypoints visit every room centre, corridor by corridor (``default_mode="waypoints"``).

    Parameters
    ----------
    width_m, height_m : float [m], at least about 6 m x 5 m
    resolution : float [m/cell]
    seed : int, the layout's random seed
    robot_radius : float [m], used to check that every room can be reached

    >>> s = office_floor(12.0, 10.0, 0.1, seed=3)
    >>> s.truth.shape, len(s.waypoints) >= 2
    ((100, 120), True)
    """
    res = _check_resolution(resolution)
    for name, v in (("width_m", width_m), ("height_m", height_m)):
        if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and v > 0):
            raise InputError(name, f"must be a positive number of metres, got {v!r}")
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
    truth = _grid(cells, res, scene="office", seed=seed, width_m=width_m, height_m=height_m)
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


# --- reachability --------------------------------------------------------------------
def footprint_offsets(robot_radius, resolution) -> np.ndarray:
    """Offsets (dx, dy) [cells] of the cells a disc of ``robot_radius`` [m] centred in cell (0, 0) overlaps.

    A cell at offset (dx, dy) is overlapped when the distance from the disc's centre to the
    nearest point of that cell's square is below the radius. (0, 0) is always included.

    >>> footprint_offsets(0.0, 0.1).tolist()
    [[0, 0]]
    >>> len(footprint_offsets(0.06, 0.1))  # the 4 side neighbours (0.05 m away) join, corners (0.07 m) do not
    5
    """
    r = float(robot_radius) / float(resolution)
    k = int(math.ceil(r + 0.5))
    d = np.arange(-k, k + 1)
    dx, dy = np.meshgrid(d, d)
    gap = np.hypot(np.maximum(np.abs(dx) - 0.5, 0.0), np.maximum(np.abs(dy) - 0.5, 0.0))
    keep = (gap < r) | ((dx == 0) & (dy == 0))
    return np.stack([dx[keep], dy[keep]], axis=1)


def traversable(truth, robot_radius=0.0) -> np.ndarray:
    """Boolean [y, x] mask of cells where a disc robot of ``robot_radius`` [m] fits (touches no occupied cell).

    Occupied means P > 0.5; outside the grid counts as occupied (the robot stays on the map).

    >>> occ = np.zeros((7, 7)); occ[3, 3] = 1
    >>> int(traversable(OccupancyGrid(occ, 0.1), 0.06).sum())  # not: the border ring, the wall, its 4 neighbours
    20
    """
    grid = truth.truth if isinstance(truth, Scene) else truth
    if not isinstance(grid, OccupancyGrid):
        grid = OccupancyGrid(np.asarray(truth, dtype=float))
    if not (isinstance(robot_radius, (int, float, np.floating)) and math.isfinite(robot_radius) and robot_radius >= 0):
        raise InputError("robot_radius", f"must be a non-negative number of metres, got {robot_radius!r}")
    occ = grid.probability > 0.5
    offsets = footprint_offsets(robot_radius, grid.resolution)
    k = int(np.abs(offsets).max())
    if k == 0:
        return ~occ
    h, w = occ.shape
    padded = np.ones((h + 2 * k, w + 2 * k), dtype=bool)
    padded[k : k + h, k : k + w] = occ
    blocked = np.zeros_like(occ)
    for dx, dy in offsets:
        blocked |= padded[k + dy : k + dy + h, k + dx : k + dx + w]
    return ~blocked


@njit(cache=True)
def _flood_fill(free, sx, sy):
    """Cells 4-connected to (sx, sy) through ``free`` cells (the start must be free)."""
    h, w = free.shape
    seen = np.zeros((h, w), dtype=np.bool_)
    stack = np.empty((h * w, 2), dtype=np.int64)
    seen[sy, sx] = True
    stack[0, 0] = sx
    stack[0, 1] = sy
    top = 1
    while top > 0:
        top -= 1
        x = stack[top, 0]
        y = stack[top, 1]
        for k in range(4):
            nx = x + (1 if k == 0 else (-1 if k == 1 else 0))
            ny = y + (1 if k == 2 else (-1 if k == 3 else 0))
            if 0 <= nx < w and 0 <= ny < h and free[ny, nx] and not seen[ny, nx]:
                seen[ny, nx] = True
                stack[top, 0] = nx
                stack[top, 1] = ny
                top += 1
    return seen


def reachable(truth, start, robot_radius=0.0) -> np.ndarray:
    """Boolean [y, x] mask of the cells a disc robot can reach from ``start`` by moving between side neighbours.

    A cell is traversable when the robot (a disc of ``robot_radius`` metres centred in the
    cell) overlaps no occupied cell (:func:`traversable`); moves go to the 4 side
    neighbours, so the robot never slips through a diagonal gap. Cells inside enclosed
    boxes are not reachable.

    Parameters
    ----------
    truth : OccupancyGrid (or Scene)
    start : (x [m], y [m][, yaw]) in the grid's frame
    robot_radius : float [m]

    >>> s = enclosed_boxes("train")
    >>> m = reachable(s.truth, s.start)
    >>> bool(m[7, 7]), bool(m[s.start_cell()[1], s.start_cell()[0]])
    (False, True)
    """
    grid = truth.truth if isinstance(truth, Scene) else truth
    free = traversable(grid, robot_radius)
    sx, sy = pose_cell(grid, start)
    if not free[sy, sx]:
        raise InputError("start", f"cell ({sx}, {sy}) is occupied or too close to a wall for a robot of radius "
                                  f"{robot_radius} m")
    return _flood_fill(free, sx, sy)


# --- names ---------------------------------------------------------------------------
SCENES = {
    "x": lambda **kw: x_image(**kw),
    "occluded-train": lambda **kw: occluded_walls("train", **kw),
    "occluded-test": lambda **kw: occluded_walls("test", **kw),
    "enclosed-train": lambda **kw: enclosed_boxes("train", **kw),
    "enclosed-test": lambda **kw: enclosed_boxes("test", **kw),
    "hollow-train": lambda **kw: enclosed_boxes("train", hollow=True, **kw),
    "hollow-test": lambda **kw: enclosed_boxes("test", hollow=True, **kw),
    "office": lambda **kw: office_floor(**kw),
}


_SCENE_MAKERS = {"x": x_image, "office": office_floor,
                 **{k: occluded_walls for k in ("occluded-train", "occluded-test")},
                 **{k: enclosed_boxes for k in ("enclosed-train", "enclosed-test", "hollow-train", "hollow-test")}}


def make_scene(name, **kwargs) -> Scene:
    """The scene called ``name`` (a key of :data:`SCENES`), built with ``kwargs`` (e.g. ``seed``).

    >>> make_scene("hollow-test").name
    'hollow-test'
    """
    if name not in SCENES:
        raise InputError("scene", f"unknown scene {name!r}; choose one of {', '.join(SCENES)}")
    maker = _SCENE_MAKERS[name]
    accepted = set(inspect.signature(maker).parameters) - {"variant", "hollow"}
    for key in kwargs:
        if key not in accepted:
            raise InputError(key, f"scene {name!r} takes no {key!r}; it takes {', '.join(sorted(accepted))}")
    return SCENES[name](**kwargs)
