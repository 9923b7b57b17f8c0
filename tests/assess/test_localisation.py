"""nav2_amcl's likelihood field against slow per-beam references, and localisation on synthetic rooms."""
import math

import numpy as np
import pytest
from scipy import ndimage

from crfmap.assess.likelihood_field import (Beams, LaserModel, LikelihoodField, beam_indices, distance_field,
                                            nav2_lethal)
from crfmap.assess.localisation import compare_localisation, localise, pose_offsets, search_poses, start_poses
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.io.map_server import load_map, save_map
from crfmap.recording import ScanSet
from crfmap.sim import Laser
from crfmap.sim.simulator import cast_rays

RES = 0.05  # [m]


# --- slow references, written from nav2_amcl's C++ line by line ---------------------------------------


def brute_occ_dist(lethal, resolution, max_dist):
    """map_cspace.cpp's result by brute force: distance to the nearest lethal cell, cut at int(max_dist / res)."""
    height, width = lethal.shape
    cell_radius = int(max_dist / resolution)
    out = np.full(lethal.shape, np.float32(max_dist), np.float32)
    sources = np.argwhere(lethal)
    for j in range(height):
        for i in range(width):
            if len(sources):
                d = min(math.hypot(i - si, j - sj) for sj, si in sources)
                if d <= cell_radius:
                    out[j, i] = d * resolution
    return out


def nav2_brushfire(lethal, scale, max_occ_dist):
    """map_cspace.cpp map_update_cspace line by line, with libstdc++'s std::priority_queue (push_heap / pop_heap).

    Each cell takes its distance to the obstacle cell its first-popped neighbour was reached from, which is
    not always the nearest one: nav2's occ_dist is an upper bound on the Euclidean distance.
    """
    def sift_up(heap, hole, value):  # __push_heap with comp(a, b) = a.occ_dist > b.occ_dist
        parent = (hole - 1) // 2
        while hole > 0 and heap[parent][0] > value[0]:
            heap[hole], hole, parent = heap[parent], parent, (parent - 1) // 2
        heap[hole] = value

    def pop(heap):  # pop_heap (__adjust_heap) then pop_back
        last = len(heap) - 1
        if last > 0:
            value, heap[last] = heap[last], heap[0]
            hole = second = 0
            while second < (last - 1) // 2:
                second = 2 * (second + 1)
                if heap[second][0] > heap[second - 1][0]:
                    second -= 1
                heap[hole], hole = heap[second], second
            if last % 2 == 0 and second == (last - 2) // 2:
                second = 2 * (second + 1)
                heap[hole], hole = heap[second - 1], second - 1
            sift_up(heap, hole, value)
        heap.pop()

    size_y, size_x = lethal.shape
    cell_radius = int(max_occ_dist / scale)
    occ = np.full(lethal.shape, np.float32(max_occ_dist), np.float32)
    marked = lethal.copy()
    heap = []
    for i in range(size_x):
        for j in range(size_y):
            if lethal[j, i]:
                occ[j, i] = 0.0
                heap.append((np.float32(0.0), i, j, i, j))
                sift_up(heap, len(heap) - 1, heap[-1])
    while heap:
        _, i, j, si, sj = heap[0]
        for ni, nj in ((i - 1, j), (i, j - 1), (i + 1, j), (i, j + 1)):  # enqueue's order
            if 0 <= ni < size_x and 0 <= nj < size_y and not marked[nj, ni]:
                d = math.sqrt((ni - si) ** 2 + (nj - sj) ** 2)
                if d <= cell_radius:
                    occ[nj, ni] = d * scale
                    heap.append((occ[nj, ni], ni, nj, si, sj))
                    sift_up(heap, len(heap) - 1, heap[-1])
                    marked[nj, ni] = True
        pop(heap)
    return occ


def naive_log_weight(probability, resolution, origin, scan_ranges, scan, pose, model):
    """likelihood_field_model.cpp sensorFunction for one scan at one laser pose, and updateFilter's range rules."""
    values = OccupancyGrid(probability).to_int8()
    occ_dist = brute_occ_dist(values >= 65, resolution, model.laser_likelihood_max_dist)
    size_y, size_x = occ_dist.shape
    map_origin_x = origin[0] + (size_x // 2) * resolution  # convertMap
    map_origin_y = origin[1] + (size_y // 2) * resolution
    range_max = min(scan.range_max, model.laser_max_range) if model.laser_max_range > 0 else scan.range_max
    range_min = max(scan.range_min, model.laser_min_range) if model.laser_min_range > 0 else scan.range_min
    ranges = [range_max if r <= range_min else float(r) for r in scan_ranges]  # short readings -> max range
    range_count = len(ranges)
    step = max(1, (range_count - 1) // (model.max_beams - 1))
    p = 1.0
    for i in range(0, range_count, step):
        obs_range = ranges[i]
        obs_bearing = scan.angle_min + i * scan.angle_increment
        if obs_range >= range_max or obs_range != obs_range:
            continue
        hit_x = pose[0] + obs_range * math.cos(pose[2] + obs_bearing)
        hit_y = pose[1] + obs_range * math.sin(pose[2] + obs_bearing)
        mi = math.floor((hit_x - map_origin_x) / resolution + 0.5) + size_x // 2
        mj = math.floor((hit_y - map_origin_y) / resolution + 0.5) + size_y // 2
        if 0 <= mi < size_x and 0 <= mj < size_y:
            z = float(occ_dist[mj, mi])
        else:
            z = model.laser_likelihood_max_dist
        pz = model.z_hit * math.exp(-(z * z) / (2 * model.sigma_hit * model.sigma_hit)) + model.z_rand / range_max
        p += pz * pz * pz
    return math.log(p)


# --- pieces ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(6))
def test_distance_field_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    height, width = rng.integers(2, 16, 2)
    lethal = rng.random((height, width)) < rng.choice([0.02, 0.1, 0.4])
    max_dist = float(rng.choice([0.12, 0.2, 0.37, 2.0]))  # 0.12 / 0.05 = 2.4 cells: cut at 2
    np.testing.assert_allclose(distance_field(lethal, RES, max_dist), brute_occ_dist(lethal, RES, max_dist),
                               rtol=1e-6)


@pytest.mark.parametrize("seed", range(4))
def test_nav2_brushfire_is_an_upper_bound_of_the_exact_distance(seed):
    """Where nav2's brushfire and the exact distance part (see the module doc): never below it, zero on obstacles."""
    rng = np.random.default_rng(seed)
    lethal = rng.random((24, 30)) < 0.05
    exact, nav2 = distance_field(lethal, RES, 0.4), nav2_brushfire(lethal, RES, 0.4)
    assert np.all(nav2 >= exact - 1e-7)
    np.testing.assert_array_equal(nav2[lethal], 0.0)
    assert nav2.max() <= np.float32(0.4)  # with the bound below: the exact cap cells are capped in nav2 too
    assert np.mean(nav2 > exact + 1e-6) < 0.15


def test_nav2_brushfire_is_exact_beside_one_straight_wall():
    lethal = np.zeros((15, 12), bool)
    lethal[:, 5] = True
    np.testing.assert_allclose(nav2_brushfire(lethal, RES, 2.0), distance_field(lethal, RES, 2.0), rtol=1e-6)


def test_distance_field_without_obstacles_is_the_cap():
    np.testing.assert_array_equal(distance_field(np.zeros((3, 4), bool), RES, 1.5), np.full((3, 4), 1.5, np.float32))


def test_nav2_lethal_is_what_nav2_loads_from_the_map_crfmap_writes(tmp_path):
    """The cells nav2's loader reads as 100 (occ_state +1 in AMCL) from a trinary map save_map writes."""
    p = np.linspace(0, 1, 1001).reshape(7, 143)
    p[0, :3] = 0.5  # unknown
    yaml_path, _ = save_map(OccupancyGrid(p, RES), tmp_path / "map.yaml", mode="trinary")
    for loader in ("jazzy", "humble"):
        loaded = load_map(yaml_path, loader=loader).to_int8()
        np.testing.assert_array_equal(nav2_lethal(p), loaded == 100)
    assert nav2_lethal(p).sum() == np.sum(np.rint(p * 100) >= 65) - 0  # 0.645 rounds to 64: not lethal


def test_beam_subsampling_follows_sensor_function():
    for n_beams, max_beams in [(180, 60), (181, 60), (361, 60), (5, 60), (1, 2), (100, 2)]:
        step = max(1, (n_beams - 1) // (max_beams - 1))
        assert beam_indices(n_beams, max_beams).tolist() == list(range(0, n_beams, step))


@pytest.mark.parametrize("model", [LaserModel(), LaserModel(max_beams=7, sigma_hit=0.1, z_hit=0.8, z_rand=0.2),
                                   LaserModel(laser_max_range=1.0, laser_min_range=0.3,
                                              laser_likelihood_max_dist=0.33)])
def test_log_weights_match_a_per_beam_loop(model):
    rng = np.random.default_rng(1)
    height, width = 13, 17
    p = rng.choice([0.0, 0.2, 0.5, 0.64, 0.66, 0.9, 1.0], (height, width), p=[.3, .1, .2, .1, .1, .1, .1])
    origin = (-0.31, 0.17)
    n_scans, n_beams = 4, 23
    ranges = rng.uniform(0.0, 1.2, (n_scans, n_beams)).astype(np.float32)
    ranges[rng.random(ranges.shape) < 0.15] = np.inf
    ranges[rng.random(ranges.shape) < 0.05] = -np.inf
    ranges[rng.random(ranges.shape) < 0.05] = np.nan
    poses = np.column_stack([rng.uniform(-0.4, 0.6, n_scans), rng.uniform(0.1, 0.9, n_scans),
                             rng.uniform(-3, 3, n_scans)])
    scans = ScanSet(ranges, -2.0, 0.17, 0.05, 1.1, poses, np.arange(n_scans, dtype=float))
    candidates = poses[:, None, :] + rng.normal(0, [0.3, 0.3, 0.5], (n_scans, 5, 3))  # some beams end off the map
    lfield = LikelihoodField.from_probability(p, RES, origin, model)
    fast = lfield.log_weights(Beams.from_scans(scans, model), candidates)
    slow = [[naive_log_weight(p, RES, origin, ranges[i], scans, candidates[i, k], model) for k in range(5)]
            for i in range(n_scans)]
    np.testing.assert_allclose(fast, slow, rtol=1e-12, atol=1e-12)


# --- localisation in a synthetic room ----------------------------------------------------------------------


def room_truth():
    """A 4 m x 3 m room with one-cell walls, a pillar, a box and a partition: P 1 on walls, 0 inside, 0.5 outside."""
    p = np.full((60, 80), 0.5)
    p[2:58, 2:78] = 0.0
    p[2, 2:78] = p[57, 2:78] = 1.0
    p[2:58, 2] = p[2:58, 77] = 1.0
    p[20:24, 20:24] = 1.0  # pillar
    p[35:45, 50:62] = 1.0  # box
    p[2:30, 40] = 1.0  # partition from the bottom wall
    return p


def room_scans():
    """The room's truth and 40 noiseless 360-beam scans from free poses 0.3 m or more from any wall."""
    p = room_truth()
    truth = OccupancyGrid(p, RES)
    clearance = ndimage.distance_transform_edt(p == 0.0) * RES
    rng = np.random.default_rng(3)
    poses = []
    while len(poses) < 40:
        x, y = rng.uniform(0.2, 3.8), rng.uniform(0.2, 2.8)
        if p[int(y / RES), int(x / RES)] == 0.0 and clearance[int(y / RES), int(x / RES)] >= 0.3:
            poses.append((x, y, rng.uniform(-math.pi, math.pi)))
    laser = Laser.with_fov(360, 360, range_max=6.0)
    poses = np.array(poses)
    scans = ScanSet(cast_rays(truth, laser, poses).astype(np.float32), laser.angle_min, laser.angle_increment,
                    laser.range_min, laser.range_max, poses, np.arange(len(poses), dtype=float))
    return p, scans


@pytest.fixture(scope="module")
def room():
    return room_scans()


CENTRED = (RES / 2, RES / 2)  # the room's origin (0, 0) moved half a cell: AMCL's rounded lookup then hits true cells


def test_perfect_map_tells_the_true_pose_apart_and_the_search_finds_it(room):
    p, scans = room
    r = localise(p, RES, CENTRED, scans, seed=0)
    s = r.summary()
    assert s["scans"] == 40 and s["beats_offsets"] >= 0.99 and s["log_margin"] > 0.2
    assert s["found"] == 1.0
    assert s["translation_error"] <= 0.02 and s["rotation_error"] <= 0.5
    assert np.median(np.hypot(*(r.start_poses - scans.laser_poses)[:, :2].T)) > 0.1  # it did have to search


def test_nav2_rounding_moves_the_best_pose_by_half_a_cell(room):
    """With the grid's own origin, AMCL reads each cell half a cell low: the search ends about (-res/2, -res/2) off."""
    p, scans = room
    r = localise(p, RES, (0.0, 0.0), scans, seed=0)
    shift = np.median(r.found_poses[:, :2] - scans.laser_poses[:, :2], axis=0)
    np.testing.assert_allclose(shift, [-RES / 2, -RES / 2], atol=0.01)
    assert r.summary()["found"] == 1.0


def test_walls_thickened_by_three_cells_localise_worse(room):
    """The issue's point: thick walls blur AMCL's likelihood field (and each extra cell blurs it more)."""
    p, scans = room
    scores = [localise(np.where(ndimage.binary_dilation(p == 1.0, iterations=k), 1.0, p) if k else p, RES, CENTRED,
                       scans, seed=0).summary() for k in range(4)]
    thin, thick = scores[0], scores[3]
    assert thick["beats_offsets"] < thin["beats_offsets"] - 0.01
    assert thick["log_margin"] < 0.6 * thin["log_margin"]
    assert thick["translation_error"] > 3 * thin["translation_error"]
    assert thick["found"] < thin["found"] - 0.1
    margins = [s["log_margin"] for s in scores]
    assert margins == sorted(margins, reverse=True) and len(set(margins)) == 4


def test_compare_pairs_maps_on_the_same_scans_and_resamples(room):
    p, scans = room
    thick = np.where(ndimage.binary_dilation(p == 1.0, iterations=3), 1.0, p)
    maps = {"raw": p, "same": p.copy(), "thick": thick}
    out = compare_localisation(maps, RES, CENTRED, scans, n_boot=300, seed=4)
    again = compare_localisation(maps, RES, CENTRED, scans, n_boot=300, seed=4)
    for name in maps:
        assert {k: v for k, v in out[name].items() if k != "seconds"} == \
            {k: v for k, v in again[name].items() if k != "seconds"}
    for m in ("beats_offsets", "log_margin", "translation_error", "rotation_error", "found"):
        assert out["raw"][m + "_diff"] == 0.0 and out["same"][m + "_diff_ci"] == (0.0, 0.0)
        assert out["same"][m + "_ci"] == out["raw"][m + "_ci"]
        lo, hi = out["thick"][m + "_ci"]
        assert lo <= out["thick"][m] <= hi
    assert out["thick"]["log_margin_diff_ci"][1] < 0  # paired: thick walls lose margin on these scans
    assert out["thick"]["translation_error_diff_ci"][0] > 0
    assert out["thick"]["scans"] == 40


def test_offsets_and_starts_are_seeded_and_in_range():
    d = pose_offsets(50, 8, seed=5)
    np.testing.assert_array_equal(d, pose_offsets(50, 8, seed=5))
    assert not np.array_equal(d, pose_offsets(50, 8, seed=6))
    dist, turn = np.hypot(d[..., 0], d[..., 1]), np.degrees(np.abs(d[..., 2]))
    assert dist.min() >= 0.05 and dist.max() <= 0.30 and turn.min() >= 2 and turn.max() <= 10
    s = start_poses(np.zeros((200, 3)), seed=5)
    assert np.hypot(s[:, 0], s[:, 1]).max() <= 0.30 and np.degrees(np.abs(s[:, 2])).max() <= 10
    assert np.hypot(s[:, 0], s[:, 1]).max() > 0.25  # the whole range is used


def test_scans_without_a_usable_beam_are_left_out(room):
    p, scans = room
    ranges = scans.ranges.copy()
    ranges[[1, 4]] = np.inf
    from dataclasses import replace
    r = localise(p, RES, CENTRED, replace(scans, ranges=ranges), seed=0)
    assert 1 not in r.scan_index and 4 not in r.scan_index and len(r.scan_index) == 38


def test_search_leaves_a_scan_without_beams_where_it_started():
    lfield = LikelihoodField.from_probability(room_truth(), RES)
    beams = Beams(np.full((1, 3), np.nan), np.zeros(3), 5.0)
    start = np.array([[1.0, 1.0, 0.2]])
    np.testing.assert_array_equal(search_poses(lfield, beams, start), start)


# --- bad input -----------------------------------------------------------------------------------------------


def _scans(n=3, **changes):
    fields = dict(ranges=np.ones((n, 5), np.float32), angle_min=0.0, angle_increment=0.1, range_min=0.0,
                  range_max=5.0, laser_poses=np.full((n, 3), 0.5), stamps=np.arange(n, dtype=float))
    fields.update(changes)
    return ScanSet(**fields)


P = np.zeros((20, 20))


@pytest.mark.parametrize("call", [
    lambda: localise(P, 0.0, (0, 0), _scans()),
    lambda: localise(P, RES, (0, 0, 0.3), _scans()),
    lambda: localise(P, RES, (0, 0, 0, 0), _scans()),
    lambda: localise(P, RES, (np.nan, 0), _scans()),
    lambda: localise(P + 2, RES, (0, 0), _scans()),
    lambda: localise(P * np.nan, RES, (0, 0), _scans()),
    lambda: localise(np.zeros(5), RES, (0, 0), _scans()),
    lambda: localise(P, RES, (0, 0), "scans"),
    lambda: localise(P, RES, (0, 0), _scans(ranges=np.full((3, 5), np.inf, np.float32))),
    lambda: localise(P, RES, (0, 0), _scans(laser_poses=np.zeros((2, 3)))),
    lambda: localise(P, RES, (0, 0), _scans(laser_poses=np.full((3, 3), np.nan))),
    lambda: localise(P, RES, (0, 0), _scans(range_max=math.inf)),
    lambda: localise(P, RES, (0, 0), _scans(), max_scans=0),
    lambda: localise(P, RES, (0, 0), _scans(), n_offsets=0),
    lambda: localise(P, RES, (0, 0), _scans(), seed=-1),
    lambda: LaserModel(max_beams=1),
    lambda: LaserModel(sigma_hit=0.0),
    lambda: LaserModel(z_hit=-0.1),
    lambda: distance_field(np.zeros((3, 3)), RES),
    lambda: pose_offsets(3, 2, translation=(0.3, 0.1)),
    lambda: compare_localisation({}, RES, (0, 0), _scans()),
    lambda: compare_localisation({"a": P}, RES, (0, 0), _scans()),
    lambda: compare_localisation({"raw": P, "b": np.zeros((3, 3))}, RES, (0, 0), _scans()),
    lambda: compare_localisation({"raw": P}, RES, (0, 0), _scans(), n_boot=-1),
    lambda: compare_localisation({"raw": P}, RES, (0, 0), _scans(), level=1.0),
    lambda: LikelihoodField.from_probability(P, RES).log_weights(Beams.from_scans(_scans()), np.zeros((2, 1, 3))),
    lambda: search_poses(LikelihoodField.from_probability(P, RES), Beams.from_scans(_scans()), np.zeros((2, 3))),
])
def test_bad_input_is_refused(call):
    with pytest.raises(InputError):
        call()
