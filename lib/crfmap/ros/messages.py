"""The messages the node exchanges, as plain values independent of the middleware, and their checks.

Backends read ROS 1/2 message objects by attribute (:func:`grid_message`, :func:`scan_message`, :func:`transforms_of`)
and build theirs from a :class:`GridMessage`; unusable messages raise :class:`BadMessage`.

>>> g = GridMessage(stamp_ns=5, frame_id="map", map_load_ns=5, resolution=0.5, width=2, height=1,
...                 origin=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0), data=np.array([-1, 100], np.int8))
>>> occupancy_grid(g).probability.tolist()
[[0.5, 1.0]]
>>> occupancy_grid(GridMessage(**{**g.__dict__, "width": 3}))
Traceback (most recent call last):
...
crfmap.ros.messages.BadMessage: data length: 2 cells for a 3 x 1 grid (width * height = 3)
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from types import SimpleNamespace

import numpy as np

from crfmap.io.nav2_values import occupancy_values
from crfmap.errors import InputError
from crfmap.frames import quaternion_to_yaw, yaw_to_quaternion
from crfmap.grid import MAX_EXTENT_M
from crfmap.io.map_server import grid_from_values
from crfmap.checks import check_cells

ANGLE_TOLERANCE = 1e-4  # [rad] float32 scan angles differing by less than this agree (as crfmap.io.bag_reader)


class BadMessage(ValueError):
    """A message the node skips: ``kind`` names the fault (logged once per kind), the text says why."""

    def __init__(self, kind, reason):
        self.kind = kind
        self.reason = reason
        super().__init__(f"{kind}: {reason}")


# --- plain values -----------------------------------------------------------------------------
@dataclass
class GridMessage:
    """nav_msgs/OccupancyGrid (and its MapMetaData) as plain values: ``origin`` (x, y, z, qx, qy, qz, qw) as received,
    so an output copies its input's info exactly; ``data`` int8, row-major from cell (0, 0)."""

    stamp_ns: int
    frame_id: str
    map_load_ns: int
    resolution: float  # [m/cell] (float32 on the wire)
    width: int
    height: int
    origin: tuple
    data: np.ndarray

    def with_data(self, data) -> "GridMessage":
        """The same header and info with new cell values."""
        return replace(self, data=np.ascontiguousarray(data, dtype=np.int8).reshape(-1))


@dataclass
class ScanMessage:
    """sensor_msgs/LaserScan as plain values (ranges float32 [m], REP 117)."""

    stamp_ns: int
    frame_id: str
    angle_min: float
    angle_max: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: np.ndarray


@dataclass
class Transform:
    """One geometry_msgs/TransformStamped as a planar pose of ``child`` in ``parent`` at ``stamp_ns``."""

    stamp_ns: int
    parent: str
    child: str
    pose: tuple  # (x [m], y [m], yaw [rad])


# --- reading any ROS message object -----------------------------------------------------------
def stamp_ns(stamp) -> int:
    """Nanoseconds of a builtin_interfaces/Time (sec, nanosec) or a ROS 1 time (secs, nsecs).

    >>> from types import SimpleNamespace as T
    >>> stamp_ns(T(sec=2, nanosec=5)), stamp_ns(T(secs=2, nsecs=5))
    (2000000005, 2000000005)
    """
    if hasattr(stamp, "nanosec"):
        return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
    return int(stamp.secs) * 1_000_000_000 + int(stamp.nsecs)


def stamp_parts(ns) -> tuple:
    """(seconds, nanoseconds) of a stamp in nanoseconds, as a ROS Time holds it."""
    ns = int(ns)
    return ns // 1_000_000_000, ns % 1_000_000_000


def grid_message(msg) -> GridMessage:
    """A nav_msgs/OccupancyGrid message object (any middleware) as a :class:`GridMessage`."""
    info = msg.info
    o = info.origin
    data = msg.data
    if isinstance(data, (bytes, bytearray, memoryview)):
        data = np.frombuffer(data, np.int8)  # rospy hands int8[] over as bytes... or a list
    return GridMessage(
        stamp_ns=stamp_ns(msg.header.stamp), frame_id=str(msg.header.frame_id), map_load_ns=stamp_ns(info.map_load_time),
        resolution=float(info.resolution), width=int(info.width), height=int(info.height),
        origin=(float(o.position.x), float(o.position.y), float(o.position.z), float(o.orientation.x),
                float(o.orientation.y), float(o.orientation.z), float(o.orientation.w)),
        data=np.asarray(data, dtype=np.int8).reshape(-1))


def scan_message(msg) -> ScanMessage:
    """A sensor_msgs/LaserScan message object (any middleware) as a :class:`ScanMessage`."""
    return ScanMessage(
        stamp_ns=stamp_ns(msg.header.stamp), frame_id=str(msg.header.frame_id), angle_min=float(msg.angle_min),
        angle_max=float(msg.angle_max), angle_increment=float(msg.angle_increment), range_min=float(msg.range_min),
        range_max=float(msg.range_max), ranges=np.asarray(msg.ranges, dtype=np.float32))


def transforms_of(msg):
    """``(transforms, faults)`` of a tf2_msgs/TFMessage: a transform whose translation is not finite or beyond
    :data:`crfmap.grid.MAX_EXTENT_M`, or whose quaternion is not a rotation, is a :class:`BadMessage` in ``faults``;
    the good ones of the same message still count."""
    out, faults = [], []
    for tr in msg.transforms:
        parent, child = str(tr.header.frame_id).lstrip("/"), str(tr.child_frame_id).lstrip("/")
        t, q = tr.transform.translation, tr.transform.rotation
        x, y = float(t.x), float(t.y)
        if not (math.isfinite(x) and math.isfinite(y)):
            faults.append(BadMessage("transform translation", f"{parent} -> {child}: ({x:g}, {y:g}) is not finite"))
            continue
        if max(abs(x), abs(y)) > MAX_EXTENT_M:  # as a bag's /tf (crfmap.io._rosmsgs.pose_of): a corrupt field
            faults.append(BadMessage("transform translation", f"{parent} -> {child}: ({x:g}, {y:g}) lies beyond "
                                                              f"{MAX_EXTENT_M:g} m"))
            continue
        try:
            yaw = quaternion_to_yaw(q, f"{parent} -> {child}")
        except InputError as exc:
            faults.append(BadMessage("non-unit quaternion", f"{exc.problem} ({parent} -> {child})"))
            continue
        out.append(Transform(stamp_ns(tr.header.stamp), parent, child, (x, y, yaw)))
    return out, faults


# --- checks -----------------------------------------------------------------------------------
def occupancy_grid(msg: GridMessage):
    """The :class:`~crfmap.grid.OccupancyGrid` of a grid message (values v -> v / 100, -1 -> 0.5), or BadMessage."""
    width, height, n = int(msg.width), int(msg.height), int(msg.data.size)
    if n == 0 and width * height == 0:  # consistent, but nothing to refine (a SLAM node before its first scan)
        raise BadMessage("empty map", f"the map is empty ({width} x {height} cells, no data): nothing to refine")
    if n != width * height:
        raise BadMessage("data length", f"{n} cells for a {width} x {height} grid (width * height = {width * height})")
    try:  # what crfmap infer refuses (crfmap --max-cells N, CRFMAP_MAX_CELLS), refused before any work
        check_cells("map", width, height)
    except InputError as exc:
        raise BadMessage("too many cells", exc.problem) from None
    resolution = float(str(np.float32(msg.resolution)))  # undo float32: 0.05, not 0.0500000007 (as bag_reader)
    if not (math.isfinite(resolution) and resolution > 0):
        raise BadMessage("resolution", f"{msg.resolution!r} is not a positive number of metres")
    x, y, _, qx, qy, qz, qw = msg.origin
    if not (math.isfinite(x) and math.isfinite(y)):
        raise BadMessage("origin", f"position ({x:g}, {y:g}) is not finite")
    try:
        yaw = quaternion_to_yaw(SimpleNamespace(x=qx, y=qy, z=qz, w=qw), "origin")
    except InputError as exc:
        raise BadMessage("non-unit quaternion", f"origin {exc.problem}") from None
    data = msg.data.reshape(height, width)
    bad = (data != -1) & ((data < 0) | (data > 100))
    if bad.any():
        raise BadMessage("values", f"{int(bad.sum())} cell(s) outside -1 and 0..100")
    # 50 stays a known 50, as when crfmap reads a bag's /map (crfmap.io.map_server.grid_from_values)
    try:
        return grid_from_values(data, resolution=resolution, origin=(x, y, yaw), frame_id=msg.frame_id or "map")
    except InputError as exc:  # e.g. an origin 1e300 m away: no map
        raise BadMessage("geometry", exc.problem) from None


def grid_out(grid, stamp_ns_, frame_id, values="trinary") -> GridMessage:
    """A :class:`GridMessage` of an OccupancyGrid, ``values`` as :func:`crfmap.io.nav2_values.occupancy_values`."""
    x, y, yaw = grid.origin
    qx, qy, qz, qw = yaw_to_quaternion(yaw)
    return GridMessage(stamp_ns=int(stamp_ns_), frame_id=frame_id, map_load_ns=int(stamp_ns_),
                       resolution=float(grid.resolution), width=grid.width, height=grid.height,
                       origin=(float(x), float(y), 0.0, qx, qy, qz, qw),
                       data=occupancy_values(grid, values).reshape(-1))


def check_scan(msg: ScanMessage) -> None:
    """Raise BadMessage for a scan the mapper cannot place (the rules of crfmap.io.bag_reader)."""
    a0, inc, a1, n = msg.angle_min, msg.angle_increment, msg.angle_max, int(msg.ranges.size)
    if not (math.isfinite(a0) and math.isfinite(a1) and math.isfinite(inc)) or inc == 0.0:
        raise BadMessage("angle_increment", f"angle_min {a0:g}, angle_max {a1:g}, angle_increment {inc:g}: "
                                            "angles must be finite with a non-zero increment")
    if n == 0:
        raise BadMessage("no ranges", "LaserScan without ranges")
    last = a0 + (n - 1) * inc
    if abs(last - a1) > abs(inc) * 1.0001 + 1e-6:
        raise BadMessage("ranges vs angles", f"{n} ranges disagree with the angles (angle_min {a0:.6g} + "
                                             f"(n - 1) * increment {inc:.6g} = {last:.6g}, angle_max {a1:.6g})")
    if not (math.isfinite(msg.range_min) and math.isfinite(msg.range_max) and 0 <= msg.range_min < msg.range_max):
        raise BadMessage("range limits", f"range_min {msg.range_min:g}, range_max {msg.range_max:g}")


def same_geometry(msg: ScanMessage, first: ScanMessage) -> None:
    """Raise BadMessage if ``msg``'s beams differ from the ``first`` scan's (the mapper's sensor)."""
    n, m = int(msg.ranges.size), int(first.ranges.size)
    if n != m:
        raise BadMessage("beam count", f"{n} beams, the first scan had {m}")
    if abs(msg.angle_min - first.angle_min) > ANGLE_TOLERANCE or abs(msg.angle_increment - first.angle_increment) * n > ANGLE_TOLERANCE:
        raise BadMessage("beam angles", f"angle_min {msg.angle_min:.6g}, increment {msg.angle_increment:.6g}; the first "
                                        f"scan had {first.angle_min:.6g}, {first.angle_increment:.6g}")
    if msg.frame_id.lstrip("/") != first.frame_id.lstrip("/"):
        raise BadMessage("laser frame", f"frame '{msg.frame_id}', the first scan was in '{first.frame_id}'")
