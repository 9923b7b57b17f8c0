"""Calibration: reliability bins and ECE by hand, the temperature against a brute-force search."""
import numpy as np
import pytest

from crfmap.assess.calibration import expected_calibration_error, fit_temperature, reliability, split_calibration
from crfmap.assess.scansplit import ScanSplit
from crfmap.crf.presets import temper
from crfmap.errors import InputError


def test_reliability_by_hand():
    p = np.array([0.05, 0.15, 0.15, 0.55, 0.95, 1.0])
    y = np.array([0, 0, 1, 1, 1, 0])
    r = reliability(p, y, bins=4)  # bins [0, .25) [.25, .5) [.5, .75) [.75, 1]; P = 1 falls in the last
    assert r["count"].tolist() == [3, 0, 1, 2]
    np.testing.assert_allclose(r["mean_p"][[0, 2, 3]], [0.35 / 3, 0.55, 0.975])
    np.testing.assert_allclose(r["share"][[0, 2, 3]], [1 / 3, 1.0, 0.5])
    assert np.isnan(r["share"][1])
    expected = (3 * abs(0.35 / 3 - 1 / 3) + abs(0.55 - 1) + 2 * abs(0.975 - 0.5)) / 6
    assert expected_calibration_error(p, y, bins=4) == pytest.approx(expected)


def test_calibrated_predictions_have_small_ece():
    rng = np.random.default_rng(1)
    p = rng.uniform(0, 1, 200_000)
    y = rng.uniform(0, 1, p.size) < p
    assert expected_calibration_error(p, y) < 0.01
    assert expected_calibration_error(temper(p, 0.3), y) > 0.1  # sharpened: over-confident


def test_temperature_recovers_a_known_softening():
    rng = np.random.default_rng(2)
    true = rng.uniform(0.02, 0.98, 100_000)
    y = (rng.uniform(0, 1, true.size) < true).astype(float)
    over = temper(true, 0.5)  # an over-confident map: the right correction is T = 2
    t = fit_temperature(over, y)
    grid = np.exp(np.linspace(np.log(0.5), np.log(8), 400))
    losses = [np.mean(-(y * np.log(temper(over, g)) + (1 - y) * np.log(1 - temper(over, g))))
              for g in grid]
    assert t == pytest.approx(grid[int(np.argmin(losses))], rel=0.01)
    assert t == pytest.approx(2.0, rel=0.05)
    assert temper(np.array([0.5]), 3.0)[0] == 0.5


def test_split_calibration_and_errors():
    sp = ScanSplit(np.array([[2, 0, 0]]), np.array([[0, 3, 0]]), np.array([[1, 0, 2]]), np.array([[0, 1, 0]]))
    out = split_calibration(sp, {"raw": sp.raw_probability()}, bins=2)
    assert out["raw"]["count"].tolist() == [1, 2] and 0 <= out["raw"]["ece"] <= 1
    with pytest.raises(InputError, match="probabilities"):
        reliability(np.array([1.5]), np.array([1]))
    with pytest.raises(InputError, match="temperature"):
        temper(np.array([0.2]), 0)
    with pytest.raises(InputError, match="shape"):
        split_calibration(sp, {"bad": np.zeros((2, 2))})


def test_reliability_agrees_with_sklearns_calibration_curve_off_the_bin_edges():
    """sklearn's calibration_curve on the same equal-width bins gives the same shares and mean P where no P lies on a
    bin edge; on an edge it puts P in the bin below (P = 0.5, an unknown cell, in [0.4, 0.5] of 10 bins, where
    reliability and the ECE put it in [0.5, 0.6)), so it does not replace reliability."""
    from sklearn.calibration import calibration_curve

    rng = np.random.default_rng(4)
    p = rng.uniform(0, 1, 5000)
    y = (rng.uniform(0, 1, p.size) < p).astype(float)
    r = reliability(p, y, bins=10)
    share, mean_p = calibration_curve(y, p, n_bins=10)
    used = r["count"] > 0
    np.testing.assert_allclose(r["share"][used], share, rtol=1e-12)
    np.testing.assert_allclose(r["mean_p"][used], mean_p, rtol=1e-12)
    on_edge = np.array([0.5, 0.5, 0.1])
    assert reliability(on_edge, np.array([1, 0, 0]), bins=10)["count"][5] == 2
    assert calibration_curve(np.array([1, 0, 0]), on_edge, n_bins=10)[1].tolist() == [0.1, 0.5]  # the same cells


def test_the_temperature_fits_log_loss_is_sklearns():
    """The fit's log-loss is sklearn.metrics.log_loss of the clipped P (kept as three numpy lines: the fit calls it
    some 40 times, and sklearn's input checks make each call about 6 times slower)."""
    from sklearn.metrics import log_loss

    from crfmap.assess.calibration import _logloss
    from crfmap.crf.presets import LOGIT_FLOOR

    rng = np.random.default_rng(5)
    p = rng.choice([0.0, 0.2, 0.5, 0.9, 1.0], 1000)
    p[::3] = rng.uniform(0, 1, p[::3].size)
    y = (rng.uniform(0, 1, p.size) < 0.4).astype(float)
    assert _logloss(p, y) == pytest.approx(log_loss(y, np.clip(p, LOGIT_FLOOR, 1 - LOGIT_FLOOR), labels=[0, 1]),
                                           rel=1e-12)

