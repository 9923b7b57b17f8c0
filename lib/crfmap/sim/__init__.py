"""Simulated sensing: the laser, how the robot drives, and the simulator that records scans of a scene.

Public API (imported on first use, so ``import crfmap.sim`` stays cheap):

- :mod:`crfmap.sim.laser`: ``Laser``, ``LEGACY_NO_RETURN``
- :mod:`crfmap.sim.motion`: ``Motion``, ``explore_reachable``, ``look_around``, ``follow_waypoints``
- :mod:`crfmap.sim.drives`: ``Explore``, ``Look``, ``Waypoints``, ``drive_for``
- :mod:`crfmap.sim.simulator`: ``simulate``, ``cast_rays``, ``add_range_noise``
- :mod:`crfmap.sim.frontiers`: ``costmap``, ``inflate``, ``shortest_paths``, ``plan_path`` (and ``frontiers``, imported from the module: it shares its name)
- :mod:`crfmap.sim.onboard`: ``ONBOARD_MAPS``, ``make_onboard``
- :mod:`crfmap.sim.exploration`: ``ExploreSettings``, ``explore``, ``map_scores``, ``navigation_task``
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
    "costmap": "frontiers",
    "inflate": "frontiers",
    "shortest_paths": "frontiers",
    "plan_path": "frontiers",
    "ONBOARD_MAPS": "onboard",
    "make_onboard": "onboard",
    "ExploreSettings": "exploration",
    "explore": "exploration",
    "map_scores": "exploration",
    "navigation_task": "exploration",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
