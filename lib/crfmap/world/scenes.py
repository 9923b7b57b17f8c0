"""Ground-truth scenes for the experiments of thesis sec. 4.1: the grid and where the robot starts.

A scene (:class:`~crfmap.world.scene.Scene`) is a 0/1 grid, nothing unknown, plus a start pose of the robot in a
free cell; :data:`SCENES` names them (:func:`make_scene`). Layouts are drawn in cell coordinates with ``x`` to the
right and ``y`` up (row 0 is the lowest ``y``); "upper left" means small ``x``, large ``y``. The thesis scenes are
:data:`THESIS_SIZE` cells square at :data:`THESIS_RESOLUTION` by default (``resolution=1.0``: cell units, as the
thesis); its robot is a point.

>>> scene = occluded_walls("train")
>>> scene.truth.shape, scene.truth.resolution
((40, 40), 0.1)
"""
from __future__ import annotations

import inspect
import math
from functools import partial

import numpy as np

from crfmap.checks import check_number, check_positive
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.world.office import office_floor
from crfmap.world.scene import Scene, scene_grid

X_IMAGE_FILE = "images/ugm_X_32x32.csv"  # 1 = white background, 0 = X stroke (UGM's X.mat)
THESIS_SIZE = 40  # [cells] side of the thesis-style scenes
THESIS_RESOLUTION = 0.1  # [m/cell]


# --- small helpers -------------------------------------------------------------------
def _cell_pose(ix, iy, resolution, yaw=0.0) -> tuple:
    """Pose at the centre of cell (ix, iy) of a grid whose origin is (0, 0, 0)."""
    return ((ix + 0.5) * resolution, (iy + 0.5) * resolution, float(yaw))


def _check_variant(variant) -> str:
    if variant not in ("train", "test"):
        raise InputError("variant", f"must be 'train' or 'test', got {variant!r}")
    return variant


def _check_size(size) -> int:
    if not isinstance(size, (int, np.integer)) or size < 20:
        raise InputError("size", f"must be an integer of at least 20 cells, got {size!r}")
    return int(size)


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
    """The "X" denoising image (thesis Fig. 20) as a 0/1 grid, the stroke occupied: :data:`X_IMAGE_FILE` under the
    data folder (inverted, and flipped so that drawn with ``origin="lower"`` it looks as in the toolbox), resized
    nearest-neighbour if ``shape`` is not 32; without the file an X of the same proportions is drawn
    (``truth.meta["source"]`` says which).

    >>> x_image().truth.shape
    (32, 32)
    """
    from crfmap.data import data_file, have_data
    if isinstance(shape, (int, np.integer)) and not isinstance(shape, bool):
        h = w = int(shape)
    else:
        try:
            h, w = (int(v) for v in shape)
        except (TypeError, ValueError):
            raise InputError("shape", f"expected an int or (height, width), got {shape!r}") from None
    if h < 4 or w < 4:
        raise InputError("shape", f"the X needs at least 4x4 cells, got {h}x{w}")
    resolution = check_positive("resolution", resolution)
    if have_data(X_IMAGE_FILE):
        path = data_file(X_IMAGE_FILE)
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
    truth = scene_grid(stroke, resolution, source=source)
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
    """The thesis's "noisy scan" (sec. 4.1.1) of a 0/1 ``truth`` (OccupancyGrid, Scene or (H, W) array): an observed
    P(occupied) per cell.

    - ``"gaussian"``: ``P = clip(truth + N(0, noise**2), 0, 1)``, the UGM denoising demo's noise (``X + randn/2``).
    - ``"flip"``: each cell's 0/1 value is flipped with probability ``noise`` (at most 0.5) and the observed bit
      ``o`` reported as the posterior under a flat prior: ``P = 1 - noise`` if ``o = 1`` else ``noise``.

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
    noise = check_number("noise", noise, low=0.0)
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
    """A walled room where small foreground walls hide parts of long background walls (thesis Fig. 27; "test": 32),
    scanned from the upper-left corner (``default_mode="look"``): LBP must fill in the small walls' shadows and the
    gaps between far beams. ``size`` [cells]: the layout scaled from :data:`THESIS_SIZE`; ``seed``: None for the
    canonical layout, or an int to jitter every wall by up to 2 cells.

    >>> s = occluded_walls("test"); s.start_cell()
    (2, 37)
    """
    variant = _check_variant(variant)
    resolution = check_positive("resolution", resolution)
    size = _check_size(size)
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
        truth=scene_grid(cells, resolution, scene=f"occluded-{variant}", seed=seed),
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
    """An office-like room with boxes (cubicles) the robot cannot enter (thesis Fig. 36; "test": 37), scanned from
    every cell the robot can reach (``default_mode="explore"``). ``hollow=True``: only the boxes' one-cell outline is
    occupied, the enclosed centre empty and unseen (Fig. 40, where LBP makes the grid worse). ``size`` [cells]: the
    layout scaled from :data:`THESIS_SIZE`; ``seed``: None for the canonical layout, or an int for 8 random boxes.

    >>> s = enclosed_boxes("train", hollow=True)
    >>> bool(s.truth.probability[7, 7] == 0.0)  # inside a hollow box
    True
    """
    variant = _check_variant(variant)
    resolution = check_positive("resolution", resolution)
    size = _check_size(size)
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
        truth=scene_grid(cells, resolution, scene=f"{kind}-{variant}", seed=seed, boxes=boxes),
        start=_cell_pose(2, size - 3, resolution),
        description=f"{size}x{size} room with {len(boxes)} {'hollow' if hollow else 'filled'} boxes the robot cannot "
        f"enter (thesis Fig. {figure})",
        default_mode="explore",
        waypoints=_corner_loop(size, size, resolution),
    )


# --- names ---------------------------------------------------------------------------
SCENES = {  # name -> the scene's maker, its variant given
    "x": partial(x_image),
    "occluded-train": partial(occluded_walls, "train"),
    "occluded-test": partial(occluded_walls, "test"),
    "enclosed-train": partial(enclosed_boxes, "train"),
    "enclosed-test": partial(enclosed_boxes, "test"),
    "hollow-train": partial(enclosed_boxes, "train", hollow=True),
    "hollow-test": partial(enclosed_boxes, "test", hollow=True),
    "office": partial(office_floor),
}


def make_scene(name, **kwargs) -> Scene:
    """The scene called ``name`` (a key of :data:`SCENES`), built with ``kwargs`` (e.g. ``seed``).

    >>> make_scene("hollow-test").name
    'hollow-test'
    """
    if name not in SCENES:
        raise InputError("scene", f"unknown scene {name!r}; choose one of {', '.join(SCENES)}")
    accepted = set(inspect.signature(SCENES[name].func).parameters) - {"variant", "hollow"}
    for key in kwargs:
        if key not in accepted:
            raise InputError(key, f"scene {name!r} takes no {key!r}; it takes {', '.join(sorted(accepted))}")
    return SCENES[name](**kwargs)
