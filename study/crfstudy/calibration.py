"""Calibration of maps compared on one scan split: each map's ECE with a spatial-block interval, paired.

The ECE is :func:`crfmap.assess.calibration.expected_calibration_error`; the resamples are the scan split's
spatial-block bootstrap (:func:`crfmap.assess.scansplit.block_resamples`), so the same ``n_boot``, ``block`` and
``seed`` give the draws of :func:`crfmap.assess.scansplit.score` and the ECE moves with the Brier score's blocks.
"""
from __future__ import annotations

import numpy as np

from crfmap.assess.calibration import DEFAULT_BINS, split_calibration
from crfmap.assess.scansplit import DEFAULT_BLOCK, block_resamples, percentile_interval
from crfmap.errors import InputError


def paired_calibration(split, predictions: dict, reference: str, n_boot: int = 200, block: int = DEFAULT_BLOCK,
                       seed: int = 0, group: str = "all", bins: int = DEFAULT_BINS, level: float = 0.95) -> dict:
    """Each prediction's ECE with a spatial-block bootstrap interval, and its paired difference to ``reference``.

    ``{name: {"ece", "ece_ci", "ece_diff", "ece_diff_ci"}}`` (the difference: name minus reference; the reference's
    own is 0). A resample's ECE is the ECE of its weighted cells: per bin and block the cell count, sum of P and count
    occupied, weighted by how often each block was drawn. ``n_boot = 0``: the point estimates, intervals None.

    >>> from crfmap.assess.scansplit import ScanSplit
    >>> sp = ScanSplit(*(np.random.default_rng(0).integers(0, 3, (8, 8)) for _ in range(4)))
    >>> p = {"raw": sp.raw_probability(), "half": np.full(sp.shape, 0.5)}
    >>> c = paired_calibration(sp, p, "raw", n_boot=50, block=4)
    >>> abs(c["raw"]["ece"] - split_calibration(sp, p)["raw"]["ece"]) < 1e-12, c["raw"]["ece_diff_ci"]
    (True, (0.0, 0.0))
    """
    if reference not in predictions:
        raise InputError("reference", f"{reference!r} is not one of the predictions ({', '.join(predictions)})")
    r = block_resamples(split, n_boot=n_boot, block=block, seed=seed)[group]
    if r.n_blocks == 0:
        raise InputError(group, "no cell of this group was observed by the split's second half")
    split_calibration(split, predictions, group, bins)  # checks each prediction's shape and P, and bins
    weights = np.ones((1, r.n_blocks)) if r.draws is None else np.vstack([np.ones(r.n_blocks), r.draws])
    eces = {}
    for name, pred in predictions.items():
        p = np.asarray(getattr(pred, "probability", pred), dtype=np.float64)[r.mask]
        which = np.minimum((p * bins).astype(np.int64), bins - 1) * r.n_blocks + r.inverse  # (bin, block) index
        size = bins * r.n_blocks
        sums = [np.bincount(which, weights=w, minlength=size).reshape(bins, r.n_blocks).T for w in (None, p, r.labels)]
        count, sum_p, sum_y = (weights @ s for s in sums)  # [resample, bin]
        eces[name] = np.abs(sum_p - sum_y).sum(axis=1) / count.sum(axis=1)  # row 0: every block once
    out = {}
    for name, e in eces.items():
        diff = e - eces[reference]
        boot = r.draws is not None and n_boot > 0
        out[name] = {"ece": float(e[0]), "ece_ci": percentile_interval(e[1:], level) if boot else None,
                     "ece_diff": float(diff[0]), "ece_diff_ci": percentile_interval(diff[1:], level) if boot else None}
    return out
