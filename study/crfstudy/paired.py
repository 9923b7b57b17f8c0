"""Paired comparisons of two methods scored on the same units (seeds, rooms, folds).

When two methods are scored on the same noise seeds (or rooms, or folds), what matters is the
difference *per unit*: the spread between units (one seed is easy, another hard) is shared by
both and cancels. :func:`paired_difference` gives the mean of each, the mean difference with a
bootstrap interval over units (:func:`scipy.stats.bootstrap`, ``paired=True``: units resampled with
replacement, the pairs kept together), and
an exact two-sided sign test (how often one method wins; ties dropped).

>>> a = [0.020, 0.018, 0.025, 0.017, 0.019]
>>> b = [0.024, 0.021, 0.027, 0.022, 0.023]
>>> d = paired_difference(a, b, n_boot=2000, seed=0)
>>> round(d["mean_difference"], 4), d["wins"], d["losses"], round(d["sign_test_p"], 4)
(-0.0036, 5, 0, 0.0625)
>>> d["difference_ci"][1] < 0
True
"""
from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.stats import bootstrap

from crfmap.errors import InputError


def sign_test(wins: int, losses: int) -> float:
    """Exact two-sided sign-test p-value of ``wins`` against ``losses`` (ties already dropped).

    >>> sign_test(5, 0), sign_test(3, 3)
    (0.0625, 1.0)
    """
    for name, v in (("wins", wins), ("losses", losses)):
        if not (isinstance(v, (int, np.integer)) and v >= 0):
            raise InputError(name, f"must be a non-negative integer, got {v!r}")
    n = int(wins) + int(losses)
    if n == 0:
        return 1.0
    k = min(wins, losses)
    tail = sum(math.comb(n, i) for i in range(k + 1)) / 2 ** n
    return float(min(1.0, 2 * tail))


def _mean_difference(a, b, axis=-1):
    return np.mean(a - b, axis=axis)


def paired_difference(a, b, n_boot: int = 10000, seed: int = 0, level: float = 0.95,
                      lower_is_better: bool = True) -> dict:
    """Method ``a`` against method ``b`` on the same units (``a[i]`` and ``b[i]`` on unit ``i``).

    Returns ``mean_a``, ``mean_b``, ``sd_a``, ``sd_b`` (population sd, as the notebooks' +-),
    ``mean_difference`` (a - b) with its bootstrap ``difference_ci`` over units, ``sd_difference``,
    ``wins`` (units where a is better than b: lower, as for an MSE, unless ``lower_is_better`` is
    False, as for an accuracy), ``losses``, ``ties`` and the sign test's ``sign_test_p``.
    """
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if x.ndim != 1 or x.shape != y.shape or x.size < 2:
        raise InputError("a, b", f"need two 1-D sequences of one length >= 2, got shapes {x.shape} and {y.shape}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise InputError("a, b", "scores must be finite")
    if not (isinstance(n_boot, (int, np.integer)) and n_boot >= 1):
        raise InputError("n_boot", f"must be a positive integer, got {n_boot!r}")
    if not 0 < level < 1:
        raise InputError("level", f"must be in (0, 1), got {level!r}")
    d = x - y
    # scipy's paired bootstrap draws the resamples; the percentile interval is np.quantile's, as before scipy did
    # the draws (scipy's own interval, by scipy.stats.quantile, can differ from it in the last bit)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # its standard error (unused) of n_boot = 1 resample
        boot = bootstrap((x, y), _mean_difference, paired=True, vectorized=True, n_resamples=int(n_boot),
                         method="percentile", rng=np.random.default_rng(seed)).bootstrap_distribution
    alpha = (1 - level) / 2
    wins, losses = int(np.sum(d < 0)), int(np.sum(d > 0))
    if not lower_is_better:
        wins, losses = losses, wins
    return {"units": int(d.size), "mean_a": float(x.mean()), "mean_b": float(y.mean()), "sd_a": float(x.std()),
            "sd_b": float(y.std()), "mean_difference": float(d.mean()), "sd_difference": float(d.std()),
            "difference_ci": (float(np.quantile(boot, alpha)), float(np.quantile(boot, 1 - alpha))),
            "wins": wins, "losses": losses, "ties": int(d.size - wins - losses),
            "sign_test_p": sign_test(wins, losses), "level": level, "n_boot": int(n_boot), "seed": int(seed)}


def value_range(rows: dict, metric: str) -> dict:
    """Smallest and largest ``metric`` over ``{name: {metric: value}}``, with the names that give them.

    >>> value_range({"a": {"mse": 0.3}, "b": {"mse": 0.1}}, "mse")
    {'min': 0.1, 'max': 0.3, 'argmin': 'b', 'argmax': 'a', 'n': 2}
    """
    if not rows:
        raise InputError("rows", "nothing to take the range of")
    missing = [k for k, v in rows.items() if metric not in v]
    if missing:
        raise InputError("rows", f"{metric!r} missing for {missing}")
    lo, hi = min(rows, key=lambda k: rows[k][metric]), max(rows, key=lambda k: rows[k][metric])
    return {"min": float(rows[lo][metric]), "max": float(rows[hi][metric]), "argmin": lo, "argmax": hi, "n": len(rows)}
