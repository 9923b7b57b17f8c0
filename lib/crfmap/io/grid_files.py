"""Any grid file by its suffix: map_server maps (``.yaml``) or exact arrays (``.npy`` with a sidecar)."""
from __future__ import annotations

from pathlib import Path

from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.io.map_server import MAP_SUFFIXES, load_map, save_map
from crfmap.io.npy_grid import load_npy, save_npy


def load_grid(path) -> OccupancyGrid:
    """Load a grid by suffix: ``.yaml``/``.yml`` -> :func:`load_map`, ``.npy`` -> :func:`load_npy`.

    An ``.npy`` grid's sidecar (``x.npy.yaml``) loads the ``x.npy`` it describes.
    """
    path = Path(path)
    name = path.name.lower()
    if name.endswith(".npy.yaml"):
        return load_npy(path.with_name(path.name[: -len(".yaml")]))
    if path.suffix.lower() in MAP_SUFFIXES:
        return load_map(path)
    if path.suffix.lower() == ".npy":
        return load_npy(path)
    raise InputError(path, f"unsupported grid file type {path.suffix or '(no suffix)'!r} "
                           "(expected .yaml/.yml map_server map or .npy)")


def save_grid(grid: OccupancyGrid, path, **options):
    """Save a grid by suffix: ``.yaml``/``.yml`` -> :func:`save_map` (``options`` go there), ``.npy`` -> :func:`save_npy`."""
    path = Path(path)
    if path.suffix.lower() in MAP_SUFFIXES:
        return save_map(grid, path, **options)
    if path.suffix.lower() == ".npy":
        if options:
            raise InputError(path, f"options {sorted(options)} only apply to map_server maps (.yaml)")
        return save_npy(grid, path)
    raise InputError(path, f"unsupported grid file type {path.suffix or '(no suffix)'!r} "
                           "(expected .yaml/.yml map_server map or .npy)")
