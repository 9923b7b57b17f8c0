"""One reader for every recording crfmap takes: a CARMEN log or a ROS 1 / ROS 2 bag. Its errors name the commands'
options (``--max-range``, ...), whose arguments it receives."""
from __future__ import annotations

from crfmap.errors import InputError
from crfmap.checks import check_path_arg

CARMEN_SUFFIXES = (".log", ".log.gz", ".clf", ".clf.gz")


def is_carmen_log(path) -> bool:
    """Whether ``path`` names a CARMEN log (by its suffix)."""
    return str(path).lower().endswith(CARMEN_SUFFIXES)


def load_recording(path, scan_topic=None, pose_source="auto", laser_mount=None, max_range=None, uses_odometry=False):
    """A Recording from a CARMEN log or a ROS1/ROS2 bag; the laser poses follow ``pose_source``.

    For a CARMEN log, 'auto' and 'truth' take the corrected FLASER poses and 'odom' the ODOM track interpolated at the
    scan stamps. ``max_range`` [m]: CARMEN only (:func:`crfmap.io.carmen.read_carmen`). ``uses_odometry``: the caller
    writes the odometry out, so a log's corrupt ODOM records are warned of."""
    path = check_path_arg(path, "log or bag")
    if not is_carmen_log(path):
        from crfmap.io.bag_reader import read_bag

        if max_range is not None:
            raise InputError("--max-range", "applies to CARMEN logs only (a bag's LaserScan states its range_max)")
        return read_bag(path, scan_topic=scan_topic, pose_source=pose_source, laser_mount=laser_mount)
    from crfmap.io.carmen import read_carmen

    if scan_topic is not None:
        raise InputError("--scan-topic", "applies to bags only, not to CARMEN logs")
    if laser_mount is not None:
        raise InputError("--laser-mount", "applies to bags only (CARMEN FLASER poses are laser poses)")
    rec = read_carmen(path, max_range="auto" if max_range is None else max_range,
                      warn=uses_odometry or pose_source == "odom")
    rec.meta["pose_source"] = "truth"
    if pose_source == "tf":
        raise InputError("--pose-source", "a CARMEN log has no tf; use truth (corrected poses) or odom")
    if pose_source == "odom":
        from crfmap.frames import interpolate_poses

        if rec.odometry is None:
            raise InputError(path, "pose source 'odom': the log has no ODOM lines")
        odom = rec.odometry
        ref = float(odom.stamps.min())
        poses, inside = interpolate_poses(odom.stamps - ref, odom.poses, rec.scans.stamps - ref)
        if not inside.any():
            raise InputError(path, "pose source 'odom': no FLASER stamp falls within the ODOM track")
        s = rec.scans
        s.ranges, s.laser_poses, s.stamps = s.ranges[inside], poses[inside], s.stamps[inside]
        s.frame_id = odom.frame_id
        rec.meta.update(pose_source="odom", scans_dropped=int((~inside).sum()))
        rec.true_poses = None
    return rec
