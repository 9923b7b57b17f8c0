"""The robot/laser simulator: exact ranges in known rooms, REP 117 codes, noise bounds, odometry, coverage."""
import math

import numpy as np
import pytest

from crfmap import cli
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.recording import Recording
from crfmap.world.scene import Scene
from crfmap.world.scenes import enclosed_boxes, make_scene
from crfmap.world.office import office_floor
from crfmap.world.reachability import reachable, traversable
from crfmap.sim.drives import Explore, Look, Waypoints
from crfmap.sim.laser import LEGACY_NO_RETURN, Laser
from crfmap.sim.simulator import add_range_noise, cast_rays, simulate
from crfmap.frames import compose
from crfmap.sim.motion import explore_reachable, follow_waypoints, look_around
from naive_raycast import walk_first_hit

RES = 0.1  # [m]
FOUR = Laser.with_fov(360, 4)  # beams at -pi, -pi/2, 0, pi/2


def box_room(width=13, height=9, origin=(0.0, 0.0, 0.0), start_cell=(3, 4), yaw=0.0):
    cells = np.zeros((height, width))
    cells[0, :] = cells[-1, :] = cells[:, 0] = cells[:, -1] = 1
    grid = OccupancyGrid(cells, resolution=RES, origin=origin)
    x, y = grid.cell_to_world(*start_cell)
    return Scene("box", grid, (float(x), float(y), yaw))


def test_axis_aligned_beams_read_whole_cells():
    scene = box_room()  # robot in cell (3, 4): walls at x = 0 and 12, y = 0 and 8
    got = cast_rays(scene.truth, FOUR, [scene.start])[0]
    np.testing.assert_allclose(got, [0.3, 0.4, 0.9, 0.4], atol=1e-12)
    turned = cast_rays(scene.truth, FOUR, [(*scene.start[:2], math.pi / 2)])[0]  # beam 0 now points +y
    np.testing.assert_allclose(turned, [0.4, 0.9, 0.4, 0.3], atol=1e-12)


def test_ranges_do_not_depend_on_where_the_grid_sits():
    plain = box_room()
    shifted = box_room(origin=(-3.0, 2.5, 0.0))
    rotated = box_room(origin=(1.0, -2.0, math.pi / 2))
    laser = Laser.with_fov(360, 72)
    want = cast_rays(plain.truth, laser, [plain.start])
    np.testing.assert_allclose(cast_rays(shifted.truth, laser, [shifted.start]), want, atol=1e-9)
    # in the rotated grid the robot must face pi/2 more to see the same room the same way
    pose = (*rotated.start[:2], math.pi / 2)
    np.testing.assert_allclose(cast_rays(rotated.truth, laser, [pose]), want, atol=1e-9)


def test_cast_matches_the_exact_line_walk_on_random_grids():
    rng = np.random.default_rng(0)
    laser = Laser.with_fov(270, 61, range_max=1.5)
    for _ in range(20):
        occ = rng.random((25, 30)) < 0.08
        grid = OccupancyGrid(occ.astype(float), resolution=RES)
        pose = (rng.uniform(0, 3.0), rng.uniform(0, 2.5), rng.uniform(-math.pi, math.pi))
        got = cast_rays(grid, laser, [pose])[0]
        cx, cy = int(pose[0] / RES), int(pose[1] / RES)
        for a, r in zip(laser.angles, got):
            end = (math.floor((pose[0] + 1.5 * math.cos(pose[2] + a)) / RES),
                   math.floor((pose[1] + 1.5 * math.sin(pose[2] + a)) / RES))
            hit = walk_first_hit(occ.tolist(), (cx, cy), end)
            if hit is None:
                assert r == math.inf
            else:
                d = math.hypot((hit[0] + 0.5) * RES - pose[0], (hit[1] + 0.5) * RES - pose[1])
                assert r == (pytest.approx(d) if d <= 1.5 else math.inf)


def test_no_return_is_inf_or_legacy_minus_one_and_too_close_is_minus_inf():
    open_floor = Scene("open", OccupancyGrid(np.zeros((30, 30)), resolution=RES), (1.55, 1.55, 0.0))
    laser = Laser.with_fov(360, 16, range_max=1.0)
    rec = simulate(open_floor, laser, "look", progress=False)
    assert np.isposinf(rec.scans.ranges).all()
    legacy = Laser.with_fov(360, 16, range_max=1.0, no_return=LEGACY_NO_RETURN)
    assert (simulate(open_floor, legacy, "look", progress=False).scans.ranges == -1.0).all()
    room = box_room()  # far wall at 0.9 m, the others at 0.3-0.4 m
    short = cast_rays(room.truth, Laser.with_fov(360, 4, range_max=0.5), [room.start])[0]
    assert np.isposinf(short[2]) and np.isfinite(short[[0, 1, 3]]).all()
    near = cast_rays(room.truth, Laser.with_fov(360, 4, range_min=0.35), [room.start])[0]
    assert np.isneginf(near[0]) and near[1] == pytest.approx(0.4)


def test_range_noise_is_bounded_and_used():
    scene = enclosed_boxes("test")
    laser = Laser.with_fov(360, 180)
    clean = simulate(scene, laser, Explore(stride=6), progress=False).scans.ranges.astype(float)
    c = 0.05
    noisy = simulate(scene, laser, Explore(stride=6), range_noise=c, seed=3, progress=False)
    noisy = noisy.scans.ranges.astype(float)
    finite = np.isfinite(clean)
    assert np.array_equal(finite, np.isfinite(noisy)) and finite.sum() > 1000
    err = (noisy - clean)[finite]
    assert np.abs(err).max() <= c + 1e-6
    assert np.abs(err).max() > 0.9 * c and abs(err.mean()) < 0.05 * c  # uses the whole band, centred
    assert np.mean(err > 0) == pytest.approx(0.5, abs=0.05)


def test_add_range_noise_floors_at_zero_and_keeps_codes():
    r = np.array([[0.01, np.inf, -np.inf, 2.0]])
    out = add_range_noise(r, 0.5, rng=np.random.default_rng(1))
    assert out[0, 0] >= 0 and np.isposinf(out[0, 1]) and np.isneginf(out[0, 2])
    with pytest.raises(InputError):
        add_range_noise(r, -0.1)


def recordings_equal(a: Recording, b: Recording) -> bool:
    pairs = [(a.scans.ranges, b.scans.ranges), (a.scans.laser_poses, b.scans.laser_poses),
             (a.scans.stamps, b.scans.stamps), (a.odometry.poses, b.odometry.poses),
             (a.odometry.twists, b.odometry.twists), (a.true_poses.poses, b.true_poses.poses),
             (a.cmd_vel.twists, b.cmd_vel.twists)]
    return all(x.shape == y.shape and np.array_equal(x, y) for x, y in pairs)


def test_same_seed_same_recording_other_seed_other_noise():
    scene = make_scene("hollow-train")
    kw = dict(laser=Laser.with_fov(180, 90), drive=Explore(stride=4), range_noise=0.02, odometry_noise=(0.01, 0.01),
              progress=False)
    a, b, c = simulate(scene, seed=1, **kw), simulate(scene, seed=1, **kw), simulate(scene, seed=2, **kw)
    assert recordings_equal(a, b)
    assert not np.array_equal(a.scans.ranges, c.scans.ranges)
    assert not np.array_equal(a.odometry.poses, c.odometry.poses)
    assert np.array_equal(a.true_poses.poses, c.true_poses.poses)  # the noise is in the sensors only


def test_perfect_odometry_equals_true_poses_and_noisy_odometry_drifts():
    scene = make_scene("enclosed-test")
    perfect = simulate(scene, drive=Explore(stride=5), progress=False)
    start = np.asarray(perfect.meta["map_to_odom"])
    np.testing.assert_allclose(perfect.odometry.poses[0], [0, 0, 0])
    in_map = compose(start, perfect.odometry.poses)
    np.testing.assert_allclose(in_map[:, :2], perfect.true_poses.poses[:, :2], atol=1e-9)
    np.testing.assert_allclose(np.cos(in_map[:, 2] - perfect.true_poses.poses[:, 2]), 1.0, atol=1e-12)
    np.testing.assert_allclose(perfect.odometry.twists, perfect.true_poses.twists, atol=1e-12)

    noisy = simulate(scene, drive=Explore(stride=5), odometry_noise=(0.01, 0.02), seed=4, progress=False)
    assert np.array_equal(noisy.true_poses.poses, perfect.true_poses.poses)
    drift = np.hypot(*(compose(start, noisy.odometry.poses)[:, :2] - noisy.true_poses.poses[:, :2]).T)
    assert drift[0] == 0 and drift[-1] > 0.1 and drift[: len(drift) // 10].mean() < drift[-len(drift) // 10 :].mean()
    # each executed step's reading is off by at most the bound, and steps that did not move read exactly
    err = (noisy.odometry.twists - noisy.true_poses.twists)[1:] * noisy.meta["dt"]
    assert np.abs(err[:, 0]).max() <= 0.01 + 1e-12 and np.abs(err[:, 1]).max() <= 0.02 + 1e-12
    still = noisy.true_poses.twists[1:, 0] == 0
    assert still.any() and (err[still, 0] == 0).all()


def test_explore_visits_and_scans_every_reachable_cell():
    for name in ("enclosed-train", "hollow-test", "x"):
        scene = make_scene(name)
        rec = simulate(scene, drive="explore", progress=False)
        grid = scene.truth
        mask = reachable(grid, scene.start)
        visited = np.zeros_like(mask)
        ix, iy = (np.floor(v).astype(int) for v in grid.world_to_cell(*rec.true_poses.poses[:, :2].T))
        visited[iy, ix] = True
        assert np.array_equal(visited, mask), name
        scanned = np.zeros_like(mask)
        sx, sy = (np.floor(v).astype(int) for v in grid.world_to_cell(*rec.scans.laser_poses[:, :2].T))
        scanned[sy, sx] = True
        assert np.array_equal(scanned, mask)
        steps = np.hypot(*np.diff(rec.true_poses.poses[:, :2], axis=0).T)
        assert steps.max() <= 0.5 * 0.1 + 1e-9  # linear_speed * dt: no teleporting
        np.testing.assert_allclose(rec.cmd_vel.twists, rec.true_poses.twists[1:], atol=1e-12)  # nothing blocked


def test_explore_stride_keeps_every_cell_near_a_scan():
    scene = make_scene("enclosed-test")
    mask = reachable(scene.truth, scene.start)
    for stride in (2, 4):
        m = explore_reachable(scene, Laser(), stride=stride)
        pos = np.floor(m.poses[m.scan_at, :2] / 0.1).astype(int)
        cells = np.argwhere(mask)[:, ::-1]
        cheb = np.abs(cells[:, None, :] - pos[None, :, :]).max(axis=2).min(axis=1)
        assert cheb.max() <= stride - 1
        assert len(m.scan_at) < mask.sum() / stride


def test_limited_fov_turns_in_place():
    scene = make_scene("occluded-train")
    m = look_around(scene, Laser.with_fov(100, 20))  # needs 4 headings to cover the circle
    assert len(m.scan_at) == 4
    assert np.ptp(m.poses[:, :2], axis=0).max() == 0  # never leaves its spot
    yaws = m.poses[m.scan_at, 2]
    np.testing.assert_allclose(np.cos(np.diff(yaws)), 0.0, atol=1e-12)  # 90 deg apart
    rec = simulate(scene, Laser.with_fov(100, 20), progress=False)
    assert rec.meta["mode"] == "look" and rec.scans.ranges.shape == (4, 20)


def test_waypoints_are_reached_without_entering_walls():
    scene = office_floor(12.0, 10.0, 0.1, seed=3)
    rec = simulate(scene, drive=Waypoints(scan_period=0.5), progress=False)
    poses = rec.true_poses.poses
    for wp in scene.waypoints:
        assert np.hypot(*(poses[:, :2] - wp).T).min() < 0.01
    free = traversable(scene.truth, scene.robot_radius)
    ix, iy = (np.floor(v).astype(int) for v in scene.truth.world_to_cell(*poses[:, :2].T))
    assert free[iy, ix].all()
    gaps = np.diff(rec.scans.stamps)
    assert np.allclose(gaps[:-1], 0.5) and 0 < gaps[-1] <= 0.5 + 1e-9
    # the commands produce the motion: |v| within the limit, executed distance = v * dt when not blocked
    v = rec.cmd_vel.twists[:, 0]
    assert v.max() <= 0.5 + 1e-12 and v.min() >= 0
    np.testing.assert_allclose(rec.true_poses.twists[1:, 0], v, atol=1e-12)


@pytest.mark.parametrize("name", ["x", "occluded-test", "hollow-train"])
def test_thesis_scenes_have_a_drivable_lap(name):
    scene = make_scene(name)
    rec = simulate(scene, drive="waypoints", progress=False)
    poses = rec.true_poses.poses
    for wp in scene.waypoints:
        assert np.hypot(*(poses[:, :2] - wp).T).min() < 0.01
    ix, iy = (np.floor(v).astype(int) for v in scene.truth.world_to_cell(*poses[:, :2].T))
    assert not scene.occupied[iy, ix].any()


def test_a_blocked_step_is_not_taken():
    scene = box_room(width=7, height=5, start_cell=(2, 2))
    goal = (0.55, 0.25)  # cell (5, 2), then push on into the wall
    m = follow_waypoints(scene, Laser(), [goal])
    assert np.hypot(*(m.poses[-1, :2] - goal)) < 0.01
    with pytest.raises(InputError, match="not reachable"):
        follow_waypoints(scene, Laser(), [(0.65, 0.25)])  # inside the wall
    with pytest.raises(InputError, match="outside"):
        follow_waypoints(scene, Laser(), [(9.0, 0.25)])


def test_laser_mount_offsets_the_scan_poses():
    scene = make_scene("enclosed-train")
    mount = (0.05, -0.02, math.pi / 2)
    rec = simulate(scene, drive=Explore(stride=5), laser_mount=mount, progress=False)
    idx = np.searchsorted(rec.true_poses.stamps, rec.scans.stamps)
    np.testing.assert_allclose(rec.scans.laser_poses, compose(rec.true_poses.poses[idx], mount), atol=1e-12)
    assert rec.laser_mount == pytest.approx(mount)


def test_recording_layout():
    scene = make_scene("enclosed-train")
    rec = simulate(scene, Laser.with_fov(240, 121, range_max=3.0), Explore(stride=3), progress=False)
    s = rec.scans
    assert s.ranges.dtype == np.float32 and s.ranges.shape[1] == 121 and s.frame_id == "map"
    assert s.angle_min == pytest.approx(-math.radians(120)) and s.angles[-1] == pytest.approx(math.radians(120))
    assert (np.diff(s.stamps) > 0).all() and (np.diff(rec.true_poses.stamps) > 0).all()
    assert rec.odometry.frame_id == "odom" and rec.odometry.child_frame_id == "base_link"
    assert rec.true_poses.frame_id == "map"
    assert len(rec.cmd_vel) == len(rec.true_poses) - 1 and rec.cmd_vel.twists.shape == (len(rec.cmd_vel), 2)
    assert rec.ground_truth is scene.truth
    assert rec.meta["scene"] == "enclosed-train" and rec.meta["no_return"] == math.inf


def test_bad_arguments():
    scene = make_scene("enclosed-train")
    with pytest.raises(InputError):
        simulate(scene, drive="teleport")
    with pytest.raises(InputError):
        simulate(scene, range_noise=-1)
    with pytest.raises(InputError):
        simulate(scene, odometry_noise=(0.1, 0.1, 0.1))
    with pytest.raises(InputError, match="no waypoints"):
        simulate(box_room(), drive="waypoints")  # the scene has none
    with pytest.raises(InputError):
        simulate(scene, start=(0.05, 0.05, 0.0))  # in the wall
    with pytest.raises(InputError):
        Laser(range_min=2.0, range_max=1.0)
    with pytest.raises(InputError):
        Laser.with_fov(400)
    with pytest.raises(InputError):
        Laser(no_return=0.0)


# --- the command ------------------------------------------------------------------------------
def parse(argv):
    return cli.build_parser().parse_args(["simulate", *argv])


def test_command_builds_the_recording(tmp_path):
    from crfmap.commands.simulate import build_recording

    args = parse(["hollow-test", str(tmp_path / "bag"), "--fov", "180", "--beams", "91", "--range", "3",
                  "--range-noise", "0.01", "--odom-noise", "0.002", "--stride", "3", "--seed", "5",
                  "--legacy-no-return", "--quiet"])
    rec = build_recording(args)
    assert rec.scans.ranges.shape[1] == 91 and rec.scans.range_max == 3.0 and rec.meta["seed"] == 5
    assert rec.meta["scene"] == "hollow-test" and rec.meta["no_return"] == -1.0
    assert not (tmp_path / "bag").exists()


def test_command_refuses_bad_input(tmp_path, capsys):
    existing = tmp_path / "bag"
    existing.mkdir()
    assert cli.main(["simulate", "x", str(existing), "--quiet"]) == 2
    assert "already exists" in capsys.readouterr().err
    assert cli.main(["simulate", "x", str(tmp_path / "new"), "--beams", "0", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "beams" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "new").exists()
    with pytest.raises(SystemExit):
        parse(["garage", str(tmp_path / "x")])
    capsys.readouterr()
    # a mode-specific option given to another mode: one line naming it, nothing written
    assert cli.main(["simulate", "enclosed-train", str(tmp_path / "new"), "--mode", "look", "--stride", "2",
                     "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--stride" in err and "explore" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize("fmt", ["ros2", "ros1"])
def test_command_writes_a_bag(tmp_path, fmt):
    bagio = pytest.importorskip("crfmap.io.bag_reader")
    out = tmp_path / ("run.bag" if fmt == "ros1" else "run")
    argv = ["simulate", "occluded-train", str(out), "--format", fmt, "--fov", "90", "--beams", "45", "--quiet"]
    assert cli.main(argv) == 0
    from crfmap.commands.simulate import build_recording

    back = bagio.read_bag(out)
    want = build_recording(parse(argv[1:]))
    assert back.scans.ranges.shape == want.scans.ranges.shape == (4, 45)  # four headings of a 90 deg laser
    np.testing.assert_allclose(back.scans.ranges, want.scans.ranges)
    np.testing.assert_allclose(back.scans.laser_poses, want.scans.laser_poses, atol=1e-6)
    assert cli.main(argv) == 2  # exists now
    assert cli.main(argv + ["--overwrite"]) == 0


def test_a_mode_setting_belongs_to_its_drive():
    scene = make_scene("enclosed-train")
    for name, value, drive in (("stride", 2, "Explore"), ("turns", 2, "Look"), ("scan_period", 0.5, "Waypoints"),
                               ("waypoints", [(0.5, 0.5)], "Waypoints"), ("robot_radius", 0.1, "Explore or Waypoints")):
        with pytest.raises(InputError, match=rf"^{name}: belongs to the drive: pass drive={drive}\("):
            simulate(scene, drive="explore", progress=False, **{name: value})
    with pytest.raises(InputError, match="^stride: must be >= 1"):
        Explore(stride=0)
    with pytest.raises(InputError, match="^turns: expected an integer"):
        Look(turns=1.5)
    with pytest.raises(InputError, match="^scan_period: must be > 0"):
        Waypoints(scan_period=0.0)
    with pytest.raises(InputError, match="^drive: expected one of"):
        simulate(scene, drive="teleport")
    with pytest.raises(InputError, match="^linear_speed: does not apply to the look drive"):
        simulate(scene, drive=Look(), linear_speed=0.3, progress=False)


def test_every_scene_mode_has_a_drive():
    from crfmap.sim.drives import DRIVES
    from crfmap.world.scene import MODES

    assert sorted(DRIVES) == sorted(MODES) and all(DRIVES[m].mode == m for m in MODES)


def test_a_mode_name_means_its_drive_with_the_defaults():
    scene = make_scene("enclosed-train")
    laser = Laser.with_fov(360, 90)
    for name, drive in (("explore", Explore()), ("look", Look())):
        a = simulate(scene, laser, name, range_noise=0.02, seed=5, progress=False)
        b = simulate(scene, laser, drive, range_noise=0.02, seed=5, progress=False)
        assert recordings_equal(a, b) and a.meta == b.meta and a.meta["mode"] == name
    two = simulate(scene, laser, Look(turns=3), progress=False)
    assert two.scans.ranges.shape == (3, 90)  # the turns reach the motion
    wide = simulate(scene, laser, Explore(stride=3, robot_radius=0.0), progress=False)
    assert wide.meta["robot_radius"] == 0.0 and len(wide.scans) < len(simulate(scene, laser, progress=False).scans)
