"""``crfmap build INPUT OUT_MAP``: an occupancy grid from a bag or a CARMEN log (thesis sec. 3.2)."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from crfmap.errors import InputError

CARMEN_SUFFIXES = (".log", ".log.gz", ".clf", ".clf.gz")
GRID_SUFFIXES = (".yaml", ".yml", ".npy")


def is_carmen_log(path) -> bool:
    """Whether ``path`` names a CARMEN log (by its suffix)."""
    return str(path).lower().endswith(CARMEN_SUFFIXES)


def load_recording(path, scan_topic=None, pose_source="auto", laser_mount=None, max_range=None):
    """A Recording from a CARMEN log or a ROS1/ROS2 bag; the laser poses follow ``pose_source``.

    For a CARMEN log, 'auto' and 'truth' take the corrected FLASER poses and 'odom'
    the raw ODOM track interpolated at the scan stamps ('tf' does not apply).
    ``max_range`` [m] (CARMEN only): readings at or beyond it are no-returns (see
    :func:`crfmap.io.carmen.read_carmen`).
    """
    from crfmap.checks import check_path_arg

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
    rec = read_carmen(path, max_range="auto" if max_range is None else max_range)
    rec.meta["pose_source"] = "truth"
    if pose_source == "tf":
        raise InputError("--pose-source", "a CARMEN log has no tf; use truth (corrected poses) or odom")
    if pose_source == "odom":
        from crfmap.io.bag_reader import interpolate_poses

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


def add_bag_options(p):
    """Options saying how to read a bag (shared with ``crfmap convert``)."""
    p.add_argument("--pose-source", choices=["auto", "tf", "odom", "truth"], default="auto",
                   help="laser poses from /tf (map -> odom -> base_link), /odom or /ground_truth_pose; "
                        "auto: the first available (CARMEN: corrected poses, or odom for the raw ODOM track)")
    p.add_argument("--scan-topic", default=None, help="LaserScan topic of a bag (default: the only one, or /scan)")
    p.add_argument("--laser-mount", type=float, nargs=3, default=None, metavar=("X", "Y", "YAW"),
                   help="the laser's pose on base_link [m, m, rad], overriding /tf_static")
    p.add_argument("--max-range", type=float, default=None, metavar="M",
                   help="CARMEN logs: the laser's maximum range; readings at or beyond it are no-returns "
                        "(default: the log's PARAM robot_front_laser_max, else see crfmap.io.carmen)")


def add_parser(sub):
    p = sub.add_parser(
        "build",
        help="build an occupancy grid from a ROS bag or a CARMEN log",
        description="Ray-cast every laser beam from its pose into a grid: cells passed are empty hits, "
        "end cells occupied hits; P = 0.5 + atan(occupied - empty)/pi (thesis eq. 16) or log-odds. "
        "REP 117: NaN/-Inf and readings outside [range_min, range_max] are dropped.",
    )
    p.add_argument("input", help="ROS1 .bag, ROS2 bag folder (or its .db3 / metadata.yaml), "
                                 "or CARMEN log (.log / .log.gz)")
    p.add_argument("output", help="map_server YAML (scale mode, keeps probabilities) or .npy")
    p.add_argument("--resolution", type=float, default=0.05, help="cell size in metres (default 0.05)")
    p.add_argument("--model", choices=["arctan", "logodds"], default="arctan",
                   help="arctan: thesis eq. 16 (default); logodds: Probabilistic Robotics ch. 9")
    p.add_argument("--free-on-no-return", type=float, default=None, metavar="M",
                   help="mark cells free up to M metres along beams that returned nothing (+Inf)")
    add_bag_options(p)
    p.add_argument("--extent", type=float, nargs=4, default=None, metavar=("XMIN", "YMIN", "XMAX", "YMAX"),
                   help="area to map in metres (default: the data's bounding box)")
    p.add_argument("--progress", action="store_true", help="show a progress bar")
    p.add_argument("--force", action="store_true", help="allow OUT_MAP to replace INPUT")
    return p


def run(args: argparse.Namespace) -> int:
    from crfmap.mapping.builder import build_grid
    from crfmap.io.grid_files import save_grid

    out = Path(args.output)
    if not str(out).lower().endswith(GRID_SUFFIXES):
        raise InputError(out, "the map must end in .yaml/.yml (map_server) or .npy")
    from crfmap.commands.outputs import check_output

    check_output([args.input], out, force=args.force)
    start = time.perf_counter()
    rec = load_recording(args.input, scan_topic=args.scan_topic, pose_source=args.pose_source,
                         laser_mount=args.laser_mount, max_range=args.max_range)
    grid = build_grid(rec.scans, args.resolution, model=args.model, extent=args.extent,
                      free_on_no_return=args.free_on_no_return or False, progress=args.progress)
    save_kw = {"mode": "scale"} if out.suffix.lower() in (".yaml", ".yml") else {}
    save_grid(grid, out, **save_kw)
    seconds = time.perf_counter() - start
    dropped = rec.meta.get("scans_dropped", 0)
    print(f"{args.input}: {len(rec.scans)} scans used ({dropped} dropped), pose source "
          f"{rec.meta.get('pose_source', '?')}, {grid.width}x{grid.height} cells at {grid.resolution:g} m, "
          f"{args.model}, {seconds:.2f} s -> {out}")
    return 0
