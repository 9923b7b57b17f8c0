"""The closed loop of thesis sec. 4.3: a simulated robot that explores and navigates with its own onboard map.

- :mod:`crfstudy.closed_loop.frontiers`: the costmap (nav2's thresholds and inflation), frontiers, Dijkstra / A*
- :mod:`crfstudy.closed_loop.onboard`: the maps a robot can carry (``ONBOARD_MAPS``: raw, online CRF, OctoMap,
  refined-on-arrival), one registry entry each
- :mod:`crfstudy.closed_loop.exploration`: ``ExploreSettings``, ``explore``, ``map_scores``, ``navigation_task``
"""
