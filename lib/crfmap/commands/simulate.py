"""``crfmap simulate SCENE OUT_BAG``: drive a simulated robot through a scene and record a ROS bag."""
from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from crfmap.errors import InputError
from crfmap.world.scene import MODES
from crfmap.world.scenes import SCENES, make_scene
from crfmap.commands.build import add_ros2_bag_options, ros2_bag_kwargs
from crfmap.checks import check_int, check_number


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "simulate",
        help="simulate a robot with a laser in a ground-truth scene and write a ROS bag",
        description="Simulate a robot with a laser scanner in a ground-truth scene (thesis sec. 3.1) and write "
        "what it recorded (scans, odometry, true poses, cmd_vel, ground-truth map) as a ROS bag.",
    )
    p.add_argument("scene", metavar="SCENE", choices=list(SCENES), help=f"one of: {', '.join(SCENES)}")
    p.add_argument("out", metavar="OUT_BAG", help="bag to write (a folder for ros2, a .bag file for ros1)")
    p.add_argument("--format", choices=("ros2", "ros1"), default="ros2", help="bag format (default ros2)")
    p.add_argument("--seed", type=int, default=0, help="seed of all simulated noise (default 0)")
    p.add_argument("--scene-seed", type=int, default=None,
                   help="seed of the scene's layout (default: the canonical layout; office: 0)")
    p.add_argument("--mode", choices=MODES, default=None,
                   help="explore = visit every reachable cell, look = turn in place at the start, "
                   "waypoints = drive through the scene's waypoints (default: the scene's own)")
    p.add_argument("--fov", type=float, default=360.0, metavar="DEG", help="laser field of view [deg] (default 360)")
    p.add_argument("--beams", type=int, default=360, metavar="N", help="beams per scan (default 360)")
    p.add_argument("--range", type=float, default=5.0, metavar="M", dest="range_max",
                   help="laser maximum range [m] (default 5)")
    p.add_argument("--range-min", type=float, default=0.05, metavar="M", help="laser minimum range [m] (default 0.05)")
    p.add_argument("--range-noise", type=float, default=0.0, metavar="C",
                   help="ranges read d +- c, c uniform in [0, C] [m] (default 0)")
    p.add_argument("--range-sigma", type=float, default=0.0, metavar="S", help="extra Gaussian range noise [m]")
    p.add_argument("--odom-noise", type=float, default=0.0, metavar="C",
                   help="odometry reads each step's translation +- c, c uniform in [0, C] [m] (default 0: perfect)")
    p.add_argument("--odom-yaw-noise", type=float, default=0.0, metavar="C",
                   help="odometry reads each step's turn +- c, c uniform in [0, C] [rad] (default 0)")
    p.add_argument("--stride", type=int, default=None, metavar="N",
                   help="explore mode only: look around only every N cells (default 1: at every cell)")
    p.add_argument("--resolution", type=float, default=None, metavar="M",
                   help="cell size of the scene [m] (default 0.1; office 0.05)")
    p.add_argument("--start-time", type=float, default=None, metavar="S",
                   help="stamp of the first pose [s since the epoch] (default 1700000000: wall-clock-like, fixed so "
                   "that reruns are identical; > 0, as ROS reads 0 as 'no time')")
    p.add_argument("--legacy-no-return", action="store_true",
                   help="report beams that hit nothing as -1 (the thesis) instead of +inf (REP 117)")

    add_ros2_bag_options(p)
    p.add_argument("--overwrite", action="store_true", help="replace OUT_BAG if it exists")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    return p


MAX_BEAMS = 100_000  # beams per scan; real scanners have a few thousand


def check_options(args):
    """Refuse options no laser or robot can have, before any work (InputError naming the option)."""
    check_int("--beams", args.beams, low=1, high=MAX_BEAMS)
    check_number("--fov", args.fov, low=0.0, low_open=True, high=360.0)
    check_number("--range", args.range_max, low=0.0, low_open=True, high=1e4)
    check_number("--range-min", args.range_min, low=0.0)
    if args.range_min >= args.range_max:
        raise InputError("--range-min", f"must be below --range ({args.range_max:g} m), got {args.range_min:g}")
    for flag, value in (("--range-noise", args.range_noise), ("--range-sigma", args.range_sigma),
                        ("--odom-noise", args.odom_noise), ("--odom-yaw-noise", args.odom_yaw_noise)):
        check_number(flag, value, low=0.0)
    if args.stride is not None:
        check_int("--stride", args.stride, low=1)
    check_int("--seed", args.seed, low=0)
    if args.scene_seed is not None:
        check_int("--scene-seed", args.scene_seed, low=0)
    if args.resolution is not None:
        check_number("--resolution", args.resolution, low=0.001, high=10.0)
    if getattr(args, "start_time", None) is not None:
        check_number("--start-time", args.start_time, low=0.0, low_open=True, high=4e9)  # ROS 1 time: uint32 s


def build_recording(args):
    """The simulated :class:`~crfmap.recording.Recording` the command would write (no file touched)."""
    check_options(args)
    from crfmap.sim.drives import Explore
    from crfmap.sim.laser import LEGACY_NO_RETURN, Laser
    from crfmap.sim.simulator import START_TIME, simulate

    scene_kwargs = {}
    if args.scene_seed is not None:
        if args.scene == "x":
            raise InputError("--scene-seed", "the 'x' scene is a fixed image; it takes no seed")
        scene_kwargs["seed"] = args.scene_seed
    if args.resolution is not None:
        if not (math.isfinite(args.resolution) and args.resolution > 0):
            raise InputError("--resolution", f"must be a positive number of metres, got {args.resolution:g}")
        scene_kwargs["resolution"] = args.resolution
    scene = make_scene(args.scene, **scene_kwargs)
    for flag, value in (("--range", args.range_max), ("--range-min", args.range_min), ("--fov", args.fov)):
        if not math.isfinite(value):
            raise InputError(flag, f"must be a finite number, got {value}")
    laser = Laser.with_fov(args.fov, args.beams, range_max=args.range_max, range_min=args.range_min,
                           no_return=LEGACY_NO_RETURN if args.legacy_no_return else math.inf)
    mode = args.mode or scene.default_mode
    if args.stride is not None and mode != "explore":
        raise InputError("--stride", f"applies to --mode explore only, not {mode}")
    drive = Explore(stride=args.stride) if args.stride is not None else mode
    return simulate(
        scene,
        laser,
        drive,
        seed=args.seed,
        range_noise=args.range_noise,
        range_sigma=args.range_sigma,
        odometry_noise=(args.odom_noise, args.odom_yaw_noise),
        t0=START_TIME if getattr(args, "start_time", None) is None else args.start_time,
        progress=not args.quiet,
    )


def run(args) -> int:
    out = Path(args.out)
    bag_kwargs = ros2_bag_kwargs(args, args.format)
    if (out.exists() or out.is_symlink()) and not args.overwrite:
        raise InputError(out, "already exists; pass --overwrite to replace it")
    from crfmap.commands.outputs import check_output_folder

    check_output_folder(out)  # --overwrite replaces a bag, never a folder of other files
    check_options(args)
    started = time.perf_counter()
    recording = build_recording(args)
    from crfmap.io.bag_writer import write_bag

    write_bag(recording, out, fmt=args.format, **bag_kwargs)
    if not args.quiet:
        scans = recording.scans
        print(f"wrote {out} ({args.format}): {args.scene}, mode {recording.meta['mode']}, {len(scans)} scans x "
              f"{scans.ranges.shape[1]} beams, {len(recording.true_poses)} poses, "
              f"{recording.true_poses.stamps[-1] - recording.true_poses.stamps[0]:.1f} s simulated, "
              f"{time.perf_counter() - started:.2f} s")
    return 0
