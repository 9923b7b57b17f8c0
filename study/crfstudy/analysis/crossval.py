"""Cross-validating a map that has no ground truth (thesis sec. 2.10.4 and 4.1.3, Table 26).

A real map has no ground truth, so the map is checked against itself: some of its known cells
are *held out* (set to 0.5, unknown), predicted from the rest, and each prediction is compared
with the held-out cell's own label in the map (occupied if P > 0.5). The thesis calls this
"leave one out cross validation" without saying what was left out; here it is defined as:

- :func:`random_folds`: the known cells split at random into ``k`` folds of (almost) equal size.
  Each fold is held out in turn. With ``k = 10`` a held-out cell has, on average, 0.4 held-out
  4-neighbours, so this is close to the literal leave-one-out (one cell at a time), which
  :func:`leave_one_out` runs on a sample of cells to check how close.
- :func:`block_folds`: square blocks of ``block`` x ``block`` cells assigned at random to folds:
  a harder test, which asks for whole patches (a piece of wall, a doorway) to be filled in.

Predictors take ``(masked_grid, held_out_mask)`` and return the predicted grid (an
:class:`~crfmap.grid.OccupancyGrid`, an array, or an :class:`~crfmap.crf.inference.result.LBPResult`):
:func:`lbp_predictor` (the CRF) and :func:`neighbour_predictor` (the baseline: the mean P of the
known cells around a held-out cell). Precision, recall and accuracy skip predictions of exactly
0.5, as everywhere in :mod:`crfmap.assess.metrics`; :attr:`CrossValidation.coverage` says how many that left.

>>> import numpy as np
>>> halves = np.repeat([[0.9]] * 3 + [[0.1]] * 3, 6, axis=1)  # a thick wall below free space
>>> folds = random_folds(np.ones(halves.shape, bool), 5, seed=0)
>>> cv = cross_validate(halves, folds, lbp_predictor(margin=None), progress=False)
>>> round(cv.report().accuracy, 3), cv.coverage
(1.0, 1.0)
>>> cv = cross_validate(halves, folds, neighbour_predictor(1), progress=False)
>>> round(cv.report().accuracy, 3), round(cv.coverage, 3)
(0.938, 0.889)
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from crfmap.checks import check_int
from crfmap.errors import InputError
from crfmap.grid import UNKNOWN, OccupancyGrid, as_grid, check_probability_array
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.regions import near_known
from crfmap.assess.metrics import evaluate, roc_curve

NOT_IN_A_FOLD = -1  # fold id of cells that are never held out (unknown cells)


def _mask(mask, name="mask") -> np.ndarray:
    m = np.asarray(mask)
    if m.ndim != 2 or m.size == 0:
        raise InputError(name, f"expected a non-empty 2-D [y, x] boolean mask, got shape {m.shape}")
    if m.dtype != bool:
        raise InputError(name, f"expected a boolean mask, got dtype {m.dtype}")
    return m


def _check_k(k, n_cells):
    k = check_int("k", k, low=2)
    if k > n_cells:
        raise InputError("k", f"{k} folds but only {n_cells} cells to share among them")
    return int(k)


def random_folds(mask, k=10, seed=0) -> np.ndarray:
    """Fold id ``[y, x]`` for every cell in ``mask``: a random split into ``k`` folds of equal size (+-1).

    Cells outside ``mask`` get :data:`NOT_IN_A_FOLD` (-1).

    >>> random_folds(np.ones((2, 3), bool), 3, seed=0)
    array([[1, 2, 1],
           [0, 0, 2]])
    """
    m = _mask(mask)
    cells = np.flatnonzero(m)
    k = _check_k(k, cells.size)
    order = np.random.default_rng(seed).permutation(cells.size)
    folds = np.full(m.shape, NOT_IN_A_FOLD, dtype=np.int64)
    folds.flat[cells[order]] = np.arange(cells.size) % k
    return folds


def block_folds(mask, k=10, block=8, seed=0) -> np.ndarray:
    """Fold id ``[y, x]`` per cell in ``mask``, whole ``block`` x ``block`` squares to one fold each.

    The grid is tiled from cell (0, 0); the blocks holding at least one cell of ``mask`` are
    dealt at random into ``k`` folds (equal numbers of blocks, +-1). Cells outside ``mask`` get -1.

    >>> block_folds(np.ones((2, 4), bool), 2, block=2, seed=0)
    array([[0, 0, 1, 1],
           [0, 0, 1, 1]])
    """
    m = _mask(mask)
    if isinstance(block, bool) or not isinstance(block, (int, np.integer)) or block < 1:
        raise InputError("block", f"need a whole number of cells >= 1, got {block!r}")
    ys, xs = np.nonzero(m)
    nbx = -(-m.shape[1] // int(block))
    block_of = (ys // block) * nbx + xs // block
    blocks = np.unique(block_of)
    k = _check_k(k, blocks.size)
    order = np.random.default_rng(seed).permutation(blocks.size)
    fold_of_block = np.empty(blocks.size, dtype=np.int64)
    fold_of_block[order] = np.arange(blocks.size) % k
    folds = np.full(m.shape, NOT_IN_A_FOLD, dtype=np.int64)
    folds[ys, xs] = fold_of_block[np.searchsorted(blocks, block_of)]
    return folds


def _box_sum(a, radius):
    """Sum of ``a`` over the (2r+1) x (2r+1) window around every cell (zero outside the grid)."""
    h, w = a.shape
    s = np.zeros((h + 1, w + 1))
    s[1:, 1:] = a.cumsum(0).cumsum(1)
    y0 = np.clip(np.arange(h) - radius, 0, h)
    y1 = np.clip(np.arange(h) + radius + 1, 0, h)
    x0 = np.clip(np.arange(w) - radius, 0, w)
    x1 = np.clip(np.arange(w) + radius + 1, 0, w)
    return s[y1][:, x1] - s[y0][:, x1] - s[y1][:, x0] + s[y0][:, x0]


def neighbour_mean(grid, radius=1) -> OccupancyGrid:
    """Every cell replaced by the mean P of the *known* cells around it (itself excluded); 0.5 if none.

    The window is (2 radius + 1) x (2 radius + 1) cells. A smoothing baseline: thresholded at
    0.5 it is the (probability-weighted) majority vote of the known neighbours.

    >>> neighbour_mean(np.array([[0.9, 0.5, 0.1, 0.2]]), 1).probability.round(2).tolist()
    [[0.5, 0.5, 0.2, 0.1]]
    """
    g = as_grid(grid)
    if isinstance(radius, bool) or not isinstance(radius, (int, np.integer)) or radius < 1:
        raise InputError("radius", f"need a whole number of cells >= 1, got {radius!r}")
    p = g.probability
    known = (p != UNKNOWN).astype(np.float64)
    total = _box_sum(p * known, int(radius)) - p * known
    count = _box_sum(known, int(radius)) - known
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count > 0, total / np.maximum(count, 1), UNKNOWN)
    return g.with_probability(np.clip(mean, 0.0, 1.0))


def neighbour_predictor(radius=1):
    """The baseline predictor for :func:`cross_validate`: :func:`neighbour_mean` of the masked grid."""
    neighbour_mean(np.full((1, 1), UNKNOWN), radius)  # check radius now, not in the first fold

    def predict(masked, held_out):
        return neighbour_mean(masked, radius)

    return predict


def lbp_predictor(hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK, margin=3, **options):
    """The CRF predictor for :func:`cross_validate`: :func:`crfmap.crf.inference.lbp.infer` on the masked grid.

    LBP runs on the cells within ``margin`` cells of a known cell of the masked grid plus the
    held-out cells (:func:`crfmap.crf.inference.regions.near_known`): the never-observed outside of a real map
    then stays out of it (under the default coupling LBP would fill it with the state of its
    border). ``margin=None`` runs on the whole grid. ``options`` go to :func:`~crfmap.crf.inference.lbp.infer`
    (``schedule``, ``max_iter``, ``tol``, ...).
    """
    if margin is not None and not (isinstance(margin, (int, np.integer)) and not isinstance(margin, bool)
                                   and margin >= 0):
        raise InputError("margin", f"must be None or a whole number of cells >= 0, got {margin!r}")

    def predict(masked, held_out):
        region = None if margin is None else near_known(masked, int(margin)) | held_out
        return infer(masked, hidden, link, region=region, **options)

    return predict


def _prediction(result, shape):
    """Probability array out of whatever a predictor returned, plus LBP diagnostics if any."""
    info = {}
    if hasattr(result, "beliefs"):  # an LBPResult
        info = {"iterations": int(result.iterations), "converged": bool(result.converged)}
        result = result.beliefs
    p = result.probability if isinstance(result, OccupancyGrid) else check_probability_array(result, "prediction")
    if p.shape != shape:
        raise InputError("prediction", f"the predictor returned shape {p.shape}, expected {shape}")
    return p, info


@dataclass
class CrossValidation:
    """What :func:`cross_validate` returns.

    Attributes
    ----------
    labels : OccupancyGrid
        The map being validated; a cell's label is occupied if P > 0.5.
    predicted : OccupancyGrid
        The prediction of every held-out cell, made while its fold was hidden; 0.5 elsewhere.
    held_out : ndarray of bool
        The cells that were held out (the folds that were run).
    folds : ndarray of int
        The fold id of every cell (-1: never held out).
    per_fold : list of dict
        For every fold run: ``fold``, ``cells``, ``seconds`` and, for LBP, ``iterations``, ``converged``.
    """

    labels: OccupancyGrid
    predicted: OccupancyGrid
    held_out: np.ndarray
    folds: np.ndarray
    per_fold: list = field(default_factory=list)

    def report(self):
        """MSE, precision, recall, accuracy and AUC over the held-out cells (:func:`crfmap.assess.metrics.evaluate`)."""
        return evaluate(self.predicted, self.labels, self.held_out)

    def roc(self):
        """(false positive rate, true positive rate, thresholds) over the held-out cells."""
        return roc_curve(self.predicted, self.labels, self.held_out)

    @property
    def coverage(self) -> float:
        """Fraction of held-out cells that got a prediction other than exactly 0.5 (the ones scored)."""
        n = int(self.held_out.sum())
        return float(np.count_nonzero(self.predicted.probability[self.held_out] != UNKNOWN) / n) if n else float("nan")

    @property
    def seconds(self) -> float:
        return float(sum(f["seconds"] for f in self.per_fold))


def cross_validate(grid, folds, predict, run=None, progress=True) -> CrossValidation:
    """Hold out each fold in turn, predict it from the rest of the map, and collect the predictions.

    Parameters
    ----------
    grid : OccupancyGrid or 2-D array
        The map; its known cells (P != 0.5) are the labels.
    folds : int array [y, x]
        Fold id per cell (:func:`random_folds`, :func:`block_folds`); -1 = never held out.
        Only known cells may be in a fold.
    predict : callable ``(masked_grid, held_out_mask) -> OccupancyGrid | array | LBPResult``
        Sees the map with the fold's cells set to 0.5 (:func:`lbp_predictor`,
        :func:`neighbour_predictor`, or your own).
    run : iterable of fold ids, optional
        The folds to run (default: all); fewer folds give a quicker, noisier estimate.
    progress : bool
        A tqdm bar over the folds.

    Returns
    -------
    CrossValidation
    """
    from tqdm.auto import tqdm

    g = as_grid(grid)
    f = np.asarray(folds)
    if f.shape != g.shape or not np.issubdtype(f.dtype, np.integer):
        raise InputError("folds", f"expected an integer array of the grid's shape {g.shape}, got {f.dtype} {f.shape}")
    if f.min() < NOT_IN_A_FOLD:
        raise InputError("folds", f"fold ids must be >= {NOT_IN_A_FOLD}, found {int(f.min())}")
    in_fold = f != NOT_IN_A_FOLD
    unknown_in_fold = int(np.count_nonzero(in_fold & ~g.known()))
    if unknown_in_fold:
        raise InputError("folds", f"{unknown_in_fold} cell(s) in a fold are unknown (0.5) in the grid; "
                                  f"only known cells have a label to compare with")
    ids = np.unique(f[in_fold])
    if run is None:
        run = ids
    else:
        run = np.asarray(list(run), dtype=np.int64)
        missing = np.setdiff1d(run, ids)
        if missing.size:
            raise InputError("run", f"fold(s) {missing.tolist()} do not occur in folds")
    predicted = np.full(g.shape, UNKNOWN)
    held_out = np.zeros(g.shape, dtype=bool)
    per_fold = []
    for fold in tqdm(run, desc="folds", unit="fold", disable=not progress):
        cells = f == fold
        masked = g.with_probability(np.where(cells, UNKNOWN, g.probability))
        t0 = time.perf_counter()
        p, info = _prediction(predict(masked, cells), g.shape)
        seconds = time.perf_counter() - t0
        predicted[cells] = p[cells]
        held_out |= cells
        per_fold.append({"fold": int(fold), "cells": int(cells.sum()), "seconds": seconds, **info})
    return CrossValidation(labels=g, predicted=g.with_probability(predicted), held_out=held_out, folds=f,
                           per_fold=per_fold)


def leave_one_out(grid, cells, predict, window=20, progress=False) -> np.ndarray:
    """The literal leave-one-out: each cell held out alone and predicted from a window around it.

    Parameters
    ----------
    grid : OccupancyGrid or 2-D array
    cells : (n, 2) int array of (x, y) known cells
    predict : a predictor as for :func:`cross_validate`
    window : int
        The prediction sees the cells within ``window`` cells (Chebyshev distance) of the
        held-out one; far cells barely move a belief, and a window keeps one cell cheap.

    Returns
    -------
    ndarray (n,) of predicted P(occupied).

    >>> g = np.array([[0.9, 0.9, 0.9], [0.1, 0.1, 0.1]])
    >>> leave_one_out(g, [[1, 0]], neighbour_predictor(1)).round(2).tolist()  # (0.9 + 0.9 + 3 x 0.1) / 5
    [0.42]
    """
    from tqdm.auto import tqdm

    g = as_grid(grid)
    c = np.asarray(cells)
    if c.ndim != 2 or c.shape[1] != 2 or not np.issubdtype(c.dtype, np.integer):
        raise InputError("cells", f"expected an (n, 2) integer array of (x, y) cells, got {c.dtype} {c.shape}")
    if isinstance(window, bool) or not isinstance(window, (int, np.integer)) or window < 1:
        raise InputError("window", f"need a whole number of cells >= 1, got {window!r}")
    h, w = g.shape
    outside = (c[:, 0] < 0) | (c[:, 0] >= w) | (c[:, 1] < 0) | (c[:, 1] >= h)
    if outside.any():
        raise InputError("cells", f"cell {c[np.argmax(outside)].tolist()} lies outside the {w} x {h} grid")
    if not g.known()[c[:, 1], c[:, 0]].all():
        bad = c[np.argmax(~g.known()[c[:, 1], c[:, 0]])].tolist()
        raise InputError("cells", f"cell {bad} is unknown (0.5) in the grid; only known cells can be left out")
    out = np.empty(len(c))
    for i, (x, y) in enumerate(tqdm(c, desc="leave one out", unit="cell", disable=not progress)):
        y0, y1 = max(0, y - window), min(h, y + window + 1)
        x0, x1 = max(0, x - window), min(w, x + window + 1)
        crop = g.probability[y0:y1, x0:x1].copy()
        crop[y - y0, x - x0] = UNKNOWN
        alone = np.zeros(crop.shape, dtype=bool)
        alone[y - y0, x - x0] = True
        ox, oy, yaw = g.origin  # the window keeps its place in the world (for predictors that use it)
        dx, dy = x0 * g.resolution, y0 * g.resolution
        corner = (ox + dx * np.cos(yaw) - dy * np.sin(yaw), oy + dx * np.sin(yaw) + dy * np.cos(yaw), yaw)
        window_grid = OccupancyGrid(crop, g.resolution, corner, g.frame_id)
        p, _ = _prediction(predict(window_grid, alone), crop.shape)
        out[i] = p[y - y0, x - x0]
    return out
