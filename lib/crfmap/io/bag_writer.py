"""Write a :class:`~crfmap.recording.Recording` as a ROS 1 or ROS 2 bag, with ``rosbags`` (no ROS install).

Topics: ``/scan`` (LaserScan, laser frame), ``/odom`` (odom -> base_link with twist), ``/cmd_vel``, ``/tf`` (map ->
odom, odom -> base_link), ``/tf_static`` (base_link -> laser), and when known ``/ground_truth_pose`` (base_link in map)
and ``/map`` (the ground truth); ``/tf_static`` and ``/map`` are latched (transient local) for a player's late
subscribers. Files are laid out as rosbag2 (:mod:`crfmap.io.rosbag2_files`) or rosbag (:mod:`crfmap.io.rosbag1_files`)
writes them. No message carries time 0: ROS reads it as "no time" (tf2 looks up the latest transform, ``rosbag play``
skips it)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from crfmap.io._rosmsgs import (CMD_VEL_TOPIC, MAP_TOPIC, ODOM_TOPIC, SCAN_TOPIC, T_GRID, T_ODOM, T_POSE_STAMPED, T_SCAN,
                       T_TF, T_TWIST, TF_STATIC_TOPIC, TF_TOPIC, TRUTH_TOPIC, MessageFactory, to_ns, typestore)
from crfmap.io.atomic import atomic_dir, atomic_path
from crfmap.errors import InputError
from crfmap.frames import compose, interpolate_poses, inverse
from crfmap.grid import OccupancyGrid
from crfmap.recording import ScanSet


def _check_recording(recording, name):
    scans = getattr(recording, "scans", None)
    if not isinstance(scans, ScanSet):
        raise InputError(name, f"expected a Recording with a ScanSet, got {type(recording).__name__}")
    ranges = np.asarray(scans.ranges)
    n = ranges.shape[0] if ranges.ndim == 2 else -1
    if ranges.ndim != 2 or ranges.shape[1] == 0:
        raise InputError(name, f"scans.ranges must be (n_scans, n_beams), got shape {ranges.shape}")
    if np.shape(scans.laser_poses) != (n, 3) or np.shape(scans.stamps) != (n,):
        raise InputError(name, f"scans need {n} laser poses (n, 3) and stamps (n,)")
    if not np.all(np.isfinite(scans.laser_poses)) or not np.all(np.isfinite(scans.stamps)):
        raise InputError(name, "scan poses and stamps must be finite")
    if np.any(np.asarray(scans.stamps) < 0):
        raise InputError(name, "stamps must be >= 0 s (ROS time)")
    if recording.ground_truth is not None and not isinstance(recording.ground_truth, OccupancyGrid):
        raise InputError(name, f"ground_truth must be an OccupancyGrid, got {type(recording.ground_truth).__name__}")
    for track_name in ("odometry", "true_poses", "cmd_vel"):
        track = getattr(recording, track_name)
        if track is None:
            continue
        m = len(track.stamps)
        if np.shape(track.poses) != (m, 3) or (track.twists is not None and np.shape(track.twists) != (m, 2)):
            raise InputError(name, f"{track_name}: need poses (n, 3) and twists (n, 2) for {m} stamps")
        if m and np.any(np.asarray(track.stamps) < 0):
            raise InputError(name, f"{track_name}: stamps must be >= 0 s (ROS time)")
    return scans


STORAGES = ("mcap", "sqlite3")
DISTROS = ("humble", "jazzy")
LATCHED_TOPICS = (TF_STATIC_TOPIC, MAP_TOPIC)


def offered_qos(topic):
    """The QoS profile crfmap offers ``topic`` with: reliable, keep-last; latched topics transient-local, depth 1."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    latched = topic in LATCHED_TOPICS
    return Qos(QosHistory.KEEP_LAST, 1 if latched else 10, QosReliability.RELIABLE,
               QosDurability.TRANSIENT_LOCAL if latched else QosDurability.VOLATILE, QosTime(0, 0),
               QosTime(0, 0), QosLiveliness.AUTOMATIC, QosTime(0, 0), False)


def write_bag(recording, path, fmt="ros2", storage="mcap", distro="humble", progress=False):
    """Write ``recording`` as a ROS 2 bag folder ``path`` (replaced if present) or a ROS 1 file ending in ``.bag``.

    ``storage``: ``"mcap"`` or ``"sqlite3"`` (``NAME_0.mcap`` / ``NAME_0.db3``). ``distro``: whose rosbag2 files to
    write: ``"humble"`` (every later rosbag2 reads them) or ``"jazzy"`` (Humble cannot). ``progress``: a tqdm bar.
    ``/tf`` holds odom -> base_link at every odometry and scan stamp (interpolated) and map -> odom at every scan stamp,
    so that map -> odom -> base_link -> laser is exactly each scan's recorded laser pose (without odometry, map -> odom
    is the identity and odom -> base_link the true pose). InputError for a message at time 0."""
    path = Path(path)
    if fmt not in ("ros2", "ros1"):
        raise InputError("format", f"expected 'ros2' or 'ros1', got {fmt!r}")
    if fmt == "ros1" and path.suffix != ".bag":
        raise InputError(path, "a ROS1 bag file must end in .bag (readers tell ROS1 from ROS2 by it)")
    if fmt == "ros2" and path.suffix == ".bag":
        raise InputError(path, "a ROS2 bag is a folder; a name ending in .bag would be taken for a ROS1 bag")
    if storage not in STORAGES:
        raise InputError("--storage", f"expected one of {', '.join(STORAGES)}, got {storage!r}")
    if distro not in DISTROS:
        raise InputError("--distro", f"expected one of {', '.join(DISTROS)}, got {distro!r}")
    scans = _check_recording(recording, path)
    store = typestore(fmt)
    make = MessageFactory(store, ros1=(fmt == "ros1"))
    messages = _recording_messages(recording, scans, make)  # [(ns, topic, msgtype, msg)]
    messages.sort(key=lambda m: m[0])  # stable: equal stamps keep their order
    zero = [topic for ns, topic, _, msg in messages if ns <= 0 or _header_ns(msg) == 0]
    if zero:
        raise InputError(path, f"{len(zero)} messages ({', '.join(sorted(set(zero)))}) would carry time 0: ROS "
                               "reads a stamp of 0 as 'no time' (tf2: the latest transform; rosbag play skips "
                               "it); shift the recording's stamps (crfmap simulate --start-time)")
    if fmt == "ros2":
        from crfmap.io.rosbag2_files import Topic, write_rosbag2

        topics = {}
        for _, topic, msgtype, _ in messages:
            topics.setdefault(topic, Topic(topic, msgtype, store, [offered_qos(topic)]))
        serialized = [(ns, topic, store.serialize_cdr(msg, msgtype))
                      for ns, topic, msgtype, msg in _bar(messages, progress)]
        with atomic_dir(path) as tmp:
            tmp.mkdir()
            write_rosbag2(tmp, path.name, serialized, topics, storage, distro)
    else:
        from crfmap.io.rosbag1_files import Rosbag1Writer

        with atomic_path(path) as tmp:
            tmp.unlink()  # rosbags' writer refuses an existing file
            with Rosbag1Writer(tmp) as writer:
                _write_all(writer, _bar(messages, progress), store, store.serialize_ros1)
    return path


def _bar(messages, progress):
    if not progress:
        return messages
    from tqdm.auto import tqdm

    return tqdm(messages, desc="writing bag", unit="msg")


def _header_ns(msg):
    """The header stamp [ns] of a message, or None (no header); a TFMessage's smallest transform stamp."""
    header = getattr(msg, "header", None)
    if header is None and hasattr(msg, "transforms"):
        stamps = [t.header.stamp for t in msg.transforms]
        return min(s.sec * 1_000_000_000 + s.nanosec for s in stamps) if stamps else None
    return None if header is None else header.stamp.sec * 1_000_000_000 + header.stamp.nanosec


def _write_all(writer, messages, store, serialize):
    connections = {}
    for ns, topic, msgtype, msg in messages:
        if topic not in connections:
            # the connection header's latching flag, as rosbag record keeps it
            extra = {"latching": 1} if topic in LATCHED_TOPICS else {}
            connections[topic] = writer.add_connection(topic, msgtype, typestore=store, **extra)
        writer.write(connections[topic], ns, serialize(msg, msgtype))


def clashing_scans(scans: ScanSet, laser_mount=(0.0, 0.0, 0.0)) -> list:
    """Pairs (i, j) of scans stamped the same nanosecond at different robot poses: a bag's tf tree, one pose per
    time, cannot hold them.

    >>> s = ScanSet(np.ones((3, 1), np.float32), 0.0, 0.0, 0.1, 5.0, np.array([[0.0, 0, 0], [1, 0, 0], [1, 0, 0]]),
    ...             np.array([0.0, 0.0, 1.0]))
    >>> clashing_scans(s)
    [(0, 1)]
    """
    scan_ns = np.array([to_ns(t) for t in scans.stamps], dtype=np.int64)
    base_at_scans = compose(np.asarray(scans.laser_poses, np.float64), inverse(np.asarray(laser_mount, np.float64)))
    order = np.argsort(scan_ns, kind="stable")
    same = np.nonzero(np.diff(scan_ns[order]) == 0)[0]
    return [(int(order[k]), int(order[k + 1])) for k in same
            if not np.allclose(base_at_scans[order[k]], base_at_scans[order[k + 1]], atol=1e-9)]


def _recording_messages(recording, scans, make):
    """Every message of the bag as (stamp [ns], topic, msgtype, message)."""
    odom = recording.odometry if recording.odometry is not None and len(recording.odometry) else None
    truth = recording.true_poses if recording.true_poses is not None and len(recording.true_poses) else None
    odom_frame = odom.frame_id if odom is not None else "odom"
    base_frame = odom.child_frame_id if odom is not None else (truth.child_frame_id if truth is not None else "base_link")
    laser_frame = scans.laser_frame_id or "laser"
    mount = np.asarray(recording.laser_mount, np.float64)
    if laser_frame == base_frame and np.any(mount != 0):
        raise InputError("recording", f"laser frame '{laser_frame}' equals the base frame but the laser mount is not zero")
    scan_ns = np.array([to_ns(t) for t in scans.stamps], dtype=np.int64)
    base_at_scans = compose(np.asarray(scans.laser_poses, np.float64), inverse(mount))
    clashes = clashing_scans(scans, mount)
    if clashes:
        i, j = clashes[0]
        raise InputError(scans.source or "recording",
                         f"{len(clashes)} scans share a stamp with another at a different pose (first: scans {i} "
                         f"and {j}, {float(scans.stamps[i]):.9g} s); a tf tree holds one pose per time")
    scans_in_odom = scans.frame_id == odom_frame
    t0 = int(scan_ns.min())
    out = []

    for i, ns in enumerate(scan_ns):
        out.append((int(ns), SCAN_TOPIC, T_SCAN, make.scan(int(ns), laser_frame, scans.ranges[i], scans)))

    # odom -> base_link knots (ns -> pose) and map -> odom knots.
    odom_knots = {}
    map_knots = {}
    if odom is not None:
        odom_ns = np.array([to_ns(t) for t in odom.stamps], dtype=np.int64)
        twists = odom.twists if odom.twists is not None else np.zeros((len(odom_ns), 2))
        for j, ns in enumerate(odom_ns):
            out.append((int(ns), ODOM_TOPIC, T_ODOM,
                        make.odometry(int(ns), odom_frame, base_frame, odom.poses[j], twists[j, 0], twists[j, 1])))
        t0 = min(t0, int(odom_ns.min()))
    if odom is not None and not scans_in_odom:
        for j, ns in enumerate(odom_ns):
            odom_knots[int(ns)] = np.asarray(odom.poses[j], np.float64)
        ref = int(odom_ns.min())
        odom_at_scans, _ = interpolate_poses((odom_ns - ref).astype(np.float64), odom.poses,
                                             (scan_ns - ref).astype(np.float64))
        for i, ns in enumerate(scan_ns):
            odom_knots.setdefault(int(ns), odom_at_scans[i])
            map_knots[int(ns)] = compose(base_at_scans[i], inverse(odom_knots[int(ns)]))
    else:
        # No odometry (map -> odom is the identity), or scans already in odom: /tf carries the scans' poses.
        for i, ns in enumerate(scan_ns):
            odom_knots[int(ns)] = base_at_scans[i]
            if not scans_in_odom:
                map_knots[int(ns)] = np.zeros(3)

    map_frame = scans.frame_id
    for ns in sorted(set(odom_knots) | set(map_knots)):
        transforms = []
        if ns in map_knots:
            transforms.append(make.transform(ns, map_frame, odom_frame, map_knots[ns]))
        if ns in odom_knots:
            transforms.append(make.transform(ns, odom_frame, base_frame, odom_knots[ns]))
        out.append((ns, TF_TOPIC, T_TF, make.tf(transforms)))

    if truth is not None:
        truth_ns = np.array([to_ns(t) for t in truth.stamps], dtype=np.int64)
        t0 = min(t0, int(truth_ns.min()))
        for j, ns in enumerate(truth_ns):
            out.append((int(ns), TRUTH_TOPIC, T_POSE_STAMPED, make.pose_stamped(int(ns), truth.frame_id, truth.poses[j])))

    cmd = recording.cmd_vel
    if cmd is not None and len(cmd) and cmd.twists is not None:
        for j, t in enumerate(cmd.stamps):
            out.append((to_ns(t), CMD_VEL_TOPIC, T_TWIST, make.twist(cmd.twists[j, 0], cmd.twists[j, 1])))
            t0 = min(t0, to_ns(t))

    if laser_frame != base_frame:
        out.append((t0, TF_STATIC_TOPIC, T_TF, make.tf([make.transform(t0, base_frame, laser_frame, mount)])))
    if recording.ground_truth is not None:
        out.append((t0, MAP_TOPIC, T_GRID, make.grid(t0, recording.ground_truth)))
    return out
