"""Scoring several predictions of a map on the same cells, with fold-level or spatial-block intervals.

Precision, recall and accuracy skip predictions of exactly 0.5 (:mod:`crfmap.assess.metrics`),
so a method that abstains on hard cells (the 3x3 neighbour mean, which has nothing to say about
a cell with no known neighbour) is scored on easier cells than one that predicts every cell.
Here every method is scored on the *common* cells: those every method predicts (P != 0.5).

- :func:`fold_scores`: cross-validation (folds of held-out cells): the pooled metrics on the common
  cells, each fold's metrics, and intervals over folds of each metric and of its paired difference
  to a reference method (the same folds: :func:`crfstudy.paired.paired_difference`).
- :func:`block_scores`: one set of cells (no folds): the pooled metrics with a spatial-block
  bootstrap interval of each metric's paired difference to the reference (blocks of ``block``
  x ``block`` cells resampled, as :func:`crfmap.assess.scansplit.score` does).

Labels: occupied where the label grid's P > 0.5; a prediction says occupied where P > 0.5.

>>> labels = np.array([[0.9, 0.1, 0.1, 0.1]])
>>> preds = {"lbp": np.array([[0.8, 0.2, 0.3, 0.4]]), "mean": np.array([[0.5, 0.2, 0.6, 0.5]])}
>>> common_mask(preds, np.ones((1, 4), bool)).tolist()
[[False, True, True, False]]
>>> classification(preds["mean"], labels, common_mask(preds, np.ones((1, 4), bool)))["accuracy"]
0.5
"""
from __future__ import annotations

import numpy as np

from crfmap.assess.scansplit import DEFAULT_BLOCK
from crfmap.errors import InputError
from crfmap.grid import UNKNOWN
from crfstudy.paired import paired_difference

METRICS = ("precision", "recall", "accuracy")


def _p(grid, name):
    p = np.asarray(getattr(grid, "probability", grid), dtype=np.float64)
    if p.ndim != 2:
        raise InputError(name, f"expected a 2-D [y, x] grid, got shape {p.shape}")
    return p


def common_mask(predictions: dict, mask) -> np.ndarray:
    """Cells of ``mask`` that every prediction decides (P != 0.5)."""
    if not predictions:
        raise InputError("predictions", "nothing to score")
    m = np.asarray(mask, dtype=bool).copy()
    for name, grid in predictions.items():
        p = _p(grid, name)
        if p.shape != m.shape:
            raise InputError(name, f"shape {p.shape} does not match the mask's {m.shape}")
        m &= p != UNKNOWN
    return m


def _counts(pred, truth):
    """[cells, TP, FP, FN, correct] of boolean arrays (occupied = positive)."""
    return np.array([pred.size, np.sum(pred & truth), np.sum(pred & ~truth), np.sum(~pred & truth),
                     np.sum(pred == truth)], dtype=np.float64)


def _metrics(c):
    n, tp, fp, fn, correct = c
    with np.errstate(invalid="ignore", divide="ignore"):
        return {"precision": float(tp / (tp + fp)) if tp + fp else float("nan"),
                "recall": float(tp / (tp + fn)) if tp + fn else float("nan"),
                "accuracy": float(correct / n) if n else float("nan"), "cells": int(n)}


def classification(prediction, labels, mask) -> dict:
    """Precision, recall, accuracy (and cells) of ``prediction`` against ``labels`` on ``mask``."""
    m = np.asarray(mask, dtype=bool)
    p, t = _p(prediction, "prediction")[m] > 0.5, _p(labels, "labels")[m] > 0.5
    return _metrics(_counts(p, t))


def fold_scores(predictions: dict, labels, held_out, folds, reference: str, n_boot: int = 10000,
                seed: int = 0, level: float = 0.95) -> dict:
    """Every prediction on the held-out cells all of them decide, per fold and pooled, paired to ``reference``.

    ``folds``: the fold id of every cell (as :func:`crfstudy.analysis.crossval.random_folds`), ``held_out``:
    the cells held out. Returns ``{"common_cells", "held_out_cells", "folds", "methods": {name: {"pooled",
    "per_fold", metric: {"fold_mean", "fold_ci"}, "vs_reference": {metric: paired_difference}}}}``;
    accuracy-like metrics: higher is better.
    """
    if reference not in predictions:
        raise InputError("reference", f"{reference!r} is not one of the predictions")
    common = common_mask(predictions, held_out)
    fold_ids = np.asarray(folds)
    ids = [int(f) for f in np.unique(fold_ids[common])]
    if len(ids) < 2:
        raise InputError("folds", f"need at least 2 folds with common cells, got {len(ids)}")
    truth = _p(labels, "labels") > 0.5
    per_fold = {name: [_metrics(_counts(_p(g, name)[common & (fold_ids == f)] > 0.5, truth[common & (fold_ids == f)]))
                       for f in ids] for name, g in predictions.items()}
    rng = np.random.default_rng(seed)
    resample = rng.integers(0, len(ids), (n_boot, len(ids)))
    alpha = (1 - level) / 2
    out = {"common_cells": int(common.sum()), "held_out_cells": int(np.asarray(held_out).sum()), "folds": ids,
           "methods": {}}
    for name, grid in predictions.items():
        entry = {"pooled": classification(grid, labels, common), "per_fold": per_fold[name], "vs_reference": {}}
        for m in METRICS:
            v = np.array([f[m] for f in per_fold[name]])
            boot = np.nanmean(v[resample], axis=1) if np.isfinite(v).any() else np.full(n_boot, np.nan)
            entry[m] = {"fold_mean": float(np.nanmean(v)) if np.isfinite(v).any() else float("nan"),
                        "fold_ci": (float(np.nanquantile(boot, alpha)), float(np.nanquantile(boot, 1 - alpha)))}
            ref = np.array([f[m] for f in per_fold[reference]])
            ok = np.isfinite(v) & np.isfinite(ref)
            if name != reference and ok.sum() >= 2:
                entry["vs_reference"][m] = paired_difference(v[ok], ref[ok], n_boot=n_boot, seed=seed, level=level,
                                                             lower_is_better=False)
        out["methods"][name] = entry
    return out


def block_scores(predictions: dict, labels, mask, reference: str, block: int = DEFAULT_BLOCK, n_boot: int = 1000,
                 seed: int = 0, level: float = 0.95) -> dict:
    """Every prediction on the cells of ``mask`` all of them decide, with spatial-block paired intervals.

    Returns ``{"common_cells", "cells", "block", "methods": {name: {metric: value, metric + "_diff":
    name minus reference, metric + "_diff_ci": interval}}}``.
    """
    if reference not in predictions:
        raise InputError("reference", f"{reference!r} is not one of the predictions")
    if not (isinstance(block, (int, np.integer)) and block >= 1):
        raise InputError("block", f"must be a positive integer, got {block!r}")
    common = common_mask(predictions, mask)
    if not common.any():
        raise InputError("mask", "no cell is decided by every prediction")
    truth = _p(labels, "labels") > 0.5
    yy, xx = np.nonzero(common)
    blocks = (yy // block) * (common.shape[1] // block + 1) + xx // block
    uniq, inverse = np.unique(blocks, return_inverse=True)
    rng = np.random.default_rng(seed)
    weights = np.array([np.bincount(rng.integers(0, uniq.size, uniq.size), minlength=uniq.size)
                        for _ in range(n_boot)], dtype=np.float64)  # [n_boot, blocks]
    alpha = (1 - level) / 2

    def per_block(name):
        p, t = _p(predictions[name], name)[common] > 0.5, truth[common]
        rows = [np.ones(p.size), p & t, p & ~t, ~p & t, p == t]
        return np.stack([np.bincount(inverse, weights=r.astype(float), minlength=uniq.size) for r in rows])

    def resampled(sums):
        n, tp, fp, fn, correct = sums @ weights.T  # [5, n_boot]
        with np.errstate(invalid="ignore", divide="ignore"):
            return {"precision": tp / (tp + fp), "recall": tp / (tp + fn), "accuracy": correct / n}

    sums = {name: per_block(name) for name in predictions}
    boot = {name: resampled(s) for name, s in sums.items()}
    out = {"common_cells": int(common.sum()), "cells": int(np.asarray(mask, bool).sum()), "block": int(block),
           "methods": {}}
    for name in predictions:
        entry = _metrics(sums[name].sum(axis=1))
        ref = _metrics(sums[reference].sum(axis=1))
        for m in METRICS:
            entry[m + "_diff"] = entry[m] - ref[m]
            d = boot[name][m] - boot[reference][m]
            d = d[np.isfinite(d)]
            entry[m + "_diff_ci"] = ((float(np.quantile(d, alpha)), float(np.quantile(d, 1 - alpha)))
                                     if d.size else (float("nan"), float("nan")))
        out["methods"][name] = entry
    return out
