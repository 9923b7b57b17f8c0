"""Baselines against slow obvious references."""
import itertools

import numpy as np
import pytest

from crfmap.assess.baselines import BASELINES, all_baselines, graph_cut, grey_closing, window_mean, window_median
from crfmap.assess.scansplit import ScanSplit


def _grid(seed=0, shape=(7, 9)):
    rng = np.random.default_rng(seed)
    p = np.round(rng.uniform(0, 1, shape), 2)
    p[rng.uniform(size=shape) < 0.3] = 0.5
    return p


def _window(p, y, x):
    return [p[j, i] for j in range(y - 1, y + 2) for i in range(x - 1, x + 2) if 0 <= j < p.shape[0] and 0 <= i < p.shape[1]]


def test_window_filters_match_loops():
    p = _grid()
    mean, med, close = window_mean(p), window_median(p), grey_closing(p)
    dil = np.array([[max(_window(p, y, x)) for x in range(p.shape[1])] for y in range(p.shape[0])])
    for y, x in itertools.product(range(p.shape[0]), range(p.shape[1])):
        known = [v for v in _window(p, y, x) if v != 0.5]
        assert mean[y, x] == pytest.approx(np.mean(known) if known else 0.5)
        assert med[y, x] == pytest.approx(np.median(known) if known else 0.5)
        assert close[y, x] == pytest.approx(min(_window(dil, y, x)))


def test_graph_cut_is_the_brute_force_map():
    from crfstudy.references import crf_energy

    p = _grid(1, (3, 4))
    hidden = [[3.0, 1.0], [1.0, 3.0]]
    best = min((np.array(bits, bool).reshape(3, 4) for bits in itertools.product([0, 1], repeat=12)),
               key=lambda s: crf_energy(s, p, hidden))
    assert np.array_equal(graph_cut(p, hidden), best.astype(float))


def test_all_baselines_names_and_ranges():
    rng = np.random.default_rng(0)
    sp = ScanSplit(*(rng.integers(0, 3, (20, 20)) for _ in range(4)))
    out = all_baselines(sp, thesis_max_iter=50)
    assert set(out) == set(BASELINES) - {"logodds"} and "raw" in out  # no scans: no log-odds
    for name, p in out.items():
        assert p.shape == (20, 20) and p.min() >= 0 and p.max() <= 1, name


def test_window_median_equals_numpys_nanmedian_of_each_window():
    import warnings

    p = np.random.default_rng(3).choice([0.1, 0.3, 0.5, 0.5, 0.7, 0.95], size=(17, 23))
    padded = np.pad(np.where(p == 0.5, np.nan, p), 1, constant_values=np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-unknown windows
        want = np.array([[np.nanmedian(padded[y:y + 3, x:x + 3]) for x in range(23)] for y in range(17)])
    np.testing.assert_array_equal(window_median(p), np.where(np.isnan(want), 0.5, want))


def _replacement_cases():
    """Grids of every small shape (1 x n and n x 1 included), with ties, exact 0 / 1 and all-unknown windows."""
    for seed in range(60):
        rng = np.random.default_rng(100 + seed)
        shape = tuple(int(n) for n in rng.integers(1, 13, 2))
        p = rng.uniform(0, 1, shape)
        if seed % 2:
            p = rng.choice([0.0, 0.1, 0.3, 0.7, 0.9, 1.0], size=shape)
        p[rng.uniform(size=shape) < rng.uniform(0, 0.9)] = 0.5
        yield p
    yield np.full((4, 3), 0.5)
    yield np.array([[0.25]])


def test_window_filters_give_the_hand_written_filters_numbers_bit_for_bit():
    """scipy.ndimage / np.nanmedian in place of the 3x3 window stack they replaced (tests/naive_replaced.py)."""
    import naive_replaced as old

    for p in _replacement_cases():
        for new, reference in ((window_mean, old.window_mean), (window_median, old.window_median),
                               (grey_closing, old.grey_closing)):
            got, want = new(p), reference(p)
            assert got.dtype == want.dtype == np.float64
            np.testing.assert_array_equal(got, want, err_msg=f"{new.__name__} on {p.shape}")
