"""Any grid file by its suffix: map_server maps (``.yaml``) or exact arrays (``.npy`` with a sidecar)."""
from __future__ import annotations

from crfmap.checks import check_grid_geometry, check_path_arg
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.io.map_server import MAP_SUFFIXES, load_map, save_map
from crfmap.io.npy_grid import load_npy, save_npy


def _kind(path):
    name = path.name.lower()
    if name.endswith(".npy.yaml"):
        return "sidecar"
    if path.suffix.lower() in MAP_SUFFIXES:
        return "map"
    if path.suffix.lower() == ".npy":
        return "npy"
    raise InputError(path, f"unsupported grid file type {path.suffix or '(no suffix)'!r} "
                           "(expected .yaml/.yml map_server map or .npy)")


def load_grid(path, *, free_thresh=None, occupied_thresh=None, loader=None) -> OccupancyGrid:
    """Load a grid by suffix: ``.yaml``/``.yml`` -> :func:`load_map` (with the thresholds and ``loader``), ``.npy`` or
    its sidecar ``x.npy.yaml`` -> :func:`load_npy` (thresholds are an error). A grid reaching beyond
    :data:`crfmap.grid.MAX_EXTENT_M` metres is refused."""
    path = check_path_arg(path, "grid file name (.yaml or .npy)", file=True)
    kind = _kind(path)
    if kind != "map" and (free_thresh is not None or occupied_thresh is not None):
        raise InputError("--free-thresh/--occupied-thresh" if free_thresh is not None else "--occupied-thresh",
                         f"apply to map_server YAML maps only, not to {path.name}")
    if kind == "sidecar":
        return load_npy(path.with_name(path.name[: -len(".yaml")]))
    if kind == "npy":
        return load_npy(path)
    options = {} if loader is None else {"loader": loader}
    grid = load_map(path, free_thresh=free_thresh, occupied_thresh=occupied_thresh, **options)
    check_grid_geometry(path, grid.resolution, grid.origin, grid.width, grid.height)
    return grid


def save_grid(grid: OccupancyGrid, path, **options):
    """Save a grid by suffix: ``.yaml``/``.yml`` -> :func:`save_map` (``options`` go there), ``.npy`` -> :func:`save_npy`."""
    path = check_path_arg(path, "grid file name (.yaml or .npy)", file=True)
    if not isinstance(grid, OccupancyGrid):
        raise InputError(path, f"expected an OccupancyGrid to save, got {type(grid).__name__}")
    if path.suffix.lower() in MAP_SUFFIXES:
        for target in (path, path.with_suffix(".pgm"), path.with_suffix(".png")):
            if target.is_dir():  # refuse before writing anything: never half a map replaced
                raise InputError(target, "is a folder; a map_server map writes a YAML file and an image there")
        return save_map(grid, path, **options)
    if path.suffix.lower() == ".npy":
        if options:
            raise InputError(path, f"options {sorted(options)} only apply to map_server maps (.yaml)")
        return save_npy(grid, path)
    raise InputError(path, f"unsupported grid file type {path.suffix or '(no suffix)'!r} "
                           "(expected .yaml/.yml map_server map or .npy)")
