"""Checked numbers: the one place where a user-supplied scalar is validated.

Every public function that takes a number from a user (a resolution, a noise bound, a seed, a count)
checks it here, so the errors read the same everywhere: ``InputError(name, what is wrong)``.
"""
from __future__ import annotations

import math

import numpy as np

from crfmap.errors import InputError


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
    """``value`` as a float > 0 (a resolution, a length, a duration)."""
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
