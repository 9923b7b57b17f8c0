"""Transforms as they arrive, and the laser's pose at a scan's stamp once tf covers it (tf2's ``canTransform``,
planar), computed exactly as :func:`crfmap.io.bag_reader.read_bag` does: a bag played into the node maps the same as
the bag read from its file.

>>> buffer = TfBuffer()
>>> buffer.add(Transform(0, "base_link", "laser", (0.1, 0.0, 0.0)), static=True)
>>> for ns, x in ((1_000_000_000, 0.0), (2_000_000_000, 2.0)):
...     buffer.add(Transform(ns, "odom", "base_link", (x, 0.0, 0.0)), static=False)
>>> status, pose, root = buffer.lookup("laser", 1.5)
>>> status, [round(v, 6) for v in pose], root
('ready', [1.1, 0.0, 0.0], 'odom')
>>> buffer.lookup("laser", 2.5)[0], buffer.lookup("laser", 0.5)[0]
('wait', 'never')
"""
from __future__ import annotations

import numpy as np

from crfmap.frames import TfTree, compose, interpolate_poses
from crfmap.ros.messages import Transform

MAX_SAMPLES = 20_000  # per moving transform; past it the older half goes (tf2 keeps 10 s)


def stamp_seconds(ns) -> float:
    """A stamp [ns] in seconds the way crfmap.io.bag_reader reads a header (sec + 1e-9 * nanosec)."""
    ns = int(ns)
    return ns // 1_000_000_000 + 1e-9 * (ns % 1_000_000_000)


class TfBuffer:
    """The tf tree of every transform received (``tree``: a :class:`crfmap.frames.TfTree`)."""

    def __init__(self):
        self.tree = TfTree()

    def add(self, transform: Transform, static: bool) -> None:
        stamp = None if static else stamp_seconds(transform.stamp_ns)
        self.tree.add(transform.parent, transform.child, transform.pose, stamp)
        if not static:
            track = self.tree.dynamic.get(transform.child.lstrip("/"), [None, []])[1]
            if len(track) > MAX_SAMPLES:
                del track[: len(track) // 2]

    def lookup(self, frame, stamp, fixed_frame=None):
        """(status, pose of ``frame`` in the fixed frame at ``stamp`` [s], fixed frame: ``fixed_frame`` or the root).

        ``status``: 'ready'; 'wait' (a moving transform has no sample at or after ``stamp`` yet, or the tree does not
        reach the fixed frame yet); 'never' (``stamp`` is before a moving transform's first sample)."""
        tree = self.tree
        frame = frame.lstrip("/")
        start, mount, _ = tree.static_chain(frame)  # as read_bag: the static mount first
        times = np.array([float(stamp)])
        poses = np.asarray(mount, np.float64)[None, :].copy()
        current, seen, moving = start, {start}, 0

        while current != fixed_frame:
            if current in tree.static:
                parent, p = tree.static[current]
                poses = compose(np.asarray(p), poses)
            elif current in tree.dynamic:
                parent, track = tree.dynamic[current]
                stamps = np.array([s for s, _ in track])
                if stamp < stamps.min():
                    return "never", None, None
                if stamp > stamps.max():
                    return "wait", None, None
                ref = stamps.min()
                at, _ = interpolate_poses(stamps - ref, np.array([p for _, p in track]), times - ref)
                poses = compose(at, poses)
                moving += 1
            else:
                break  # the root
            if parent in seen:
                return "wait", None, None  # a loop: a broken tree, perhaps mid-update
            seen.add(parent)
            current = parent
        if moving == 0 or (fixed_frame is not None and current != fixed_frame):
            return "wait", None, None
        return "ready", tuple(float(v) for v in poses[0]), current
