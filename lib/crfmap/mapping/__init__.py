"""From scans to an occupancy grid: the thesis's arctan builder, the log-odds baseline, and the online mapper.

Public API (imported on first use, so ``import crfmap.mapping`` stays cheap):
"""
from __future__ import annotations

from crfmap.lazy import api_listing, attach

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
__getattr__, __dir__, __all__ = attach(__name__, _API)
__doc__ += api_listing(__name__, _API)
