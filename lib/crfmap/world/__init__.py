"""The world a robot maps: ground-truth scenes (the thesis's and procedural office floors) and where a robot can go.

Public API (imported on first use, so ``import crfmap.world`` stays cheap):
"""
from __future__ import annotations

from crfmap.lazy import api_listing, attach

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
__doc__ += api_listing(__name__, _API)
