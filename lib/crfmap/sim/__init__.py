"""Simulated sensing: the laser, how the robot drives, and the simulator that records scans of a scene.

Public API (imported on first use, so ``import crfmap.sim`` stays cheap):
"""
from __future__ import annotations

from crfmap.lazy import api_listing, attach

_API = {
    "Laser": "laser",
    "LEGACY_NO_RETURN": "laser",
    "Motion": "motion",
    "explore_reachable": "motion",
    "look_around": "motion",
    "follow_waypoints": "motion",
    "Explore": "drives",
    "Look": "drives",
    "Waypoints": "drives",
    "drive_for": "drives",
    "simulate": "simulator",
    "cast_rays": "simulator",
    "add_range_noise": "simulator",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
__doc__ += api_listing(__name__, _API)
