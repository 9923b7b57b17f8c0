"""ROS map_server maps: a YAML file (``image, mode, resolution, origin [x, y, yaw], negate, occupied_thresh,
free_thresh``) beside a greyscale image (PGM or PNG; any image Pillow reads loads).

Loading follows nav2_map_server's ``map_io.cpp`` (``loadMapYaml`` + ``loadMapFromFile``) value for value, with
Jazzy+'s or Humble's pixel rules (:mod:`crfmap.io.nav2_loader`); saving follows its ``saveMapToFile``. A loaded grid
holds the OccupancyGrid values map_server would publish, divided by 100 (unknown, -1, becomes 0.5). Exact grids are
``.npy`` files (:mod:`crfmap.io.npy_grid`); :mod:`crfmap.io.grid_files` chooses by suffix."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
from PIL import Image

from crfmap.io._yaml import finite_number, format_number, read_mapping
from crfmap.io._yaml import write_text as _write_text  # looked up here at call time, so a test can make it fail
from crfmap.io.atomic import atomic_paths, unit_lock
from crfmap.io.image_guard import check_map_image
from crfmap.checks import check_grid_geometry, check_path_arg, check_number
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid, check_probability_array
from crfmap.io.nav2_loader import DEFAULT_LOADER, LOADERS, occupancy, read_pixels

MAP_MODES = ("trinary", "scale", "raw")
MAP_SUFFIXES = (".yaml", ".yml")
IMAGE_FORMATS = ("pgm", "png")

# Pixel values both map savers write in trinary mode.
FREE_PIXEL, OCCUPIED_PIXEL, UNKNOWN_PIXEL = 254, 0, 205

# Save defaults: map_saver's since Jazzy (navigation2 PR #5278) and ROS 1's. Humble's free 0.25 would read its own
# unknown pixel 205 (occ = 50/255 = 0.196) as free (slam_toolbox issue #587).
OCCUPIED_THRESH_DEFAULT = 0.65
FREE_THRESH_DEFAULT = 0.196
# Scale mode with thresholds 0 and 1 makes nav2's grey image lossless: occ = value / 100.
SCALE_THRESHOLDS = (1.0, 0.0)  # (occupied, free)

_REQUIRED_KEYS = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")
_PNM_SEP = rb"(?:\s|#[^\n]*\n)+"
_PNM_HEADER = re.compile(rb"\A(P[1-6])" + _PNM_SEP + rb"(\d+)" + _PNM_SEP + rb"(\d+)")
_PNM_BINARY_HEADER = re.compile(rb"\A(P[56])" + (_PNM_SEP + rb"(\d+)") * 3 + rb"\s")


# --- reading the YAML -----------------------------------------------------------------------
def _check_thresholds(occupied, free, source):
    for key, value in (("occupied_thresh", occupied), ("free_thresh", free)):
        if not 0.0 <= value <= 1.0:
            raise InputError(source, f"'{key}' must lie in [0, 1], got {value:g}")
    if not free < occupied:
        raise InputError(source, f"free_thresh ({free:g}) must be smaller than occupied_thresh ({occupied:g})")


def read_map_yaml(yaml_path) -> dict:
    """Parse and check a map_server YAML file, as nav2's ``loadMapYaml`` does; all keys but ``mode`` are required.

    Returns the keys (``origin`` as 3 floats, ``negate`` 0/1, ``mode`` default ``"trinary"``), plus ``image_path``
    (relative to the YAML's folder) and ``extra`` (any other keys). Stricter than nav2: ``negate`` must be
    0/1/true/false, thresholds lie in [0, 1] with free < occupied, resolution is positive."""
    path = check_path_arg(yaml_path, "map YAML file name", file=True)
    doc = read_mapping(path, "map YAML file")
    for key in _REQUIRED_KEYS:
        if key not in doc:
            raise InputError(path, f"missing key '{key}'")
    image = doc["image"]
    if not isinstance(image, str) or not image.strip():
        raise InputError(path, f"key 'image' must be an image file name, got {image!r}")
    resolution = finite_number(doc["resolution"], path, "resolution")  # [m/cell]
    if resolution <= 0:
        raise InputError(path, f"key 'resolution' must be positive (metres per cell), got {resolution:g}")
    origin = doc["origin"]
    if not isinstance(origin, (list, tuple)) or len(origin) != 3:
        raise InputError(path, f"key 'origin' must be a list [x, y, yaw] of 3 numbers, got {origin!r}")
    origin = tuple(finite_number(v, path, "origin") for v in origin)
    negate = doc["negate"]
    if isinstance(negate, str) and negate.strip().lower() in ("0", "1", "true", "false"):
        negate = negate.strip().lower() in ("1", "true")
    if isinstance(negate, bool) or negate in (0, 1) and isinstance(negate, int):
        negate = int(negate)
    else:
        raise InputError(path, f"key 'negate' must be 0, 1, true or false, got {negate!r}")
    occupied = finite_number(doc["occupied_thresh"], path, "occupied_thresh")
    free = finite_number(doc["free_thresh"], path, "free_thresh")
    _check_thresholds(occupied, free, path)
    mode = doc.get("mode", "trinary")
    if isinstance(mode, (str, int, float)) and not isinstance(mode, bool):
        mode = str(mode).lower()  # nav2 and ROS 1 lower-case it: "Trinary" is trinary
    if mode not in MAP_MODES:
        raise InputError(path, f"unknown mode {mode!r} (expected one of {', '.join(MAP_MODES)})")
    image_path = Path(image) if Path(image).is_absolute() else path.parent / image
    extra = {k: v for k, v in doc.items() if k not in _REQUIRED_KEYS + ("mode",)}
    return dict(image=image, image_path=image_path, resolution=resolution, origin=origin,
                negate=negate, occupied_thresh=occupied, free_thresh=free, mode=mode, extra=extra)


# --- reading the image ----------------------------------------------------------------------
def _check_pnm_header(image_path, source, context):
    """Clear messages for empty or truncated PNM files (Pillow's are vaguer)."""
    with open(image_path, "rb") as f:
        head = f.read(512)
    match = _PNM_HEADER.match(head)
    if not match:
        return
    width, height = int(match.group(2)), int(match.group(3))
    if width == 0 or height == 0:
        raise InputError(source, f"empty image ({width} x {height} pixels){context}")
    binary = _PNM_BINARY_HEADER.match(head)
    if binary:  # P5 (grey) / P6 (colour): the header fixes the number of pixel bytes
        maxval = int(binary.group(4))
        expected = width * height * (1 if binary.group(1) == b"P5" else 3) * (1 if maxval < 256 else 2)
        found = Path(image_path).stat().st_size - binary.end()
        if found < expected:
            raise InputError(source, f"truncated image: its header promises {width} x {height} pixels "
                                     f"({expected} bytes) but the file holds {found} bytes{context}")


def _check_image_header(image_path, source, context):
    check_map_image(image_path, context)
    _check_pnm_header(image_path, source, context)


def _optional_thresh(name, value):
    if value is None:
        return None
    return check_number(name, value, low=0.0, high=1.0)


def load_map(yaml_path, *, occupied_thresh=None, free_thresh=None, loader=DEFAULT_LOADER) -> OccupancyGrid:
    """Load a map_server map (YAML + image) exactly as nav2's map_server would publish it.

    ``loader``: ``"jazzy"`` (default: Jazzy, Kilted, Rolling) or ``"humble"``, whose per-pixel rules differ
    (:mod:`crfmap.io.nav2_loader`). The top image row is the highest y; cell (0, 0) sits at ``origin``; a value of 50
    stays a known 50 (:func:`grid_from_values`). ``occupied_thresh`` / ``free_thresh`` override the file's, e.g.
    ``free_thresh=0.196`` keeps a Humble map's unknown pixels (205) unknown. ``grid.meta`` holds the YAML's keys as
    stated, plus ``source``, ``image_path`` and ``loader``, so that :func:`save_map` can write the same kind of map.
    InputError naming the file for a missing or bad YAML or key, and a missing, unreadable, truncated or empty image."""
    if loader not in LOADERS:
        raise InputError("--loader", f"unknown nav2 loader {loader!r} (expected one of {', '.join(LOADERS)})")
    occ_t = _optional_thresh("occupied_thresh", occupied_thresh)
    free_t = _optional_thresh("free_thresh", free_thresh)
    path = check_path_arg(yaml_path, "map YAML file name", file=True)
    with unit_lock(path.parent, exclusive=False):  # the YAML and the image of one save_map
        params = read_map_yaml(path)
        pixels = read_pixels(params["image_path"], f" (the image of {path})", _check_image_header)
    occ_t = params["occupied_thresh"] if occ_t is None else occ_t
    free_t = params["free_thresh"] if free_t is None else free_t
    if occupied_thresh is not None or free_thresh is not None:
        _check_thresholds(occ_t, free_t, "load_map thresholds")
    values = occupancy(pixels, params["mode"], params["negate"], occ_t, free_t, loader=loader)
    check_grid_geometry(path, params["resolution"], params["origin"], values.shape[1], values.shape[0])
    meta = dict(params["extra"])
    meta.update({key: params[key] for key in ("image", "mode", "negate", "occupied_thresh", "free_thresh")})
    meta.update(source=str(yaml_path), image_path=str(params["image_path"]), loader=loader)
    return grid_from_values(values[::-1], resolution=params["resolution"], origin=params["origin"],
                            frame_id="map", meta=meta)


def grid_from_values(values, **grid_kwargs) -> OccupancyGrid:
    """OccupancyGrid of int8 OccupancyGrid data [y, x]; 50 becomes P = nextafter(0.5, 1), a known 50.

    >>> grid_from_values(np.array([[50, -1]], np.int8)).to_int8().tolist()
    [[50, -1]]
    """
    grid = OccupancyGrid.from_int8(values, **grid_kwargs)
    fifty = np.asarray(values) == 50
    if fifty.any():
        grid = grid.with_probability(np.where(fifty, np.nextafter(0.5, 1.0), grid.probability))
    return grid


# --- writing ------------------------------------------------------------------------------
def _format_name(name: str) -> str:
    if re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9_.+\-]*", name):
        return name
    return json.dumps(name)  # a JSON string is a valid YAML double-quoted scalar


def map_yaml_text(image_name, mode, resolution, origin, occupied_thresh, free_thresh) -> str:
    """The YAML nav2's map_saver writes: same keys, order and layout, no final newline.

    >>> print(map_yaml_text("map.pgm", "trinary", 0.05, (-1.5, 2, 0), 0.65, 0.196))
    image: map.pgm
    mode: trinary
    resolution: 0.05
    origin: [-1.5, 2, 0]
    negate: 0
    occupied_thresh: 0.65
    free_thresh: 0.196
    """
    origin_text = ", ".join(format_number(v) for v in origin)
    return (f"image: {_format_name(image_name)}\nmode: {mode}\nresolution: {format_number(resolution)}\n"
            f"origin: [{origin_text}]\nnegate: 0\noccupied_thresh: {format_number(occupied_thresh)}\n"
            f"free_thresh: {format_number(free_thresh)}")


def pixels_from_occupancy(values, mode, occupied_thresh, free_thresh):
    """nav2's ``tryWriteMapToFile`` per-cell rule: (grey uint8, alpha uint8 or None), top row first.

    Trinary: ``v <= rint(100 free)`` -> 254, ``v >= rint(100 occupied)`` -> 0, else and unknown -> 205. Scale: grey
    ``(100 - v) / 100``, unknown -> grey 0.5 and transparent (GraphicsMagick may round a tie to the other grey level;
    the value read back is the same). Raw: grey ``v``, unknown -> 255."""
    v = np.asarray(values, dtype=np.int16)[::-1]  # image rows: top row = highest y
    unknown = (v < 0) | (v > 100)
    if mode == "trinary":
        grey = np.full(v.shape, UNKNOWN_PIXEL, dtype=np.uint8)
        grey[v >= int(np.rint(occupied_thresh * 100.0))] = OCCUPIED_PIXEL
        grey[v <= int(np.rint(free_thresh * 100.0))] = FREE_PIXEL
        grey[unknown] = UNKNOWN_PIXEL
        return grey, None
    if mode == "scale":
        grey = np.rint((100.0 - v) / 100.0 * 255.0)
        grey[unknown] = np.rint(0.5 * 255.0)
        alpha = np.where(unknown, 0, 255).astype(np.uint8)
        return grey.astype(np.uint8), alpha
    if mode == "raw":
        return np.where(unknown, 255, v).astype(np.uint8), None
    raise InputError("mode", f"unknown map mode {mode!r} (expected one of {', '.join(MAP_MODES)})")


def _write_image(path, grey, alpha, image_format):
    """Write the pixels; ``path`` is a temporary file, so the format is given explicitly."""
    if image_format == "pgm":  # the header GraphicsMagick writes; PGM has no alpha channel
        height, width = grey.shape
        with open(path, "wb") as f:
            f.write(b"P5\n%d %d\n255\n" % (width, height))
            f.write(np.ascontiguousarray(grey).tobytes())
    elif alpha is None:
        Image.fromarray(grey, mode="L").save(path, format="PNG")
    else:  # nav2 writes scale maps as TrueColorMatte (RGBA)
        rgba = np.stack([grey, grey, grey, alpha], axis=-1)
        Image.fromarray(rgba, mode="RGBA").save(path, format="PNG")


def _resolve_save_options(grid, mode, occupied_thresh, free_thresh, image_format):
    meta = grid.meta or {}
    if mode is None:
        mode = meta.get("mode") if meta.get("mode") in MAP_MODES else "trinary"
    if mode not in MAP_MODES:
        raise InputError("mode", f"unknown map mode {mode!r} (expected one of {', '.join(MAP_MODES)})")
    same_kind = meta.get("mode") == mode
    if mode == "scale":
        default_occ, default_free = SCALE_THRESHOLDS
    elif same_kind and "occupied_thresh" in meta and "free_thresh" in meta:
        default_occ, default_free = meta["occupied_thresh"], meta["free_thresh"]
    else:
        default_occ, default_free = OCCUPIED_THRESH_DEFAULT, FREE_THRESH_DEFAULT
    occ = float(default_occ) if occupied_thresh is None else _optional_thresh("occupied_thresh", occupied_thresh)
    free = float(default_free) if free_thresh is None else _optional_thresh("free_thresh", free_thresh)
    _check_thresholds(occ, free, "save_map thresholds")
    if image_format is None:
        old = Path(str(meta.get("image", ""))).suffix.lower().lstrip(".")
        image_format = old if same_kind and old in IMAGE_FORMATS else ("png" if mode == "scale" else "pgm")
    image_format = str(image_format).lower().lstrip(".")
    if image_format not in IMAGE_FORMATS:
        raise InputError("image_format", f"{image_format!r} is not supported (expected pgm or png)")
    return mode, occ, free, image_format


def save_map(grid: OccupancyGrid, yaml_path, mode=None, occupied_thresh=None, free_thresh=None,
             image_format=None, saver="humble"):
    """Write ``grid`` as a map_server map, as nav2's map_saver does; returns (yaml_path, image_path).

    The image is ``<yaml stem>.<image_format>`` beside the YAML; ``negate`` is 0; cells are ``grid.to_int8()``. Defaults
    (``None``): ``mode`` and, for the same mode, thresholds and image format from ``grid.meta`` (a loaded map writes
    back unchanged), else trinary, 0.65 / 0.196 and pgm. Scale uses :data:`SCALE_THRESHOLDS` and png: only PNG keeps the
    alpha that marks unknown (a scale PGM's unknown reloads as 50, P = 0.5). A trinary map reloads unchanged when
    ``free_thresh <= 0.196`` and ``occupied_thresh < 1``. ``saver``: ``"humble"`` writes the thresholds used into the
    YAML, as Humble's map_saver does; ``"jazzy"`` writes a trinary YAML with 0.65 / 0.196 whatever classified the cells
    (map_saver since navigation2 PR #5278)."""
    yaml_path = Path(yaml_path)
    if yaml_path.suffix.lower() not in MAP_SUFFIXES:
        raise InputError(yaml_path, "a map_server map file must end in .yaml or .yml")
    if not isinstance(grid, OccupancyGrid):
        raise InputError(yaml_path, f"expected an OccupancyGrid to save, got {type(grid).__name__}")
    check_probability_array(grid.probability, yaml_path)  # changed in place since it was made? (NaN, > 1)
    mode, occ, free, image_format = _resolve_save_options(grid, mode, occupied_thresh, free_thresh,
                                                          image_format)
    image_path = yaml_path.with_suffix("." + image_format)
    grey, alpha = pixels_from_occupancy(grid.to_int8(), mode, occ, free)
    if saver not in LOADERS:
        raise InputError("saver", f"unknown map_saver {saver!r} (expected one of {', '.join(LOADERS)})")
    yaml_occ, yaml_free = (OCCUPIED_THRESH_DEFAULT, FREE_THRESH_DEFAULT) if (
        saver == "jazzy" and mode == "trinary") else (occ, free)
    text = map_yaml_text(image_path.name, mode, grid.resolution, grid.origin, yaml_occ, yaml_free)
    # renamed as one unit: concurrent writers leave one writer's image with that writer's YAML
    with atomic_paths(image_path, yaml_path) as (tmp_image, tmp_yaml):
        _write_image(tmp_image, grey, alpha, image_format)
        _write_text(tmp_yaml, text)
    return yaml_path, image_path


__all__ = [
    "MAP_MODES", "OCCUPIED_THRESH_DEFAULT", "FREE_THRESH_DEFAULT", "read_map_yaml", "load_map",
    "save_map", "map_yaml_text", "grid_from_values", "pixels_from_occupancy",
]
