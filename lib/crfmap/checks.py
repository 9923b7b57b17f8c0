"""Checked inputs: numbers, masks, paths and sizes a user gives, so the errors read the same everywhere
(``InputError(name, what is wrong)``). Domain checks (a potential table's layout) stay with their domain.
"""
from __future__ import annotations

import math
import os
import stat
from pathlib import Path

import numpy as np

from crfmap.errors import InputError
from crfmap.environment import number


def check_number(name, value, low=None, low_open=False, high=None, infinite=False) -> float:
    """``value`` as a float; InputError naming ``name`` unless finite (or +inf with ``infinite``), >= ``low`` (> with
    ``low_open``), <= ``high``.

    >>> check_number("noise", 0.25, low=0)
    0.25
    >>> check_number("noise", -1, low=0)
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: noise: must be >= 0, got -1
    """
    numeric = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
    if not numeric or not (math.isfinite(value) or (infinite and value == math.inf)):
        raise InputError(name, f"expected a finite number{' or inf' if infinite else ''}, got {value!r}")
    value = float(value)
    if low is not None and (value < low or (low_open and value == low)):
        raise InputError(name, f"must be {'>' if low_open else '>='} {low:g}, got {value:g}")
    if high is not None and value > high:
        raise InputError(name, f"must be <= {high:g}, got {value:g}")
    return value


def check_positive(name, value) -> float:
    """``value`` as a float > 0 (a resolution, a length, a duration).

    >>> check_positive("resolution", 0)
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: resolution: must be > 0, got 0
    """
    return check_number(name, value, low=0.0, low_open=True)


def check_int(name, value, low=None, high=None) -> int:
    """``value`` as an int (a count, a seed, a size); bools and floats are refused.

    >>> check_int("seed", 3)
    3
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise InputError(name, f"expected an integer, got {value!r}")
    value = int(value)
    if low is not None and value < low:
        raise InputError(name, f"must be >= {low}, got {value}")
    if high is not None and value > high:
        raise InputError(name, f"must be <= {high}, got {value}")
    return value


def check_mask(name, mask, shape=None) -> np.ndarray:
    """``mask`` as a boolean array (2-D, of ``shape`` when given); InputError naming ``name`` for another dtype: read by
    truth value, P(occupied) or a label image passed where cells are chosen would choose almost every cell.

    >>> check_mask("region", np.full((2, 2), 0.3))
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: region: expected a boolean mask (True: the cell is chosen), got float64 values (write e.g. values > 0.5)
    """
    values = np.asarray(mask)
    if values.dtype != np.bool_:
        raise InputError(name, f"expected a boolean mask (True: the cell is chosen), got {values.dtype} values "
                               "(write e.g. values > 0.5)")
    if values.ndim != 2:
        raise InputError(name, f"expected a 2-D [y, x] mask, got shape {values.shape}")
    if shape is not None and values.shape != tuple(shape):
        raise InputError(name, f"mask shape {values.shape} does not match the grid {tuple(shape)}")
    return values


def check_settings(name, value, classes: dict, wanted: str):
    """``value`` if it is an instance of one of ``classes`` ({name: settings class}), or the class called ``value``
    with its defaults; else InputError ``name: {wanted}, got {value!r}`` (a schedule, a drive, ...).

    >>> check_settings("mode", "a", {"a": complex}, "must be a")
    0j
    """
    if isinstance(value, tuple(classes.values())):
        return value
    if isinstance(value, str) and value in classes:
        return classes[value]()
    raise InputError(name, f"{wanted}, got {value!r}")


# --- limits on what an input may ask for (checked before allocating) ------------------------------
MAX_CELLS_DEFAULT = 100_000_000  # a 10000 x 10000 grid; same bound as the grid builder's
MAX_CELLS_ENV = "CRFMAP_MAX_CELLS"  # raise the bound: e.g. CRFMAP_MAX_CELLS=400000000 (or crfmap --max-cells)
MAX_TEXT_BYTES = 1 << 20  # a map YAML, sidecar or bag metadata.yaml is a few hundred bytes


def max_cells() -> int:
    """The largest grid (in cells) an input may ask for: ``$CRFMAP_MAX_CELLS`` (no "no limit") or 100 million.

    >>> max_cells() >= 1
    True
    """
    given = number(MAX_CELLS_ENV, "cells")
    return MAX_CELLS_DEFAULT if given is None else given


def check_cells(source, width, height, what="grid") -> int:
    """``width * height`` unless it exceeds :func:`max_cells` (InputError naming ``source``).

    >>> check_cells("map.pgm", 20000, 20000)
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: map.pgm: a 20000 x 20000 grid (400,000,000 cells) exceeds the limit of 100,000,000 cells (raise it with crfmap --max-cells N or CRFMAP_MAX_CELLS)
    """
    cells = int(width) * int(height)
    limit = max_cells()
    if cells > limit:
        raise InputError(source, f"a {int(width)} x {int(height)} {what} ({cells:,} cells) exceeds the limit of "
                                 f"{limit:,} cells (raise it with crfmap --max-cells N or {MAX_CELLS_ENV})")
    return cells


def check_input_file(path, what, missing=None):
    """``path`` as a Path if it is an existing regular file (a FIFO or device would hang a reader).

    >>> check_input_file("/dev/null", "map YAML file")
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: /dev/null: not a regular file (a device, FIFO or socket), expected map YAML file
    """
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(repr(path), f"expected a file name ({what}), got {type(path).__name__}")
    path = Path(path)
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        raise InputError(path, missing or f"{what} not found") from None
    except OSError as exc:
        raise InputError(path, f"cannot read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(mode):
        raise InputError(path, f"is a folder, expected {what}")
    if not stat.S_ISREG(mode):
        raise InputError(path, f"not a regular file (a device, FIFO or socket), expected {what}")
    return path


def check_path_arg(path, what="file name", file=False):
    """``path`` as a Path; InputError for anything that is not a str or os.PathLike, and (``file``) for a name ending
    in a path separator (``Path("out.npy/")`` is ``out.npy``: a write would make a file of a folder's name).

    >>> check_path_arg(None)
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: None: expected a file name, got NoneType
    >>> check_path_arg("out.npy/", file=True)
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: out.npy/: ends in '/', a folder's name; expected a file name
    """
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(repr(path), f"expected a {what}, got {type(path).__name__}")
    text = os.fspath(path)
    if file and isinstance(text, str) and text.endswith(("/", os.sep)):
        raise InputError(text, f"ends in {text[-1]!r}, a folder's name; expected a {what}")
    return Path(path)


from crfmap.grid import MAX_EXTENT_M  # noqa: E402  (re-exported: the bound on a grid's reach, [m])


def check_grid_geometry(source, resolution, origin, width, height):
    """InputError naming ``source`` unless the grid's corners lie within :data:`MAX_EXTENT_M` metres.

    >>> check_grid_geometry("map.yaml", 1e308, (0, 0, 0), 8, 6)
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: map.yaml: resolution 1e+308 m x 8 x 6 cells and origin (0, 0) reach beyond 1e+08 m: a unit mistake or a corrupt field?
    """
    span = float(resolution) * max(int(width), int(height))
    reach = max(abs(float(origin[0])), abs(float(origin[1]))) + span
    if not (math.isfinite(reach) and reach <= MAX_EXTENT_M):
        raise InputError(source, f"resolution {float(resolution):g} m x {int(width)} x {int(height)} cells and origin "
                                 f"({float(origin[0]):g}, {float(origin[1]):g}) reach beyond {MAX_EXTENT_M:g} m: "
                                 "a unit mistake or a corrupt field?")
