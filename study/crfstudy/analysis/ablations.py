"""What the certainty preset's CRF coupling adds beyond recalibrating each cell: ablations and calibrated twins.

The preset does two things: it recalibrates each cell's observation (its evidence x = hits - passes
becomes P = sigmoid(l(x))), and it couples neighbouring cells (hidden coupling J, LBP within
``margin`` cells of an observation). Its ablations (:func:`ablation_presets`) take one piece away:

- ``"J = 0"``: no coupling, the per-cell recalibration alone (LBP then returns the observation);
- ``"no margin"``: LBP over the whole grid;
- ``"no cap"``: no ``limit`` on one cell's |log-odds|.

Independent-cell models fitted on a training split (the scan-split labels of its second half):

- :class:`IsotonicEvidence`: P(occupied | x), the isotonic (non-decreasing) regression of the labels
  on x by pool-adjacent-violators; the best calibration of x alone that keeps its order;
- :class:`PlattRaw`: the raw arctan grid's calibrated twin, P = sigmoid(alpha + beta logit(P_raw)),
  fitted by Newton's method on the log-loss.

Both are fitted on every cell the training split's second half observed (x = 0 included: they
also learn what a never-seen cell is, which the raw grid leaves at 0.5).

>>> iso = IsotonicEvidence.fit(np.array([-2, -1, 0, 1, 2]), np.array([0, 1, 0, 1, 1]))
>>> iso.predict(np.array([-2, 0, 2])).round(3).tolist()
[0.0, 0.5, 1.0]
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from crfmap.crf.presets import LOGIT_FLOOR, coupling_table, get_preset
from crfmap.errors import InputError

ABLATIONS = ("J = 0", "no margin", "no cap")

CERTAINTY = "certainty"  # the model searched here (the gated default is this model plus its evidence gate)


def ablation_presets(base: str | None = None) -> dict:
    """{name: Preset}: the ``base`` preset (None: the certainty preset, the model this study is about) and its ablations (see the module docstring)."""
    p = get_preset(CERTAINTY) if base is None else get_preset(base)
    return {p.name: p, "J = 0": replace(p, hidden=coupling_table(0.0)), "no margin": replace(p, margin=None),
            "no cap": replace(p, limit=math.inf)}


def evidence(split) -> np.ndarray:
    """The first half's signed evidence x = hits - passes, [y, x] float."""
    return split.first_hits.astype(np.float64) - split.first_passes


def _pav(values, y, w):
    """Weighted isotonic regression of ``y`` (ordered by ``values``, increasing) by pool-adjacent-violators."""
    means, weights, sizes = [], [], []
    for yi, wi in zip(y, w):
        means.append(yi); weights.append(wi); sizes.append(1)
        while len(means) > 1 and means[-2] > means[-1]:  # pool the last two blocks
            m2, w2, s2 = means.pop(), weights.pop(), sizes.pop()
            m1, w1, s1 = means.pop(), weights.pop(), sizes.pop()
            means.append((m1 * w1 + m2 * w2) / (w1 + w2)); weights.append(w1 + w2); sizes.append(s1 + s2)
    return np.repeat(means, sizes)


@dataclass(frozen=True)
class IsotonicEvidence:
    """Non-decreasing P(occupied | x) fitted to labels; between fitted x values linear, beyond them constant."""

    x: np.ndarray  # the distinct training evidence values, increasing
    p: np.ndarray  # the fitted P at each

    @classmethod
    def fit(cls, x, labels, weights=None) -> "IsotonicEvidence":
        x = np.asarray(x, dtype=np.float64).ravel()
        y = np.asarray(labels, dtype=np.float64).ravel()
        w = np.ones_like(y) if weights is None else np.asarray(weights, dtype=np.float64).ravel()
        if x.size == 0 or x.shape != y.shape or w.shape != y.shape:
            raise InputError("labels", f"need equal non-empty x, labels and weights, got {x.shape}, {y.shape}, "
                             f"{w.shape}")
        if not np.all(np.isfinite(x)) or np.any((y < 0) | (y > 1)) or np.any(w < 0):
            raise InputError("labels", "x must be finite, labels in [0, 1], weights non-negative")
        values, inverse = np.unique(x, return_inverse=True)
        sw = np.bincount(inverse, weights=w, minlength=values.size)
        keep = sw > 0
        mean = np.bincount(inverse, weights=w * y, minlength=values.size)[keep] / sw[keep]
        return cls(values[keep], _pav(values[keep], mean, sw[keep]))

    @classmethod
    def fit_split(cls, split) -> "IsotonicEvidence":
        """Fitted on the cells ``split``'s second half observed, with its labels."""
        mask = split.group("all")
        return cls.fit(evidence(split)[mask], split.labels()[mask])

    def predict(self, x) -> np.ndarray:
        return np.interp(np.asarray(x, dtype=np.float64), self.x, self.p)

    def predict_split(self, split, fill_unseen: bool = True) -> np.ndarray:
        """P of every cell of ``split``'s first half; ``fill_unseen=False`` leaves never-seen cells at 0.5."""
        p = self.predict(evidence(split))
        return p if fill_unseen else np.where(split.first_hits + split.first_passes > 0, p, 0.5)


def _logit(p):
    q = np.clip(np.asarray(p, dtype=np.float64), LOGIT_FLOOR, 1 - LOGIT_FLOOR)  # P_raw of 0 or 1: a finite logit
    return np.log(q / (1 - q))


@dataclass(frozen=True)
class PlattRaw:
    """P = sigmoid(alpha + beta logit(P)): a grid's P recalibrated by logistic regression."""

    alpha: float
    beta: float

    @classmethod
    def fit(cls, probability, labels, steps: int = 100, tol: float = 1e-12) -> "PlattRaw":
        z = _logit(probability).ravel()
        y = np.asarray(labels, dtype=np.float64).ravel()
        if z.size == 0 or z.shape != y.shape:
            raise InputError("labels", f"need equal non-empty P and labels, got {z.shape} and {y.shape}")
        # grouped by distinct P (a grid from counts has few): one Newton step costs the groups, not the cells
        values, inverse = np.unique(z, return_inverse=True)
        n = np.bincount(inverse, minlength=values.size).astype(np.float64)
        k = np.bincount(inverse, weights=y, minlength=values.size)
        features = np.stack([np.ones_like(values), values], axis=1)
        theta = np.zeros(2)
        for _ in range(steps):
            q = 1 / (1 + np.exp(-(features @ theta)))
            grad = features.T @ (k - n * q)
            hess = (features * (n * q * (1 - q))[:, None]).T @ features + 1e-12 * np.eye(2)
            step = np.linalg.solve(hess, grad)
            theta = theta + step
            if np.max(np.abs(step)) < tol:
                break
        return cls(float(theta[0]), float(theta[1]))

    @classmethod
    def fit_split(cls, split) -> "PlattRaw":
        mask = split.group("all")
        return cls.fit(split.raw_probability()[mask], split.labels()[mask])

    def predict(self, probability) -> np.ndarray:
        return 1 / (1 + np.exp(-(self.alpha + self.beta * _logit(probability))))


# LBP over the whole grid ("no margin") creeps in never-seen space: on ACES its largest message change is
# still 6e-5 after 5000 iterations. It stops at 1e-4 or after 1000 float32 iterations (its state is reported).
WHOLE_GRID_LBP = {"tol": 1e-4, "max_iter": 1000, "dtype": np.float32}


def ablation_predictions(split, calibrators: dict | None = None, unseen_policies: bool = True) -> tuple:
    """({name: P}, {name: LBP summary}) on ``split``: the preset's ablations and the fitted calibrators.

    ``calibrators``: {name: fitted :class:`IsotonicEvidence` or :class:`PlattRaw`} (fitted on the
    training recording). With ``unseen_policies`` each also gets a twin ``name + ", unseen at 0.5"``
    that, like the raw grid and the preset far from observations, says nothing about never-seen cells.
    """
    out, lbp = {}, {}
    observed = split.first_hits + split.first_passes > 0
    for name, preset in ablation_presets().items():
        if name not in ABLATIONS:  # the base preset itself
            continue
        if name == "J = 0":  # no coupling: LBP returns the observation (tested), so skip running it
            out[name] = preset.observation(hits=split.first_hits, passes=split.first_passes)
            continue
        options = WHOLE_GRID_LBP if preset.margin is None else {"max_iter": 5000}
        r = preset.refine(hits=split.first_hits, passes=split.first_passes, **options)
        out[name] = r.beliefs.probability
        lbp[name] = {"converged": r.converged, "iterations": r.iterations, "last_change": r.last_change}
    for name, model in (calibrators or {}).items():
        p = model.predict_split(split) if isinstance(model, IsotonicEvidence) else model.predict(split.raw_probability())
        out[name] = p
        if unseen_policies:
            out[name + ", unseen at 0.5"] = np.where(observed, p, 0.5)
    return out, lbp
