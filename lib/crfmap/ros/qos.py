"""The QoS of each topic the node uses, as ROS users expect them (in ROS 1: maps latched, the rest plain).

- Maps: reliable, transient local, keep last 1, as map_server and slam_toolbox publish them (a late subscriber,
  such as nav2's costmap with ``map_subscribe_transient_local``, still gets the last map).
- Scans: rclcpp's ``SensorDataQoS``; the node's reader keeps more (``reader_depth``, its own whatever the writer's),
  so a mapper busy with one scan loses none of the next.
- ``/tf``, ``/tf_static``: tf2_ros's listener and broadcasters."""
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
