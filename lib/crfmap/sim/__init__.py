"""Simulated sensing: the laser, how the robot drives, and the simulator that records scans of a scene.

Public API (imported on first use, so ``import crfmap.sim`` stays cheap):

- :mod:`crfmap.sim.laser`: ``Laser``, ``LEGACY_NO_RETURN``
- :mod:`crfmap.sim.motion`: ``Motion``, ``explore_reachable``, ``look_around``, ``follow_waypoints``
- :mod:`crfmap.sim.drives`: ``Explore``, ``Look``, ``Waypoints``, ``drive_for``
- :mod:`crfmap.sim.simulator`: ``simulate``, ``cast_rays``, ``add_range_noise``
"""
from __future__ import annotations

from crfmap.lazy import attach

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
