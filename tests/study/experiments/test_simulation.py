"""The simulator notebook's helpers: ray casting cell by cell, end points, odometry, timed builds, figures."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from crfmap.grid import OccupancyGrid  # noqa: E402
from crfmap.sim import Laser, Waypoints, simulate  # noqa: E402
from crfmap.world import office_floor  # noqa: E402
from crfstudy.experiments import simulation  # noqa: E402


def test_cells_until_hit_stops_at_the_first_occupied_cell_or_the_grid_edge():
    occupied = np.zeros((2, 4), dtype=bool)
    occupied[0, 2] = True
    cells = np.array([[0, 0], [1, 0], [2, 0], [3, 0]])
    path, hit = simulation.cells_until_hit(cells, occupied)
    assert path.tolist() == [[0, 0], [1, 0], [2, 0]] and hit == (2, 0)
    path, hit = simulation.cells_until_hit(np.array([[0, 1], [1, 1], [2, 2]]), occupied)
    assert path.tolist() == [[0, 1], [1, 1]] and hit is None  # (2, 2) is off the grid
    occupied[0, 0] = True  # the robot's own cell is not tested
    assert simulation.cells_until_hit(cells, occupied)[1] == (2, 0)


def test_ray_paths_agree_with_the_library_and_the_tie_rules_differ_on_the_gap():
    occupied = np.zeros((4, 9), dtype=bool)
    occupied[0:2, 4] = occupied[0:3, 8] = True
    paths = simulation.ray_paths(occupied, (0, 3), {"a": (8, 2), "b": (8, 0)})
    assert all(hit == library for _, hit, library in paths.values())
    assert paths["a"][1] == (8, 2) and paths["b"][1] == (8, 0)  # (8, 0)'s ray passes above the middle column
    occupied[2, 4] = True  # a taller middle column stops it
    assert simulation.ray_paths(occupied, (0, 3), {"b": (8, 0)})["b"][1:] == ((4, 2), (4, 2))
    gap = np.zeros((3, 5), dtype=bool)
    gap[1, 1] = gap[0, 2] = True
    (listing, other) = simulation.tie_rule_paths(gap, (0, 0), (4, 2)).values()
    assert listing[1] is None and other[1] == (1, 1)
    assert simulation.first_hit(gap, (0, 0), (4, 2)) is None


@pytest.fixture(scope="module")
def look():
    scene = office_floor(6.0, 5.0, 0.1, seed=0)
    return scene, simulate(scene, Laser.with_fov(240, 31, range_max=3.0), drive="look", seed=0, progress=False)


def test_tie_rule_count_counts_every_beam(look):
    scene, rec = look
    differ, n_rays = simulation.tie_rule_count(scene.truth, rec.scans, 3.0)
    assert n_rays == rec.scans.ranges.size and 0 <= differ < n_rays


def test_end_points_lie_at_the_ranges_and_mostly_in_occupied_cells(look):
    scene, rec = look
    pose = rec.scans.laser_poses[0]
    ends, hit = simulation.scan_end_points(pose, rec.scans.ranges[0], rec.scans.angles, 3.0)
    distance = np.hypot(*(ends - pose[:2]).T)
    np.testing.assert_allclose(distance[~hit], 3.0)
    np.testing.assert_allclose(distance[hit], rec.scans.ranges[0][hit], rtol=1e-6)
    x, y = simulation.end_points(rec)
    assert x.size == np.isfinite(rec.scans.ranges).sum()
    share = simulation.discretisation_share(rec, scene.truth)
    assert share["end_points"] == x.size and share["in_truth_occupied_cell"] > 0.5


def test_in_occupied_cell_clips_points_off_the_grid():
    truth = OccupancyGrid(np.array([[0.0, 1.0]]), resolution=1.0)
    good, ix, iy = simulation.in_occupied_cell(np.array([0.5, 1.5, 9.0]), np.array([0.5, 0.5, 0.5]), truth)
    assert good.tolist() == [False, True, True] and ix.tolist() == [0, 1, 1] and iy.tolist() == [0, 0, 0]


def test_noise_free_odometry_is_the_true_path_and_its_scans_the_true_scans():
    office = office_floor(8.0, 6.0, 0.1, seed=0)
    rec = simulate(office, Laser.with_fov(360, 36, range_max=4.0), drive=Waypoints(office.waypoints[:1], scan_period=1.0),
                   dt=0.2, seed=0, progress=False, odometry_noise=(0.0, 0.0))
    np.testing.assert_allclose(simulation.odometry_in_map(rec)[:, :2], rec.true_poses.poses[:, :2], atol=1e-9)
    np.testing.assert_allclose(simulation.scans_on_odometry(rec).laser_poses, rec.scans.laser_poses, atol=1e-9)
    summary = simulation.motion_summary(rec)
    assert summary["steps"] == len(rec.cmd_vel) and summary["max_position_error_m"] < 1e-9
    assert summary["path_length_m"] > 0


def test_timed_build_and_its_summaries(look):
    _, rec = look
    grid, seconds = simulation.timed_build(rec.scans, 0.1, "arctan", repeats=2)
    row = simulation.recording_summary("sim", rec)
    assert row["scans"] == len(rec.scans) and row["pose_source"]
    row["arctan"] = simulation.build_summary(grid, seconds, row)
    row["logodds"] = dict(row["arctan"], occupied_cells=7)
    row["cells_with_an_occupied_hit"] = 3
    assert row["arctan"]["scans_per_second"] == pytest.approx(row["scans"] / seconds)
    header, rows = simulation.builder_table({"repeats": 2, "sim": row})  # entries that are not dicts are skipped
    assert len(rows) == 1 and len(rows[0]) == len(header) and rows[0][7].endswith("/ 7")


def test_the_figures_have_their_panels(look):
    scene, rec = look
    occupied = np.zeros((4, 9), dtype=bool)
    occupied[0:2, 4] = True
    paths = simulation.ray_paths(occupied, (0, 3), {"a": (8, 2)})
    assert simulation.raycast_figure(occupied, (0, 3), paths).axes[0].get_title().startswith("Fig. 11")
    gap = np.zeros((3, 5), dtype=bool)
    gap[1, 1] = gap[0, 2] = True
    assert len(simulation.tie_rule_figure(gap, (0, 0), (4, 2), simulation.tie_rule_paths(gap, (0, 0), (4, 2))).axes) >= 2
    pose = rec.scans.laser_poses[0]
    ends, hit = simulation.scan_end_points(pose, rec.scans.ranges[0], rec.scans.angles, 3.0)
    fig = simulation.scan_figure(scene.truth, pose, ends, hit, 3.0, "one scan")
    assert [ax.get_title() for ax in fig.axes if ax.get_title()] == ["Fig. 13: ground truth (0/1 cells)", "one scan"]
    fig = simulation.discretisation_figure(scene.truth, {0.0: rec}, ends[hit][0], {0.0: 0.5})
    assert fig.axes[0].get_xlim() == pytest.approx((ends[hit][0][0] - 1.0, ends[hit][0][0] + 1.0))
    fig = simulation.motion_figure(scene.truth, {0: rec, 1: rec}, {"m": scene.truth}, {"m": 0.0})
    assert any(ax.get_title().startswith("m (arctan model; MSE vs truth 0.0000)") for ax in fig.axes)
    grids = {(key, model): scene.truth for key in "rs" for model in ("arctan", "logodds")}
    numbers = {key: {"arctan": {"seconds": 0.01}, "logodds": {"seconds": 0.02}} for key in "rs"}
    fig = simulation.real_maps_figure({"r": ("label", rec), "s": ("label", rec)}, grids, numbers, 0.1)
    assert sum(ax.get_title().endswith("20 ms") for ax in fig.axes) == 2
    plt.close("all")
