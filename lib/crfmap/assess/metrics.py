"""How good a grid is against ground truth (thesis sec. 2.10, with its eq. 12/13 swap fixed).

- MSE over all cells (eq. 11).
- Precision = TP / (TP + FP), recall = TP / (TP + FN), accuracy = (TP + TN) / all, positive class
  = occupied, a cell predicted occupied if P > 0.5, counted only over cells whose prediction is
  not exactly 0.5 (unknown). (The thesis's eq. 12 and 13 swap precision and recall.)
- ROC by sweeping the threshold over every distinct predicted value; AUC by the trapezoid rule.
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
    """ROC curve: (false positive rate, true positive rate, thresholds), from (0, 0) to (1, 1).

    A cell counts as predicted occupied when P >= threshold; thresholds run over every
    distinct predicted value, high to low. Unknown cells (P = 0.5) are included by default,
    since ranking them is part of the classifier; ``include_unknown=False`` drops them.

    >>> fpr, tpr, _ = roc_curve([[0.9, 0.8, 0.3, 0.1]], [[1, 0, 1, 0]])
    >>> fpr.tolist(), tpr.tolist()
    ([0.0, 0.0, 0.5, 0.5, 1.0], [0.0, 0.5, 0.5, 1.0, 1.0])
    """
    p, t = _pair(pred, truth, mask)
    if not include_unknown:
        keep = p != UNKNOWN
        p, t = p[keep], t[keep]
    pos = t > 0.5
    n_pos, n_neg = int(pos.sum()), int((~pos).sum())
    if n_pos == 0 or n_neg == 0:
        raise InputError("truth", "ROC needs both occupied and empty cells in the truth")
    order = np.argsort(-p, kind="stable")
    p_sorted, pos_sorted = p[order], pos[order]
    tp = np.cumsum(pos_sorted)
    fp = np.cumsum(~pos_sorted)
    last_of_value = np.r_[np.flatnonzero(np.diff(p_sorted)), p_sorted.size - 1]
    tpr = np.r_[0.0, tp[last_of_value] / n_pos]
    fpr = np.r_[0.0, fp[last_of_value] / n_neg]
    thresholds = np.r_[np.inf, p_sorted[last_of_value]]
    return fpr, tpr, thresholds


def auc(pred, truth, mask=None, include_unknown=True) -> float:
    """Area under the ROC curve (trapezoid rule; ties count half).

    >>> auc([[0.9, 0.8, 0.3, 0.1]], [[1, 0, 1, 0]])
    0.75
    """
    fpr, tpr, _ = roc_curve(pred, truth, mask, include_unknown)
    return float(np.trapezoid(tpr, fpr)) if hasattr(np, "trapezoid") else float(np.trapz(tpr, fpr))


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
