"""``crfmap convert INPUT OUT_BAG``: a CARMEN log (or a bag) as a ROS2 or ROS1 bag."""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from crfmap.errors import InputError
from crfmap.commands.build import add_bag_options, add_ros2_bag_options, ros2_bag_kwargs
from crfmap.io.recordings import load_recording


def add_parser(sub):
    p = sub.add_parser(
        "convert",
        help="convert a CARMEN log (or a bag) to a ROS2 or ROS1 bag",
        description="Write /scan, /odom, /tf, /tf_static and /ground_truth_pose (corrected poses) of a CARMEN "
        "log, or a bag, as a ROS bag. No message gets time 0 (ROS reads it as 'no time'): ODOM records stamped 0 "
        "or out of order are dropped, stamps starting at 0 shifted by 1700000000 s, and scans whose stamps cannot "
        "place them stamped by their order, 0.1 s apart (odometry dropped), each with a warning.",
    )
    p.add_argument("input", help="CARMEN log (.log / .log.gz), ROS1 .bag or ROS2 bag folder")
    p.add_argument("output", help="ROS2 bag folder, or ROS1 file ending in .bag")
    p.add_argument("--format", choices=["ros2", "ros1"], default=None,
                   help="bag format (default: ros1 if OUT_BAG ends in .bag, else ros2)")
    add_bag_options(p)
    add_ros2_bag_options(p)
    return p


def recording_stamps(rec):
    """Every stamp [s] of a recording: scans, odometry, true poses, cmd_vel."""
    tracks = [rec.scans] + [t for t in (rec.odometry, rec.true_poses, rec.cmd_vel) if t is not None]
    return np.concatenate([np.asarray(t.stamps, np.float64) for t in tracks])


ORDER_PERIOD = 0.1  # [s] between scans stamped by their order (10 Hz, a common laser rate in CARMEN logs)


def stamps_from_order(rec, source):
    """``rec``, or, if its scan stamps cannot place them in a tf tree (all 0, or repeated at different poses), ``rec``
    with scan i stamped ``START_TIME + i * ORDER_PERIOD``, true poses with it, odometry and cmd_vel dropped, warned."""
    from crfmap.io.bag_writer import clashing_scans
    from crfmap.sim.simulator import START_TIME

    clashes = clashing_scans(rec.scans, rec.laser_mount)
    if not clashes:
        return rec
    scan_stamps = np.asarray(rec.scans.stamps, np.float64)
    stamps = START_TIME + ORDER_PERIOD * np.arange(len(scan_stamps))
    dropped = [name for name in ("odometry", "cmd_vel") if getattr(rec, name) is not None and len(getattr(rec, name))]
    truth = rec.true_poses
    if truth is not None and np.array_equal(np.asarray(truth.stamps, np.float64), scan_stamps):
        truth = replace(truth, stamps=stamps.copy())  # the poses the scans were taken at
    elif truth is not None:
        truth, dropped = None, dropped + ["true poses"]
    said = ("every scan is stamped 0" if not np.any(scan_stamps) else
            f"{len(clashes)} of {len(scan_stamps)} scans repeat a stamp at another pose")
    warnings.warn(f"{source}: {said}, so tf cannot place them; stamped by their order instead, "
                  f"{START_TIME:.0f} s + {ORDER_PERIOD:g} s per scan"
                  + (f"; {' and '.join(dropped)} dropped (their stamps do not fit those)" if dropped else ""),
                  stacklevel=2)
    return replace(rec, scans=replace(rec.scans, stamps=stamps), true_poses=truth, odometry=None, cmd_vel=None)


def shift_zero_start(rec, source):
    """``rec``, its stamps shifted by the simulator's start time if any rounds to 0 ns, with a warning: a clock that
    starts at 0 is an older simulation's, and shifted it is what a rerun writes now."""
    from crfmap.sim.simulator import START_TIME

    if np.min(recording_stamps(rec)) >= 0.5e-9:
        return rec
    warnings.warn(f"{source}: stamps start at 0 s, which ROS reads as 'no time'; every stamp shifted by "
                  f"{START_TIME:.0f} s", stacklevel=2)
    moved = {}
    for name in ("odometry", "true_poses", "cmd_vel"):
        track = getattr(rec, name)
        if track is not None:
            moved[name] = replace(track, stamps=np.asarray(track.stamps, np.float64) + START_TIME)
    return replace(rec, scans=replace(rec.scans, stamps=np.asarray(rec.scans.stamps, np.float64) + START_TIME),
                   **moved)


def run(args: argparse.Namespace) -> int:
    from crfmap.io.bag_writer import write_bag

    out = Path(args.output)
    fmt = args.format or ("ros1" if out.suffix == ".bag" else "ros2")
    if fmt == "ros1" and out.suffix != ".bag":
        raise InputError(out, "a ROS1 bag file must end in .bag")
    if fmt == "ros2" and out.suffix == ".bag":
        raise InputError(out, "a ROS2 bag is a folder; drop the .bag suffix or use --format ros1")
    if Path(args.input).resolve() == out.resolve():
        raise InputError(out, "the output would replace the input")
    from crfmap.commands.outputs import check_output_folder

    check_output_folder(out)
    start = time.perf_counter()
    rec = load_recording(args.input, scan_topic=args.scan_topic, pose_source=args.pose_source,
                         laser_mount=args.laser_mount, max_range=args.max_range, uses_odometry=True)
    rec = shift_zero_start(stamps_from_order(rec, args.input), args.input)
    write_bag(rec, out, fmt=fmt, progress=sys.stderr.isatty(), **ros2_bag_kwargs(args, fmt))
    n_odom = len(rec.odometry) if rec.odometry is not None else 0
    print(f"{args.input}: {len(rec.scans)} scans, {n_odom} odometry poses -> {fmt} bag {out} "
          f"({time.perf_counter() - start:.2f} s)")
    return 0
