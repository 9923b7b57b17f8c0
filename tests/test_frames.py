"""crfmap.frames: planar pose algebra against homogeneous matrices, interpolation, and tf tree following."""
import math

import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.frames import (TfTree, compose, interpolate_poses, inverse, quaternion_to_yaw, wrap_angle,
                           yaw_to_quaternion)
from naive_frames import angle_diff, pose_of, se2


def random_poses(rng, n):
    return np.column_stack([rng.uniform(-5, 5, (n, 2)), rng.uniform(-4, 4, n)])


def test_wrap_angle_lands_in_half_open_interval_and_keeps_the_direction():
    a = np.linspace(-20, 20, 401)
    w = wrap_angle(a)
    assert (w >= -math.pi).all() and (w < math.pi).all()
    np.testing.assert_allclose(np.cos(w), np.cos(a), atol=1e-12)
    np.testing.assert_allclose(np.sin(w), np.sin(a), atol=1e-12)


def test_compose_and_inverse_match_matrices():
    rng = np.random.default_rng(3)
    a, b = random_poses(rng, 50), random_poses(rng, 50)
    got = compose(a, b)
    want = np.array([pose_of(se2(*p) @ se2(*q)) for p, q in zip(a, b)])
    np.testing.assert_allclose(got[:, :2], want[:, :2], atol=1e-12)
    assert angle_diff(got[:, 2], want[:, 2]).max() < 1e-12
    inv = inverse(a)
    want_inv = np.array([pose_of(np.linalg.inv(se2(*p))) for p in a])
    np.testing.assert_allclose(inv[:, :2], want_inv[:, :2], atol=1e-12)
    assert angle_diff(inv[:, 2], want_inv[:, 2]).max() < 1e-12
    for identity in (compose(a, inv), compose(inv, a)):
        assert np.abs(identity[:, :2]).max() < 1e-12 and angle_diff(identity[:, 2], 0.0).max() < 1e-12
    # one pose against many broadcasts like the matrices do
    np.testing.assert_allclose(compose(a[0], b), compose(np.tile(a[0], (50, 1)), b), atol=0)


def test_interpolation_between_knots_takes_the_short_way_round():
    stamps = np.array([0.0, 1.0, 3.0])
    poses = np.array([[0.0, 0.0, 3.0], [2.0, 1.0, -3.0], [2.0, 5.0, -2.0]])
    times = np.array([0.5, 2.0, -1.0, 4.0])
    got, inside = interpolate_poses(stamps, poses, times)
    np.testing.assert_allclose(got[0, :2], [1.0, 0.5])
    assert angle_diff(got[0, 2], math.pi).max() < 1e-12  # halfway from 3 to -3 through pi, not through 0
    np.testing.assert_allclose(got[1], [2.0, 3.0, -2.5], atol=1e-12)
    assert inside.tolist() == [True, True, False, False]


def test_interpolation_at_knots_is_exact_and_the_last_of_equal_stamps_wins():
    rng = np.random.default_rng(5)
    stamps = np.sort(rng.uniform(0, 10, 20))
    poses = random_poses(rng, 20)
    order = rng.permutation(20)  # unsorted input
    got, inside = interpolate_poses(stamps[order], poses[order], stamps)
    assert np.array_equal(got, poses) and inside.all()
    got, _ = interpolate_poses([0.0, 1.0, 1.0, 2.0], [[0, 0, 0], [5, 5, 1], [1, 1, 0.5], [2, 2, 0]], [1.0])
    assert got[0].tolist() == [1.0, 1.0, 0.5]


def test_quaternion_round_trip():
    class Q:
        def __init__(self, x, y, z, w):
            self.x, self.y, self.z, self.w = x, y, z, w

    for yaw in np.linspace(-math.pi, math.pi, 13)[:-1]:
        q = yaw_to_quaternion(yaw)
        assert math.isclose(sum(v * v for v in q), 1.0)
        assert angle_diff(quaternion_to_yaw(Q(*q)), yaw) < 1e-12


def test_tf_tree_chains_static_and_moving_transforms():
    mount = (0.1, -0.05, math.pi / 2)
    tree = TfTree()
    tree.add("/base_link", "laser", mount)  # ROS1 names lose their leading '/'
    for t in (0.0, 1.0, 2.0):
        tree.add("map", "odom", (0.5 * t, 0.0, 0.1 * t), stamp=t)
        tree.add("odom", "base_link", (t, 2.0 * t, 0.3 * t), stamp=t)
    tree.add("elsewhere", "odom", (9.0, 9.0, 0.0), stamp=0.5)  # a second parent: ignored
    assert tree.conflicts == 1
    times = np.array([0.5, 1.5, 2.5])
    poses, inside, root, moving = tree.poses_in_root("laser", np.zeros(3), times)
    assert root == "map" and moving == 2 and inside.tolist() == [True, True, False]
    for t, got in zip(times[:2], poses[:2]):
        want = pose_of(se2(0.5 * t, 0.0, 0.1 * t) @ se2(t, 2.0 * t, 0.3 * t) @ se2(*mount))
        np.testing.assert_allclose(got[:2], want[:2], atol=1e-12)
        assert angle_diff(got[2], want[2]) < 1e-12


def test_static_chain_stops_where_asked_and_loops_are_errors():
    tree = TfTree()
    tree.add("base_link", "plate", (1.0, 0.0, 0.0))
    tree.add("plate", "laser", (0.0, 1.0, 0.0))
    top, pose, passed = tree.static_chain("laser")
    assert top == "base_link" and passed == ["laser", "plate", "base_link"]
    np.testing.assert_allclose(pose, [1.0, 1.0, 0.0])
    assert tree.static_chain("laser", stop="plate")[0] == "plate"
    tree.add("laser", "base_link", (0.0, 0.0, 0.0), stamp=0.0)  # closes a loop
    with pytest.raises(InputError, match="run.bag: the tf tree has a loop"):
        tree.poses_in_root("laser", np.zeros(3), np.array([0.0]), source="run.bag")
