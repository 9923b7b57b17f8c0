"""ROS 2 with a ROS install: the node's topics through rclpy (any RMW the install uses). rclpy's signal handlers
stay off: the command handles SIGINT and SIGTERM, so a refinement in progress finishes before the node stops."""
from __future__ import annotations

from crfmap.errors import InputError
from crfmap.ros.messages import stamp_parts


def import_rclpy():
    try:
        import rclpy
        from nav_msgs.msg import MapMetaData, OccupancyGrid
        from sensor_msgs.msg import LaserScan
        from tf2_msgs.msg import TFMessage
    except ImportError as exc:
        raise InputError("--backend rclpy", f"rclpy is not importable ({exc}; source a ROS 2 install first, or use "
                                            "--backend dds, which needs none)") from None
    return rclpy, {"grid": OccupancyGrid, "metadata": MapMetaData, "scan": LaserScan, "tf": TFMessage}


def qos_profile(profile, reader=False):
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=profile.reader_depth if reader and profile.reader_depth else profile.depth,
        reliability=ReliabilityPolicy.RELIABLE if profile.reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if profile.transient_local else DurabilityPolicy.VOLATILE)


def _fill_info(info, msg):
    sec, nanosec = stamp_parts(msg.map_load_ns)
    info.map_load_time.sec, info.map_load_time.nanosec = int(sec), int(nanosec)
    info.resolution = float(msg.resolution)
    info.width, info.height = int(msg.width), int(msg.height)
    p, q = info.origin.position, info.origin.orientation
    p.x, p.y, p.z, q.x, q.y, q.z, q.w = (float(v) for v in msg.origin)
    return info


class RclpyBackend:
    """The node's middleware over rclpy (domain and RMW from the environment, as every ROS 2 tool)."""

    def __init__(self, name="crfmap_node"):
        self.rclpy, self.types = import_rclpy()
        try:
            from rclpy.signals import SignalHandlerOptions

            self.rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        except ImportError:  # before Humble: no option to leave the signals alone
            self.rclpy.init()
        self.node = self.rclpy.create_node(name)

    def subscribe(self, topic, kind, profile, callback):
        return self.node.create_subscription(self.types[kind], topic, callback, qos_profile(profile, reader=True))

    def publisher(self, topic, kind, profile):
        pub = self.node.create_publisher(self.types[kind], topic, qos_profile(profile))
        types = self.types

        def send(msg):
            if kind == "metadata":
                pub.publish(_fill_info(types["metadata"](), msg))
                return
            out = types["grid"]()
            out.header.stamp.sec, out.header.stamp.nanosec = (int(v) for v in stamp_parts(msg.stamp_ns))
            out.header.frame_id = msg.frame_id
            _fill_info(out.info, msg)
            out.data = msg.data.astype("int8", copy=False)  # rclpy takes an array('b') or a sequence of ints
            pub.publish(out)

        return send

    def spin_once(self, timeout):
        self.rclpy.spin_once(self.node, timeout_sec=max(float(timeout), 0.0))

    def close(self):
        self.node.destroy_node()
        self.rclpy.try_shutdown()
