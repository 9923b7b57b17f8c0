"""ROS 1 and ROS 2 bags -> :class:`~crfmap.recording.Recording`, with ``rosbags`` (no ROS install).

Every scan is placed in a fixed frame by composing the transform chain at its header stamp (REP 105: map -> odom ->
base_link -> laser; :class:`crfmap.frames.TfTree`). Ranges are kept as recorded (REP 117 filtering is the grid
builder's job). Writing is :mod:`crfmap.io.bag_writer`."""
from __future__ import annotations

import math
import sqlite3
import struct
import zlib
from pathlib import Path

import numpy as np

from crfmap.io._rosmsgs import (CMD_VEL_TOPIC, MAP_TOPIC, ODOM_TOPIC, SCAN_TOPIC, T_GRID, T_ODOM, T_POSE_STAMPED, T_SCAN,
                       T_TWIST, TF_STATIC_TOPIC, TF_TOPIC, TF_TYPES, TRUTH_TOPIC, grid_from_message, pose_of,
                       to_seconds, typestore)
from crfmap.checks import check_input_file, check_path_arg
from crfmap.io.rosbag1_files import BAG_MAGIC, check_records
from crfmap.errors import InputError
from crfmap.frames import TfTree, compose, interpolate_poses
from crfmap.recording import Recording, ScanSet, Trajectory
from crfmap.io._yaml import load_text, read_text_file

POSE_SOURCES = ("auto", "tf", "odom", "truth")
ANGLE_TOLERANCE = 1e-4  # [rad] scan geometry differing by less than this counts as the same (float32 angles)


# --- reading --------------------------------------------------------------------------------


def _bag_location(path: Path):
    """(path to open, 'ros1' | 'ros2') for a .bag file, a ROS2 folder, its .db3/.mcap or metadata.yaml."""
    if not path.exists():
        raise InputError(path, "no such file or folder")
    if path.is_dir():
        if not (path / "metadata.yaml").exists():
            raise InputError(path, "folder without metadata.yaml: not a ROS2 bag")
        _check_metadata(path, path / "metadata.yaml")
        return path, "ros2"
    if path.suffix == ".bag":
        check_input_file(path, "ROS1 bag file")  # a FIFO would block the reader
        if _starts_with(path, BAG_MAGIC):  # its records within the file, its chunks' sizes true (else rosbags says)
            try:
                check_records(path)
            except InputError as exc:
                raise InputError(path, f"cannot read the bag: {exc.problem}") from None
        return path, "ros1"
    if path.name == "metadata.yaml" or path.suffix in (".db3", ".mcap"):
        if (path.parent / "metadata.yaml").exists():
            _check_metadata(path, path.parent / "metadata.yaml")
            return path.parent, "ros2"
        if path.suffix in (".db3", ".mcap"):  # a bare storage file: its own metadata is enough
            return path, "ros2"
        raise InputError(path, "no metadata.yaml beside it: not part of a ROS2 bag folder")
    raise InputError(path, "not a ROS bag (expected a ROS1 .bag file or a ROS2 bag folder)")


def _starts_with(path, magic: bytes) -> bool:
    with open(path, "rb") as f:
        return f.read(len(magic)) == magic


def _check_metadata(path, metadata):
    """Read a ROS2 bag's metadata.yaml strictly first: a hostile one is refused in one line, not hanging the reader."""
    try:
        doc = load_text(read_text_file(metadata, "ROS2 bag metadata (metadata.yaml)"), metadata)
    except InputError as exc:
        raise InputError(path, f"metadata.yaml: {exc.problem}") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("rosbag2_bagfile_information"), dict):
        raise InputError(path, "metadata.yaml has no 'rosbag2_bagfile_information' mapping: not a ROS2 bag")
    for f in doc["rosbag2_bagfile_information"].get("relative_file_paths") or []:
        if isinstance(f, str) and (metadata.parent / f).exists():
            check_input_file(metadata.parent / f, "ROS2 bag storage file")


def _reader_errors():
    from rosbags.highlevel import AnyReaderError
    from rosbags.rosbag1 import ReaderError as Reader1Error
    from rosbags.rosbag2 import ReaderError as Reader2Error
    from rosbags.serde import SerdeError

    # What a damaged bag makes rosbags (or the libraries under it) raise.
    return (AnyReaderError, Reader1Error, Reader2Error, SerdeError, sqlite3.Error, OSError, EOFError,
            struct.error, zlib.error, ValueError, KeyError, IndexError)


READER_MODULES = ("rosbags", "backports", "compression", "lz4")  # rosbags and its decompressors (zstd, lz4)


def raised_by_reader(exc: BaseException) -> bool:
    """Whether ``exc`` (an Exception) came out of the bag-reading libraries, its innermost Python frame theirs: a bag
    they cannot decode makes them raise what no list names (``ZstdError``, ``TypeError``), the bag's fault; the same
    exception from crfmap's own code stays a traceback.

    >>> raised_by_reader(ValueError("x"))  # never raised: no frame at all
    False
    """
    if not isinstance(exc, Exception):
        return False
    tb, last = exc.__traceback__, None
    while tb is not None:
        tb, last = tb.tb_next, tb
    return last is not None and last.tb_frame.f_globals.get("__name__", "").split(".")[0] in READER_MODULES


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


def _add_transforms(c, msg, static, path, topic, index):
    for tr in msg.transforms:
        stamp = None if static else to_seconds(tr.header.stamp)
        where = f"{path}: {topic} message {index} ({tr.header.frame_id} -> {tr.child_frame_id})"
        c.tf.add(tr.header.frame_id, tr.child_frame_id, pose_of(tr.transform, where), stamp)


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
                    pose = pose_of(msg.pose.pose, f"{path}: {conn.topic} message {index}")
                    c.odom.append((stamp, *pose, float(msg.twist.twist.linear.x), float(msg.twist.twist.angular.z)))
                    c.odom_frames = (msg.header.frame_id.lstrip("/"), msg.child_frame_id.lstrip("/"))
                elif kind in ("tf", "tf_static"):
                    _add_transforms(c, msg, kind == "tf_static", path, conn.topic, index)
                elif kind == "truth":
                    c.truth.append((stamp, *pose_of(msg.pose, f"{path}: {conn.topic} message {index}")))
                    c.truth_frame = msg.header.frame_id.lstrip("/")
                elif kind == "map":
                    c.grid = msg
                elif kind == "cmd_vel":
                    c.cmd.append((stamp, float(msg.linear.x), float(msg.angular.z)))
    except InputError:
        raise
    except Exception as exc:
        if not (isinstance(exc, errors) or raised_by_reader(exc)):
            raise
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
    """Read a ROS1 ``.bag`` or a ROS2 bag folder (or its ``.db3``/``.mcap``/``metadata.yaml``) into a Recording.

    ``scan_topic``: the LaserScan topic, by default the only one (or ``/scan``). ``pose_source`` of the laser poses:
    ``"tf"`` (map -> odom -> base_link, or odom -> base_link), ``"odom"`` (``/odom``), ``"truth"``
    (``/ground_truth_pose``) or ``"auto"``, the first available in that order. ``laser_mount`` (x, y, yaw) overrides
    ``/tf_static``. ``scans.laser_poses`` are in ``scans.frame_id`` (map or odom); scans outside the pose track's time
    span are dropped; ``meta`` says which pose source was used and how many scans were dropped."""
    path = check_path_arg(path, "bag file or folder")
    if pose_source not in POSE_SOURCES:
        raise InputError("pose_source", f"expected one of {', '.join(POSE_SOURCES)}, got {pose_source!r}")
    if laser_mount is not None:
        try:
            laser_mount = np.asarray(laser_mount, np.float64)
        except (TypeError, ValueError):
            raise InputError("laser_mount", f"expected finite (x, y, yaw), got {laser_mount!r}") from None
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
