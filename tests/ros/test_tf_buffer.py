"""Scans placed through tf as they arrive: the same poses crfmap.io.bag_reader.read_bag computes from the whole bag."""
import numpy as np

from crfmap.frames import TfTree
from crfmap.ros.messages import Transform
from crfmap.ros.tf_buffer import TfBuffer, stamp_seconds


def test_lookup_waits_until_every_moving_transform_covers_the_stamp():
    buffer = TfBuffer()
    buffer.add(Transform(0, "base_link", "laser", (0.2, 0.0, np.pi / 2)), static=True)
    buffer.add(Transform(10**9, "odom", "base_link", (0.0, 0.0, 0.0)), static=False)
    assert buffer.lookup("laser", 1.0)[0] == "ready"
    buffer.add(Transform(10**9, "map", "odom", (1.0, 0.0, 0.0)), static=False)
    assert buffer.lookup("laser", 1.5)[0] == "wait"
    buffer.add(Transform(2 * 10**9, "odom", "base_link", (2.0, 0.0, 0.0)), static=False)
    assert buffer.lookup("laser", 1.5)[0] == "wait"  # map -> odom has nothing after 1 s yet
    buffer.add(Transform(2 * 10**9, "map", "odom", (1.0, 0.0, 0.0)), static=False)
    status, pose, root = buffer.lookup("laser", 1.5)
    assert status == "ready" and root == "map"
    np.testing.assert_allclose(pose, (2.2, 0.0, np.pi / 2))
    assert buffer.lookup("laser", 1.5, fixed_frame="odom")[2] == "odom"
    assert buffer.lookup("laser", 0.5)[0] == "never"
    assert buffer.lookup("nowhere", 1.5)[0] == "wait"  # no moving transform reaches it


def test_poses_equal_the_whole_trees_poses_bit_for_bit():
    rng = np.random.default_rng(3)
    stamps = np.sort(rng.uniform(1e9, 1e9 + 30, 200))  # an epoch-like clock, as real bags have
    poses = np.column_stack([np.cumsum(rng.normal(0, 0.1, 200)), np.cumsum(rng.normal(0, 0.1, 200)),
                             np.cumsum(rng.normal(0, 0.3, 200))])
    ns = [int(round(s * 1e9)) for s in stamps]
    whole, buffer = TfTree(), TfBuffer()
    whole.add("base_link", "laser", (0.1, 0.0, 0.5))
    buffer.add(Transform(0, "base_link", "laser", (0.1, 0.0, 0.5)), static=True)
    for k in range(200):
        whole.add("odom", "base_link", tuple(poses[k]), stamp=stamp_seconds(ns[k]))
    scan_times = [stamp_seconds(n + 1234567) for n in ns[:-1:7]]
    start, mount, _ = whole.static_chain("laser")
    expected, _, _, _ = whole.poses_in_root(start, mount, np.array(scan_times))
    got, k = [], 0
    for t in scan_times:  # live: each scan looked up as soon as tf covers it
        while buffer.lookup("laser", t)[0] != "ready":
            buffer.add(Transform(ns[k], "odom", "base_link", tuple(poses[k])), static=False)
            k += 1
        got.append(buffer.lookup("laser", t)[1])
    assert np.array_equal(np.array(got), expected)
