"""How good a grid is against ground truth (thesis sec. 2.10, with its eq. 12/13 swap fixed).

- MSE over all cells (eq. 11).
- Precision = TP / (TP + FP), recall = TP / (TP + FN), accuracy = (TP + TN) / all, positive class = occupied, a cell
  predicted occupied if P > 0.5, counted only over cells whose prediction is not exactly 0.5 (unknown).
- ROC by sweeping the threshold over every distinct predicted value; AUC by the trapezoid rule
  (:func:`sklearn.metrics.roc_curve` keeping every point, :func:`sklearn.metrics.auc`).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from crfmap.errors import InputError
from crfmap.grid import UNKNOWN, OccupancyGrid, check_probability_array


def _values(grid, name):
    if isinstance(grid, OccupancyGrid):
        return grid.probability
    return check_probability_array(grid, name)


def _pair(pred, truth, mask=None):
    p = _values(pred, "prediction")
    t = _values(truth, "truth")
    if p.shape != t.shape:
        raise InputError("prediction", f"shape {p.shape} does not match the truth's {t.shape}")
    if mask is not None:
        mask = np.asarray(mask, bool)
        if mask.shape != p.shape:
            raise InputError("mask", f"shape {mask.shape} does not match the grids' {p.shape}")
        p, t = p[mask], t[mask]
    return p.ravel(), t.ravel()


@dataclass
class Confusion:
    tp: int
    fp: int
    fn: int
    tn: int
    unknown: int  # cells left out because the prediction is exactly 0.5

    @property
    def precision(self):
        return self.tp / (self.tp + self.fp) if self.tp + self.fp else float("nan")

    @property
    def recall(self):
        return self.tp / (self.tp + self.fn) if self.tp + self.fn else float("nan")

    @property
    def accuracy(self):
        n = self.tp + self.fp + self.fn + self.tn
        return (self.tp + self.tn) / n if n else float("nan")


def mse(pred, truth, mask=None) -> float:
    """Mean squared error over all cells (or the cells in ``mask``).

    >>> mse([[1.0, 0.5]], [[1.0, 0.0]])
    0.125
    """
    p, t = _pair(pred, truth, mask)
    return float(np.mean((p - t) ** 2)) if p.size else float("nan")


def confusion(pred, truth, mask=None, threshold=0.5) -> Confusion:
    """Confusion counts over cells whose prediction is not exactly 0.5; truth occupied if > 0.5.

    >>> c = confusion([[0.9, 0.2, 0.5, 0.7]], [[1, 0, 1, 0]])
    >>> (c.tp, c.fp, c.fn, c.tn, c.unknown)
    (1, 1, 0, 1, 1)
    """
    p, t = _pair(pred, truth, mask)
    known = p != UNKNOWN
    pred_occ = p[known] > threshold
    true_occ = t[known] > 0.5
    return Confusion(
        tp=int(np.sum(pred_occ & true_occ)),
        fp=int(np.sum(pred_occ & ~true_occ)),
        fn=int(np.sum(~pred_occ & true_occ)),
        tn=int(np.sum(~pred_occ & ~true_occ)),
        unknown=int(np.sum(~known)),
    )


def roc_curve(pred, truth, mask=None, include_unknown=True):
    """ROC curve (false positive rate, true positive rate, thresholds) from (0, 0) to (1, 1): predicted occupied when
    P >= threshold, for every distinct P, high to low. Unknown cells (P = 0.5) are included by default, since ranking
    them is part of the classifier.

    >>> fpr, tpr, _ = roc_curve([[0.9, 0.8, 0.3, 0.1]], [[1, 0, 1, 0]])
    >>> fpr.tolist(), tpr.tolist()
    ([0.0, 0.0, 0.5, 0.5, 1.0], [0.0, 0.5, 0.5, 1.0, 1.0])
    """
    p, t = _pair(pred, truth, mask)
    if not include_unknown:
        keep = p != UNKNOWN
        p, t = p[keep], t[keep]
    pos = t > 0.5
    if pos.all() or not pos.any():
        raise InputError("truth", "ROC needs both occupied and empty cells in the truth")
    from sklearn.metrics import roc_curve as sklearn_roc_curve  # here: a second to import, mse and confusion need none

    # every distinct P a threshold (drop_intermediate=False): the points the trapezoid of auc sums over
    return sklearn_roc_curve(pos, p, pos_label=True, drop_intermediate=False)


def auc(pred, truth, mask=None, include_unknown=True) -> float:
    """Area under the ROC curve (trapezoid rule; ties count half).

    >>> auc([[0.9, 0.8, 0.3, 0.1]], [[1, 0, 1, 0]])
    0.75
    """
    from sklearn.metrics import auc as trapezoid_area

    fpr, tpr, _ = roc_curve(pred, truth, mask, include_unknown)
    return float(trapezoid_area(fpr, tpr))


@dataclass
class Report:
    mse: float
    precision: float
    recall: float
    accuracy: float
    auc: float
    tp: int
    fp: int
    fn: int
    tn: int
    unknown: int

    def as_dict(self):
        return asdict(self)


def evaluate(pred, truth, mask=None) -> Report:
    """MSE, precision, recall, accuracy, AUC and the confusion counts in one go."""
    c = confusion(pred, truth, mask)
    try:
        area = auc(pred, truth, mask)
    except InputError:
        area = float("nan")
    return Report(mse(pred, truth, mask), c.precision, c.recall, c.accuracy, area,
                  c.tp, c.fp, c.fn, c.tn, c.unknown)
