"""ROS messages <-> crfmap values, for :mod:`crfmap.io.bag_reader` and :mod:`crfmap.io.bag_writer` (the interface)."""
from __future__ import annotations

import math

import numpy as np

from crfmap.errors import InputError
from crfmap.frames import quaternion_to_yaw, yaw_to_quaternion
from crfmap.grid import MAX_EXTENT_M
from crfmap.io.map_server import grid_from_values

T_SCAN = "sensor_msgs/msg/LaserScan"
T_ODOM = "nav_msgs/msg/Odometry"
T_TWIST = "geometry_msgs/msg/Twist"
T_TF = "tf2_msgs/msg/TFMessage"
T_POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
T_GRID = "nav_msgs/msg/OccupancyGrid"
TF_TYPES = ("tf2_msgs/msg/TFMessage", "tf/msg/tfMessage")  # ROS2 / ROS1 names of /tf messages

# The topics crfmap writes, and reads by default
SCAN_TOPIC, ODOM_TOPIC, CMD_VEL_TOPIC = "/scan", "/odom", "/cmd_vel"
TF_TOPIC, TF_STATIC_TOPIC = "/tf", "/tf_static"
TRUTH_TOPIC, MAP_TOPIC = "/ground_truth_pose", "/map"


# --- values out of messages ---------------------------------------------------------------
def pose_of(msg_pose, source="pose"):
    """(x, y, yaw) of a geometry_msgs Pose or Transform; InputError naming ``source`` for a position not finite or
    beyond :data:`crfmap.grid.MAX_EXTENT_M` (refused here, naming the message), or a quaternion not a rotation."""
    p = getattr(msg_pose, "position", None) or getattr(msg_pose, "translation")
    q = getattr(msg_pose, "orientation", None) or getattr(msg_pose, "rotation")
    x, y = float(p.x), float(p.y)
    if not (math.isfinite(x) and math.isfinite(y)):
        raise InputError(source, f"position ({x:g}, {y:g}) is not finite")
    if max(abs(x), abs(y)) > MAX_EXTENT_M:
        raise InputError(source, f"position ({x:g}, {y:g}) lies beyond {MAX_EXTENT_M:g} m: a unit mistake or a "
                                 "corrupt field?")
    return (x, y, quaternion_to_yaw(q, source))


def to_ns(seconds) -> int:
    """A time [s] as integer nanoseconds (bag and header stamps), the nearest to the float itself
    (whole seconds apart from the fraction: at 1.7e9 s a product with 1e9 would be 256 ns coarse)."""
    seconds = float(seconds)
    whole = math.floor(seconds)
    return int(whole) * 1_000_000_000 + int(round((seconds - whole) * 1e9))


def to_seconds(stamp) -> float:
    """A builtin_interfaces/Time (or ROS1 time) as float seconds."""
    return stamp.sec + 1e-9 * stamp.nanosec


def grid_from_message(msg, source, topic):
    """The OccupancyGrid of a nav_msgs/OccupancyGrid message; errors name ``source`` and ``topic``."""
    info = msg.info
    data = np.asarray(msg.data, dtype=np.int8)
    if data.size != int(info.width) * int(info.height) or data.size == 0:
        raise InputError(source, f"{topic}: {data.size} cells for a {info.width} x {info.height} grid")
    resolution = float(str(np.float32(info.resolution)))  # undo the float32 of MapMetaData: 0.05, not 0.0500000007
    try:  # grid_from_values: 50 stays a known 50
        return grid_from_values(data.reshape(int(info.height), int(info.width)), resolution=resolution,
                                origin=pose_of(info.origin, f"{source}: {topic} origin"), frame_id=msg.header.frame_id or "map")
    except InputError as exc:
        raise InputError(source, f"{topic}: {exc.problem}") from None


# --- messages out of values ---------------------------------------------------------------
def typestore(fmt):
    """The rosbags typestore for ``fmt``: ROS2 Humble, or ROS1 Noetic plus tf2_msgs/TFMessage."""
    from rosbags.typesys import Stores, get_typestore, get_types_from_msg

    if fmt == "ros2":
        return get_typestore(Stores.ROS2_HUMBLE)
    store = get_typestore(Stores.ROS1_NOETIC)
    # Noetic's store lacks tf2_msgs; /tf in ROS1 Noetic is tf2_msgs/TFMessage (same md5 as tf/tfMessage).
    store.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", T_TF))
    return store


class MessageFactory:
    """Builds messages of one typestore (ROS1 headers carry a seq, ROS2 ones do not)."""

    def __init__(self, store, ros1):
        self.t = store.types
        self.ros1 = ros1
        self.seq = 0

    def time(self, ns):
        return self.t["builtin_interfaces/msg/Time"](sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000))

    def header(self, ns, frame):
        if self.ros1:
            self.seq += 1
            return self.t["std_msgs/msg/Header"](seq=self.seq, stamp=self.time(ns), frame_id=frame)
        return self.t["std_msgs/msg/Header"](stamp=self.time(ns), frame_id=frame)

    def vector(self, x=0.0, y=0.0, z=0.0):
        return self.t["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z))

    def quaternion(self, yaw):
        x, y, z, w = yaw_to_quaternion(float(yaw))
        return self.t["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w)

    def pose(self, p):
        return self.t["geometry_msgs/msg/Pose"](
            position=self.t["geometry_msgs/msg/Point"](x=float(p[0]), y=float(p[1]), z=0.0),
            orientation=self.quaternion(p[2]))

    def twist(self, v, w):
        return self.t[T_TWIST](linear=self.vector(v), angular=self.vector(z=w))

    def transform(self, ns, parent, child, p):
        return self.t["geometry_msgs/msg/TransformStamped"](
            header=self.header(ns, parent), child_frame_id=child,
            transform=self.t["geometry_msgs/msg/Transform"](translation=self.vector(p[0], p[1]),
                                                             rotation=self.quaternion(p[2])))

    def tf(self, transforms):
        return self.t[T_TF](transforms=transforms)

    def scan(self, ns, frame, ranges, scans):
        n = len(ranges)
        return self.t[T_SCAN](
            header=self.header(ns, frame), angle_min=float(scans.angle_min),
            angle_max=float(scans.angle_min + (n - 1) * scans.angle_increment),
            angle_increment=float(scans.angle_increment), time_increment=0.0, scan_time=0.0,
            range_min=float(scans.range_min), range_max=float(scans.range_max),
            ranges=np.ascontiguousarray(ranges, dtype=np.float32), intensities=np.zeros(0, np.float32))

    def odometry(self, ns, frame, child, p, v, w):
        return self.t[T_ODOM](
            header=self.header(ns, frame), child_frame_id=child,
            pose=self.t["geometry_msgs/msg/PoseWithCovariance"](pose=self.pose(p), covariance=np.zeros(36)),
            twist=self.t["geometry_msgs/msg/TwistWithCovariance"](twist=self.twist(v, w), covariance=np.zeros(36)))

    def pose_stamped(self, ns, frame, p):
        return self.t[T_POSE_STAMPED](header=self.header(ns, frame), pose=self.pose(p))

    def grid(self, ns, grid):
        info = self.t["nav_msgs/msg/MapMetaData"](
            map_load_time=self.time(ns), resolution=float(grid.resolution), width=int(grid.width),
            height=int(grid.height), origin=self.pose(grid.origin))
        return self.t[T_GRID](header=self.header(ns, grid.frame_id), info=info,
                              data=grid.to_int8().reshape(-1).astype(np.int8))
