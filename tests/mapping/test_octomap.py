"""OctoMap's update on a grid: a hand-worked case, the traversal's rules, and the real OctoMap library."""
import math

import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.mapping.octomap import CLAMP_MAX, CLAMP_MIN, _ray_cells, octomap_grid
from crfmap.recording import ScanSet


def _logit(p):
    return math.log(p / (1 - p))


def _scans(ranges, poses, angle_min=0.0, increment=0.0):
    r = np.asarray(ranges, np.float32)
    return ScanSet(r, angle_min, increment, 0.01, 20.0, np.asarray(poses, np.float64), np.arange(len(r), dtype=float))


def test_hand_worked_two_beams_three_scans():
    # one row of 6 cells of 1 m; the laser in cell 0 looks along +x. Scan 1: two beams end in cell 3
    # (cells 0-2 free once although two beams pass them, cell 3 occupied once); scan 2: one beam to cell 4
    # passes cell 3 and a second beam ends there (occupied wins: cell 3 is hit, not missed); scan 3 = scan 1.
    s = _scans([[2.9, 3.3], [4.0, 2.7], [2.9, 3.3]], [[0.5, 0.5, 0.0]] * 3)  # ends at x = 0.5 + r
    g = octomap_grid(s, 1.0, bounds=(0, 0, 6, 1))
    hit, miss = _logit(0.7), _logit(0.4)
    lo, hi = _logit(CLAMP_MIN), _logit(CLAMP_MAX)
    expected_l = [max(3 * miss, lo), max(3 * miss, lo), max(3 * miss, lo), min(3 * hit, hi), hit]
    expected = 1 / (1 + np.exp(-np.array(expected_l)))
    np.testing.assert_allclose(g.probability[0, :5], expected, atol=1e-6)
    assert g.probability[0, 5] == 0.5  # never reached: unknown
    # 3 misses = -1.216 stays above the clamp -2; 3 hits = 2.54 below 3.5: no clamping yet. Ten scans clamp both.
    g10 = octomap_grid(_scans([[2.9, 3.3]] * 10, [[0.5, 0.5, 0.0]] * 10), 1.0, bounds=(0, 0, 6, 1))
    np.testing.assert_allclose(g10.probability[0, :4], [CLAMP_MIN] * 3 + [CLAMP_MAX], atol=1e-6)


def test_traversal_is_four_connected_and_excludes_the_end():
    buf = np.empty((32, 2), np.int64)
    n = _ray_cells(0.5, 0.5, 3.2, 2.7, 10, 10, buf)
    cells = [tuple(c) for c in buf[:n]]
    assert cells[0] == (0, 0) and (3, 2) not in cells
    for a, b in zip(cells, cells[1:] + [(3, 2)]):
        assert abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1  # one side at a time, never a corner jump
    # every cell the segment's interior passes through is listed (sampled densely)
    t = np.linspace(0, 1, 20001)[:-1]
    passed = {(int(np.floor(0.5 + 2.7 * s)), int(np.floor(0.5 + 2.2 * s))) for s in t} - {(3, 2)}
    assert passed == set(cells)
    assert _ray_cells(0.2, 0.2, 0.9, 0.7, 10, 10, buf) == 0  # same cell: nothing free


def test_checks_its_parameters():
    s = _scans([[1.0]], [[0.5, 0.5, 0.0]])
    with pytest.raises(InputError, match="p_hit"):
        octomap_grid(s, 0.1, p_hit=1.2)
    with pytest.raises(InputError, match="clamp"):
        octomap_grid(s, 0.1, clamp_min=0.6)


def _random_scans(seed, n_scans=6, n_beams=40):
    rng = np.random.default_rng(seed)
    poses = np.column_stack([rng.uniform(2.1, 2.9, n_scans), rng.uniform(2.1, 2.9, n_scans),
                             rng.uniform(-np.pi, np.pi, n_scans)])
    ranges = rng.uniform(0.3, 1.8, (n_scans, n_beams)).astype(np.float32)
    return ScanSet(ranges, -np.pi, 2 * np.pi / n_beams, 0.01, 20.0, poses, np.arange(n_scans, dtype=float))


@pytest.mark.parametrize("seed", [0, 1])
def test_matches_the_octomap_library(seed):
    octomap = pytest.importorskip("octomap")  # octomap-python: the real OctoMap (C++), test extra
    res = 0.1
    scans = _random_scans(seed)
    grid = octomap_grid(scans, res, bounds=(0, 0, 5, 5))
    tree = octomap.OcTree(res)  # OctoMap's defaults: hit 0.7, miss 0.4, clamping 0.1192 / 0.971
    z = 0.5 * res  # the laser's plane through the middle of one voxel layer: the 3-D walk stays in it
    angles = scans.angle_min + scans.angle_increment * np.arange(scans.ranges.shape[1])
    for r, (x, y, yaw) in zip(scans.ranges, scans.laser_poses):
        a = yaw + angles
        points = np.column_stack([x + r * np.cos(a), y + r * np.sin(a), np.full(len(r), z)])
        tree.insertPointCloud(points, np.array([x, y, z]))
    ours = grid.probability
    theirs = np.full_like(ours, 0.5)
    for iy in range(ours.shape[0]):
        for ix in range(ours.shape[1]):
            node = tree.search(np.array([(ix + 0.5) * res, (iy + 0.5) * res, z]))
            try:
                theirs[iy, ix] = node.getOccupancy()
            except octomap.NullPointerException:
                pass  # never observed
    # a point on a cell boundary may fall either side in float32 vs float64: allow a handful of cells
    differ = np.abs(ours - theirs) > 1e-5
    assert (ours != 0.5).sum() > 300
    assert differ.sum() <= 3, np.argwhere(differ)


def test_updater_scan_by_scan_equals_the_whole_recording():
    from crfmap.mapping.octomap import OctoMapUpdater

    rng = np.random.default_rng(3)
    n, beams = 12, 45
    poses = np.column_stack([rng.uniform(1, 3, n), rng.uniform(1, 3, n), rng.uniform(-3, 3, n)])
    ranges = rng.uniform(0.2, 2.5, (n, beams)).astype(np.float32)
    ranges[rng.random((n, beams)) < 0.1] = np.inf  # no returns: dropped, as in the whole-recording update
    s = ScanSet(ranges, -math.pi, 2 * math.pi / beams, 0.05, 5.0, poses, np.arange(n, dtype=float))
    whole = octomap_grid(s, 0.1, bounds=(0, 0, 4, 4))
    up = OctoMapUpdater.for_sensor((0, 0, 4, 4), 0.1, s.angle_min, s.angle_increment, beams, 0.05, 5.0)
    for r, p in zip(ranges, poses):
        up.add_scan(r, p)
    assert up.scans == n
    np.testing.assert_array_equal(up.grid().probability, whole.probability)
    with pytest.raises(InputError, match="ranges"):
        up.add_scan(ranges[0, :3], poses[0])
    with pytest.raises(InputError, match="laser_pose"):
        up.add_scan(ranges[0], (9.0, 9.0, 0.0))
