"""Small good and bad input files for the hostile-input catalogue (each written into a test folder)."""
from __future__ import annotations

import gzip
import math
import os
import struct
import zlib
from pathlib import Path

import numpy as np

from crfmap.grid import OccupancyGrid
from crfmap.recording import Recording, ScanSet, Trajectory


def good_grid(shape=(6, 8)):
    p = np.full(shape, 0.5)
    p[1:3, 2:5] = 0.9
    p[4, :] = 0.1
    return OccupancyGrid(p, resolution=0.05, origin=(1.0, 2.0, 0.0))


def good_npy(d, name="in.npy"):
    from crfmap.io.grid_files import save_grid

    return save_grid(good_grid(), Path(d) / name)


def good_map(d, name="map.yaml", mode="trinary"):
    from crfmap.io.grid_files import save_grid

    save_grid(good_grid(), Path(d) / name, mode=mode)
    return Path(d) / name


def map_yaml(d, text, name="bad.yaml", image=True):
    """A map YAML with the given text; ``image``: also write a good 8x6 PGM named img.pgm beside it."""
    d = Path(d)
    if image:
        (d / "img.pgm").write_bytes(b"P5\n8 6\n255\n" + bytes([254]) * 48)
    (d / name).write_text(text)
    return d / name


GOOD_YAML = "image: img.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"


def carmen_text(n_scans=4, n=9, reading=2.0, pose=(0.0, 0.0, 0.0), extra="", stamp=None):
    """A tiny corrected CARMEN log: n_scans FLASER lines of n equal readings plus ODOM lines."""
    lines = ["# message formats defined: PARAM SYNC ODOM FLASER", "PARAM robot_frontlaser_offset 0.0 nohost 0"]
    for k in range(n_scans):
        t = stamp if stamp is not None else 1.0 + k
        x, y, th = pose[0] + 0.1 * k, pose[1], pose[2]
        ranges = " ".join(f"{reading:.2f}" if isinstance(reading, float) else str(reading) for _ in range(n))
        lines.append(f"ODOM {x} {y} {th} 0.1 0.0 0.0 {t} nohost {t}")
        lines.append(f"FLASER {n} {ranges} {x} {y} {th} {x} {y} {th} {t} nohost {t}")
    return "\n".join(lines) + "\n" + extra


def carmen_log(d, text=None, name="log.log", **kw):
    path = Path(d) / name
    data = (text if text is not None else carmen_text(**kw)).encode()
    path.write_bytes(gzip.compress(data) if name.endswith(".gz") else data)
    return path


def gzip_bomb(path, expanded_mb=700, text=False):
    """A gzip file a few hundred kB long that expands to ``expanded_mb`` MB (concatenated members)."""
    member = gzip.compress((b"# no FLASER here\n" * (10 << 16))[: 10 << 20] if text else b"\0" * (10 << 20),
                           compresslevel=9)
    with open(path, "wb") as f:
        for _ in range(expanded_mb // 10):
            f.write(member)
    return path


def small_recording(n_scans=4, n_beams=8):
    ranges = np.full((n_scans, n_beams), 2.0, np.float32)
    stamps = 1.0 + 0.1 * np.arange(n_scans)
    poses = np.column_stack([0.1 * np.arange(n_scans), np.zeros(n_scans), np.zeros(n_scans)])
    scans = ScanSet(ranges, -1.0, 2.0 / (n_beams - 1), 0.1, 10.0, poses, stamps, frame_id="odom",
                    laser_frame_id="base_link")
    odom = Trajectory(stamps.copy(), poses.copy(), "odom", "base_link", np.zeros((n_scans, 2)))
    return Recording(scans, (0.0, 0.0, 0.0), odom, None)


def good_bag(d, name="bag", fmt="ros2"):
    from crfmap.io.bag_writer import write_bag

    path = Path(d) / name
    write_bag(small_recording(), path, fmt=fmt)
    return path


def tf_bag(d, quaternion, name="tfbag", fmt="ros2", x0=0.0):
    """A bag whose /tf odom -> base_link uses ``quaternion`` (x, y, z, w) and a scan in base_link; the robot
    drives along x from ``x0`` [m]."""

    from crfmap.io._rosmsgs import typestore

    store = typestore(fmt)
    T = store.types
    path = Path(d) / (name + (".bag" if fmt == "ros1" else ""))
    if fmt == "ros2":
        from rosbags.rosbag2 import Writer
        writer = Writer(path, version=9)
        ser = store.serialize_cdr
    else:
        from rosbags.rosbag1 import Writer
        writer = Writer(path)
        ser = store.serialize_ros1

    def tmsg(name):
        return name if fmt == "ros2" or "tf2" not in name else "tf2_msgs/msg/TFMessage"

    def header(t, frame):
        stamp = T["builtin_interfaces/msg/Time"](sec=int(t), nanosec=int(round(t % 1 * 1e9)))
        kw = dict(stamp=stamp, frame_id=frame)
        if fmt == "ros1":
            kw["seq"] = 0
        return T["std_msgs/msg/Header"](**kw)

    with writer as w:
        kw = {} if fmt == "ros1" else {}
        c_tf = w.add_connection("/tf", tmsg("tf2_msgs/msg/TFMessage"), typestore=store, **kw)
        c_scan = w.add_connection("/scan", tmsg("sensor_msgs/msg/LaserScan"), typestore=store)
        for k, t in enumerate((1.0, 1.5, 2.0, 2.5)):
            q = T["geometry_msgs/msg/Quaternion"](x=quaternion[0], y=quaternion[1], z=quaternion[2], w=quaternion[3])
            tr = T["geometry_msgs/msg/Transform"](translation=T["geometry_msgs/msg/Vector3"](x=x0 + 0.1 * k, y=0.0, z=0.0),
                                                  rotation=q)
            ts = T["geometry_msgs/msg/TransformStamped"](header=header(t, "odom"), child_frame_id="base_link",
                                                         transform=tr)
            msg = T["tf2_msgs/msg/TFMessage"](transforms=[ts])
            w.write(c_tf, int(t * 1e9), ser(msg, tmsg("tf2_msgs/msg/TFMessage")))
            if k in (1, 2):
                scan = T["sensor_msgs/msg/LaserScan"](
                    header=header(t, "base_link"), angle_min=-1.0, angle_max=1.0, angle_increment=0.5,
                    time_increment=0.0, scan_time=0.0, range_min=0.1, range_max=5.0,
                    ranges=np.ones(5, np.float32), intensities=np.zeros(0, np.float32))
                w.write(c_scan, int(t * 1e9), ser(scan, tmsg("sensor_msgs/msg/LaserScan")))
    return path


def png_header_only(path, width, height):
    """A PNG whose header claims width x height 8-bit grey pixels, with one tiny IDAT chunk."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    body = zlib.compress(b"\0" * 1000)
    Path(path).write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", body) + chunk(b"IEND", b""))
    return path


def npy_with_header(path, header: bytes, payload=b""):
    """A version 1.0/2.0 .npy with a hand-written header dict."""
    pad = (-(len(header) + 1 + 12)) % 64
    text = header + b" " * pad + b"\n"
    version = (1, 0) if len(text) < 65536 else (2, 0)
    size = struct.pack("<H", len(text)) if version == (1, 0) else struct.pack("<I", len(text))
    Path(path).write_bytes(b"\x93NUMPY" + bytes(version) + size + text + payload)
    return path


def fifo(path):
    os.mkfifo(path)
    return path


def deep_yaml(depth=20000):
    return "image: " + "[" * depth + "]" * depth + "\n"


def alias_bomb(levels=9):
    lines = ['a0: &a0 ["x","x","x","x","x","x","x","x","x"]']
    for i in range(1, levels):
        lines.append(f"a{i}: &a{i} [" + ",".join([f"*a{i - 1}"] * 9) + "]")
    return "\n".join(lines) + f"\nimage: *a{levels - 1}\nresolution: *a{levels - 1}\n"


__all__ = ["math"]
