"""Paired comparisons against slow obvious references."""
import itertools
import math

import numpy as np
import pytest

from crfmap.errors import InputError
from crfstudy.paired import paired_difference, sign_test, value_range


@pytest.mark.parametrize("wins,losses", [(0, 0), (5, 0), (3, 3), (12, 4), (1, 9), (20, 0)])
def test_sign_test_is_the_exact_binomial_two_sided_p(wins, losses):
    n = wins + losses
    # every outcome at most as likely as the observed one (the binomial is symmetric at 1/2)
    p = sum(math.comb(n, k) for k in range(n + 1) if math.comb(n, k) <= math.comb(n, wins)) / 2 ** n if n else 1.0
    assert sign_test(wins, losses) == pytest.approx(p)


def test_paired_difference_is_the_mean_of_the_differences_and_its_interval_is_paired():
    rng = np.random.default_rng(1)
    hardness = rng.uniform(0.01, 0.05, 20)  # per-seed difficulty, shared by both methods
    b = hardness + 0.004
    a = hardness + rng.normal(0, 0.0005, 20)
    d = paired_difference(a, b, n_boot=4000, seed=0)
    assert d["mean_difference"] == pytest.approx(np.mean(a - b))
    assert d["mean_a"] == pytest.approx(a.mean()) and d["sd_b"] == pytest.approx(b.std())
    lo, hi = d["difference_ci"]
    assert lo <= d["mean_difference"] <= hi < 0
    # the spread between seeds (sd ~0.012) is far wider than the paired interval
    assert hi - lo < 0.1 * (a.std() + b.std())
    assert (d["wins"], d["losses"], d["ties"]) == (20, 0, 0) and d["sign_test_p"] == pytest.approx(2 / 2 ** 20)


def test_paired_bootstrap_matches_enumeration_on_three_units():
    a, b = np.array([1.0, 2.0, 4.0]), np.array([0.5, 0.0, 1.0])
    means = np.array([np.mean(c) for c in itertools.product(a - b, repeat=3)])  # every resample, equally likely
    lo, hi = paired_difference(a, b, n_boot=200000, seed=0, level=0.5)["difference_ci"]
    # each bound is where the exact (discrete) distribution of resampled means crosses 25 % / 75 %
    for bound, q in ((lo, 0.25), (hi, 0.75)):
        assert np.mean(means <= bound + 1e-9) >= q - 0.01 and np.mean(means < bound - 1e-9) <= q + 0.01


def test_higher_is_better_swaps_wins_and_losses():
    d = paired_difference([0.9, 0.8, 0.7], [0.5, 0.6, 0.7], lower_is_better=False)
    assert (d["wins"], d["losses"], d["ties"]) == (2, 0, 1)


@pytest.mark.parametrize("a,b", [([1.0], [2.0]), ([1, 2], [1, 2, 3]), ([1, np.nan], [1, 2])])
def test_bad_input_is_refused(a, b):
    with pytest.raises(InputError):
        paired_difference(a, b)


def test_value_range_names_where_the_extremes_are():
    r = value_range({"ll": {"mse": 0.32}, "ul": {"mse": 0.126}, "lr": {"mse": 0.2}}, "mse")
    assert (r["min"], r["argmin"], r["max"], r["argmax"]) == (0.126, "ul", 0.32, "ll")
    with pytest.raises(InputError):
        value_range({"a": {}}, "mse")


def test_sign_test_agrees_with_scipys_binomtest():
    """scipy.stats.binomtest differs in the last digits (its cdf is not exact rational arithmetic): the exact sum
    stays, and scipy is the independent check."""
    from scipy.stats import binomtest

    for n in range(1, 61):
        for wins in range(n + 1):
            assert sign_test(wins, n - wins) == pytest.approx(binomtest(wins, n, 0.5).pvalue, rel=1e-12, abs=0)


def test_paired_bootstrap_gives_the_hand_written_intervals_bit_for_bit():
    """scipy.stats.bootstrap(paired=True) draws the same resamples from the same seed as the loop it replaced."""
    import naive_replaced as old

    for seed in range(60):
        rng = np.random.default_rng(500 + seed)
        n = int(rng.integers(2, 25))
        a, b = rng.normal(size=n), rng.normal(size=n)
        if seed % 3 == 0:
            a, b = a.round(1), b.round(1)  # ties among resampled means
        n_boot = int(rng.choice([1, 2, 7, 100, 2000]))
        level = float(rng.choice([0.5, 0.9, 0.95, 0.99]))
        got = paired_difference(a, b, n_boot=n_boot, seed=seed, level=level)["difference_ci"]
        assert got == old.paired_bootstrap_interval(a - b, n_boot, seed, level)
    same = paired_difference([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], n_boot=50)  # every difference 0: a degenerate interval
    assert same["difference_ci"] == (0.0, 0.0)
