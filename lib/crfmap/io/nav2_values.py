"""What nav2 reads from a map crfmap makes: the OccupancyGrid values map_server publishes from the trinary file.

nav2's costmap (``trinary_costmap: true``, ``lethal_cost_threshold: 100``) reads every value below 100 as free, so
a map published in percent would open every wall; the live node publishes, and the navigation metrics score, these."""
from __future__ import annotations

import functools

import numpy as np

from crfmap.errors import InputError
from crfmap.grid import UNKNOWN
from crfmap.io.map_server import FREE_THRESH_DEFAULT, OCCUPIED_THRESH_DEFAULT, pixels_from_occupancy
from crfmap.io.nav2_loader import DEFAULT_LOADER, LOADERS, Pixels, occupancy

VALUE_MODES = ("trinary", "percent")  # what a published OccupancyGrid holds: nav2's reading, or P in percent


@functools.lru_cache(maxsize=len(LOADERS))
def _value_table(loader: str) -> np.ndarray:
    """nav2's OccupancyGrid value of each written value -1..100 (index v + 1): map_saver's trinary pixel, loaded."""
    written = np.arange(-1, 101, dtype=np.int16).reshape(1, -1)
    grey, _ = pixels_from_occupancy(written, "trinary", OCCUPIED_THRESH_DEFAULT, FREE_THRESH_DEFAULT)
    loaded = occupancy(Pixels.from_grey8(grey), "trinary", 0, OCCUPIED_THRESH_DEFAULT, FREE_THRESH_DEFAULT,
                       loader=loader)
    return loaded[0]


def nav2_values(probability, loader: str = DEFAULT_LOADER) -> np.ndarray:
    """int8 [y, x]: what nav2's map_server (``loader``'s rules) publishes from the trinary map of P that ``crfmap
    infer`` writes: 100 lethal, 0 free, -1 unknown.

    >>> nav2_values(np.array([[0.645, 0.6451, 0.205, 0.2051, 0.5]])).tolist()
    [[-1, 100, 0, -1, -1]]
    """
    if loader not in LOADERS:
        raise InputError("loader", f"unknown nav2 loader {loader!r} (expected one of {', '.join(LOADERS)})")
    p = np.asarray(getattr(probability, "probability", probability), dtype=np.float64)  # an OccupancyGrid's P
    if p.ndim != 2:
        raise InputError("probability", f"expected a 2-D [y, x] array, got shape {p.shape}")
    if not np.all(np.isfinite(p)) or p.min(initial=0.0) < 0 or p.max(initial=0.0) > 1:
        raise InputError("probability", "must be probabilities in [0, 1]")
    written = np.rint(p * 100.0).astype(np.int16)  # OccupancyGrid.to_int8: the percent the file holds
    written[p == UNKNOWN] = -1
    return _value_table(loader)[written + 1]


def occupancy_values(grid, mode: str = "trinary") -> np.ndarray:
    """int8 [y, x] OccupancyGrid data of a grid: ``"trinary"`` (:func:`nav2_values`, what nav2 navigates on) or
    ``"percent"`` (``rint(100 P)``, -1 where P is exactly 0.5: the probabilities, for tools that read them).

    >>> occupancy_values(np.array([[0.9, 0.3, 0.1]])).tolist(), occupancy_values(np.array([[0.9, 0.3, 0.1]]), "percent").tolist()
    ([[100, -1, 0]], [[90, 30, 10]])
    """
    if mode not in VALUE_MODES:
        raise InputError("values", f"must be one of {', '.join(VALUE_MODES)}, got {mode!r}")
    if mode == "trinary":
        return nav2_values(grid)
    p = np.asarray(getattr(grid, "probability", grid), dtype=np.float64)
    out = np.rint(p * 100.0).clip(0, 100).astype(np.int8)
    out[p == UNKNOWN] = -1
    return out
