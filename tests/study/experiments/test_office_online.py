"""Notebook 07's online helpers: snapshots equal the builder on the scans so far, numbers follow the updates."""
import numpy as np
import pytest

from crfmap.crf.inference.lbp import infer
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK
from crfstudy.experiments.office_online import (default_table_drift, map_online, near_versus_offline, online_numbers,
                                             versus_offline)
from crfmap.grid import UNKNOWN
from crfmap.mapping.builder import build_grid
from crfmap.mapping.online import OnlineMapper
from crfmap.recording import ScanSet


def room_scans(n=10, beams=41, seed=1):
    """Scans in a 4 m x 3 m box room, ranges cast analytically to its walls."""
    rng = np.random.default_rng(seed)
    angles = np.linspace(-np.pi / 2, np.pi / 2, beams)
    poses = np.column_stack([rng.uniform(0.8, 3.2, n), rng.uniform(0.8, 2.2, n), rng.uniform(-np.pi, np.pi, n)])
    a = poses[:, 2:3] + angles
    c, s = np.cos(a), np.sin(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(c > 0, (4.0 - poses[:, :1]) / c, np.where(c < 0, -poses[:, :1] / c, np.inf))
        ty = np.where(s > 0, (3.0 - poses[:, 1:2]) / s, np.where(s < 0, -poses[:, 1:2] / s, np.inf))
    ranges = np.minimum(tx, ty).astype(np.float32)
    return ScanSet(ranges, float(angles[0]), float(angles[1] - angles[0]), 0.05, 8.0, poses,
                   0.5 * np.arange(n), source="room")


def test_snapshots_are_the_grids_of_the_scans_so_far():
    scans = room_scans()
    mapper = OnlineMapper.for_scans(scans, 0.1, radius=1.5, max_iter=4)
    run = map_online(mapper, scans, snapshot_at=[3, 7])
    assert sorted(run.snapshots) == [3, 7, 10] and len(run.updates) == 10 and run.busy_seconds > 0
    bounds = mapper.observations().bounds()
    for n, (observed, believed) in run.snapshots.items():
        offline = build_grid(scans.head(n), 0.1, bounds=bounds)
        np.testing.assert_array_equal(observed.probability, offline.probability)
        assert believed.shape == observed.shape
    assert np.array_equal(run.snapshots[10][1].probability, mapper.beliefs().probability)


def test_numbers_follow_the_updates_and_the_last_snapshot():
    scans = room_scans()
    mapper = OnlineMapper.for_scans(scans, 0.1, radius=1.5, max_iter=4)
    run = map_online(mapper, scans)
    numbers = online_numbers(mapper, run, log_seconds=4.5)
    seconds = np.array([u.seconds for u in run.updates])
    assert numbers["ms_per_scan_median"] == pytest.approx(1e3 * np.median(seconds))
    assert numbers["ms_per_scan_max"] == pytest.approx(1e3 * seconds.max())
    assert numbers["real_time_factor"] == pytest.approx(4.5 / run.busy_seconds)
    assert numbers["fraction_of_scans_settled"] == np.mean([u.converged for u in run.updates])
    observed, believed = run.snapshots[10]
    occupied = observed.probability > 0.5
    assert numbers["observed_occupied_cells"] == occupied.sum() > 0
    never = observed.probability == UNKNOWN
    given = never & (np.abs(believed.probability - UNKNOWN) > 0.01)
    assert numbers["never_observed_cells_given_a_state"] == given.sum()
    assert 0.0 <= numbers["never_observed_fraction_made_occupied"] <= 1.0
    assert (numbers["radius_m"], numbers["max_iter_per_scan"]) == (1.5, 4)


WEAK = np.array([[1.5, 1.0], [1.0, 1.5]])  # LBP has one fixed point with it


def test_online_then_finish_reaches_the_offline_fixed_point():
    scans = room_scans()
    numbers, offline_grid = versus_offline(scans, 0.1, WEAK, tol=1e-7)
    assert np.array_equal(offline_grid.probability, build_grid(scans, 0.1).probability)
    assert numbers["observations_equal_builder"] and numbers["same_grid"]
    assert numbers["finish_converged"] and numbers["offline_converged"]
    assert numbers["max_abs_belief_difference"] < 1e-4 and numbers["cells_differing_over_0.001"] == 0
    offline = infer(offline_grid, WEAK, DEFAULT_LINK, tol=1e-7, max_iter=20000, dtype=np.float32)
    assert numbers["offline_iterations"] == offline.iterations


def test_near_observations_compare_on_the_mappers_region():
    scans = room_scans()
    _, offline_grid = versus_offline(scans, 0.1, WEAK, tol=1e-7)
    near = OnlineMapper.for_scans(scans, 0.1, preset="thesis", margin=2, radius=1.5, max_iter=4)
    near.run(scans)
    region = near.region()
    numbers = near_versus_offline(scans, 0.1, offline_grid, WEAK, near, tol=1e-7)
    assert numbers["margin_cells"] == 2 and numbers["region_cells"] == region.sum() < region.size
    assert numbers["weak_converged"] and numbers["weak_max_abs_belief_difference"] < 1e-4
    assert 0.0 <= numbers["default_same_state_fraction"] <= 1.0
    capped = near_versus_offline(scans, 0.1, offline_grid, WEAK, near, tol=1e-12, cold_max_iter=3)
    cold = infer(offline_grid, DEFAULT_HIDDEN, DEFAULT_LINK, tol=1e-12, max_iter=3, dtype=np.float32, region=region)
    assert capped["default_offline_iterations"] == 3  # the cold default-table run stops at its own cap
    assert capped["default_offline_last_max_change"] == float(cold.max_change[np.isfinite(cold.max_change)][-1])


def test_default_table_drift_counts_what_moves():
    scans = room_scans()
    grid = build_grid(scans, 0.1)
    numbers = default_table_drift(grid, tol=1e-9, iterations=3)
    first = infer(grid, DEFAULT_HIDDEN, DEFAULT_LINK, tol=1e-9, max_iter=3)
    second = infer(grid, DEFAULT_HIDDEN, DEFAULT_LINK, tol=1e-9, max_iter=3, messages=first.messages)
    moving = np.abs(second.beliefs.probability - first.beliefs.probability) > 0.1
    assert numbers["iterations"] == first.iterations + second.iterations
    assert numbers["cells_moving_over_0.1_in_last_3_iterations"] == moving.sum()
    assert 0.0 <= numbers["of_which_never_observed"] <= 1.0
