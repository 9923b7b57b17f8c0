"""crfmap.io.bag_reader: Recording <-> ROS1/ROS2 bags, pose chains, bad bags; the `crfmap convert` command."""
import math

import numpy as np
import pytest
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore

from crfmap.data import data_file, have_data
from crfmap.io.bag_reader import read_bag
from crfmap.io.bag_writer import write_bag
from crfmap.cli import main
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.recording import Recording, ScanSet, Trajectory
from naive_frames import angle_diff, pose_of, se2

ROS2_BAG = "rosbags/olin_comprobo24_turtlebot4/macfirst_floor_take_2"
ROS1_BAG = "rosbags/zaki0929_bagfiles/2019_jan17_expt04_bagfile.bag"
FORMATS = [("ros2", "bag2"), ("ros1", "bag1.bag")]


MOUNT = (0.1, -0.05, math.pi / 2)


def make_recording(n_scans=5, n_beams=8):
    """A small hand-made run: odometry at 33 Hz, scans at 10 Hz, a rotated laser, a truth map."""
    rng = np.random.default_rng(7)
    ranges = rng.uniform(0.5, 4.0, (n_scans, n_beams)).astype(np.float32)
    ranges[0, 1], ranges[1, 2], ranges[2, 3], ranges[3, 0] = np.inf, np.nan, -np.inf, 25.0
    stamps = 1.0 + 0.1 * np.arange(n_scans)
    odom_t = 0.95 + 0.03 * np.arange(25)
    odom_p = np.column_stack([0.2 * odom_t, 0.1 * odom_t ** 2, 0.5 * odom_t + 2.9])  # yaw crosses pi
    odometry = Trajectory(odom_t, odom_p, "odom", "base_link",
                          np.column_stack([np.full(25, 0.2), np.full(25, 0.5)]))
    base = np.column_stack([0.21 * stamps + 1, 0.1 * stamps - 2, 0.52 * stamps + 3.0])
    laser = np.array([pose_of(se2(*b) @ se2(*MOUNT)) for b in base])
    scans = ScanSet(ranges, -0.7, 0.2, 0.1, 10.0, laser, stamps, frame_id="map", laser_frame_id="laser")
    truth = Trajectory(stamps.copy(), base, "map", "base_link")
    cmd = Trajectory(stamps.copy(), np.zeros((n_scans, 3)), "base_link", "base_link",
                     np.column_stack([np.full(n_scans, 0.3), np.linspace(-1, 1, n_scans)]))
    grid = OccupancyGrid(np.array([[0, 1, 0.5], [1, 1, 0]], float), resolution=0.05, origin=(-1.0, -2.0, 0.3))
    return Recording(scans, MOUNT, odometry, truth, cmd, grid)


@pytest.mark.parametrize("fmt, name", FORMATS)
def test_round_trip(tmp_path, fmt, name):
    rec = make_recording()
    path = tmp_path / name
    write_bag(rec, path, fmt=fmt)
    back = read_bag(path)
    s, b = rec.scans, back.scans
    assert b.ranges.dtype == np.float32
    np.testing.assert_array_equal(b.ranges.view(np.uint32), s.ranges.view(np.uint32))  # bit for bit, NaN too
    np.testing.assert_allclose(b.stamps, s.stamps, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.laser_poses[:, :2], s.laser_poses[:, :2], rtol=0, atol=1e-9)
    assert angle_diff(b.laser_poses[:, 2], s.laser_poses[:, 2]).max() < 1e-9
    assert (b.frame_id, b.laser_frame_id) == ("map", "laser")
    assert back.meta["pose_source"] == "tf" and back.meta["scans_dropped"] == 0
    # LaserScan stores float32 angles and limits.
    assert b.angle_min == np.float32(s.angle_min) and b.angle_increment == np.float32(s.angle_increment)
    assert (b.range_min, b.range_max) == (np.float32(0.1), np.float32(10.0))
    np.testing.assert_allclose(back.laser_mount, MOUNT, atol=1e-12)
    o, ob = rec.odometry, back.odometry
    np.testing.assert_allclose(ob.stamps, o.stamps, atol=1e-9)
    np.testing.assert_allclose(ob.poses[:, :2], o.poses[:, :2], atol=1e-12)
    assert angle_diff(ob.poses[:, 2], o.poses[:, 2]).max() < 1e-12
    np.testing.assert_allclose(ob.twists, o.twists, atol=1e-12)
    assert (ob.frame_id, ob.child_frame_id) == ("odom", "base_link")
    np.testing.assert_allclose(back.true_poses.poses[:, :2], rec.true_poses.poses[:, :2], atol=1e-12)
    np.testing.assert_allclose(back.cmd_vel.twists, rec.cmd_vel.twists, atol=1e-12)
    np.testing.assert_allclose(back.cmd_vel.stamps, rec.cmd_vel.stamps, atol=1e-9)
    g = back.ground_truth
    np.testing.assert_array_equal(g.probability, rec.ground_truth.probability)
    assert g.resolution == 0.05 and np.allclose(g.origin, (-1.0, -2.0, 0.3))


@pytest.mark.parametrize("fmt, name", FORMATS)
def test_pose_sources(tmp_path, fmt, name):
    rec = make_recording()
    path = tmp_path / name
    write_bag(rec, path, fmt=fmt)
    truth = read_bag(path, pose_source="truth")
    np.testing.assert_allclose(truth.scans.laser_poses[:, :2], rec.scans.laser_poses[:, :2], atol=1e-9)
    assert truth.scans.frame_id == "map"
    odom = read_bag(path, pose_source="odom")
    assert odom.scans.frame_id == "odom"
    # Expected: odometry interpolated linearly at each scan stamp, then the mount.
    o = rec.odometry
    for t, got in zip(odom.scans.stamps, odom.scans.laser_poses):
        j = np.searchsorted(o.stamps, t) - 1
        f = (t - o.stamps[j]) / (o.stamps[j + 1] - o.stamps[j])
        base = o.poses[j] + f * (o.poses[j + 1] - o.poses[j])  # this track's yaw steps are < pi
        want = pose_of(se2(*base) @ se2(*MOUNT))
        np.testing.assert_allclose(got[:2], want[:2], atol=1e-9)
        assert angle_diff(got[2], want[2]) < 1e-9
    # The wrong mount changes every laser yaw by the mount's 90 degrees.
    bare = read_bag(path, laser_mount=(0.0, 0.0, 0.0))
    np.testing.assert_allclose(angle_diff(bare.scans.laser_poses[:, 2], rec.scans.laser_poses[:, 2]), math.pi / 2)


def test_scans_outside_the_pose_track_are_dropped(tmp_path):
    rec = make_recording()
    keep = (rec.odometry.stamps > 1.15) & (rec.odometry.stamps < 1.35)
    o = rec.odometry
    rec.odometry = Trajectory(o.stamps[keep], o.poses[keep], o.frame_id, o.child_frame_id, o.twists[keep])
    write_bag(rec, tmp_path / "b", fmt="ros2")
    back = read_bag(tmp_path / "b", pose_source="odom")
    np.testing.assert_allclose(back.scans.stamps, [1.2, 1.3])
    assert back.meta["scans_dropped"] == 3 and back.meta["scans_total"] == 5
    np.testing.assert_array_equal(back.scans.ranges, rec.scans.ranges[2:4])
    # Through /tf every scan has a pose (the writer publishes odom -> base_link at every scan).
    assert read_bag(tmp_path / "b").meta["scans_dropped"] == 0


def test_without_odometry_tf_still_places_the_scans(tmp_path):
    rec = make_recording()
    rec.odometry = None
    write_bag(rec, tmp_path / "b.bag", fmt="ros1")
    back = read_bag(tmp_path / "b.bag")
    assert back.odometry is None and back.meta["pose_source"] == "tf"
    np.testing.assert_allclose(back.scans.laser_poses[:, :2], rec.scans.laser_poses[:, :2], atol=1e-9)


def test_rewriting_replaces_and_leaves_no_temporaries(tmp_path):
    rec = make_recording()
    write_bag(rec, tmp_path / "b", fmt="ros2")
    rec.scans.ranges[:] = 1.5
    write_bag(rec, tmp_path / "b", fmt="ros2")
    assert np.all(read_bag(tmp_path / "b").scans.ranges == np.float32(1.5))
    write_bag(rec, tmp_path / "c.bag", fmt="ros1")
    write_bag(rec, tmp_path / "c.bag", fmt="ros1")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b", "c.bag"]


def test_read_accepts_the_db3_and_metadata_of_a_ros2_bag(tmp_path):
    write_bag(make_recording(), tmp_path / "b", fmt="ros2", storage="sqlite3")
    (db3,) = (tmp_path / "b").glob("*.db3")
    for p in (db3, tmp_path / "b" / "metadata.yaml"):
        assert len(read_bag(p).scans) == 5


# --- bad input ----------------------------------------------------------------------------------
def custom_ros2_bag(path, scans=(), odom=()):
    """A ROS2 bag written directly with rosbags: scans as (stamp, angle_min, angle_max, increment, n)."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    T = store.types

    def header(t, frame):
        return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=int(t), nanosec=int(t % 1 * 1e9)),
                                        frame_id=frame)

    with Writer2(path, version=9) as w:
        if scans:
            c = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=store)
            for t, a0, a1, inc, n in scans:
                msg = T["sensor_msgs/msg/LaserScan"](
                    header=header(t, "base_link"), angle_min=a0, angle_max=a1, angle_increment=inc,
                    time_increment=0.0, scan_time=0.0, range_min=0.1, range_max=5.0,
                    ranges=np.ones(n, np.float32), intensities=np.zeros(0, np.float32))
                w.write(c, int(t * 1e9), store.serialize_cdr(msg, "sensor_msgs/msg/LaserScan"))
        if odom:
            c = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=store)
            for t in odom:
                v3 = T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
                msg = T["nav_msgs/msg/Odometry"](
                    header=header(t, "odom"), child_frame_id="base_link",
                    pose=T["geometry_msgs/msg/PoseWithCovariance"](
                        pose=T["geometry_msgs/msg/Pose"](
                            position=T["geometry_msgs/msg/Point"](x=t, y=0.0, z=0.0),
                            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)),
                        covariance=np.zeros(36)),
                    twist=T["geometry_msgs/msg/TwistWithCovariance"](
                        twist=T["geometry_msgs/msg/Twist"](linear=v3, angular=v3), covariance=np.zeros(36)))
                w.write(c, int(t * 1e9), store.serialize_cdr(msg, "nav_msgs/msg/Odometry"))
    return path


def test_custom_bag_helper_makes_a_readable_bag(tmp_path):
    path = custom_ros2_bag(tmp_path / "ok", scans=[(1.0, -1.0, 1.0, 0.5, 5), (2.0, -1.0, 1.0, 0.5, 5)],
                           odom=[0.5, 1.5, 2.5])
    rec = read_bag(path)
    assert rec.meta["pose_source"] == "odom" and len(rec.scans) == 2
    np.testing.assert_allclose(rec.scans.laser_poses[:, 0], [1.0, 2.0])


@pytest.mark.parametrize("scans, odom, problem", [
    ([], [0.5, 1.5], "no sensor_msgs/LaserScan topic"),
    ([(1.0, -1.0, 1.0, 0.5, 5), (2.0, -1.0, 1.0, 0.5, 9)], [0.5, 2.5], "/scan message 1: 9 ranges disagree"),
    ([(1.0, -1.0, 1.0, 0.5, 5), (2.0, -1.0, 2.0, 0.5, 7)], [0.5, 2.5], "/scan message 1: 7 beams, earlier scans have 5"),
    ([(1.0, -1.0, 1.0, 0.0, 5)], [0.5, 2.5], "/scan message 0: angle_min/angle_max/angle_increment"),
    ([(1.0, -1.0, 1.0, 0.5, 5)], [], "no pose source"),
    ([(1.0, -1.0, 1.0, 0.5, 5)], [1.5, 2.5], "none of the 1 scans falls within"),
])
def test_bad_bags_name_the_file(tmp_path, scans, odom, problem):
    path = custom_ros2_bag(tmp_path / "bad", scans=scans, odom=odom)
    with pytest.raises(InputError) as info:
        read_bag(path)
    assert str(info.value).startswith(str(path)) and problem in str(info.value)


def test_one_beam_tolerance_on_angle_max(tmp_path):
    # Drivers differ on whether angle_max is the last beam or one increment past it: both load.
    path = custom_ros2_bag(tmp_path / "ok", scans=[(1.0, -1.0, 1.5, 0.5, 5)], odom=[0.5, 1.5])
    assert read_bag(path).scans.ranges.shape == (1, 5)


def test_truncated_ros1_bag(tmp_path):
    path = tmp_path / "b.bag"
    write_bag(make_recording(), path, fmt="ros1")
    data = path.read_bytes()
    path.write_bytes(data[: len(data) * 2 // 3])
    with pytest.raises(InputError, match="b.bag: cannot read the bag"):
        read_bag(path)


def test_garbage_db3(tmp_path):
    write_bag(make_recording(), tmp_path / "b", fmt="ros2", storage="sqlite3")
    (db3,) = (tmp_path / "b").glob("*.db3")
    db3.write_bytes(b"this is not sqlite " * 200)
    with pytest.raises(InputError, match="cannot read the bag") as info:
        read_bag(tmp_path / "b")
    assert str(tmp_path / "b") in str(info.value)


def test_missing_and_unrecognised_paths(tmp_path):
    with pytest.raises(InputError, match="nothing.bag: no such file"):
        read_bag(tmp_path / "nothing.bag")
    (tmp_path / "folder").mkdir()
    with pytest.raises(InputError, match="folder: folder without metadata.yaml"):
        read_bag(tmp_path / "folder")
    (tmp_path / "a.txt").write_text("x")
    with pytest.raises(InputError, match="a.txt: not a ROS bag"):
        read_bag(tmp_path / "a.txt")


def test_missing_requested_pose_source_and_bad_arguments(tmp_path):
    rec = make_recording()
    rec.true_poses = None
    write_bag(rec, tmp_path / "b", fmt="ros2")
    with pytest.raises(InputError, match="pose source 'truth': no /ground_truth_pose"):
        read_bag(tmp_path / "b", pose_source="truth")
    with pytest.raises(InputError, match="pose_source"):
        read_bag(tmp_path / "b", pose_source="gps")
    with pytest.raises(InputError, match="no topic '/laser'"):
        read_bag(tmp_path / "b", scan_topic="/laser")
    with pytest.raises(InputError, match="is not a sensor_msgs/LaserScan"):
        read_bag(tmp_path / "b", scan_topic="/odom")
    with pytest.raises(InputError, match="format"):
        write_bag(rec, tmp_path / "c", fmt="mcap")
    with pytest.raises(InputError, match="must end in .bag"):
        write_bag(rec, tmp_path / "c", fmt="ros1")
    with pytest.raises(InputError, match="is a folder"):
        write_bag(rec, tmp_path / "c.bag", fmt="ros2")
    assert not (tmp_path / "c").exists() and not (tmp_path / "c.bag").exists()


# --- real bags -----------------------------------------------------------------------------------
@pytest.mark.skipif(not have_data(ROS2_BAG), reason="ROS2 bag not downloaded")
def test_real_ros2_bag():
    rec = read_bag(data_file(ROS2_BAG))
    assert rec.meta["scans_total"] == 357 and rec.meta["scans_dropped"] == 1  # the first scan predates /tf
    assert rec.scans.ranges.shape == (356, 720)
    assert rec.scans.laser_frame_id == "rplidar_link" and rec.scans.frame_id == "odom"
    assert rec.meta["pose_source"] == "tf" and rec.meta["base_frame"] == "base_link"
    np.testing.assert_allclose(rec.laser_mount, (0.00393584, 0.0, math.pi / 2), atol=1e-9)  # /tf_static
    assert len(rec.odometry) == 920 and len(rec.cmd_vel) == 192
    assert not np.isfinite(rec.scans.ranges).all()  # kept as recorded, REP 117 values included
    # /odom and /tf agree on this robot.
    odom = read_bag(data_file(ROS2_BAG), pose_source="odom")
    common = np.isin(rec.scans.stamps, odom.scans.stamps)
    np.testing.assert_allclose(rec.scans.laser_poses[common, :2], odom.scans.laser_poses[:, :2], atol=0.02)


@pytest.mark.skipif(not have_data(ROS1_BAG), reason="ROS1 bag not downloaded")
def test_real_ros1_bag():
    rec = read_bag(data_file(ROS1_BAG))
    assert rec.meta["format"] == "ros1" and rec.meta["scans_total"] == 962
    assert rec.scans.ranges.shape[1] == 726 and len(rec.scans) >= 950
    assert len(rec.odometry) == 977 and len(rec.cmd_vel) == 110
    assert rec.scans.laser_frame_id == "base_link" and rec.laser_mount == (0.0, 0.0, 0.0)


# --- the `crfmap convert` command ------------------------------------------------------------
CARMEN_LOG = """PARAM robot_frontlaser_offset 0.0 nohost 0
PARAM robot_front_laser_max 9.0 nohost 0
ODOM 0 0 0 0 0 0 0.5 host 0.5
FLASER 5 1.0 1.1 9.0 1.2 1.3 0.0 0.0 0.0 0.0 0.0 0.0 1.0 host 1.0
ODOM 0.1 0 0.1 0 0 0 1.5 host 1.5
FLASER 5 1.0 9.0 1.2 1.2 1.3 0.1 0.0 0.1 0.1 0.0 0.1 2.0 host 2.0
ODOM 0.2 0 0.1 0 0 0 2.5 host 2.5
"""


@pytest.mark.parametrize("out_name, args, fmt", [("out", [], "ros2"), ("out.bag", [], "ros1"),
                                                  ("out.bag", ["--format", "ros1"], "ros1")])
def test_convert_carmen_log(tmp_path, capsys, out_name, args, fmt):
    log = tmp_path / "run.log"
    log.write_text(CARMEN_LOG)
    out = tmp_path / out_name
    assert main(["convert", str(log), str(out), *args]) == 0
    line = capsys.readouterr().out
    assert line.count("\n") == 1 and f"{fmt} bag" in line
    rec = read_bag(out)
    assert rec.meta["format"] == fmt
    np.testing.assert_array_equal(rec.scans.ranges, np.float32([[1.0, 1.1, np.inf, 1.2, 1.3],
                                                                [1.0, np.inf, 1.2, 1.2, 1.3]]))
    np.testing.assert_allclose(rec.scans.laser_poses, [[0, 0, 0], [0.1, 0, 0.1]], atol=1e-9)
    np.testing.assert_allclose(rec.true_poses.poses, [[0, 0, 0], [0.1, 0, 0.1]], atol=1e-12)
    assert len(rec.odometry) == 3


@pytest.mark.parametrize("content, out_name, match", [
    ("FLASER 5 1 2\n", "out", "run.log: line 1"),
    (None, "out", "run.log: no such file"),
    (CARMEN_LOG, "out", "must end in .bag"),
])
def test_convert_bad_input_exits_2(tmp_path, capsys, content, out_name, match):
    log = tmp_path / "run.log"
    if content is not None:
        log.write_text(content)
    out = tmp_path / out_name
    extra = ["--format", "ros1"] if match == "must end in .bag" else []
    assert main(["convert", str(log), str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and match in err
    assert sorted(p.name for p in tmp_path.iterdir()) == (["run.log"] if content is not None else [])
