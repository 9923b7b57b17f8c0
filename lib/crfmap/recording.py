"""What a robot recorded (laser scans, poses, odometry, commands) independent of file format: readers and the
simulator produce it, the grid builder and the bag writer consume it. Units are SI (metres, radians, seconds); poses
are (x, y, yaw) with yaw counter-clockwise from +x (REP 103).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from crfmap.checks import check_int


@dataclass
class Trajectory:
    """Timed planar poses of one frame in another (e.g. base_link in odom)."""

    stamps: np.ndarray  # (n,) [s]
    poses: np.ndarray  # (n, 3) x [m], y [m], yaw [rad]
    frame_id: str = "odom"  # the fixed frame
    child_frame_id: str = "base_link"  # the moving frame
    twists: np.ndarray | None = None  # (n, 2) forward speed [m/s], yaw rate [rad/s], if known

    def __len__(self):
        return len(self.stamps)


@dataclass
class ScanSet:
    """Laser scans with the laser's pose in a fixed frame at each scan. ``ranges[i, k]`` is beam k of scan i at angle
    ``angle_min + k * angle_increment`` in the laser frame; REP 117: +inf = no return, -inf = too close, NaN = invalid.
    """

    ranges: np.ndarray  # (n_scans, n_beams) float32 [m]
    angle_min: float  # [rad]
    angle_increment: float  # [rad]
    range_min: float  # [m]
    range_max: float  # [m]
    laser_poses: np.ndarray  # (n_scans, 3) pose of the laser in frame_id
    stamps: np.ndarray  # (n_scans,) [s]
    frame_id: str = "map"
    laser_frame_id: str = "laser"
    source: str = ""  # where the scans came from, for messages

    def __len__(self):
        return int(self.ranges.shape[0])

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.ranges.shape[1])

    def head(self, n) -> "ScanSet":
        """The first ``n`` scans (all of them if there are fewer), every per-scan field cut alike.

        >>> s = ScanSet(np.ones((3, 2), np.float32), 0.0, 0.1, 0.1, 5.0, np.zeros((3, 3)), np.arange(3.0))
        >>> first = s.head(2)
        >>> len(first), first.laser_poses.shape, first.stamps.tolist()
        (2, (2, 3), [0.0, 1.0])
        """
        n = check_int("n", n, low=0)
        return replace(self, ranges=self.ranges[:n], laser_poses=self.laser_poses[:n], stamps=self.stamps[:n])

    def every(self, step) -> "ScanSet":
        """Every ``step``-th scan from the first (a lighter set of the same run), every per-scan field cut alike.

        >>> s = ScanSet(np.ones((5, 2), np.float32), 0.0, 0.1, 0.1, 5.0, np.zeros((5, 3)), np.arange(5.0))
        >>> s.every(2).stamps.tolist(), len(s.every(1))
        ([0.0, 2.0, 4.0], 5)
        """
        step = check_int("step", step, low=1)
        return replace(self, ranges=self.ranges[::step], laser_poses=self.laser_poses[::step],
                       stamps=self.stamps[::step])


@dataclass
class Recording:
    """Everything a (real or simulated) run records, as a bag would hold it: ``scans.laser_poses`` in ``map`` (true or
    corrected), ``odometry`` base_link in odom as the wheels report it, ``true_poses`` base_link in map when known."""

    scans: ScanSet
    laser_mount: tuple = (0.0, 0.0, 0.0)  # base_link -> laser (x, y, yaw), from /tf_static
    odometry: Trajectory | None = None
    true_poses: Trajectory | None = None
    cmd_vel: Trajectory | None = None  # poses unused (zeros); twists = commanded (v, w)
    ground_truth: object | None = None  # an OccupancyGrid, when known
    meta: dict = field(default_factory=dict)
