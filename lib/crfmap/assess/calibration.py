"""Is a map's P(occupied) a probability? Reliability diagrams, expected calibration error, a temperature.

On a scan split (:mod:`crfmap.assess.scansplit`) the cells the second half observed are cut by their predicted P into
``bins`` equal-width bins on [0, 1]; in each bin the mean P is set against the share of cells the second half calls
occupied. A calibrated map has the two equal in every bin; :func:`expected_calibration_error` is the cell-weighted mean
gap. :func:`fit_temperature` fits a preset's temperature T by the log-loss on a recording's second half: fit it on the
training recording only, then apply it unchanged elsewhere.

>>> p = np.array([0.1, 0.1, 0.9, 0.9]); y = np.array([0, 1, 1, 1])
>>> round(expected_calibration_error(p, y, bins=10), 3)
0.25
>>> reliability(p, y, bins=2)["share"].tolist()
[0.5, 1.0]
"""
from __future__ import annotations

import math

import numpy as np

from crfmap.crf.presets import LOGIT_FLOOR, temper
from crfmap.errors import InputError

DEFAULT_BINS = 10
TEMPERATURE_RANGE = (0.05, 20.0)  # the search interval of fit_temperature


def _check(p, labels, bins):
    p = np.asarray(p, dtype=np.float64).ravel()
    y = np.asarray(labels, dtype=np.float64).ravel()
    if p.shape != y.shape or p.size == 0:
        raise InputError("predictions", f"need one label per prediction, got {p.size} and {y.size}")
    if not np.all(np.isfinite(p)) or p.min() < 0 or p.max() > 1:
        raise InputError("predictions", "must be probabilities in [0, 1]")
    if not (isinstance(bins, (int, np.integer)) and bins >= 1):
        raise InputError("bins", f"must be a positive integer, got {bins!r}")
    return p, y


def reliability(p, labels, bins: int = DEFAULT_BINS) -> dict:
    """Per bin of P: ``edges`` (bins + 1), ``count``, ``mean_p`` and ``share`` occupied (NaN where empty)."""
    p, y = _check(p, labels, bins)
    which = np.minimum((p * bins).astype(np.int64), bins - 1)
    count = np.bincount(which, minlength=bins).astype(np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_p = np.bincount(which, weights=p, minlength=bins) / count
        share = np.bincount(which, weights=y, minlength=bins) / count
    return {"edges": np.linspace(0, 1, bins + 1), "count": count.astype(np.int64), "mean_p": mean_p, "share": share}


def expected_calibration_error(p, labels, bins: int = DEFAULT_BINS) -> float:
    """``sum_b n_b / n |mean P_b - share_b|`` over the non-empty bins."""
    r = reliability(p, labels, bins)
    used = r["count"] > 0
    return float(np.sum(r["count"][used] * np.abs(r["mean_p"][used] - r["share"][used])) / r["count"].sum())


def _logloss(p, y):
    q = np.clip(p, LOGIT_FLOOR, 1 - LOGIT_FLOOR)
    return float(-np.mean(y * np.log(q) + (1 - y) * np.log(1 - q)))


def fit_temperature(p, labels, tol: float = 1e-4) -> float:
    """The T in :data:`TEMPERATURE_RANGE` minimising the log-loss of :func:`crfmap.crf.presets.temper` (what a preset's
    ``temperature`` does: ``sigmoid(logit(P) / T)``), by golden section on log T."""
    p, y = _check(p, labels, 1)
    lo, hi = math.log(TEMPERATURE_RANGE[0]), math.log(TEMPERATURE_RANGE[1])
    g = (math.sqrt(5) - 1) / 2
    a, b = hi - g * (hi - lo), lo + g * (hi - lo)
    fa, fb = _logloss(temper(p, math.exp(a)), y), _logloss(temper(p, math.exp(b)), y)
    while hi - lo > tol:
        if fa <= fb:
            hi, b, fb = b, a, fa
            a = hi - g * (hi - lo)
            fa = _logloss(temper(p, math.exp(a)), y)
        else:
            lo, a, fa = a, b, fb
            b = lo + g * (hi - lo)
            fb = _logloss(temper(p, math.exp(b)), y)
    return float(math.exp((lo + hi) / 2))


def split_calibration(split, predictions: dict, group: str = "all", bins: int = DEFAULT_BINS) -> dict:
    """``{name: {"ece": float, **reliability}}`` of predictions on a scan split's ``group`` of cells."""
    mask = split.group(group)
    labels = split.labels()[mask]
    out = {}
    for name, p in predictions.items():
        values = np.asarray(getattr(p, "probability", p), dtype=np.float64)
        if values.shape != split.shape:
            raise InputError(name, f"prediction shape {values.shape} does not match the split's grid {split.shape}")
        out[name] = dict(reliability(values[mask], labels, bins), ece=expected_calibration_error(values[mask], labels,
                                                                                                   bins))
    return out

