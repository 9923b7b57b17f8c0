"""``crfmap node refine|map``: crfmap live between SLAM and navigation, over ROS 2 (DDS) or ROS 1; SIGINT and
SIGTERM end it cleanly, and it prints what it did on stderr."""
from __future__ import annotations

import argparse
import signal
import threading

from crfmap.io.nav2_values import VALUE_MODES
from crfmap.crf.presets import DEFAULT_PRESET, PRESETS
from crfmap.errors import InputError
from crfmap.checks import check_number

BACKENDS = ("dds", "rclpy", "rospy")


def add_parser(sub):
    p = sub.add_parser(
        "node", help="run crfmap as a live ROS node: refine maps, or map from scans and tf",
        description="A live ROS node. 'refine': subscribe to a nav_msgs/OccupancyGrid (e.g. slam_toolbox's /map), "
        "refine each new map as 'crfmap infer' does, publish it with the same header and info. 'map': map online "
        "from sensor_msgs/LaserScan and tf, publish /map and /map_metadata, and on stop the converged final map.")
    modes = p.add_subparsers(dest="mode", metavar="MODE", required=True)
    refine = modes.add_parser("refine", help="refine each new OccupancyGrid and publish it")
    refine.add_argument("--input", default="/map", metavar="TOPIC", help="nav_msgs/OccupancyGrid to refine (default /map)")
    refine.add_argument("--output", default="/map_refined", metavar="TOPIC",
                        help="where the refined map goes (default /map_refined)")
    mapping = modes.add_parser("map", help="map online from LaserScan and tf")
    mapping.add_argument("--scan", default="/scan", metavar="TOPIC", help="sensor_msgs/LaserScan topic (default /scan)")
    mapping.add_argument("--map", default="/map", metavar="TOPIC", help="map topic to publish (default /map)")
    mapping.add_argument("--metadata", default="/map_metadata", metavar="TOPIC",
                         help="nav_msgs/MapMetaData topic to publish (default /map_metadata)")
    mapping.add_argument("--bounds", type=float, nargs=4, default=(-20.0, -20.0, 20.0, 20.0),
                         metavar=("XMIN", "YMIN", "XMAX", "YMAX"),
                         help="the map's extent in the fixed frame [m] (default -20 -20 20 20; the map does not grow)")
    mapping.add_argument("--resolution", type=float, default=0.05, metavar="M", help="cell size [m] (default 0.05)")
    mapping.add_argument("--fixed-frame", default=None, metavar="FRAME",
                         help="frame to map in (default: the root of the tf tree, map when map -> odom is published)")
    mapping.add_argument("--radius", type=float, default=4.0, metavar="M",
                         help="LBP runs within this distance of the laser after each scan (default 4)")
    mapping.add_argument("--preset", choices=list(PRESETS), default=DEFAULT_PRESET,
                         help=f"the CRF's configuration, as for 'crfmap infer' (crfmap.crf.presets; default "
                         f"{DEFAULT_PRESET}): " + "; ".join(f"{name}: {p.purpose}" for name, p in PRESETS.items()))
    mapping.add_argument("--margin", type=int, default=None, metavar="CELLS",
                         help="only cells within CELLS of an observed cell take part (default: the preset's, "
                         + ", ".join(f"{name} {'every cell' if p.margin is None else p.margin}"
                                     for name, p in PRESETS.items()) + "; -1: every cell, the thesis's model)")
    mapping.add_argument("--scan-log", default=None, metavar="FILE",
                         help="write one line per integrated scan: stamp [ns] and laser pose x y yaw in the fixed "
                         "frame (what the published map holds)")
    for mode in (refine, mapping):
        mode.add_argument("--backend", choices=BACKENDS, default="dds",
                          help="dds (default): ROS 2 over Cyclone DDS, no ROS install needed; rclpy: a ROS 2 "
                          "install's client library; rospy: ROS 1 through a running roscore")
        mode.add_argument("--domain", type=int, default=None, metavar="ID",
                          help="DDS domain (default: $ROS_DOMAIN_ID, else 0; dds backend)")
        mode.add_argument("--period", type=float, default=1.0, metavar="S",
                          help="publish at most once per S seconds (default 1)")
        mode.add_argument("--values", choices=VALUE_MODES, default="trinary",
                          help="what the published OccupancyGrid holds: trinary (default: 100 lethal, 0 free, -1 "
                          "unknown, as map_server publishes crfmap infer's map) or percent (P x 100)")
    return p


def _check(args):
    check_number("--period", args.period, low=0.0)
    if args.mode == "map":
        check_number("--resolution", args.resolution, low=0.0, low_open=True)
        xmin, ymin, xmax, ymax = args.bounds
        if not (xmin < xmax and ymin < ymax):
            raise InputError("--bounds", f"need XMIN < XMAX and YMIN < YMAX, got {' '.join(f'{v:g}' for v in args.bounds)}")
        check_number("--radius", args.radius, low=0.0, low_open=True)
        if args.margin is not None and args.margin < -1:
            raise InputError("--margin", f"must be -1 or a whole number of cells, got {args.margin}")
    if args.domain is not None and args.backend != "dds":
        raise InputError("--domain", f"applies to the dds backend only (the {args.backend} backend has its own setup)")
    if args.backend == "dds":  # the middleware's settings, before any work: a bad one is refused in one line
        from crfmap.ros.dds import dds_configuration, domain_id

        domain_id(args.domain)
        dds_configuration()


def make_backend(name, domain=None):
    """The backend called ``name``; InputError (one line) when its middleware is not importable."""
    if name == "dds":
        from crfmap.ros.dds import DdsBackend

        return DdsBackend(domain)
    if name == "rclpy":
        from crfmap.ros.rclpy_backend import RclpyBackend

        return RclpyBackend()
    from crfmap.ros.rospy_backend import RospyBackend

    return RospyBackend()


def make_node(args):
    from crfmap.ros.node import MapNode, RefineNode

    if args.mode == "refine":
        return RefineNode(args.input, args.output, period=args.period, values=args.values)
    options = {"preset": args.preset, "radius": args.radius}
    if args.margin is not None:  # else the preset's own
        options["margin"] = None if args.margin == -1 else args.margin
    return MapNode(args.bounds, args.resolution, scan_topic=args.scan, map_topic=args.map,
                   metadata_topic=args.metadata, fixed_frame=args.fixed_frame, period=args.period,
                   mapper_options=options, scan_log=args.scan_log, values=args.values)


def run(args: argparse.Namespace) -> int:
    from crfmap.ros.node import log_line, spin

    _check(args)
    node = make_node(args)
    backend = make_backend(args.backend, args.domain)
    stop = threading.Event()
    previous = {sig: signal.signal(sig, lambda signum, frame: stop.set()) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        log_line(f"{args.mode} mode over {args.backend}; SIGINT or SIGTERM ends it")
        summary = spin(node, backend, stop)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        backend.close()
        getattr(node, "close", lambda: None)()
    log_line(f"stopped: {summary}")
    return 0
