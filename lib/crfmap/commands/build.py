"""``crfmap build INPUT OUT_MAP``: an occupancy grid from a bag or a CARMEN log (thesis sec. 3.2)."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from crfmap.errors import InputError
from crfmap.io.recordings import load_recording


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


def add_ros2_bag_options(p):
    """How a ROS 2 bag is written (``simulate`` and ``convert``)."""
    p.add_argument("--storage", choices=["mcap", "sqlite3"], default=None,
                   help="ROS 2 storage: mcap (default; rosbag2's default since Jazzy, Humble reads it with "
                   "ros-humble-rosbag2-storage-mcap) or sqlite3 (Humble's default)")
    p.add_argument("--distro", choices=["humble", "jazzy"], default=None,
                   help="whose rosbag2 files to write: humble (default: metadata version 5, sqlite3 schema 3; "
                   "every later rosbag2 reads them) or jazzy (version 9, schema 4, type hashes; Humble cannot "
                   "read them)")


def ros2_bag_kwargs(args, fmt):
    """write_bag keywords from the ROS 2 bag options; they do not apply to ROS 1 bags."""
    if fmt == "ros1":
        for flag in ("storage", "distro"):
            if getattr(args, flag, None) is not None:
                raise InputError("--" + flag, "applies to ROS 2 bags only, not to ROS 1 .bag files")
        return {}
    return {"storage": args.storage or "mcap", "distro": args.distro or "humble"}


def add_map_output_options(p):
    """How a map_server YAML output is written, and which nav2 loader judges it (shared with ``infer``)."""
    p.add_argument("--mode", default=None, choices=["trinary", "scale", "raw"],
                   help="map_server mode of a YAML output. trinary (default): nav2's map_saver's, P >= 0.65 occupied, "
                   "P <= 0.2 free, else unknown. scale: P to a percent, NOT for navigation (nav2 sees almost no "
                   "obstacles). Exact probabilities: write a .npy")
    p.add_argument("--save-occupied-thresh", type=float, default=None, metavar="P",
                   help="occupied_thresh of a YAML output (default: map_saver's 0.65; scale: 1)")
    p.add_argument("--save-free-thresh", type=float, default=None, metavar="P",
                   help="free_thresh of a YAML output (default: map_saver's 0.196; scale: 0)")
    p.add_argument("--loader", default="jazzy", choices=["humble", "jazzy"],
                   help="nav2 map loader whose rules read YAML maps: jazzy (Jazzy, Kilted, Rolling; default) "
                   "or humble")


def save_map_output(grid, out, args) -> str:
    """Save ``grid`` to ``out`` with the map output options; returns what nav2 will see, counted on the written file
    loaded back with nav2's rules (``args.loader``) and the costmap's defaults."""
    from crfmap.io.grid_files import save_grid

    if str(out).lower().endswith((".yaml", ".yml")):
        args.mode = args.mode or "trinary"
        from crfmap.io.map_server import FREE_THRESH_DEFAULT, OCCUPIED_THRESH_DEFAULT, load_map
        from crfmap.io.nav2_costmap import describe_for_nav2

        occ, free = args.save_occupied_thresh, args.save_free_thresh
        if args.mode == "trinary":  # map_saver's thresholds, not those of a loaded input map
            occ = OCCUPIED_THRESH_DEFAULT if occ is None else occ
            free = FREE_THRESH_DEFAULT if free is None else free
        save_grid(grid, out, mode=args.mode, occupied_thresh=occ, free_thresh=free, saver="jazzy")
        seen = load_map(out, loader=args.loader).to_int8()
        return f"{describe_for_nav2(seen)} ({args.loader} loader; P >= 0.65 in the grid: " \
               f"{int((grid.probability >= 0.65).sum())})"
    if getattr(args, "mode", None) is not None:
        raise InputError("--mode", f"applies to map_server YAML outputs only, not to {out}")
    for flag in ("save_occupied_thresh", "save_free_thresh"):
        if getattr(args, flag, None) is not None:
            raise InputError("--" + flag.replace("_", "-"), "applies to map_server YAML outputs only, not .npy")
    save_grid(grid, out)
    return "exact probabilities (.npy, not a nav2 map)"


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
    p.add_argument("output", help="map_server YAML (trinary by default, see --mode) or .npy (exact P)")
    p.add_argument("--resolution", type=float, default=0.05, help="cell size in metres (default 0.05)")
    p.add_argument("--model", choices=["arctan", "logodds"], default="arctan",
                   help="arctan: thesis eq. 16 (default); logodds: Probabilistic Robotics ch. 9")
    p.add_argument("--free-on-no-return", type=float, default=None, metavar="M",
                   help="mark cells free up to M metres along beams that returned nothing (+Inf)")
    add_bag_options(p)
    p.add_argument("--bounds", type=float, nargs=4, default=None, metavar=("XMIN", "YMIN", "XMAX", "YMAX"),
                   help="area to map in metres (default: the data's bounding box)")
    p.add_argument("--progress", action="store_true", default=None,
                   help="show a progress bar (default: when stderr is a terminal)")
    add_map_output_options(p)
    p.add_argument("--force", action="store_true", help="allow OUT_MAP to replace INPUT")
    return p


def run(args: argparse.Namespace) -> int:
    from crfmap.mapping.builder import build_grid

    from crfmap.commands.outputs import check_grid_output, check_output

    check_grid_output(args.output)  # before Path() drops a trailing '/'
    out = Path(args.output)

    check_output([args.input], out, force=args.force)
    start = time.perf_counter()
    rec = load_recording(args.input, scan_topic=args.scan_topic, pose_source=args.pose_source,
                         laser_mount=args.laser_mount, max_range=args.max_range)
    grid = build_grid(rec.scans, args.resolution, model=args.model, bounds=args.bounds,
                      free_on_no_return=args.free_on_no_return or False,
                      progress=args.progress or sys.stderr.isatty())
    nav2_view = save_map_output(grid, out, args)
    seconds = time.perf_counter() - start
    dropped = rec.meta.get("scans_dropped", 0)
    print(f"{args.input}: {len(rec.scans)} scans used ({dropped} dropped), pose source "
          f"{rec.meta.get('pose_source', '?')}, {grid.width}x{grid.height} cells at {grid.resolution:g} m, "
          f"{args.model}, {seconds:.2f} s -> {out}: {nav2_view}")
    return 0
