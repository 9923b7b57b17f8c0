"""ROS 1: the node's topics through a running roscore with rospy (Debian: ``apt-get install python3-rospy``).

Debian's ROS 1 lives in the system Python's ``dist-packages``; when ``rospy`` is not importable otherwise, that
folder goes at the end of ``sys.path``, so crfmap's virtual environment uses it without a ROS workspace."""
from __future__ import annotations

import gc
import os
import sys
import time
import warnings

from crfmap.errors import InputError
from crfmap.ros.messages import stamp_parts

DEBIAN_DIST_PACKAGES = "/usr/lib/python3/dist-packages"
# rospy (Debian's 1.15/1.16) calls Condition.notifyAll and leaves XML-RPC sockets to the garbage collector: warnings
# about ROS's code, not crfmap's, that would end every node run with lines a user cannot act on
ROS1_MODULES = r"(rospy|rosgraph|roslib|genpy|rosmaster)(\.|$)"


def import_rospy():
    """rospy, importing it from Debian's dist-packages if needed; InputError (one line) if there is none."""
    try:
        import rospy
    except ImportError:
        if not os.path.isdir(os.path.join(DEBIAN_DIST_PACKAGES, "rospy")) or DEBIAN_DIST_PACKAGES in sys.path:
            raise InputError("--backend rospy", "rospy is not importable (ROS 1: apt-get install ros-core "
                                                "python3-rospy python3-nav-msgs python3-sensor-msgs python3-tf2-msgs)") from None
        sys.path.append(DEBIAN_DIST_PACKAGES)
        try:
            import rospy
        except ImportError as exc:
            raise InputError("--backend rospy", f"rospy is installed but does not import ({exc})") from None
    return rospy


def _types():
    try:
        from nav_msgs.msg import MapMetaData, OccupancyGrid
        from sensor_msgs.msg import LaserScan
        from tf2_msgs.msg import TFMessage
    except ImportError as exc:
        raise InputError("--backend rospy", f"ROS 1 message packages missing ({exc}; apt-get install python3-nav-msgs "
                                            "python3-sensor-msgs python3-tf2-msgs)") from None
    return {"grid": OccupancyGrid, "metadata": MapMetaData, "scan": LaserScan, "tf": TFMessage}


def _fill_info(info, msg, rospy):
    info.map_load_time = rospy.Time(*stamp_parts(msg.map_load_ns))
    info.resolution = float(msg.resolution)
    info.width, info.height = int(msg.width), int(msg.height)
    p, q = info.origin.position, info.origin.orientation
    p.x, p.y, p.z, q.x, q.y, q.z, q.w = (float(v) for v in msg.origin)
    return info


class RospyBackend:
    """The node's middleware over rospy (the master from ROS_MASTER_URI, as every ROS 1 tool)."""

    def __init__(self, name="crfmap_node"):
        self.rospy = import_rospy()
        self.types = _types()
        for category in (DeprecationWarning, ResourceWarning):
            warnings.filterwarnings("ignore", category=category, module=ROS1_MODULES)
        # rospy's own signal handlers would shut it down mid-refinement; the command handles SIGINT/SIGTERM
        self.rospy.init_node(name, anonymous=False, disable_signals=True)
        self.handles = []

    def subscribe(self, topic, kind, profile, callback):
        sub = self.rospy.Subscriber(topic, self.types[kind], callback, queue_size=profile.reader_depth or profile.depth)
        self.handles.append(sub)
        return sub

    def publisher(self, topic, kind, profile):
        pub = self.rospy.Publisher(topic, self.types[kind], queue_size=profile.depth, latch=profile.latched)
        self.handles.append(pub)
        rospy, types = self.rospy, self.types

        def send(msg):
            if kind == "metadata":
                pub.publish(_fill_info(types["metadata"](), msg, rospy))
                return
            out = types["grid"]()
            out.header.stamp = rospy.Time(*stamp_parts(msg.stamp_ns))
            out.header.frame_id = msg.frame_id
            _fill_info(out.info, msg, rospy)
            out.data = msg.data.tolist()
            pub.publish(out)

        return send

    def spin_once(self, timeout):
        # rospy calls the callbacks from its own threads; the node drains what they queued
        time.sleep(min(max(float(timeout), 0.0), 0.02))

    def close(self):
        for handle in self.handles:
            handle.unregister()
        self.handles.clear()
        with warnings.catch_warnings():  # rospy's shutdown and its sockets collected now, not at some later line
            warnings.simplefilter("ignore", ResourceWarning)
            warnings.simplefilter("ignore", DeprecationWarning)
            self.rospy.signal_shutdown("crfmap node stopped")
            gc.collect()
