"""ROS1 and ROS2 bags <-> :class:`~crfmap.recording.Recording`, with ``rosbags`` (no ROS install).

Writing (:func:`write_bag`) produces the topics a ROS user expects from a robot:
``/scan`` (sensor_msgs/LaserScan in the laser frame), ``/odom`` (nav_msgs/Odometry,
odom -> base_link with twist), ``/cmd_vel`` (geometry_msgs/Twist), ``/tf`` (map -> odom
and odom -> base_link), ``/tf_static`` (base_link -> laser), and, when known,
``/ground_truth_pose`` (geometry_msgs/PoseStamped, base_link in map) and ``/map``
(nav_msgs/OccupancyGrid of the ground truth).

Reading (:func:`read_bag`) places every scan in a fixed frame by composing the
transform chain at the scan's header stamp (REP 105: map -> odom -> base_link -> laser),
interpolating the moving transforms in time and applying the static mount from
``/tf_static``. Scans outside the pose track's time span are dropped and counted in
``recording.meta``. Ranges are kept as recorded (REP 117 filtering is the grid
builder's job).

The pose algebra and the tf tree live in :mod:`crfmap.frames` (``compose``, ``inverse``,
``interpolate_poses`` and ``wrap_angle`` are importable from here too); building and
decoding the messages themselves is :mod:`crfmap._rosmsgs`.
"""
from __future__ import annotations

import math
import sqlite3
import struct
import zlib
from pathlib import Path

import numpy as np

from .atomic import atomic_dir, atomic_path
from ._rosmsgs import (T_GRID, T_ODOM, T_POSE_STAMPED, T_SCAN, T_TF, T_TWIST, TF_TYPES, MessageFactory,
                       grid_from_message, pose_of, to_ns, to_seconds, typestore)
from .errors import InputError
from .frames import TfTree, compose, interpolate_poses, inverse
from .frames import wrap_angle  # noqa: F401  (re-exported: crfmap.bagio.wrap_angle predates crfmap.frames)
from .grid import OccupancyGrid
from .recording import Recording, ScanSet, Trajectory

POSE_SOURCES = ("auto", "tf", "odom", "truth")
SCAN_TOPIC, ODOM_TOPIC, CMD_VEL_TOPIC = "/scan", "/odom", "/cmd_vel"
TF_TOPIC, TF_STATIC_TOPIC = "/tf", "/tf_static"
TRUTH_TOPIC, MAP_TOPIC = "/ground_truth_pose", "/map"
ANGLE_TOLERANCE = 1e-4  # [rad] scan geometry differing by less than this counts as the same (float32 angles)


# --- writing --------------------------------------------------------------------------------


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


def write_bag(recording, path, fmt="ros2"):
    """Write a :class:`~crfmap.recording.Recording` as a ROS2 bag folder or a ROS1 ``.bag`` file.

    Parameters
    ----------
    recording : Recording
    path : str or Path
        ROS2: a folder (created; replaced if present). ROS1: a file ending in ``.bag``.
    fmt : {'ros2', 'ros1'}

    Notes
    -----
    ``/tf`` holds odom -> base_link at every odometry stamp (and at every scan stamp,
    interpolated) and map -> odom at every scan stamp, chosen so that
    map -> odom -> base_link -> laser is exactly the recorded laser pose of each scan.
    Without odometry, map -> odom is the identity and odom -> base_link the true pose.

    Examples
    --------
    >>> write_bag(recording, "/tmp/run_bag", fmt="ros2")  # doctest: +SKIP
    >>> read_bag("/tmp/run_bag").scans.ranges.shape  # doctest: +SKIP
    (120, 360)
    """
    path = Path(path)
    if fmt not in ("ros2", "ros1"):
        raise InputError("format", f"expected 'ros2' or 'ros1', got {fmt!r}")
    if fmt == "ros1" and path.suffix != ".bag":
        raise InputError(path, "a ROS1 bag file must end in .bag (readers tell ROS1 from ROS2 by it)")
    if fmt == "ros2" and path.suffix == ".bag":
        raise InputError(path, "a ROS2 bag is a folder; a name ending in .bag would be taken for a ROS1 bag")
    scans = _check_recording(recording, path)
    store = typestore(fmt)
    make = MessageFactory(store, ros1=(fmt == "ros1"))
    messages = _recording_messages(recording, scans, make)  # [(ns, topic, msgtype, msg)]
    messages.sort(key=lambda m: m[0])  # stable: equal stamps keep their order
    if fmt == "ros2":
        from rosbags.rosbag2 import Writer

        with atomic_dir(path) as tmp:
            with Writer(tmp, version=Writer.VERSION_LATEST) as writer:
                _write_all(writer, messages, store, store.serialize_cdr)
    else:
        from rosbags.rosbag1 import Writer

        with atomic_path(path) as tmp:
            tmp.unlink()  # rosbags' writer refuses an existing file
            with Writer(tmp) as writer:
                _write_all(writer, messages, store, store.serialize_ros1)
    return path


def _write_all(writer, messages, store, serialize):
    connections = {}
    for ns, topic, msgtype, msg in messages:
        if topic not in connections:
            connections[topic] = writer.add_connection(topic, msgtype, typestore=store)
        writer.write(connections[topic], ns, serialize(msg, msgtype))


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
    order = np.argsort(scan_ns, kind="stable")
    same = np.nonzero(np.diff(scan_ns[order]) == 0)[0]
    for k in same:
        i, j = order[k], order[k + 1]
        if not np.allclose(base_at_scans[i], base_at_scans[j], atol=1e-9):
            raise InputError("recording", f"scans {i} and {j} share the stamp {scans.stamps[i]!r} s but not "
                                          "the pose; a tf tree holds one pose per time")
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
        # odom -> base_link is the odometry (interpolated at the scan stamps too, so /tf covers
        # every scan); map -> odom at each scan closes the chain onto the recorded laser pose.
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


# --- reading --------------------------------------------------------------------------------


def _bag_location(path: Path):
    """(path to open, 'ros1' | 'ros2') for a .bag file, a ROS2 folder, its .db3/.mcap or metadata.yaml."""
    if not path.exists():
        raise InputError(path, "no such file or folder")
    if path.is_dir():
        if not (path / "metadata.yaml").exists():
            raise InputError(path, "folder without metadata.yaml: not a ROS2 bag")
        return path, "ros2"
    if path.suffix == ".bag":
        return path, "ros1"
    if path.name == "metadata.yaml" or path.suffix in (".db3", ".mcap"):
        if not (path.parent / "metadata.yaml").exists():
            raise InputError(path, "no metadata.yaml beside it: not part of a ROS2 bag folder")
        return path.parent, "ros2"
    raise InputError(path, "not a ROS bag (expected a ROS1 .bag file or a ROS2 bag folder)")


def _reader_errors():
    from rosbags.highlevel import AnyReaderError
    from rosbags.rosbag1 import ReaderError as Reader1Error
    from rosbags.rosbag2 import ReaderError as Reader2Error
    from rosbags.serde import SerdeError

    # What a damaged bag makes rosbags (or the libraries under it) raise.
    return (AnyReaderError, Reader1Error, Reader2Error, SerdeError, sqlite3.Error, OSError, EOFError,
            struct.error, zlib.error, ValueError, KeyError, IndexError)


class _Collected:
    """Everything read_bag takes from the messages, before poses are computed."""

    def __init__(self):
        self.scans = []  # (stamp [s], ranges float32)
        self.scan_geometry = None  # (angle_min, angle_increment, range_min, range_max, frame_id)
        self.n_beams = None
        self.range_limits_vary = False
        self.odom = []  # (stamp, x, y, yaw, v, w)
        self.odom_frames = None
        self.truth = []  # (stamp, x, y, yaw)
        self.truth_frame = "map"
        self.cmd = []  # (stamp, v, w)
        self.grid = None
        self.tf = TfTree()  # from /tf and /tf_static


def _add_scan(c, path, topic, index, stamp, msg):
    n = len(msg.ranges)
    a0, inc, a1 = float(msg.angle_min), float(msg.angle_increment), float(msg.angle_max)
    where = f"{topic} message {index}"
    if not (math.isfinite(a0) and math.isfinite(a1) and math.isfinite(inc) and inc != 0.0):
        raise InputError(path, f"{where}: angle_min/angle_max/angle_increment must be finite with a non-zero increment")
    if n == 0:
        raise InputError(path, f"{where}: LaserScan without ranges")
    last = a0 + (n - 1) * inc
    if abs(last - a1) > abs(inc) * 1.0001 + 1e-6:
        expected = int(round((a1 - a0) / inc)) + 1
        raise InputError(
            path, f"{where}: {n} ranges disagree with its angles (angle_min {a0:.6g} + (n-1) * increment "
            f"{inc:.6g} = {last:.6g}, angle_max {a1:.6g}: about {expected} beams)")
    geometry = (a0, inc, float(msg.range_min), float(msg.range_max), msg.header.frame_id)
    if c.scan_geometry is None:
        c.scan_geometry = geometry
        c.n_beams = n
    else:
        if n != c.n_beams:
            raise InputError(path, f"{where}: {n} beams, earlier scans have {c.n_beams} (inconsistent beam count)")
        g0 = c.scan_geometry
        if abs(a0 - g0[0]) > ANGLE_TOLERANCE or abs(inc - g0[1]) * n > ANGLE_TOLERANCE:
            raise InputError(path, f"{where}: beam angles differ from earlier scans (angle_min {a0:.6g} vs "
                                   f"{g0[0]:.6g}, increment {inc:.6g} vs {g0[1]:.6g})")
        if geometry[4] != g0[4]:
            raise InputError(path, f"{where}: frame '{geometry[4]}', earlier scans are in '{g0[4]}'")
        if geometry[2:4] != g0[2:4]:
            c.range_limits_vary = True
    c.scans.append((stamp, np.array(msg.ranges, dtype=np.float32)))


def _add_transforms(c, msg, static):
    for tr in msg.transforms:
        stamp = None if static else to_seconds(tr.header.stamp)
        c.tf.add(tr.header.frame_id, tr.child_frame_id, pose_of(tr.transform), stamp)


def _pick_topic(path, conns, msgtype_names, wanted, preferred, what, required_choice=True):
    """The topic to read for one kind of message; None if absent and not asked for."""
    topics = sorted({c.topic for c in conns if c.msgtype in msgtype_names})
    if wanted is not None:
        if wanted not in {c.topic for c in conns}:
            raise InputError(path, f"no topic {wanted!r} (topics: {', '.join(sorted({c.topic for c in conns}))})")
        if wanted not in topics:
            raise InputError(path, f"topic {wanted!r} is not a {what}")
        return wanted
    if not topics:
        return None
    if len(topics) == 1:
        return topics[0]
    if preferred in topics:
        return preferred
    if required_choice:
        raise InputError(path, f"several {what} topics ({', '.join(topics)}); choose one")
    return topics[0]


def _collect(path, location, scan_topic):
    from rosbags.highlevel import AnyReader

    errors = _reader_errors()
    c = _Collected()
    try:
        with AnyReader([location], default_typestore=typestore("ros2")) as reader:
            conns = reader.connections
            scan_topic = _pick_topic(path, conns, (T_SCAN,), scan_topic, SCAN_TOPIC, "sensor_msgs/LaserScan")
            if scan_topic is None:
                raise InputError(path, "no sensor_msgs/LaserScan topic in the bag")
            odom_topic = _pick_topic(path, conns, (T_ODOM,), None, ODOM_TOPIC, "nav_msgs/Odometry",
                                     required_choice=False)
            topics = {scan_topic: "scan", odom_topic: "odom", TF_TOPIC: "tf", TF_STATIC_TOPIC: "tf_static",
                      TRUTH_TOPIC: "truth", MAP_TOPIC: "map", CMD_VEL_TOPIC: "cmd_vel"}
            types = {"scan": (T_SCAN,), "odom": (T_ODOM,), "tf": TF_TYPES, "tf_static": TF_TYPES,
                     "truth": (T_POSE_STAMPED,), "map": (T_GRID,), "cmd_vel": (T_TWIST,)}
            wanted = [x for x in conns if x.topic in topics and x.msgtype in types[topics[x.topic]]]
            counts = {}
            for conn, bag_ns, raw in reader.messages(connections=wanted):
                kind = topics[conn.topic]
                index = counts.get(kind, 0)
                counts[kind] = index + 1
                msg = reader.deserialize(raw, conn.msgtype)
                header = getattr(msg, "header", None)
                stamp = to_seconds(header.stamp) if header is not None else 0.0
                if stamp == 0.0:
                    stamp = bag_ns * 1e-9  # no (or an unset) header stamp: use the recording time
                if kind == "scan":
                    _add_scan(c, path, conn.topic, index, stamp, msg)
                elif kind == "odom":
                    pose = pose_of(msg.pose.pose)
                    c.odom.append((stamp, *pose, float(msg.twist.twist.linear.x), float(msg.twist.twist.angular.z)))
                    c.odom_frames = (msg.header.frame_id.lstrip("/"), msg.child_frame_id.lstrip("/"))
                elif kind in ("tf", "tf_static"):
                    _add_transforms(c, msg, static=(kind == "tf_static"))
                elif kind == "truth":
                    c.truth.append((stamp, *pose_of(msg.pose)))
                    c.truth_frame = msg.header.frame_id.lstrip("/")
                elif kind == "map":
                    c.grid = msg
                elif kind == "cmd_vel":
                    c.cmd.append((stamp, float(msg.linear.x), float(msg.angular.z)))
    except InputError:
        raise
    except errors as exc:
        raise InputError(path, f"cannot read the bag, corrupt or truncated? ({type(exc).__name__}: {exc})") from None
    c.scan_topic = scan_topic
    return c


def _mount_on(c, path, laser_frame, base_frame, laser_mount):
    """Pose of the laser frame in ``base_frame`` (from /tf_static, or the caller's override)."""
    if laser_mount is not None:
        return np.asarray(laser_mount, np.float64)
    if laser_frame == base_frame:
        return np.zeros(3)
    top, pose, passed = c.tf.static_chain(laser_frame, stop=base_frame)
    if top != base_frame:
        raise InputError(path, f"no /tf_static transform chain from '{base_frame}' to the laser frame "
                               f"'{laser_frame}' (give laser_mount to state it)")
    return pose


def read_bag(path, scan_topic=None, pose_source="auto", laser_mount=None) -> Recording:
    """Read a ROS1 ``.bag`` or a ROS2 bag folder into a :class:`~crfmap.recording.Recording`.

    Parameters
    ----------
    path : str or Path
        A ROS1 ``.bag`` file, a ROS2 bag folder, or its ``.db3``/``.mcap``/``metadata.yaml``.
    scan_topic : str, optional
        The LaserScan topic; by default the only one (or ``/scan``).
    pose_source : {'auto', 'tf', 'odom', 'truth'}
        Where the laser poses come from: the ``/tf`` tree (map -> odom -> base_link, or
        odom -> base_link), ``/odom`` messages, or ``/ground_truth_pose``. 'auto' takes
        the first available in that order.
    laser_mount : (x, y, yaw), optional
        The laser's pose on the robot, overriding ``/tf_static``.

    Returns
    -------
    Recording
        ``scans.laser_poses`` in the fixed frame (``scans.frame_id``: map or odom);
        ``meta`` says which pose source was used and how many scans were dropped.

    Examples
    --------
    >>> rec = read_bag(data_file("rosbags/olin_comprobo24_turtlebot4/macfirst_floor_take_2"))  # doctest: +SKIP
    >>> rec.laser_mount  # doctest: +SKIP
    (0.00393584, 0.0, 1.5707963267948966)
    """
    path = Path(path)
    if pose_source not in POSE_SOURCES:
        raise InputError("pose_source", f"expected one of {', '.join(POSE_SOURCES)}, got {pose_source!r}")
    if laser_mount is not None:
        laser_mount = np.asarray(laser_mount, np.float64)
        if laser_mount.shape != (3,) or not np.all(np.isfinite(laser_mount)):
            raise InputError("laser_mount", f"expected finite (x, y, yaw), got {laser_mount!r}")
    location, fmt = _bag_location(path)
    c = _collect(path, location, scan_topic)
    if not c.scans:
        raise InputError(path, f"topic {c.scan_topic!r} has no messages")

    stamps = np.array([s for s, _ in c.scans])
    ranges = np.stack([r for _, r in c.scans])
    angle_min, angle_inc, range_min, range_max, laser_frame = c.scan_geometry
    laser_frame = laser_frame.lstrip("/") or "laser"

    odometry = None
    if c.odom:
        o = np.array(c.odom)
        odometry = Trajectory(o[:, 0], o[:, 1:4], frame_id=c.odom_frames[0], child_frame_id=c.odom_frames[1],
                              twists=o[:, 4:6])
    base_frame = odometry.child_frame_id if odometry is not None else "base_link"
    true_poses = None
    if c.truth:
        t = np.array(c.truth)
        true_poses = Trajectory(t[:, 0], t[:, 1:4], frame_id=c.truth_frame, child_frame_id=base_frame)

    # The tf tree: start from the laser frame (or from the base frame with a given mount).
    if laser_mount is not None:
        tf_start, tf_mount = base_frame, laser_mount
    else:
        tf_start, tf_mount, _ = c.tf.static_chain(laser_frame)
    tf_result = c.tf.poses_in_root(tf_start, tf_mount, stamps, source=path) if c.tf.dynamic else None
    has_tf = tf_result is not None and tf_result[3] > 0

    source = pose_source
    if source == "auto":
        source = "tf" if has_tf else "odom" if odometry is not None else "truth" if true_poses is not None else None
        if source is None:
            raise InputError(path, "no pose source: no /tf transforms reaching the laser frame "
                                   f"'{laser_frame}', no nav_msgs/Odometry and no {TRUTH_TOPIC}")
    if source == "tf":
        if not has_tf:
            raise InputError(path, f"pose source 'tf': no /tf transforms reaching the laser frame '{laser_frame}'")
        poses, inside, fixed_frame, _ = tf_result
        mount_base = base_frame if base_frame in c.tf.static_chain(laser_frame)[2] else tf_start
        mount = _mount_on(c, path, laser_frame, mount_base, laser_mount)
        base_frame = mount_base
    else:
        track = odometry if source == "odom" else true_poses
        if track is None:
            what = "no nav_msgs/Odometry topic" if source == "odom" else f"no {TRUTH_TOPIC} topic"
            raise InputError(path, f"pose source '{source}': {what}")
        mount = _mount_on(c, path, laser_frame, base_frame, laser_mount)
        ref = track.stamps.min()
        at, inside = interpolate_poses(track.stamps - ref, track.poses, stamps - ref)
        poses = compose(at, mount)
        fixed_frame = track.frame_id

    n_total = len(stamps)
    if not inside.any():
        raise InputError(path, f"none of the {n_total} scans falls within the time span of the "
                               f"'{source}' pose track")
    scans = ScanSet(
        ranges=ranges[inside], angle_min=angle_min, angle_increment=angle_inc, range_min=range_min,
        range_max=range_max, laser_poses=poses[inside], stamps=stamps[inside], frame_id=fixed_frame,
        laser_frame_id=laser_frame, source=str(path))

    cmd_vel = None
    if c.cmd:
        k = np.array(c.cmd)
        cmd_vel = Trajectory(k[:, 0], np.zeros((len(k), 3)), frame_id=base_frame, child_frame_id=base_frame,
                             twists=k[:, 1:3])
    ground_truth = grid_from_message(c.grid, path, MAP_TOPIC) if c.grid is not None else None
    meta = {
        "source": str(path), "format": fmt, "scan_topic": c.scan_topic, "pose_source": source,
        "scans_total": n_total, "scans_dropped": int(n_total - inside.sum()),
        "scans_dropped_reason": "stamp outside the pose track's time span",
        "fixed_frame": fixed_frame, "base_frame": base_frame, "laser_frame": laser_frame,
    }
    if c.range_limits_vary:
        meta["range_limits_vary"] = True
    if c.tf.conflicts:
        meta["tf_conflicts"] = c.tf.conflicts
    return Recording(scans=scans, laser_mount=tuple(float(v) for v in mount), odometry=odometry,
                     true_poses=true_poses, cmd_vel=cmd_vel, ground_truth=ground_truth, meta=meta)
