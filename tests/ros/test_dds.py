"""`crfmap node refine` over real Cyclone DDS (loopback, two processes): the node's refined maps equal
`crfmap infer` on the same grids, every payload it sends equals rosbags' CDR of the same message, a late
subscriber gets the last map (transient local), bad maps are logged once and skipped, SIGTERM ends it."""
import signal

import numpy as np
import pytest

from crfmap.data import data_file, have_data
from crfmap.cli import main as crfmap_main
from crfmap.io.grid_files import load_grid
from crfmap.io.nav2_values import nav2_values
from crfmap.io.npy_grid import save_npy
from crfmap.ros.messages import GridMessage, grid_message, grid_out, occupancy_grid

pytest.importorskip("cyclonedds", reason="the DDS backend needs cyclonedds (pip install 'crfmap[ros]')")

from ros_support import (NodeProcess, decode_grid, loopback_dds, padded, rosbags_grid_bytes, take_raw,  # noqa: E402
                         wait_matched, wait_raw)

OLIN = "rosbags/olin_comprobo24_turtlebot4/mac_1st_floor_final.yaml"
INTEL = "carmen/intel-corrected.log.gz"


def _intel_grid():
    from crfmap.io.carmen import read_carmen
    from crfmap.mapping import build_grid

    return build_grid(read_carmen(data_file(INTEL)).scans, 0.1)


def _expected(source, tmp_path, name, *options):
    """`crfmap infer` of a grid (an OccupancyGrid, or a map file) written for nav2 and read back by nav2's loader, as
    the node publishes it: 100 / 0 / -1."""
    from crfmap.io.map_server import load_map

    out = tmp_path / f"{name}_out.yaml"
    if not isinstance(source, str):
        save_npy(source, tmp_path / f"{name}_in.npy")
        source = tmp_path / f"{name}_in.npy"
    assert crfmap_main(["infer", str(source), str(out), *options]) == 0
    return load_map(out).to_int8().reshape(-1)


def _writer_reader(participant, kind_in="grid"):
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from crfmap.ros import dds_types, qos
    from crfmap.ros.dds import dds_qos

    writer = DataWriter(participant, Topic(participant, "rt/map", dds_types.OccupancyGrid), qos=dds_qos(qos.MAP))
    reader = DataReader(participant, Topic(participant, "rt/map_refined", dds_types.OccupancyGrid),
                        qos=dds_qos(qos.MAP, reader=True))
    return writer, reader


def _send(writer, msg):
    from crfmap.ros.dds import native_message

    writer.write(native_message("grid", msg))


@pytest.mark.skipif(not (have_data(OLIN) and have_data(INTEL)), reason="needs the shared data (CRFMAP_DATA)")
def test_refine_node_over_dds(tmp_path, monkeypatch):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from crfmap.ros import dds_types, qos
    from crfmap.ros.dds import dds_qos

    env = loopback_dds(tmp_path, monkeypatch)
    olin_file = load_grid(data_file(OLIN))
    olin = grid_out(olin_file, 1_700_000_000_123_456_789, "map")
    # the map the node receives is the file's grid itself (trinary: 0, 100, -1 carry P exactly)
    assert np.array_equal(occupancy_grid(olin).probability, olin_file.probability)
    intel = grid_out(_intel_grid(), 1_700_000_100_000_000_001, "map")
    # the node gets the map as map_server publishes the file, its free_thresh 0.25 reading unknown grey as free;
    # crfmap infer keeps those cells unknown unless given the file's own threshold
    expected = {"olin": _expected(str(data_file(OLIN)), tmp_path, "olin", "--free-thresh", "0.25"),
                "intel": _expected(occupancy_grid(intel), tmp_path, "intel")}

    node = NodeProcess(["refine", "--period", "0"], env)
    participant = DomainParticipant(int(env["ROS_DOMAIN_ID"]))
    try:
        writer, reader = _writer_reader(participant)
        node.wait_for("publishing /map_refined")
        wait_matched(writer)
        # bad maps first: each is logged once with its reason and nothing is published for it
        wrong_length = GridMessage(**{**olin.__dict__, "data": olin.data[:-1]})
        _send(writer, wrong_length)
        node.wait_for(r"skipping a /map message: .*cells for a .*\[data length")
        _send(writer, GridMessage(**{**olin.__dict__, "resolution": float("nan")}))
        node.wait_for(r"skipping a /map message: .*\[resolution")
        _send(writer, GridMessage(**{**olin.__dict__, "origin": (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)}))
        node.wait_for(r"skipping a /map message: .*quaternion.*\[non-unit quaternion")

        for name, msg in (("olin", olin), ("intel", intel)):
            _send(writer, msg)
            (payload,) = wait_raw(reader, 1)
            out = msg.with_data(expected[name])
            # the bytes a ROS 2 node decodes: rosbags' serialization of the expected message, padded as DDSI does
            assert payload == padded(rosbags_grid_bytes(out)), name
            decoded = grid_message(decode_grid(payload))
            assert (decoded.stamp_ns, decoded.frame_id, decoded.width, decoded.height) == \
                   (msg.stamp_ns, msg.frame_id, msg.width, msg.height)
            assert np.array_equal(decoded.data, expected[name]), name
        # nothing came for the bad maps
        assert node.log().count("refined /map") == 2

        # a subscriber that starts now still gets the last map (transient local, depth 1)
        late = DataReader(participant, Topic(participant, "rt/map_refined", dds_types.OccupancyGrid),
                          qos=dds_qos(qos.MAP, reader=True))
        (last,) = wait_raw(late, 1)
        assert np.array_equal(grid_message(decode_grid(last)).data, expected["intel"])
    finally:
        status = node.stop(signal.SIGTERM)
        participant = None
    assert status == 0, node.log()
    assert "stopped: 5 maps received, 2 refined and published" in node.log(), node.log()
    assert node.log().count("[data length") == 1


def test_refine_node_outlives_a_publisher_that_leaves(tmp_path, monkeypatch):
    """A publisher leaving hands the node's reader an invalid sample (its instance's state): skipped, not a crash."""
    import gc

    from cyclonedds.domain import DomainParticipant

    from crfmap.grid import OccupancyGrid

    env = loopback_dds(tmp_path, monkeypatch)
    grid = OccupancyGrid(np.where(np.arange(48).reshape(6, 8) % 5 == 0, 1.0, 0.5), resolution=0.1)
    node = NodeProcess(["refine", "--period", "0"], env)
    try:
        node.wait_for("publishing /map_refined")
        for k in range(2):  # the second publisher starts after the first has gone
            participant = DomainParticipant(int(env["ROS_DOMAIN_ID"]))
            writer, reader = _writer_reader(participant)
            wait_matched(writer)
            _send(writer, grid_out(grid, 1_700_000_000_000_000_000 + k, "map"))
            stamps = set()
            while 1_700_000_000_000_000_000 + k not in stamps:
                stamps |= {grid_message(decode_grid(p)).stamp_ns for p in wait_raw(reader, 1)}
            writer = reader = participant = None
            gc.collect()  # the participant and its writer go: the node's reader sees the instance unregistered
        node.wait_for("refined /map .*stamp 1700000000.000 s")
    finally:
        status = node.stop(signal.SIGTERM)
    assert status == 0 and "Traceback" not in node.log(), node.log()
    assert "stopped: 2 maps received, 2 refined and published" in node.log(), node.log()


OLIN_BAG = "rosbags/olin_comprobo24_turtlebot4/macfirst_floor_take_2"


def _dds_sample(msgtype, msg):
    """The Cyclone DDS sample of a rosbags LaserScan or TFMessage (what a bag player sends)."""
    from crfmap.ros import dds_types as T

    def header(h):
        return T.Header(stamp=T.Time(sec=h.stamp.sec, nanosec=h.stamp.nanosec), frame_id=h.frame_id)

    if msgtype == "sensor_msgs/msg/LaserScan":
        return T.LaserScan(header=header(msg.header), angle_min=msg.angle_min, angle_max=msg.angle_max,
                           angle_increment=msg.angle_increment, time_increment=msg.time_increment,
                           scan_time=msg.scan_time, range_min=msg.range_min, range_max=msg.range_max,
                           ranges=[float(v) for v in msg.ranges], intensities=[float(v) for v in msg.intensities])
    return T.TFMessage(transforms=[
        T.TransformStamped(header=header(tr.header), child_frame_id=tr.child_frame_id, transform=T.Transform(
            translation=T.Vector3(x=tr.transform.translation.x, y=tr.transform.translation.y,
                                  z=tr.transform.translation.z),
            rotation=T.Quaternion(x=tr.transform.rotation.x, y=tr.transform.rotation.y, z=tr.transform.rotation.z,
                                  w=tr.transform.rotation.w))) for tr in msg.transforms])


def _play(bag, writers, rate, drop_scans=()):
    """Send the bag's /scan, /tf and /tf_static at ``rate`` times real time (a ros2 bag play); {topic: messages sent}.

    ``drop_scans``: stamps [s] of scans not sent (what a lossy link does to best-effort scans).
    """
    import time

    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        conns = [c for c in reader.connections if c.topic in writers]
        start_bag = start_wall = None
        sent = dict.fromkeys(writers, 0)
        for conn, ns, raw in reader.messages(connections=conns):
            if start_bag is None:
                start_bag, start_wall = ns, time.monotonic()
            delay = start_wall + (ns - start_bag) * 1e-9 / rate - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == "/scan" and msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec in drop_scans:
                continue
            writers[conn.topic].write(_dds_sample(conn.msgtype, msg))
            sent[conn.topic] += 1
    return sent


QUIET = 10.0  # [s] after the bag: no new map and no new integrated scan for this long ends the wait (not an assert)


def _final_map(maps, scan_log, last_stamp):
    """The payload of the last map the node publishes: the one of the bag's last scan, or the last before quiet."""
    import time

    from crfmap.ros.tf_buffer import stamp_seconds

    payload, size, quiet_since = None, -1, time.monotonic()
    while time.monotonic() - quiet_since < QUIET:
        got = take_raw(maps)
        grown = scan_log.exists() and scan_log.stat().st_size != size
        if got or grown:
            quiet_since = time.monotonic()
            size = scan_log.stat().st_size if scan_log.exists() else -1
        if got:
            payload = got[-1]
            if stamp_seconds(grid_message(decode_grid(payload)).stamp_ns) == last_stamp:
                break
        time.sleep(0.05)
    assert payload is not None, "the node published no map"
    return payload


@pytest.mark.skipif(not have_data(OLIN_BAG), reason="needs the shared data (CRFMAP_DATA)")
def test_map_node_over_dds_equals_online_mapper_on_the_scans_it_integrated(tmp_path, monkeypatch):
    """The bag played at 10x: the node's final /map equals OnlineMapper fed exactly the scans the node integrated.

    Scans are best effort (sensor-data QoS): a loaded machine may lose some in transport (the cause of
    the earlier mismatch with OnlineMapper on every scan of the bag), so the test drops every 25th scan
    itself and the comparison is with the scans that made the map. The node
    accounts for every scan (its summary: integrated of received, skipped, lost in transport) and its
    --scan-log says which scans at which laser poses made the map; those poses must be read_bag's own
    (tf over DDS places a scan as the bag file does), and the map must be OnlineMapper's on exactly them.
    """
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from crfmap.io.bag_reader import read_bag
    from crfmap.mapping import OnlineMapper
    from crfmap.mapping.builder import scan_bounds
    from crfmap.ros import dds_types as T
    from crfmap.ros import qos
    from crfmap.ros.dds import dds_qos
    from crfmap.ros.tf_buffer import stamp_seconds

    env = loopback_dds(tmp_path, monkeypatch)
    bag = data_file(OLIN_BAG)
    scans = read_bag(bag).scans
    bounds = scan_bounds(scans)
    scan_log = tmp_path / "integrated.txt"
    node = NodeProcess(["map", "--bounds", *map(repr, bounds), "--resolution", "0.05", "--radius", "4",
                        "--margin", "3", "--period", "0.5", "--scan-log", str(scan_log)], env)
    participant = DomainParticipant(int(env["ROS_DOMAIN_ID"]))
    try:
        def writer(topic, kind, profile):
            return DataWriter(participant, Topic(participant, "rt" + topic, T.TYPES[kind]), qos=dds_qos(profile))

        writers = {"/scan": writer("/scan", "scan", qos.SCAN), "/tf": writer("/tf", "tf", qos.TF),
                   "/tf_static": writer("/tf_static", "tf", qos.TF_STATIC)}
        maps = DataReader(participant, Topic(participant, "rt/map", T.OccupancyGrid), qos=dds_qos(qos.MAP, reader=True))
        metadata = DataReader(participant, Topic(participant, "rt/map_metadata", T.MapMetaData),
                              qos=dds_qos(qos.MAP, reader=True))
        node.wait_for("publishing /map_metadata")
        for w in writers.values():
            wait_matched(w)
        # bad messages first: logged once each, skipped
        writers["/scan"].write(T.LaserScan(header=T.Header(stamp=T.Time(sec=1), frame_id="laser"), angle_increment=0.0,
                                           range_min=0.1, range_max=5.0, ranges=[1.0, 1.0]))
        node.wait_for(r"skipping a /scan message: .*\[angle_increment")
        writers["/tf"].write(T.TFMessage(transforms=[T.TransformStamped(
            header=T.Header(stamp=T.Time(sec=1), frame_id="odom"), child_frame_id="elsewhere",
            transform=T.Transform(rotation=T.Quaternion(x=0.0, y=0.0, z=0.0, w=2.0)))]))
        node.wait_for(r"skipping a /tf message: .*\[non-unit quaternion")

        dropped = set(scans.stamps[12::25].tolist())  # a lossy link: these scans never reach the node
        sent = _play(bag, writers, rate=10.0, drop_scans=dropped)
        payload = _final_map(maps, scan_log, scans.stamps[-1])
        got = grid_message(decode_grid(payload))
        assert payload == padded(rosbags_grid_bytes(got))
        want = padded(rosbags_grid_bytes(got, "metadata"))
        while wait_raw(metadata, 1)[-1] != want:  # the final map's metadata comes right after it
            pass
    finally:
        status = node.stop(signal.SIGINT)
        participant = None
    assert status == 0, node.log()

    logged = [line.split() for line in scan_log.read_text().splitlines()]
    stamps = [int(v[0]) for v in logged]
    poses = np.array([[float(c) for c in v[1:]] for v in logged]).reshape(-1, 3)
    index = {s: i for i, s in enumerate(scans.stamps)}
    which = [index[stamp_seconds(ns)] for ns in stamps]  # every logged scan is one of the bag's
    assert which == sorted(set(which)), "scans integrated twice or out of the bag's order"
    assert not dropped & {scans.stamps[i] for i in which}
    assert len(which) >= len(scans) // 2, f"only {len(which)} of {len(scans)} scans integrated:\n{node.log()}"
    n = stamps.index(got.stamp_ns) + 1  # the final map holds the scans logged up to its stamp
    assert n == len(stamps)
    np.testing.assert_array_equal(poses, scans.laser_poses[which])  # tf over DDS places scans as read_bag does
    mapper = OnlineMapper.for_sensor(bounds, 0.05, scans.angle_min, scans.angle_increment, scans.ranges.shape[1],
                                     scans.range_min, scans.range_max, radius=4.0, margin=3)
    for i in which:
        mapper.integrate(scans.ranges[i], scans.laser_poses[i])
    expected = nav2_values(mapper.nav2_map()).reshape(-1)
    assert (got.width, got.height, got.frame_id) == (mapper.width, mapper.height, "odom")
    assert np.array_equal(got.data, expected), f"{int(np.sum(got.data != expected))} cells differ"
    # every scan is accounted for, lost ones visibly
    summary = node.wait_for("stopped: ")
    assert f"stopped: {len(which)} scans integrated of " in summary, summary
    received = int(summary.split(" received")[0].rsplit(" ", 1)[1])
    lost = sum(int(part.rsplit(": ", 1)[1]) for part in summary.split("; ") if part.startswith("lost in transport on /scan"))
    print(f"{sent['/scan']} scans sent ({len(scans)} placed by read_bag), {received} received, {lost} counted lost in "
          f"transport, {len(which)} integrated; {summary}")
    assert len(which) <= received <= sent["/scan"]  # the bad scan sent first is skipped, not received
