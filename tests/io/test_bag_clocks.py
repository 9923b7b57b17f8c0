"""Clocks ROS tools read right: no message of any bag crfmap writes at time 0, and every scan resolves
through tf2's lookup rules, at its own stamp, to the laser pose it was recorded at."""
import math

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from crfmap.commands.convert import shift_zero_start
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.io.bag_writer import write_bag
from crfmap.io.carmen import read_carmen
from crfmap.sim.simulator import START_TIME, simulate
from crfmap.sim.laser import Laser
from crfmap.world.scene import Scene

WRITERS = [("ros1", None, None), ("ros2", "mcap", "humble"), ("ros2", "sqlite3", "humble"),
           ("ros2", "mcap", "jazzy"), ("ros2", "sqlite3", "jazzy")]


# --- tf2's lookup rules (tf2/src/buffer_core.cpp, cache.cpp), transcribed --------------------------
class ExtrapolationError(LookupError):
    pass


def _slerp(q0, q1, ratio):
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    dot = float(q0 @ q1)
    if dot < 0:  # the shorter way round, as tf2::slerp
        q1, dot = -q1, -dot
    if dot > 0.9995:
        q = q0 + ratio * (q1 - q0)
        return q / np.linalg.norm(q)
    theta = math.acos(dot)
    return (math.sin((1 - ratio) * theta) * q0 + math.sin(ratio * theta) * q1) / math.sin(theta)


class Tf2Buffer:
    """A tf2 BufferCore whose cache holds the whole bag (a player's buffer looking up in time).

    Rules: /tf_static holds for every time; a stamp of 0 asks for the latest common time of the
    chain's dynamic links; between two samples of a link, translation is interpolated linearly and
    rotation by slerp; a time before a link's first sample or after its last is refused.
    """

    def __init__(self):
        self.parent, self.static, self.samples = {}, {}, {}

    def add(self, transform, static):
        child, stamp = transform.child_frame_id.lstrip("/"), transform.header.stamp
        self.parent[child] = transform.header.frame_id.lstrip("/")
        t, r = transform.transform.translation, transform.transform.rotation
        value = (np.array([t.x, t.y, t.z]), np.array([r.x, r.y, r.z, r.w]))
        if static:
            self.static[child] = value
        else:
            self.samples.setdefault(child, {})[stamp.sec * 10**9 + stamp.nanosec] = value

    def _chain(self, frame, target):
        links = []
        while frame != target:
            if frame not in self.parent:
                raise LookupError(f"{frame} is not connected to {target}")
            links.append(frame)
            frame = self.parent[frame]
        return links

    def _at(self, child, ns):
        if child in self.static:
            return self.static[child]
        stamps = sorted(self.samples[child])
        if ns in self.samples[child]:
            return self.samples[child][ns]
        if ns < stamps[0] or ns > stamps[-1]:
            raise ExtrapolationError(f"{child} at {ns} ns: outside [{stamps[0]}, {stamps[-1]}]")
        k = int(np.searchsorted(stamps, ns))
        (t0, (p0, q0)), (t1, (p1, q1)) = (stamps[k - 1], self.samples[child][stamps[k - 1]]), \
            (stamps[k], self.samples[child][stamps[k]])
        ratio = (ns - t0) / (t1 - t0)
        return p0 + ratio * (p1 - p0), _slerp(q0, q1, ratio)

    def lookup(self, target, source, ns):
        """(x, y, yaw) of ``source`` in ``target`` at ``ns`` (0: the latest common time)."""
        links = self._chain(source, target)
        if ns == 0:
            dynamic = [max(self.samples[c]) for c in links if c not in self.static]
            ns = min(dynamic) if dynamic else 0
        x = np.zeros(3)
        q = np.array([0.0, 0.0, 0.0, 1.0])
        for child in links:  # compose parent_T_child from the source up: T = link * T
            p, r = self._at(child, ns)
            x = p + _rotate(r, x)
            q = _qmul(r, q)
        return x[0], x[1], math.atan2(2 * (q[3] * q[2] + q[0] * q[1]), 1 - 2 * (q[1] ** 2 + q[2] ** 2))


def _qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz])


def _rotate(q, v):
    return _qmul(_qmul(q, np.r_[v, 0.0]), q * np.array([-1, -1, -1, 1]))[:3]


def test_tf2_rules_on_a_hand_made_buffer():
    from types import SimpleNamespace as N

    def tf(parent, child, ns, x, yaw):
        return N(child_frame_id=child, header=N(frame_id=parent, stamp=N(sec=ns // 10**9, nanosec=ns % 10**9)),
                 transform=N(translation=N(x=x, y=0.0, z=0.0),
                             rotation=N(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))))
    buf = Tf2Buffer()
    buf.add(tf("map", "base", 10, 0.0, 0.0), False)
    buf.add(tf("map", "base", 20, 2.0, 1.0), False)
    buf.add(tf("base", "laser", 1, 1.0, 0.0), True)
    assert buf.lookup("map", "laser", 15) == pytest.approx((1.0 + math.cos(0.5), math.sin(0.5), 0.5))
    assert buf.lookup("map", "laser", 0) == pytest.approx((2.0 + math.cos(1.0), math.sin(1.0), 1.0))  # latest
    with pytest.raises(ExtrapolationError):
        buf.lookup("map", "laser", 21)


# --- recordings crfmap writes -------------------------------------------------------------------------
def simulated():
    walls = np.zeros((40, 40))
    walls[[0, -1], :] = walls[:, [0, -1]] = 1.0
    scene = Scene("room", OccupancyGrid(walls, resolution=0.1), (2.0, 1.5, 0.3))
    return simulate(scene, Laser.with_fov(360, 12, range_max=3.0), "look", odometry_noise=(0.01, 0.02), seed=4,
                    laser_mount=(0.12, -0.03, 0.4), progress=False)


CARMEN_LOG = """PARAM robot_front_laser_max 50.0
ODOM 0 0 0 0 0 0 0.000246 pippo 0.000246
ODOM 0.02 0 0 0.2 0 0 0.10 pippo 0.10
ODOM 5 5 1 0 0 0 0 pippo 0
FLASER 4 1.0 2.0 3.0 4.0 0.1 0.2 0.1 0.1 0.2 0.1 0.15 pippo 0.15
ODOM 0.05 0.01 0.05 0.2 0.1 0 0.25 pippo 0.25
ODOM 4 4 0 0 0 0 0.20 pippo 0.20
FLASER 4 1.5 2.5 3.5 4.5 0.3 0.25 0.2 0.3 0.25 0.2 0.35 pippo 0.35
ODOM 0.09 0.02 0.1 0.2 0.1 0 0.45 pippo 0.45
"""


def carmen(tmp_path):
    (tmp_path / "run.log").write_text(CARMEN_LOG)
    with pytest.warns(UserWarning, match="dropped 2 of 6 ODOM records"):
        return read_carmen(tmp_path / "run.log")


def _check_bag(path, rec):
    buf, scans, n = Tf2Buffer(), [], 0
    from rosbags.typesys import Stores, get_typestore

    # Humble's sqlite3 bags hold no message definitions (as Humble records them): readers bring the types
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        for conn, log_ns, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            n += 1
            assert log_ns > 0, conn.topic
            header = getattr(msg, "header", None)
            stamps = [header.stamp] if header is not None else [t.header.stamp for t in getattr(msg, "transforms", [])]
            assert all(s.sec * 10**9 + s.nanosec > 0 for s in stamps), conn.topic
            if conn.topic in ("/tf", "/tf_static"):
                for t in msg.transforms:
                    buf.add(t, static=conn.topic == "/tf_static")
            elif conn.topic == "/scan":
                scans.append(msg.header)
    assert n > len(scans) == len(rec.scans) > 0
    for header in scans:
        ns = header.stamp.sec * 10**9 + header.stamp.nanosec
        i = int(np.argmin(np.abs(np.asarray(rec.scans.stamps) - ns * 1e-9)))
        got = buf.lookup(rec.scans.frame_id, header.frame_id, ns)
        want = rec.scans.laser_poses[i]
        assert got[:2] == pytest.approx(tuple(want[:2]), abs=1e-6), (path, ns)
        assert math.remainder(got[2] - want[2], 2 * math.pi) == pytest.approx(0.0, abs=1e-6)


def _bag_path(tmp_path, fmt, storage, distro, name):
    return tmp_path / (f"{name}.bag" if fmt == "ros1" else f"{name}_{storage}_{distro}")


@pytest.mark.parametrize("fmt, storage, distro", WRITERS)
def test_simulated_bags_have_no_zero_stamp_and_resolve_through_tf2(tmp_path, fmt, storage, distro):
    rec = simulated()
    assert rec.scans.stamps[0] == START_TIME
    kw = {} if fmt == "ros1" else {"storage": storage, "distro": distro}
    _check_bag(write_bag(rec, _bag_path(tmp_path, fmt, storage, distro, "sim"), fmt=fmt, **kw), rec)


@pytest.mark.parametrize("fmt, storage, distro", WRITERS)
def test_converted_carmen_bags_have_no_zero_stamp_and_resolve_through_tf2(tmp_path, fmt, storage, distro):
    rec = carmen(tmp_path)
    kw = {} if fmt == "ros1" else {"storage": storage, "distro": distro}
    _check_bag(write_bag(rec, _bag_path(tmp_path, fmt, storage, distro, "log"), fmt=fmt, **kw), rec)


def test_a_zero_stamp_is_refused_and_convert_shifts_a_zero_start(tmp_path):
    rec = simulated()
    from dataclasses import replace

    zero = replace(rec, scans=replace(rec.scans, stamps=rec.scans.stamps - START_TIME),
                   odometry=replace(rec.odometry, stamps=rec.odometry.stamps - START_TIME),
                   true_poses=replace(rec.true_poses, stamps=rec.true_poses.stamps - START_TIME),
                   cmd_vel=replace(rec.cmd_vel, stamps=rec.cmd_vel.stamps - START_TIME))
    with pytest.raises(InputError, match="time 0"):
        write_bag(zero, tmp_path / "z.bag", fmt="ros1")
    assert not (tmp_path / "z.bag").exists()
    with pytest.warns(UserWarning, match="shifted by 1700000000 s"):
        shifted = shift_zero_start(zero, "old.bag")
    np.testing.assert_allclose(shifted.scans.stamps, rec.scans.stamps, rtol=0, atol=1e-6)
    _check_bag(write_bag(shifted, tmp_path / "s.bag", fmt="ros1"), shifted)
    assert shift_zero_start(rec, "new.bag") is rec


TF2_SCRIPT = """
import json, math, sys, warnings
import genpy, rosbag, tf2_py
warnings.simplefilter("ignore")  # tf2_py asks for geometry_msgs classes; rosbag's generated ones work
buf, scans = tf2_py.BufferCore(genpy.Duration(1e6)), []
with rosbag.Bag(sys.argv[1]) as bag:
    for topic, msg, _ in bag.read_messages(start_time=genpy.Time(0, 1)):  # rosbag play's query
        if topic in ("/tf", "/tf_static"):
            for tr in msg.transforms:
                (buf.set_transform_static if topic == "/tf_static" else buf.set_transform)(tr, "bag")
        elif topic == "/scan":
            scans.append(msg.header)
out = []
for h in scans:
    tr = buf.lookup_transform_core("map", h.frame_id, h.stamp)
    q, p = tr.transform.rotation, tr.transform.translation
    out.append([h.stamp.to_nsec(), p.x, p.y, math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y ** 2 + q.z ** 2))])
print(json.dumps(out))
"""


def _debian_tf2():
    import subprocess
    from pathlib import Path

    if not Path("/usr/bin/python3").exists():
        return "no /usr/bin/python3"
    probe = subprocess.run(["/usr/bin/python3", "-c", "import rosbag, tf2_py"], capture_output=True)
    return None if probe.returncode == 0 else "Debian's python3-tf2 and python3-rosbag are not installed"


@pytest.mark.skipif(_debian_tf2() is not None, reason=str(_debian_tf2()))
def test_ros1_tf2_itself_resolves_every_scan_to_its_pose(tmp_path):
    import json
    import subprocess

    rec = simulated()
    path = write_bag(rec, tmp_path / "sim.bag", fmt="ros1")
    out = subprocess.run(["/usr/bin/python3", "-c", TF2_SCRIPT, str(path)], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    got = np.array(json.loads(out.stdout))
    assert len(got) == len(rec.scans)  # every scan played, none at time 0
    np.testing.assert_allclose(got[:, 1:3], rec.scans.laser_poses[:, :2], atol=1e-6)
    np.testing.assert_allclose(np.remainder(got[:, 3] - rec.scans.laser_poses[:, 2] + np.pi, 2 * np.pi) - np.pi, 0,
                               atol=1e-6)
