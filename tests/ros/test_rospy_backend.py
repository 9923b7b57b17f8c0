"""`crfmap node map --backend rospy` through a real roscore: a crfmap-written ROS 1 bag played with
`rosbag play` gives the /map that OnlineMapper makes of the same scans (skipped where Debian's ros-core is
not installed)."""
import os
import shutil
import signal
import socket
import subprocess
import sys
import textwrap
import time
import xmlrpc.client
from dataclasses import replace

import numpy as np
import pytest

from crfmap.data import data_file, have_data
from ros_support import TIMEOUT, NodeProcess  # noqa: E402
from crfmap.io.nav2_values import nav2_values

INTEL = "carmen/intel-corrected.log.gz"


def _ros1_missing():
    if not (shutil.which("roscore") and shutil.which("rosbag")):
        return "ROS 1 is not installed (Debian: apt-get install ros-core python3-rospy python3-rosbag " \
               "python3-nav-msgs python3-sensor-msgs python3-tf2-msgs)"
    from crfmap.errors import InputError
    from crfmap.ros.rospy_backend import _types, import_rospy

    try:
        import_rospy()
        _types()
    except InputError as exc:
        return str(exc)
    return None


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


LISTENER = textwrap.dedent("""
    import sys
    import numpy as np
    from crfmap.ros.rospy_backend import _types, import_rospy
    rospy = import_rospy()
    OccupancyGrid = _types()["grid"]
    rospy.init_node("crfmap_test_listener", disable_signals=True)
    want = int(sys.argv[1])
    while True:  # /map is latched: each new subscriber gets the latest map at once
        msg = rospy.wait_for_message("/map", OccupancyGrid, timeout=float(sys.argv[3]))
        if msg.header.stamp.secs * 1_000_000_000 + msg.header.stamp.nsecs == want:
            break
    np.save(sys.argv[2], np.array(msg.data, np.int8))
    print(msg.header.frame_id, msg.info.width, msg.info.height)
""")


@pytest.mark.skipif(_ros1_missing() is not None, reason=str(_ros1_missing()))
@pytest.mark.skipif(not have_data(INTEL), reason="needs the shared data (CRFMAP_DATA)")
def test_map_node_through_roscore(tmp_path):
    from crfmap.io.bag_reader import read_bag
    from crfmap.io.bag_writer import write_bag
    from crfmap.io.carmen import read_carmen
    from crfmap.mapping import OnlineMapper
    from crfmap.mapping.builder import scan_bounds

    recording = read_carmen(data_file(INTEL))
    recording = replace(recording, scans=recording.scans.head(30), odometry=None, cmd_vel=None, true_poses=None)
    bag = write_bag(recording, tmp_path / "intel30.bag", fmt="ros1")
    scans = read_bag(bag).scans
    bounds = scan_bounds(scans)
    mapper = OnlineMapper.for_sensor(bounds, 0.1, scans.angle_min, scans.angle_increment, scans.ranges.shape[1],
                                     scans.range_min, scans.range_max, radius=4.0, margin=3)
    mapper.run(scans)
    expected = nav2_values(mapper.nav2_map()).reshape(-1)
    last = int(round(scans.stamps[-1] * 1e9))

    port = _free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_IP="127.0.0.1",
               ROS_HOME=str(tmp_path / "ros_home"), ROS_LOG_DIR=str(tmp_path / "ros_log"))
    env.pop("ROS_HOSTNAME", None)
    core = subprocess.Popen(["roscore", "-p", str(port)], env=env, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    node = None
    try:
        master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
        deadline = time.monotonic() + TIMEOUT
        while True:
            try:
                master.getSystemState("/crfmap_test")
                break
            except OSError:
                assert time.monotonic() < deadline, "roscore did not start"
                time.sleep(0.2)
        node = NodeProcess(["map", "--backend", "rospy", "--bounds", *map(repr, bounds), "--resolution", "0.1",
                            "--radius", "4", "--margin", "3", "--period", "0.3"], env)
        node.wait_for("publishing /map_metadata")
        subprocess.run(["rosbag", "play", "--quiet", "-r", "40", str(bag)], env=env, check=True, timeout=TIMEOUT,
                       stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL)
        out = tmp_path / "map.npy"
        listened = subprocess.run([sys.executable, "-c", LISTENER, str(last), str(out), str(TIMEOUT)], env=env,
                                  capture_output=True, text=True, timeout=TIMEOUT + 30)
        assert listened.returncode == 0, listened.stderr
        frame, width, height = listened.stdout.split()
        assert (frame, int(width), int(height)) == (scans.frame_id, mapper.width, mapper.height)
        got = np.load(out)
        assert np.array_equal(got, expected), f"{int(np.sum(got != expected))} cells differ"
    finally:
        if node is not None:
            status = node.stop(signal.SIGTERM)
        os.killpg(core.pid, signal.SIGINT)
        try:
            core.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(core.pid, signal.SIGKILL)
    assert status == 0, node.log()
    assert f"stopped: {len(scans)} scans integrated" in node.log(), node.log()


MAP_TALKER = textwrap.dedent("""
    import sys
    from crfmap.ros.rospy_backend import _types, import_rospy
    rospy = import_rospy()
    OccupancyGrid = _types()["grid"]
    rospy.init_node("crfmap_test_talker", disable_signals=True)
    pub = rospy.Publisher("/map", OccupancyGrid, queue_size=1, latch=True)
    m = OccupancyGrid()
    m.header.stamp, m.header.frame_id = rospy.Time(5, 0), "map"
    m.info.resolution, m.info.width, m.info.height = 0.05, 20, 10
    m.info.origin.orientation.w = 1.0
    m.data = [-1] * 100 + [100] * 20 + [0] * 80
    pub.publish(m)
    got = rospy.wait_for_message("/map_refined", OccupancyGrid, timeout=float(sys.argv[1]))
    print(len(got.data))
""")


@pytest.mark.skipif(_ros1_missing() is not None, reason=str(_ros1_missing()))
def test_refine_node_through_roscore_stops_without_ros_warnings(tmp_path):
    """Refine one map over rospy, then SIGINT: exit 0, and no warning line about rospy's own code (Debian's rospy
    calls Condition.notifyAll and leaves XML-RPC sockets to the garbage collector)."""
    port = _free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_IP="127.0.0.1",
               ROS_HOME=str(tmp_path / "ros_home"), ROS_LOG_DIR=str(tmp_path / "ros_log"))
    env.pop("ROS_HOSTNAME", None)
    core = subprocess.Popen(["roscore", "-p", str(port)], env=env, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    node = None
    try:
        master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
        deadline = time.monotonic() + TIMEOUT
        while True:
            try:
                master.getSystemState("/crfmap_test")
                break
            except OSError:
                assert time.monotonic() < deadline, "roscore did not start"
                time.sleep(0.2)
        node = NodeProcess(["refine", "--backend", "rospy", "--period", "0"], env)
        node.wait_for("publishing /map_refined")
        talker = subprocess.run([sys.executable, "-c", MAP_TALKER, str(TIMEOUT)], env=env, capture_output=True,
                                text=True, timeout=TIMEOUT + 30)
        assert talker.returncode == 0 and talker.stdout.split() == ["200"], talker.stderr
        node.wait_for(r"refined /map \(20 x 10 cells")
        status = node.stop(signal.SIGINT)
        node.wait_for("stopped: 1 maps received, 1 refined and published")
    finally:
        if node is not None and node.proc.poll() is None:
            node.stop(signal.SIGKILL)
        os.killpg(core.pid, signal.SIGINT)
        try:
            core.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(core.pid, signal.SIGKILL)
    assert status == 0, node.log()
    assert not [line for line in node.lines if "warning" in line.lower()], node.log()
