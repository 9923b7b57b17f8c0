"""The occupancy grid: P(occupied) per cell plus the metadata of nav_msgs/OccupancyGrid.

Convention (ROS's, REP 103): the array is indexed ``probability[y, x]``; row 0 is the lowest y, column 0 the lowest
x; cell (0, 0)'s lower-left corner sits at ``origin`` (x [m], y [m], yaw [rad]) in ``frame_id``; a cell is
``resolution`` metres wide. 0.5 means unknown (never observed), as in the thesis.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from crfmap.errors import InputError

UNKNOWN = 0.5  # P(occupied) of a cell nobody has seen
MAX_EXTENT_M = 1e8  # [m] no map reaches this far (the Earth is 4e7 m round): a unit mistake or a corrupt field


def check_probability_array(values, name="grid") -> np.ndarray:
    """Return ``values`` as a 2-D float array in [0, 1], or raise :class:`InputError`.

    >>> check_probability_array([[0.0, 0.5], [1.0, 0.25]]).shape
    (2, 2)
    """
    if isinstance(values, np.ma.MaskedArray):  # np.asarray would drop the mask and read masked cells as data
        if np.ma.count_masked(values):
            raise InputError(name, f"a masked array with {int(np.ma.count_masked(values))} masked cell(s): fill them "
                                   "first (values.filled(0.5) makes them unknown)")
        values = values.data
    arr = np.asarray(values)
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer) or arr.dtype == bool):
        raise InputError(name, f"expected a numeric array, got dtype {arr.dtype}")
    if arr.ndim != 2:
        raise InputError(name, f"expected a 2-D array [y, x], got {arr.ndim}-D with shape {arr.shape}")
    if arr.size == 0:
        raise InputError(name, f"empty grid (shape {arr.shape})")
    if not np.issubdtype(arr.dtype, np.floating):
        arr = arr.astype(np.float64)
    lo, hi = float(arr.min()), float(arr.max())  # NaN spreads into both, an infinity into one: no full-size temporary
    if not (math.isfinite(lo) and math.isfinite(hi)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise InputError(name, f"{bad} cell(s) are NaN or infinite")
    if lo < 0.0 or hi > 1.0:
        raise InputError(name, f"values must be probabilities in [0, 1], found range [{lo:g}, {hi:g}]")
    return arr


@dataclass
class OccupancyGrid:
    """P(occupied) on a regular grid, with its place in the world.

    >>> g = OccupancyGrid(np.full((2, 3), 0.5), resolution=0.05)
    >>> g.width, g.height
    (3, 2)
    """

    probability: np.ndarray
    resolution: float = 1.0  # [m/cell]
    origin: tuple = (0.0, 0.0, 0.0)  # (x [m], y [m], yaw [rad]) of cell (0, 0)'s corner
    frame_id: str = "map"
    meta: dict = field(default_factory=dict)  # free-form provenance (e.g. the map YAML's extra keys)

    def __post_init__(self):
        self.probability = check_probability_array(self.probability, "grid")
        number = (int, float, np.integer, np.floating)
        if not (isinstance(self.resolution, number) and not isinstance(self.resolution, (bool, np.bool_))
                and math.isfinite(self.resolution) and self.resolution > 0):
            raise InputError("resolution", f"must be a positive number of metres, got {self.resolution!r}")
        self.resolution = float(self.resolution)
        given = self.origin
        if isinstance(given, (str, bytes)) or not hasattr(given, "__len__") or len(given) not in (2, 3) \
                or not all(isinstance(v, number) and not isinstance(v, (bool, np.bool_)) for v in given):
            raise InputError("origin", f"must be (x, y[, yaw]) numbers, got {given!r}")
        origin = tuple(float(v) for v in given) + ((0.0,) if len(given) == 2 else ())
        if not all(math.isfinite(v) for v in origin):
            raise InputError("origin", f"must be finite, got {given!r}")
        # every cell's corner must be a number: (x, y) and the far corner within MAX_EXTENT_M (checks.py's bound)
        reach = max(abs(origin[0]), abs(origin[1])) + self.resolution * max(self.probability.shape)
        if not reach <= MAX_EXTENT_M:
            raise InputError("origin", f"{given!r} with {self.probability.shape[1]} x {self.probability.shape[0]} "
                                       f"cells of {self.resolution:g} m reaches beyond {MAX_EXTENT_M:g} m: a unit "
                                       "mistake or a corrupt field?")
        self.origin = origin

    @property
    def height(self) -> int:
        return int(self.probability.shape[0])

    @property
    def width(self) -> int:
        return int(self.probability.shape[1])

    @property
    def shape(self) -> tuple:
        return self.probability.shape

    def with_probability(self, probability) -> "OccupancyGrid":
        """The same grid metadata with new cell values."""
        return replace(self, probability=np.asarray(probability), meta=dict(self.meta))

    def copy(self) -> "OccupancyGrid":
        return self.with_probability(self.probability.copy())

    def world_to_cell(self, x, y):
        """Cell indices (ix, iy) (floats, floor them for the cell) of world points."""
        ox, oy, yaw = self.origin
        dx, dy = np.asarray(x, float) - ox, np.asarray(y, float) - oy
        c, s = math.cos(yaw), math.sin(yaw)
        return (c * dx + s * dy) / self.resolution, (-s * dx + c * dy) / self.resolution

    def cell_to_world(self, ix, iy):
        """World coordinates of cell centres (ix, iy)."""
        ox, oy, yaw = self.origin
        u = (np.asarray(ix, float) + 0.5) * self.resolution
        v = (np.asarray(iy, float) + 0.5) * self.resolution
        c, s = math.cos(yaw), math.sin(yaw)
        return ox + c * u - s * v, oy + s * u + c * v

    def bounds(self):
        """(xmin, ymin, xmax, ymax) [m]: the world rectangle the cells cover (their bounding box if rotated), as
        :func:`crfmap.mapping.build_grid` takes it (``bounds=``).

        >>> OccupancyGrid(np.zeros((2, 3)), 0.5, origin=(1.0, 2.0, 0.0)).bounds()
        (1.0, 2.0, 2.5, 3.0)
        """
        ox, oy, yaw = self.origin
        if yaw == 0.0:  # exact sums, no rounding through cos/sin
            return (float(ox), float(oy), float(ox + self.width * self.resolution),
                    float(oy + self.height * self.resolution))
        u = np.array([0.0, self.width, 0.0, self.width]) * self.resolution
        v = np.array([0.0, 0.0, self.height, self.height]) * self.resolution
        c, s = math.cos(yaw), math.sin(yaw)
        x, y = ox + c * u - s * v, oy + s * u + c * v
        return (float(x.min()), float(y.min()), float(x.max()), float(y.max()))

    def to_int8(self) -> np.ndarray:
        """nav_msgs/OccupancyGrid data as a [y, x] int8 array: -1 unknown (P exactly 0.5), else 0..100."""
        p = self.probability
        out = np.rint(p * 100.0).clip(0, 100).astype(np.int8)
        out[p == UNKNOWN] = -1
        return out

    @classmethod
    def from_int8(cls, data, **kwargs) -> "OccupancyGrid":
        """Grid from nav_msgs/OccupancyGrid values (-1 unknown -> 0.5, v -> v/100)."""
        data = np.asarray(data)
        if data.ndim != 2:
            raise InputError("occupancy data", f"expected a 2-D [y, x] array, got shape {data.shape}")
        bad = (data != -1) & ((data < 0) | (data > 100))
        if bad.any():
            raise InputError("occupancy data", f"{int(bad.sum())} value(s) outside -1 and 0..100")
        p = np.where(data < 0, UNKNOWN, data.astype(np.float64) / 100.0)
        return cls(p, **kwargs)

    def known(self) -> np.ndarray:
        """Boolean mask of observed cells (P not exactly 0.5)."""
        return self.probability != UNKNOWN


def as_grid(grid, name="grid") -> OccupancyGrid:
    """``grid`` if it is an :class:`OccupancyGrid`, else a checked array of P(occupied) as one (default metadata).

    >>> as_grid([[0.5, 1.0]]).shape
    (1, 2)
    """
    if isinstance(grid, OccupancyGrid):
        return grid
    return OccupancyGrid(check_probability_array(grid, name))
