"""The QoS of each topic the node uses, as ROS users expect them (independent of the middleware).

- Maps (``/map``, ``/map_refined``, ``/map_metadata``): reliable, transient local, keep last 1,
  as map_server and slam_toolbox publish them, so a subscriber that starts late still gets
  the last map. A nav2 costmap subscribes to ``/map`` that way (``map_subscribe_transient_local``).
- Scans: sensor-data QoS (rclcpp's ``SensorDataQoS``: best effort, volatile, keep last 5). The
  node's reader keeps more (``reader_depth``): a reader's depth is its own and matches any
  writer, and a mapper busy with one scan then loses none of the next.
- ``/tf``: reliable, volatile, keep last 100 (tf2_ros's listener and broadcaster).
- ``/tf_static``: reliable, transient local (tf2_ros's static broadcaster keeps 1, the listener 100).

In ROS 1 these become: maps latched, everything else plain (TCPROS is always reliable).
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Profile:
    """One topic's QoS: reliability, durability, and the history depth (keep last)."""

    reliable: bool
    transient_local: bool
    depth: int
    reader_depth: int | None = None  # the subscriber's own depth, if it differs from the writers'

    @property
    def latched(self) -> bool:
        """ROS 1's word for transient local."""
        return self.transient_local

    def describe(self) -> str:
        """One line for logs and the README, e.g. 'reliable, transient local, depth 1'."""
        return (f"{'reliable' if self.reliable else 'best effort'}, "
                f"{'transient local' if self.transient_local else 'volatile'}, depth {self.depth}")


MAP = Profile(reliable=True, transient_local=True, depth=1)
SCAN = Profile(reliable=False, transient_local=False, depth=5, reader_depth=200)
TF = Profile(reliable=True, transient_local=False, depth=100, reader_depth=1000)
TF_STATIC = Profile(reliable=True, transient_local=True, depth=1, reader_depth=100)
