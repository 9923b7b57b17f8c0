"""crfmap.mapping.builder: ray casting into hit counts, the thesis's arctan grid, the log-odds baseline, `crfmap build`."""
import math

import numpy as np
import pytest

import naive_builder as naive
from crfmap.data import data_file, have_data
from crfmap.io.carmen import read_carmen
from crfmap.mapping.builder import (HitCounter, arctan_probability, build_grid, count_hits, logodds_to_probability,
                            scan_bounds)
from crfmap.cli import main
from crfmap.errors import InputError
from crfmap.recording import ScanSet

INTEL = "carmen/intel-corrected.log.gz"
ACES = "carmen/aces-corrected.log.gz"
ROS2_BAG = "rosbags/olin_comprobo24_turtlebot4/macfirst_floor_take_2"


def one_beam(r, range_min=0.1, range_max=5.0, pose=(0.05, 0.05, 0.0)):
    """A single beam along the laser's x axis."""
    return ScanSet(np.array([[r]], np.float32), 0.0, 0.0, range_min, range_max, np.array([pose], float), np.zeros(1))


def random_scans(seed, n_scans=6, n_beams=15, special=True):
    """Scans inside a 4 m x 3 m box, with NaN/-Inf/+Inf/too short/too long readings sprinkled in."""
    rng = np.random.default_rng(seed)
    ranges = rng.uniform(0.05, 2.5, (n_scans, n_beams)).astype(np.float32)
    if special:
        for value in (np.nan, -np.inf, np.inf, np.inf, 0.02, 7.0, 2.0):  # 2.0 = range_max
            ranges[rng.integers(n_scans), rng.integers(n_beams)] = value
    poses = np.column_stack([rng.uniform(1.6, 2.4, n_scans), rng.uniform(1.1, 1.9, n_scans),
                             rng.uniform(-np.pi, np.pi, n_scans)])
    return ScanSet(ranges, -2.0, 4.0 / (n_beams - 1), 0.1, 2.0, poses, np.arange(n_scans, dtype=float))


BOUNDS = (-1.0, -1.5, 5.0, 4.5)  # holds every ray of random_scans, even 2.5 m no-return ones


# --- counts against the reference ---------------------------------------------------------
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("free", [False, 1.5])
def test_counts_match_naive_reference(seed, free):
    scans = random_scans(seed)
    res = 0.1
    occ, emp = count_hits(scans, res, bounds=BOUNDS, free_on_no_return=free)
    ref_occ, ref_emp = naive.count_hits(scans, occ.shape, BOUNDS[:2], res, free_on_no_return=free or 0.0)
    assert occ.shape == (60, 60)
    assert occ.sum() > 0 and emp.sum() > 0
    np.testing.assert_array_equal(occ, ref_occ)
    np.testing.assert_array_equal(emp, ref_emp)


def test_one_beam_cells_and_eq16():
    # Laser in cell (0, 0), a 0.36 m return along +x at 0.1 m cells: cells 0..3 passed, cell 4 hit.
    occ, emp = count_hits(one_beam(0.36), 0.1, bounds=(0, 0, 0.6, 0.1))
    assert occ.tolist() == [[0, 0, 0, 0, 1, 0]]
    assert emp.tolist() == [[1, 1, 1, 1, 0, 0]]
    p = build_grid(one_beam(0.36), 0.1, bounds=(0, 0, 0.6, 0.1)).probability[0]
    # eq. 16: x = -1 -> 0.5 + atan(-1)/pi = 0.25; x = +1 -> 0.75; never seen -> 0.5
    np.testing.assert_allclose(p, [0.25, 0.25, 0.25, 0.25, 0.75, 0.5])


def test_arctan_grid_is_eq16_of_the_counts():
    scans = random_scans(3)
    occ, emp = count_hits(scans, 0.1, bounds=BOUNDS)
    grid = build_grid(scans, 0.1, bounds=BOUNDS)
    expected = 0.5 + np.arctan(occ.astype(float) - emp) / np.pi
    np.testing.assert_allclose(grid.probability, expected, rtol=0, atol=1e-15)
    never = (occ == 0) & (emp == 0)
    assert never.any() and np.all(grid.probability[never] == 0.5)
    assert grid.origin == (BOUNDS[0], BOUNDS[1], 0.0) and grid.resolution == 0.1
    # Repeated evidence approaches but never reaches certainty (thesis sec. 3.2).
    assert arctan_probability(np.array([1000]), np.array([0]))[0] < 1.0


@pytest.mark.parametrize("seed", [0, 4])
def test_logodds_matches_naive_reference(seed):
    scans = random_scans(seed)
    grid = build_grid(scans, 0.1, model="logodds", bounds=BOUNDS, p_hit=0.7, p_miss=0.4, logodds_limit=1.0)
    ref = naive.logodds(scans, grid.shape, BOUNDS[:2], 0.1, 0.7, 0.4, 1.0)
    np.testing.assert_allclose(grid.probability, ref, rtol=0, atol=1e-12)
    assert np.any(np.isclose(ref, 1 / (1 + math.exp(-1.0))))  # the clamp was reached somewhere


def test_logodds_formulas_single_scan_and_clamp():
    grid = build_grid(one_beam(0.36), 0.1, model="logodds", bounds=(0, 0, 0.6, 0.1), p_hit=0.7, p_miss=0.4)
    # One observation: P = 1 - 1/(1 + exp(log(p/(1-p)))) = p exactly.
    np.testing.assert_allclose(grid.probability[0], [0.4, 0.4, 0.4, 0.4, 0.7, 0.5])
    # Twenty identical scans: l = 20 * log(7/3) = 16.9 is clamped to the limit.
    s = one_beam(0.36)
    many = ScanSet(np.repeat(s.ranges, 20, 0), 0.0, 0.0, 0.1, 5.0, np.repeat(s.laser_poses, 20, 0), np.arange(20.0))
    g = build_grid(many, 0.1, model="logodds", bounds=(0, 0, 0.6, 0.1), logodds_limit=3.0)
    np.testing.assert_allclose(g.probability[0, 4], 1 - 1 / (1 + math.exp(3.0)))
    np.testing.assert_allclose(g.probability[0, 0], 1 - 1 / (1 + math.exp(-3.0)))
    assert logodds_to_probability(np.array([800.0]))[0] == 1.0  # no overflow warning


def test_logodds_counts_each_cell_once_per_scan():
    # Two beams of one scan pass the laser's cell: one update there, not two.
    s = ScanSet(np.array([[0.36, 0.36]], np.float32), 0.0, 0.1, 0.1, 5.0, np.array([[0.05, 0.05, 0.0]]), np.zeros(1))
    g = build_grid(s, 0.1, model="logodds", bounds=(0, 0, 0.6, 0.6))
    assert g.probability[0, 0] == pytest.approx(0.4)
    occ, emp = count_hits(s, 0.1, bounds=(0, 0, 0.6, 0.6))
    assert emp[0, 0] == 2  # while the thesis's counts are per beam


# --- REP 117 ---------------------------------------------------------------------------------
@pytest.mark.parametrize("r", [np.nan, -np.inf, np.inf, 0.05, 6.0])
def test_rep117_dropped_readings_touch_nothing(r):
    occ, emp = count_hits(one_beam(r), 0.1, bounds=(0, 0, 1, 1))
    assert occ.sum() == 0 and emp.sum() == 0


def test_range_limits_are_inclusive_and_range_max_is_the_legacy_no_return():
    occ, _ = count_hits(one_beam(0.1), 0.1, bounds=(0, 0, 1, 1))
    assert occ.sum() == 1  # range_min itself is valid
    occ, emp = count_hits(one_beam(5.0, range_max=5.0), 0.1, bounds=(0, 0, 6, 1))
    assert occ.sum() == 0 and emp.sum() == 0  # range_max = "nothing returned" (legacy code)
    occ, _ = count_hits(one_beam(5.0, range_max=5.0), 0.1, bounds=(0, 0, 6, 1), max_range_is_no_return=False)
    assert occ.sum() == 1


def test_free_on_no_return_clears_up_to_the_range_only():
    occ, emp = count_hits(one_beam(np.inf), 0.1, bounds=(0, 0, 3, 0.1), free_on_no_return=1.0)
    assert occ.sum() == 0
    assert emp[0].tolist() == [1] * 11 + [0] * 19  # cells 0..10: x from 0.05 to 1.05 m
    # NaN and -Inf never clear space, only +Inf does.
    for r in (np.nan, -np.inf):
        occ, emp = count_hits(one_beam(r), 0.1, bounds=(0, 0, 3, 0.1), free_on_no_return=1.0)
        assert emp.sum() == 0
    # True means "up to range_max".
    _, emp = count_hits(one_beam(np.inf, range_max=2.0), 0.1, bounds=(0, 0, 3, 0.1), free_on_no_return=True)
    assert emp.sum() == 21


# --- bounds -------------------------------------------------------------------------------------
def test_bounds_from_data_holds_every_end_point():
    scans = random_scans(5)
    occ, _ = count_hits(scans, 0.05)
    grid = build_grid(scans, 0.05)
    assert grid.shape == occ.shape
    xmin, ymin, xmax, ymax = scan_bounds(scans)
    ox, oy, _ = grid.origin
    assert ox <= xmin and oy <= ymin
    assert ox + grid.width * 0.05 >= xmax - 1e-9 and oy + grid.height * 0.05 >= ymax - 1e-9
    ok = np.isfinite(scans.ranges) & (scans.ranges >= 0.1) & (scans.ranges < 2.0)
    assert occ.sum() == ok.sum()  # every valid return landed inside the grid
    assert math.isclose(ox / 0.05, round(ox / 0.05), abs_tol=1e-6)  # origin snapped to the resolution


def test_given_bounds_cut_beams_without_false_walls():
    occ, emp = count_hits(one_beam(2.0), 0.1, bounds=(0, 0, 1.0, 0.1))
    assert occ.sum() == 0 and emp[0].tolist() == [1] * 10


def test_pose_outside_bounds_is_an_input_error():
    with pytest.raises(InputError, match="bounds.*scan 0.*outside"):
        build_grid(one_beam(1.0, pose=(5.0, 0.05, 0.0)), 0.1, bounds=(0, 0, 1, 1))


@pytest.mark.parametrize("kwargs, match", [
    (dict(resolution=0.0), "resolution"),
    (dict(resolution=float("nan")), "resolution"),
    (dict(model="bayes"), "model"),
    (dict(model="logodds", p_hit=0.4), "p_hit"),
    (dict(model="logodds", p_miss=1.0), "p_miss"),
    (dict(bounds=(1, 0, 0, 1)), "bounds"),
    (dict(free_on_no_return=-1.0), "free_on_no_return"),
    (dict(resolution=1e-5), "too large"),
])
def test_bad_arguments(kwargs, match):
    kw = dict(resolution=0.1)
    kw.update(kwargs)
    with pytest.raises(InputError, match=match):
        build_grid(random_scans(0), **kw)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_hit_counter_one_scan_at_a_time_equals_the_whole_recording(seed):
    """Scans added one by one, in any order, give count_hits's counts and build_grid's grid."""
    scans = random_scans(seed, n_scans=8)
    counter = HitCounter.for_scans(scans, 0.1, bounds=BOUNDS, free_on_no_return=1.5)
    for i in np.random.default_rng(seed).permutation(len(scans)):
        before = (counter.occupied.copy(), counter.empty.copy())
        cells = counter.add_scan(scans.ranges[i], scans.laser_poses[i])
        # the cells listed are the cells the scan's beams passed, once each: those whose counts
        # moved, plus none that did not (every listed cell gained a hit)
        moved = (counter.occupied != before[0]) | (counter.empty != before[1])
        listed = np.zeros_like(moved)
        listed[cells[:, 1], cells[:, 0]] = True
        assert len(np.unique(cells, axis=0)) == len(cells)
        np.testing.assert_array_equal(listed, moved)
    occupied, empty = count_hits(scans, 0.1, bounds=BOUNDS, free_on_no_return=1.5)
    np.testing.assert_array_equal(counter.occupied, occupied)
    np.testing.assert_array_equal(counter.empty, empty)
    grid = build_grid(scans, 0.1, bounds=BOUNDS, free_on_no_return=1.5)
    np.testing.assert_array_equal(counter.grid().probability, grid.probability)
    assert counter.grid().origin == grid.origin and counter.scans == len(scans)


def test_hit_counter_for_a_sensor_and_bad_scans():
    counter = HitCounter.for_sensor((0.0, 0.0, 4.0, 3.0), 0.1, -1.0, 0.1, 21, 0.05, 5.0)
    assert counter.occupied.shape == (30, 40) and np.all(counter.grid().probability == 0.5)
    assert len(counter.add_scan(np.full(21, np.nan, np.float32), (1.0, 1.0, 0.0))) == 0
    with pytest.raises(InputError, match="ranges"):
        counter.add_scan(np.ones(3, np.float32), (1.0, 1.0, 0.0))
    with pytest.raises(InputError, match="laser_pose"):
        counter.add_scan(np.ones(21, np.float32), (np.inf, 1.0, 0.0))
    with pytest.raises(InputError, match="outside"):
        counter.add_scan(np.ones(21, np.float32), (9.0, 1.0, 0.0))
    with pytest.raises(InputError, match="n_beams"):
        HitCounter.for_sensor((0.0, 0.0, 4.0, 3.0), 0.1, -1.0, 0.1, 0, 0.05, 5.0)


def test_bad_scans():
    s = random_scans(0)
    s.laser_poses[2, 0] = np.nan
    with pytest.raises(InputError, match="scan 2"):
        build_grid(s, 0.1)
    with pytest.raises(InputError, match="range_min"):
        build_grid(one_beam(1.0, range_min=3.0, range_max=2.0), 0.1)
    with pytest.raises(InputError, match="ScanSet"):
        build_grid(np.zeros((3, 3)), 0.1)


# --- real data: walls line up ------------------------------------------------------------------
def wall_statistics(grid):
    """(occupied share of known cells, share of occupied cells with an occupied 8-neighbour)."""
    occ = grid.probability > 0.5
    pad = np.pad(occ, 1)
    h, w = occ.shape
    neighbours = sum(pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
                     for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0))
    return occ.sum() / grid.known().sum(), (occ & (neighbours > 0)).sum() / occ.sum()


def hits_on_walls(occupied, empty):
    """Share of occupied hits that land in cells more often hit than passed: high when scans agree."""
    return occupied[occupied > empty].sum() / occupied.sum()


@pytest.mark.parametrize("name", [INTEL, ACES])
@pytest.mark.skipif(not (have_data(INTEL) and have_data(ACES)), reason="CARMEN logs not downloaded")
def test_carmen_maps_have_crisp_walls(name):
    rec = read_carmen(data_file(name))
    for model in ("arctan", "logodds"):
        grid = build_grid(rec.scans, 0.05, model=model)
        share, connected = wall_statistics(grid)
        assert share < 0.1, (model, share)  # walls are thin; rooms are free
        assert connected > 0.8, (model, connected)  # and continuous, not speckle
    occ, emp = count_hits(rec.scans, 0.05)
    assert hits_on_walls(occ, emp) > 0.3  # Intel 0.5, ACES 0.4; a wrong mount gives ~0.1


@pytest.mark.skipif(not have_data(ROS2_BAG), reason="ROS2 bag not downloaded")
def test_ros2_bag_map_needs_the_laser_mount():
    from crfmap.io.bag_reader import read_bag

    bag = data_file(ROS2_BAG)
    with_mount = read_bag(bag)
    without = read_bag(bag, laser_mount=(0.0, 0.0, 0.0))
    crisp = hits_on_walls(*count_hits(with_mount.scans, 0.05))
    blurred = hits_on_walls(*count_hits(without.scans, 0.05))
    assert crisp > 0.4 and crisp > 2 * blurred, (crisp, blurred)
    share, connected = wall_statistics(build_grid(with_mount.scans, 0.05))
    assert share < 0.1 and connected > wall_statistics(build_grid(without.scans, 0.05))[1]


# --- the `crfmap build` command -----------------------------------------------------------
@pytest.mark.parametrize("suffix", [".npy", ".yaml"])
def test_build_command_writes_a_map(small_log, tmp_path, capsys, suffix):
    from crfmap.io.grid_files import load_grid

    out = tmp_path / f"map{suffix}"
    scale = ["--mode", "scale"] if suffix == ".yaml" else []  # scale keeps P to a percent (trinary: tests/io/test_nav2.py)
    assert main(["build", str(small_log), str(out), "--resolution", "0.1", *scale]) == 0
    line = capsys.readouterr().out.strip()
    assert "\n" not in line and "2 scans used" in line and str(out) in line
    grid = load_grid(out)
    expected = build_grid(read_carmen(small_log).scans, 0.1)
    assert grid.shape == expected.shape
    np.testing.assert_allclose(grid.probability, expected.probability, atol=0.005 if suffix == ".yaml" else 0)


def _write(path, content):
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content is not None:
        path.write_text(content)
    return path


@pytest.mark.parametrize("name, content, match", [
    ("missing.log", None, "missing.log: no such file"),
    ("bad.log", "FLASER 3 1 2\n", "bad.log: line 1"),
    ("junk.bag", b"#ROSBAG V2.0\n" + b"\0" * 50, "junk.bag"),
    ("notes.txt", "hi", "notes.txt: not a ROS bag"),
])
def test_build_command_bad_input_exits_2(tmp_path, capsys, name, content, match):
    src = _write(tmp_path / name, content)
    out = tmp_path / "out.npy"
    assert main(["build", str(src), str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and match in err
    assert not out.exists() and not list(tmp_path.glob("out*"))


def test_build_command_rejects_unknown_output_type(small_log, tmp_path, capsys):
    assert main(["build", str(small_log), str(tmp_path / "map.png")]) == 2
    assert "map.png" in capsys.readouterr().err
    assert not (tmp_path / "map.png").exists()


def test_build_command_from_a_bag_and_with_raw_odometry(small_log, tmp_path, capsys):
    from crfmap.io.bag_reader import read_bag
    from crfmap.io.bag_writer import write_bag

    rec = read_carmen(small_log)
    write_bag(rec, tmp_path / "bag", fmt="ros2")
    assert main(["build", str(tmp_path / "bag"), str(tmp_path / "from_bag.npy"), "--resolution", "0.1"]) == 0
    assert "pose source tf" in capsys.readouterr().out
    from_bag = np.load(tmp_path / "from_bag.npy")
    assert np.array_equal(from_bag, build_grid(read_bag(tmp_path / "bag").scans, 0.1).probability)
    # Same map as from the log itself, up to cells that float32 beam angles move across a boundary.
    direct = build_grid(rec.scans, 0.1).probability
    assert from_bag.shape == direct.shape and np.mean(from_bag != direct) < 0.05
    # CARMEN with --pose-source odom: the ODOM track (none in this log) -> a clear error.
    assert main(["build", str(small_log), str(tmp_path / "odom.npy"), "--pose-source", "odom"]) == 2
    assert "no ODOM lines" in capsys.readouterr().err


@pytest.mark.parametrize("option", [["--scan-topic", "/scan"], ["--laser-mount", "0", "0", "1"],
                                    ["--pose-source", "tf"], ["--resolution", "-1"]])
def test_build_command_options_that_do_not_apply(small_log, tmp_path, capsys, option):
    assert main(["build", str(small_log), str(tmp_path / "m.npy"), *option]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert not (tmp_path / "m.npy").exists()
