"""Occupancy grids as exact ``.npy`` files: the float P(occupied) array [y, x], bit for bit.

A plain ``.npy`` cannot hold where the grid lies, so a sidecar YAML beside it, ``<name>.npy.yaml``, holds
``resolution``, ``origin`` and ``frame_id``."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from crfmap.checks import check_cells, check_grid_geometry, check_input_file, check_path_arg
from crfmap.io._yaml import finite_number, format_number, read_mapping, write_text
from crfmap.io.atomic import atomic_paths, unit_lock
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid, check_probability_array


def npy_sidecar_path(npy_path) -> Path:
    """The sidecar of ``map.npy``: ``map.npy.yaml`` (``map.yaml`` would clash with a map_server map)."""
    npy_path = Path(npy_path)
    return npy_path.with_name(npy_path.name + ".yaml")


def save_npy(grid: OccupancyGrid, path) -> Path:
    """Save P(occupied) exactly, plus its sidecar; returns ``path``. Both are renamed as one unit: a concurrent
    :func:`load_npy` sees the old pair or the new one, never one of each."""
    path = check_path_arg(path, "file name ending in .npy", file=True)
    if path.suffix.lower() != ".npy":
        raise InputError(path, "an .npy grid file must end in .npy")
    if not isinstance(grid, OccupancyGrid):
        raise InputError(path, f"expected an OccupancyGrid to save, got {type(grid).__name__}")
    check_probability_array(grid.probability, path)  # changed in place since it was made? (NaN, > 1)
    sidecar = npy_sidecar_path(path)
    text = (f"# crfmap grid metadata for {path.name}: P(occupied) as float [y, x], row 0 = lowest y\n"
            f"resolution: {format_number(grid.resolution)}\n"
            f"origin: [{', '.join(format_number(v) for v in grid.origin)}]\n"
            f"frame_id: {json.dumps(grid.frame_id)}\n")
    with atomic_paths(path, sidecar) as (tmp, tmp_sidecar):
        with open(tmp, "wb") as f:  # a file object: np.save would append .npy to a name
            np.save(f, np.ascontiguousarray(grid.probability), allow_pickle=False)
        write_text(tmp_sidecar, text)
    return path


def _read_sidecar(sidecar):
    doc = read_mapping(sidecar, "crfmap .npy metadata (resolution, origin, frame_id)")
    resolution = finite_number(doc.get("resolution", 1.0), sidecar, "resolution")
    if resolution <= 0:
        raise InputError(sidecar, f"key 'resolution' must be positive, got {resolution:g}")
    origin = doc.get("origin", [0.0, 0.0, 0.0])
    if not isinstance(origin, (list, tuple)) or len(origin) not in (2, 3):
        raise InputError(sidecar, f"key 'origin' must be a list [x, y, yaw], got {origin!r}")
    origin = tuple(finite_number(v, sidecar, "origin") for v in origin)
    frame_id = doc.get("frame_id", "map")
    if not isinstance(frame_id, str):
        raise InputError(sidecar, f"key 'frame_id' must be a string, got {frame_id!r}")
    if len(frame_id) > 256 or any(not c.isprintable() for c in frame_id):
        raise InputError(sidecar, f"key 'frame_id' must be a short printable name, got {frame_id[:40]!r}")
    return resolution, origin, frame_id


def load_npy(path) -> OccupancyGrid:
    """Load a P(occupied) ``.npy`` grid (2-D float in [0, 1]) and its sidecar; without one: resolution 1 m, origin
    (0, 0, 0), frame ``map``."""
    path = check_input_file(check_path_arg(path, file=True), ".npy grid file")
    sidecar = npy_sidecar_path(path)
    with unit_lock(path.parent, exclusive=False):  # the array and its sidecar of one save_npy
        with open(path, "rb") as f:
            _check_header(f, path)
        try:
            arr = np.load(path, allow_pickle=False)
        except (ValueError, OverflowError) as exc:
            raise InputError(path, f"not a plain .npy array ({exc})") from None
        except (OSError, EOFError) as exc:
            raise InputError(path, f"unreadable .npy file ({exc})") from None
        if not isinstance(arr, np.ndarray):
            arr.close()
            raise InputError(path, "is an .npz archive, expected a single .npy array")
        has_sidecar = sidecar.exists() or sidecar.is_symlink()
        geometry = _read_sidecar(sidecar) if has_sidecar else (1.0, (0.0, 0.0, 0.0), "map")
    arr = check_probability_array(arr, path)  # 2-D, not empty, finite, in [0, 1]
    resolution, origin, frame_id = geometry
    check_grid_geometry(sidecar if has_sidecar else path, resolution, origin, arr.shape[1], arr.shape[0])
    return OccupancyGrid(arr, resolution=resolution, origin=origin, frame_id=frame_id,
                         meta={"source": str(path)})


def _check_header(f, path):
    """Refuse from the header alone what should not be read: not .npy, not a float grid, too many cells."""
    try:
        version = np.lib.format.read_magic(f)
        if version not in ((1, 0), (2, 0), (3, 0)):
            raise ValueError(f"unknown .npy version {version}")
        reader = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, _, dtype = reader(f, max_header_size=10_000)
    except (ValueError, OverflowError, SyntaxError, TypeError, EOFError, OSError) as exc:
        if str(exc).startswith("Header info length") or "max_header_size" in str(exc):
            raise InputError(path, "not a plain .npy array (its header is longer than 10000 bytes)") from None
        if f.tell() == 0 or isinstance(exc, EOFError):
            raise InputError(path, f"not an .npy file or truncated ({exc})") from None
        raise InputError(path, f"not a plain .npy array ({exc})") from None
    if dtype.hasobject:
        raise InputError(path, "not a plain .npy array: it holds Python objects (pickled data); expected a float array")
    if len(shape) == 2 and shape[0] and shape[1] and dtype.kind != "f":
        raise InputError(path, f"expected float probabilities, got dtype {dtype}")
    if len(shape) == 2:
        check_cells(path, shape[1], shape[0])
