"""The hand-written code that maintained libraries replaced (issue 36), kept as the reference of the old numbers.

Each function is the library code as it was before the replacement (at 0d36a66), loops and all; the tests check
the scipy / scikit-learn / lazy_loader versions against it bit for bit (tests/assess/test_baselines.py,
test_metrics.py, test_paired.py, tests/test_lazy.py).
"""
import importlib
import sys

import numpy as np

UNKNOWN = 0.5


def _windows(p, fill):
    """The 9 shifted copies of ``p`` (3x3 window, edges padded with ``fill``): shape (9, H, W)."""
    h, w = p.shape
    padded = np.full((h + 2, w + 2), fill, dtype=np.float64)
    padded[1:-1, 1:-1] = p
    return np.stack([padded[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)])


def window_mean(p):
    """Mean P of the observed (P != 0.5) cells in each cell's 3x3 window; 0.5 where there are none."""
    win = _windows(np.where(p == UNKNOWN, np.nan, p), np.nan)
    known = np.isfinite(win)
    n = known.sum(axis=0)
    total = np.where(known, win, 0.0).sum(axis=0)
    return np.where(n > 0, total / np.maximum(n, 1), UNKNOWN)


def window_median(p):
    """Median P of the observed cells in each cell's 3x3 window; 0.5 where there are none."""
    win = np.sort(_windows(np.where(p == UNKNOWN, np.nan, p), np.nan), axis=0)
    n = np.isfinite(win).sum(axis=0)
    low = np.take_along_axis(win, np.maximum(n - 1, 0)[None] // 2, axis=0)[0]
    high = np.take_along_axis(win, (n // 2)[None], axis=0)[0]
    return np.where(n > 0, np.where(n % 2 == 1, high, (low + high) / 2), UNKNOWN)


def grey_closing(p):
    """3x3 maximum (cells outside the grid ignored), then 3x3 minimum."""
    dilated = _windows(p, -np.inf).max(axis=0)
    return _windows(dilated, np.inf).min(axis=0)


def roc_curve(p, truth):
    """(fpr, tpr, thresholds) over every distinct value of the flat ``p``, high to low, from (0, 0)."""
    pos = truth > 0.5
    n_pos, n_neg = int(pos.sum()), int((~pos).sum())
    order = np.argsort(-p, kind="stable")
    p_sorted, pos_sorted = p[order], pos[order]
    tp = np.cumsum(pos_sorted)
    fp = np.cumsum(~pos_sorted)
    last_of_value = np.r_[np.flatnonzero(np.diff(p_sorted)), p_sorted.size - 1]
    tpr = np.r_[0.0, tp[last_of_value] / n_pos]
    fpr = np.r_[0.0, fp[last_of_value] / n_neg]
    thresholds = np.r_[np.inf, p_sorted[last_of_value]]
    return fpr, tpr, thresholds


def auc(p, truth):
    """Trapezoid area under :func:`roc_curve`."""
    fpr, tpr, _ = roc_curve(p, truth)
    return float(np.trapezoid(tpr, fpr)) if hasattr(np, "trapezoid") else float(np.trapz(tpr, fpr))


def paired_bootstrap_interval(d, n_boot, seed, level):
    """The percentile interval of the mean of the differences ``d``, units drawn with replacement."""
    rng = np.random.default_rng(seed)
    boot = d[rng.integers(0, d.size, (n_boot, d.size))].mean(axis=1)
    alpha = (1 - level) / 2
    return float(np.quantile(boot, alpha)), float(np.quantile(boot, 1 - alpha))


def attach(package, api):
    """(``__getattr__``, ``__dir__``, ``__all__``) of a package exposing ``api`` = {name: submodule}, lazily."""
    def __getattr__(name):
        module = api.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(api))

    return __getattr__, __dir__, sorted(api)
