"""Checked inputs: the one place where a user-supplied scalar or a pair of grids is validated.

Every public function that takes a number from a user (a resolution, a noise bound, a seed, a count)
or an observed grid with its truth checks it here, so the errors read the same everywhere:
``InputError(name, what is wrong)``. Domain checks (a scene variant, a potential table's layout) stay
with their domain.
"""
from __future__ import annotations

import math

import numpy as np

from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid, check_probability_array


def check_number(name, value, low=None, low_open=False, high=None) -> float:
    """``value`` as a float; InputError naming ``name`` unless finite, >= ``low`` (> with ``low_open``), <= ``high``.

    >>> check_number("noise", 0.25, low=0)
    0.25
    >>> check_number("noise", -1, low=0)
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: noise: must be >= 0, got -1
    """
    numeric = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
    if not numeric or not math.isfinite(value):
        raise InputError(name, f"expected a finite number, got {value!r}")
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


def check_pair(observed, truth, grids_only=False) -> tuple:
    """The probability arrays of an observed grid and its truth, checked to have one shape.

    Each may be an :class:`~crfmap.grid.OccupancyGrid` or (unless ``grids_only``) an array of
    probabilities.

    >>> obs, tru = check_pair(OccupancyGrid(np.full((2, 2), 0.5)), np.zeros((2, 2)))
    >>> check_pair(obs, np.zeros((3, 2)))
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: truth: shape (3, 2) does not match the observed grid's (2, 2)
    """
    arrays = []
    for name, grid in (("observed", observed), ("truth", truth)):
        if isinstance(grid, OccupancyGrid):
            arrays.append(grid.probability)
        elif grids_only:
            raise InputError(name, f"expected an OccupancyGrid, got {type(grid).__name__}")
        else:
            arrays.append(check_probability_array(grid, name))
    if arrays[0].shape != arrays[1].shape:
        raise InputError("truth", f"shape {arrays[1].shape} does not match the observed grid's {arrays[0].shape}")
    return tuple(arrays)
