"""Planar poses (x, y, yaw) and the tf tree that chains them (REP 103 / REP 105).

A pose ``a`` of frame A in its parent P is the transform that takes coordinates in A to coordinates in P.
:func:`compose` chains them (``compose(map_T_odom, odom_T_base)`` is base_link in map), :func:`inverse` undoes one,
:func:`interpolate_poses` samples a moving one in time; all are vectorised over leading axes (a row of 3 or (n, 3)).
:class:`TfTree` holds the transforms of a bag's ``/tf`` and ``/tf_static`` and follows them from a frame up to the
root of its tree at given times, as ``tf2`` ``lookupTransform`` does for a planar robot.
"""
from __future__ import annotations

import math

import numpy as np

from crfmap.errors import InputError

TWO_PI = 2.0 * math.pi


def wrap_angle(a):
    """Angles wrapped to [-pi, pi), as float64.

    >>> wrap_angle([np.pi, -np.pi, 4.0]).round(4).tolist()
    [-3.1416, -3.1416, -2.2832]
    """
    return (np.asarray(a, dtype=np.float64) + np.pi) % (2 * np.pi) - np.pi


def compose(a, b):
    """Pose ``a`` then ``b`` (b expressed in a's frame): the pose of b's frame in a's parent.

    >>> compose([1.0, 0.0, np.pi / 2], [1.0, 0.0, 0.0]).round(6).tolist()
    [1.0, 1.0, 1.570796]
    """
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([a[..., 0] + c * b[..., 0] - s * b[..., 1],
                     a[..., 1] + s * b[..., 0] + c * b[..., 1],
                     wrap_angle(a[..., 2] + b[..., 2])], axis=-1)


def inverse(a):
    """The pose whose composition with ``a`` is the identity.

    >>> inverse([1.0, 0.0, np.pi / 2]).round(6).tolist()
    [-0.0, 1.0, -1.570796]
    """
    a = np.asarray(a, np.float64)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([-c * a[..., 0] - s * a[..., 1], s * a[..., 0] - c * a[..., 1], wrap_angle(-a[..., 2])], axis=-1)


def interpolate_poses(stamps, poses, times):
    """Poses at ``times`` by linear interpolation (yaw unwrapped), and a mask of times inside the track (outside,
    the end pose). Of several poses at one stamp the last wins.

    >>> p, ok = interpolate_poses([0.0, 1.0], [[0, 0, 3.0], [2, 0, -3.0]], [0.5, 2.0])
    >>> p[0].round(3).tolist(), ok.tolist()
    ([1.0, 0.0, -3.142], [True, False])
    """
    stamps = np.asarray(stamps, np.float64)
    poses = np.asarray(poses, np.float64)
    times = np.asarray(times, np.float64)
    order = np.argsort(stamps, kind="stable")
    stamps, poses = stamps[order], poses[order]
    keep = np.append(np.diff(stamps) > 0, True)  # the last of equal stamps wins
    stamps, poses = stamps[keep], poses[keep]
    yaw = np.unwrap(poses[:, 2])
    out = np.stack([np.interp(times, stamps, poses[:, 0]), np.interp(times, stamps, poses[:, 1]),
                    wrap_angle(np.interp(times, stamps, yaw))], axis=-1)
    # a pose sampled exactly at a knot keeps its value bit for bit (the unwrap/wrap round trip of yaw is not exact)
    idx = np.searchsorted(stamps, times)
    exact = (idx < len(stamps)) & (stamps[np.minimum(idx, len(stamps) - 1)] == times)
    out[exact, 2] = poses[idx[exact], 2]
    inside = (times >= stamps[0]) & (times <= stamps[-1])
    return out, inside


def yaw_to_quaternion(yaw):
    """(x, y, z, w) of a rotation by ``yaw`` [rad] about +z.

    >>> [round(v, 6) for v in yaw_to_quaternion(np.pi / 2)]
    [0.0, 0.0, 0.707107, 0.707107]
    """
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


QUATERNION_NORM_TOLERANCE = 0.01  # tf2 refuses |x²+y²+z²+w² - 1| above this (TF_DENORMALIZED_QUATERNION)


def quaternion_to_yaw(q, source="quaternion"):
    """Yaw [rad] of a quaternion ``q`` with attributes x, y, z, w (e.g. a geometry_msgs/Quaternion).

    tf2's rule: a squared norm more than :data:`QUATERNION_NORM_TOLERANCE` from 1 is an InputError naming ``source``;
    one within it is normalised before use (the yaw formula holds for unit quaternions only).

    >>> from types import SimpleNamespace as Q
    >>> round(quaternion_to_yaw(Q(x=0.0, y=0.0, z=0.7071, w=0.7071)), 4)
    1.5708
    >>> quaternion_to_yaw(Q(x=0.0, y=0.0, z=0.0, w=0.0), "/tf odom -> base_link")
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: /tf odom -> base_link: quaternion (0, 0, 0, 0) is not a rotation (squared norm 0; tf2 refuses more than 0.01 away from 1)
    """
    x, y, z, w = float(q.x), float(q.y), float(q.z), float(q.w)
    norm2 = x * x + y * y + z * z + w * w
    if not (math.isfinite(norm2) and abs(norm2 - 1.0) <= QUATERNION_NORM_TOLERANCE):
        raise InputError(source, f"quaternion ({x:g}, {y:g}, {z:g}, {w:g}) is not a rotation (squared norm "
                                 f"{norm2:g}; tf2 refuses more than {QUATERNION_NORM_TOLERANCE:g} away from 1)")
    n = math.sqrt(norm2)
    x, y, z, w = x / n, y / n, z / n, w / n
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


class TfTree:
    """Static and moving transforms between frames, each frame with one parent (a tf tree).

    ``static[child] = (parent, pose)``; ``dynamic[child] = [parent, [(stamp [s], pose), ...]]``. Frame names lose a
    leading '/' (ROS1's '/odom' is 'odom' in tf2). ``conflicts`` counts moving transforms of a second parent, ignored.

    >>> tree = TfTree()
    >>> tree.add("base_link", "laser", (0.1, 0.0, 0.0))
    >>> for t, x in ((0.0, 0.0), (1.0, 2.0)):
    ...     tree.add("odom", "base_link", (x, 0.0, 0.0), stamp=t)
    >>> poses, inside, root, moving = tree.poses_in_root("laser", (0.0, 0.0, 0.0), np.array([0.5]))
    >>> poses.round(6).tolist(), root, moving
    ([[1.1, 0.0, 0.0]], 'odom', 1)
    """

    def __init__(self):
        self.static = {}
        self.dynamic = {}
        self.conflicts = 0

    def add(self, parent, child, pose, stamp=None):
        """Add the pose of ``child`` in ``parent``: static (``stamp=None``) or at ``stamp`` [s]."""
        parent, child = parent.lstrip("/"), child.lstrip("/")
        if stamp is None:
            self.static[child] = (parent, pose)  # the latest static transform of a frame wins
            return
        entry = self.dynamic.setdefault(child, [parent, []])
        if entry[0] != parent:
            self.conflicts += 1  # a frame has one parent in a tf tree; ignore the others
            return
        entry[1].append((stamp, pose))

    def static_chain(self, frame, stop=None):
        """Follow the static transforms up from ``frame`` until ``stop``, a frame without a static parent, or a loop:
        (top frame, pose of ``frame`` in it, frames passed)."""
        pose = np.zeros(3)
        passed = [frame]
        while frame in self.static and frame != stop:
            parent, p = self.static[frame]
            pose = compose(p, pose)
            frame = parent
            if frame in passed:
                break  # a loop: a broken tf tree
            passed.append(frame)
        return frame, pose, passed

    def poses_in_root(self, start_frame, start_pose, times, source="tf"):
        """(poses (n, 3) of ``start_frame`` (times ``start_pose``) in the root of the tree at ``times`` [s], mask of
        times inside every moving transform's span, root frame, moving transforms passed); a loop: InputError."""
        poses = np.broadcast_to(start_pose, (len(times), 3)).copy()
        inside = np.ones(len(times), bool)
        frame, seen, moving = start_frame, {start_frame}, 0
        while True:
            if frame in self.static:
                parent, p = self.static[frame]
                poses = compose(np.asarray(p), poses)
            elif frame in self.dynamic:
                parent, track = self.dynamic[frame]
                stamps = np.array([s for s, _ in track])
                ref = stamps.min()
                at, ok = interpolate_poses(stamps - ref, np.array([p for _, p in track]), times - ref)
                poses = compose(at, poses)
                inside &= ok
                moving += 1
            else:
                return poses, inside, frame, moving
            if parent in seen:
                raise InputError(source, f"the tf tree has a loop through '{parent}'")
            seen.add(parent)
            frame = parent
