"""crfmap.sim.motion: every drive keeps speed limits, its poses follow its steps, and scans fall on poses.

The drives are also tested end to end through ``simulate`` in test_simulator.py.
"""
import math

import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.frames import wrap_angle
from crfmap.grid import OccupancyGrid
from crfmap.sim.motion import Motion, explore_reachable, follow_waypoints, look_around
from crfmap.world.scene import Scene
from crfmap.world.scenes import enclosed_boxes, occluded_walls
from crfmap.sim.laser import Laser

DT, V, W = 0.1, 0.5, 1.5  # [s], [m/s], [rad/s]: the drives' defaults


def replay(start, moves):
    """Poses from the steps, one at a time: turn half, move along that heading, turn the other half."""
    x, y, yaw = start
    out = [(x, y, yaw)]
    for d, a in moves:
        x, y = x + d * math.cos(yaw + a / 2), y + d * math.sin(yaw + a / 2)
        yaw = float(wrap_angle(yaw + a))
        out.append((x, y, yaw))
    return np.array(out)


def drives():
    boxes = enclosed_boxes("train")
    walls = occluded_walls("test")
    return [
        ("explore", boxes, explore_reachable(boxes, Laser.with_fov(180, 9), stride=3)),
        ("look", walls, look_around(walls, Laser.with_fov(100, 9), turns=2)),
        ("waypoints", walls, follow_waypoints(walls, Laser(), walls.waypoints[:3])),
    ]


@pytest.mark.parametrize("name, scene, motion", drives(), ids=["explore", "look", "waypoints"])
def test_a_drive_is_consistent(name, scene, motion):
    assert isinstance(motion, Motion) and motion.dt == DT
    n = len(motion)
    assert motion.poses.shape == (n + 1, 3) and motion.moves.shape == motion.commands.shape == (n, 2)
    np.testing.assert_allclose(motion.poses[0], scene.start, atol=0)
    replayed = replay(scene.start, motion.moves)
    np.testing.assert_allclose(motion.poses[:, :2], replayed[:, :2], atol=1e-9)
    assert np.abs(wrap_angle(motion.poses[:, 2] - replayed[:, 2])).max() < 1e-9
    assert np.abs(motion.moves[:, 0]).max() <= V * DT + 1e-12
    assert np.abs(motion.moves[:, 1]).max() <= W * DT + 1e-12
    assert (np.diff(motion.scan_at) > 0).all() and motion.scan_at[0] >= 0 and motion.scan_at[-1] <= n
    if name != "waypoints":  # planned drives execute exactly what they command
        np.testing.assert_allclose(motion.commands * DT, motion.moves, atol=1e-12)


def test_look_around_turns_in_place_by_whole_headings():
    scene = Scene("room", OccupancyGrid(np.zeros((5, 5)), 0.1), (0.25, 0.25, 0.3))
    m = look_around(scene, Laser.with_fov(100, 9), turns=2)  # 4 headings per turn
    assert len(m.scan_at) == 8 and (m.moves[:, 0] == 0).all()
    yaws = m.poses[m.scan_at, 2]
    np.testing.assert_allclose(wrap_angle(yaws - 0.3 - np.arange(8) * math.pi / 2), 0.0, atol=1e-12)


def test_bad_drive_arguments_name_the_argument():
    scene = enclosed_boxes("train")
    laser = Laser()
    for call, match in (
        (lambda: explore_reachable(scene, laser, stride=0), "stride"),
        (lambda: explore_reachable(scene, laser, dt=0.0), "dt"),
        (lambda: look_around(scene, laser, turns=True), "turns"),
        (lambda: look_around(scene, laser, angular_speed=float("nan")), "angular_speed"),
        (lambda: follow_waypoints(scene, laser, [1.0, 1.0]), "waypoints"),  # not (k, 2)
        (lambda: follow_waypoints(Scene("bare", scene.truth, scene.start), laser), "waypoints"),
        (lambda: follow_waypoints(scene, laser, scan_period=-1.0), "scan_period"),
    ):
        with pytest.raises(InputError, match=match):
            call()
