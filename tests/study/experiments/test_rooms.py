"""Statistics over generated rooms: odometry poses, baselines, scoring on the same cells, intervals."""
import numpy as np
import pytest

from crfmap.errors import InputError
from crfstudy.experiments import rooms
from crfmap.grid import OccupancyGrid
from crfmap.sim.simulator import simulate


def test_odometry_scans_equal_the_true_poses_without_noise_and_drift_with_it():
    scene = rooms.room("enclosed", 0)
    exact = simulate(scene, drive="waypoints", seed=0, progress=False)
    np.testing.assert_allclose(rooms.odometry_scans(exact).laser_poses, exact.scans.laser_poses, atol=1e-9)
    noisy = simulate(scene, drive="waypoints", seed=0, odometry_noise=(0.01, 0.01), progress=False)
    drift = np.abs(rooms.odometry_scans(noisy).laser_poses[:, :2] - noisy.scans.laser_poses[:, :2]).max()
    assert 0.0 < drift < 2.0


def test_neighbour_mean3_matches_a_loop():
    rng = np.random.default_rng(1)
    p = rng.choice([0.0, 0.25, 0.5, 0.75, 1.0], size=(6, 7))
    got = rooms.neighbour_mean3(OccupancyGrid(p)).probability
    for y in range(6):
        for x in range(7):
            window = p[max(y - 1, 0):y + 2, max(x - 1, 0):x + 2]
            known = window[window != 0.5]
            assert got[y, x] == pytest.approx(known.mean() if known.size else 0.5)


def test_every_method_is_scored_on_the_same_cells():
    truth = OccupancyGrid(np.array([[1.0, 0.0, 0.0, 1.0]]))
    observed = OccupancyGrid(np.array([[0.75, 0.25, 0.5, 0.5]]))
    decided = OccupancyGrid(np.array([[1.0, 0.0, 0.0, 0.0]]))
    s = rooms.score_methods({"before": observed, "after": decided}, truth, observed)
    assert s["before"]["recall_seen"] == s["after"]["recall_seen"] == 1.0  # seen cells: the first two
    assert s["before"]["coverage_unseen"] == 0.0 and s["after"]["coverage_unseen"] == 1.0
    assert s["after"]["accuracy_unseen"] == 0.5  # one of the two unseen cells right
    assert s["after"]["mse"] == pytest.approx(0.25)


def test_summary_and_interval():
    run = {"methods": ["m"], "per_room": [{"m": {"mse": v}} for v in (0.1, 0.2, 0.3, float("nan"))],
           "unseen_fraction": [0.5] * 4, "settings": {}}
    s = rooms.summarise(run)["m"]["mse"]
    assert s["n"] == 3 and s["mean"] == pytest.approx(0.2) and s["sd"] == pytest.approx(0.1)
    assert 0.1 <= s["low"] <= 0.2 <= s["high"] <= 0.3
    assert rooms.flat_summary(run, rooms.summarise(run))["rooms"] == 4


def test_bad_kind_and_no_rooms_are_named():
    with pytest.raises(InputError, match="kind"):
        rooms.room("kitchen", 0)
    with pytest.raises(InputError, match="seeds"):
        rooms.run_rooms("occluded", [])
