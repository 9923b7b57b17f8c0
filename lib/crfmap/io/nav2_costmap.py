"""What nav2's costmap makes of a map: ``nav2_costmap_2d``'s static layer, ``interpretValue``.

The static layer reads each OccupancyGrid value as an unsigned char (so -1 is 255) and, with nav2's defaults
(``lethal_cost_threshold`` 100, ``trinary_costmap`` true, ``unknown_cost_value`` 255, ``track_unknown_space`` true as in
nav2's shipped parameters):

- ``value == unknown_cost_value`` -> NO_INFORMATION (255), or FREE (0) without unknown tracking;
- ``value >= lethal_cost_threshold`` -> LETHAL_OBSTACLE (254);
- otherwise FREE (0) in a trinary costmap, else ``value / lethal_threshold * 254`` (truncated).

Rolling adds ``inscribed_obstacle_cost_value`` (99 -> INSCRIBED, 253): ``inscribed_value=99`` models it.
ROS 1's costmap_2d is the same rule.

>>> import numpy as np
>>> static_layer_costs(np.array([[-1, 0, 64, 99, 100]], np.int8)).tolist()
[[255, 0, 0, 0, 254]]
>>> nav2_counts(np.array([[-1, 0, 64, 99, 100]], np.int8))
{'occupied': 1, 'free': 3, 'unknown': 1}
"""
from __future__ import annotations

import numpy as np

LETHAL_OBSTACLE, INSCRIBED_INFLATED_OBSTACLE, NO_INFORMATION, FREE_SPACE = 254, 253, 255, 0


def static_layer_costs(values, lethal_threshold=100, trinary=True, unknown_cost_value=255,
                       track_unknown=True, inscribed_value=None) -> np.ndarray:
    """Costs (uint8) the static layer gives OccupancyGrid ``values`` (int8 -1 / 0..100)."""
    v = np.asarray(values).astype(np.int16) & 0xFF  # int8 -> unsigned char, as in C++
    lethal_threshold = max(min(int(lethal_threshold), 100), 0)
    scaled = (v.astype(np.float64) / max(lethal_threshold, 1) * LETHAL_OBSTACLE).astype(np.int64)
    out = np.where(trinary, FREE_SPACE, scaled).astype(np.int64)
    out = np.where(v >= lethal_threshold, LETHAL_OBSTACLE, out)
    if inscribed_value is not None:
        out = np.where(v == inscribed_value, INSCRIBED_INFLATED_OBSTACLE, out)
    out = np.where(v == unknown_cost_value, NO_INFORMATION if track_unknown else FREE_SPACE, out)
    return out.astype(np.uint8)


def nav2_counts(values, **costmap_options) -> dict:
    """Cells LETHAL_OBSTACLE (``occupied``), NO_INFORMATION (``unknown``) and the rest (``free``) in nav2's costmap."""
    costs = static_layer_costs(values, **costmap_options)
    occupied = int((costs == LETHAL_OBSTACLE).sum())
    unknown = int((costs == NO_INFORMATION).sum())
    return {"occupied": occupied, "free": int(costs.size) - occupied - unknown, "unknown": unknown}


def describe_for_nav2(values, **costmap_options) -> str:
    c = nav2_counts(values, **costmap_options)
    return f"{c['occupied']} occupied, {c['free']} free, {c['unknown']} unknown cells under nav2's defaults"


__all__ = ["static_layer_costs", "nav2_counts", "describe_for_nav2", "LETHAL_OBSTACLE", "NO_INFORMATION",
           "FREE_SPACE", "INSCRIBED_INFLATED_OBSTACLE"]
