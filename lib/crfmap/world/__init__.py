"""The world a robot maps: ground-truth scenes (the thesis's and procedural office floors) and where a robot can go.

Public API (imported on first use, so ``import crfmap.world`` stays cheap):

- :mod:`crfmap.world.scene`: ``Scene``, ``MODES``
- :mod:`crfmap.world.scenes`: ``SCENES``, ``make_scene``, ``x_image``, ``noisy_image``, ``occluded_walls``, ``enclosed_boxes``
- :mod:`crfmap.world.office`: ``office_floor``
- :mod:`crfmap.world.reachability`: ``traversable``, ``reachable``, ``pose_cell``, ``footprint_offsets``
"""
from __future__ import annotations

from crfmap.lazy import attach

_API = {
    "Scene": "scene",
    "MODES": "scene",
    "SCENES": "scenes",
    "make_scene": "scenes",
    "x_image": "scenes",
    "noisy_image": "scenes",
    "occluded_walls": "scenes",
    "enclosed_boxes": "scenes",
    "office_floor": "office",
    "traversable": "reachability",
    "reachable": "reachability",
    "pose_cell": "reachability",
    "footprint_offsets": "reachability",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
