"""From scans to an occupancy grid: the thesis's arctan builder, the log-odds baseline, and the online mapper.

Public API (imported on first use, so ``import crfmap.mapping`` stays cheap):

- :mod:`crfmap.mapping.builder`: ``build_grid``, ``count_hits``, ``HitCounter``, ``scan_bounds``, ``arctan_probability``, ``logodds_to_probability``
- :mod:`crfmap.mapping.online`: ``OnlineMapper``, ``ScanUpdate``
"""
from __future__ import annotations

import importlib

_API = {
    "build_grid": "builder",
    "count_hits": "builder",
    "HitCounter": "builder",
    "scan_bounds": "builder",
    "arctan_probability": "builder",
    "logodds_to_probability": "builder",
    "OnlineMapper": "online",
    "ScanUpdate": "online",
}
__all__ = sorted(_API)


def __getattr__(name):
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_API))
