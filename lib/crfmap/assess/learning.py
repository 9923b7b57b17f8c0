"""Learning the CRF's two tables from a grid with known ground truth (thesis sec. 2.7, 3.5).

Three learners, each returning a :class:`LearningResult`:

- :func:`learn_thesis`: the thesis's method exactly, a coordinate search on the 8 entries (4 hidden, 4 link).
- :func:`learn_gradient` (our default): the same objective, LBP's MSE against the truth, by gradient descent on the
  log of the entries: they stay positive, and a step is relative to the entry's size, which the thesis's fixed
  alpha = 0.01 is not (0.1 % of a hidden entry of 10 but 100 % of a link entry of 0.01).
- :func:`learn_pseudolikelihood`: the pseudo-likelihood of the truth (Besag), the learner of the Matlab toolbox the
  thesis compared against. Each cell's conditional given its true neighbours and its observation is exact and cheap,
  so no inference runs during learning and the gradient is exact.

A table matters only up to scale for LBP, so learned tables are reported at the scales of the thesis's defaults
(:func:`rescale`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import inspect

import numpy as np

from crfmap.checks import check_int, check_number
from crfmap.errors import InputError
from crfmap.crf.inference.lbp import infer
from crfmap.assess.metrics import mse
from crfmap.crf.model.potentials import check_table, DEFAULT_HIDDEN, DEFAULT_LINK
from crfmap.grid import OccupancyGrid, check_probability_array

ENTRY_NAMES = ("hidden oo", "hidden oe", "hidden eo", "hidden ee", "link oo", "link oe", "link eo", "link ee")


def check_pair(observed, truth, grids_only=False) -> tuple:
    """The probability arrays of an observed grid and its truth (each an OccupancyGrid or, unless ``grids_only``, an
    array of P), checked to have one shape.

    >>> obs, tru = check_pair(OccupancyGrid(np.full((2, 2), 0.5)), np.zeros((2, 2)))
    >>> check_pair(obs, np.zeros((3, 2)))
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: truth: shape (3, 2) does not match the observed grid's (2, 2)
    """
    arrays = []
    for name, grid in (("observed", observed), ("truth", truth)):
        if isinstance(grid, OccupancyGrid):
            arrays.append(grid.probability)
        elif grids_only:
            raise InputError(name, f"expected an OccupancyGrid, got {type(grid).__name__}")
        else:
            arrays.append(check_probability_array(grid, name))
    if arrays[0].shape != arrays[1].shape:
        raise InputError("truth", f"shape {arrays[1].shape} does not match the observed grid's {arrays[0].shape}")
    return tuple(arrays)


@dataclass
class LearningResult:
    """Learned tables plus the trace of the search (a list of dicts, one per step, keys by learner)."""

    hidden: np.ndarray
    link: np.ndarray
    mse_before: float
    mse_after: float
    trace: list = field(default_factory=list)
    method: str = "thesis"


def check_lbp_options(lbp_options) -> dict:
    """``lbp_options`` as a dict of :func:`crfmap.crf.inference.lbp.infer`'s keyword arguments (None: {}).

    >>> check_lbp_options({"grid": 1})
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: lbp_options: 'grid' is not a keyword option of crfmap.crf.inference.lbp.infer (expected some of dtype, init, max_iter, messages, pairing, region, schedule, threads, tol)
    """
    if lbp_options is None:
        return {}
    if not isinstance(lbp_options, dict):
        raise InputError("lbp_options", f"expected a dict of infer's keyword options, got {type(lbp_options).__name__}")
    allowed = sorted(name for name, p in inspect.signature(infer).parameters.items() if p.kind == p.KEYWORD_ONLY)
    for key in lbp_options:
        if key not in allowed:
            raise InputError("lbp_options", f"{key!r} is not a keyword option of crfmap.crf.inference.lbp.infer "
                                            f"(expected some of {', '.join(allowed)})")
    return dict(lbp_options)


def check_mask(mask, shape):
    """``mask`` as a boolean array of ``shape`` that selects at least one cell (None: every cell)."""
    if mask is None:
        return np.ones(shape, bool)
    values = np.asarray(mask)
    if values.dtype != np.bool_:
        raise InputError("mask", f"expected a boolean array (True: the cell counts), got dtype {values.dtype}")
    if values.shape != tuple(shape):
        raise InputError("mask", f"shape {values.shape} does not match the grids' {tuple(shape)}")
    if not values.any():
        raise InputError("mask", "selects no cell")
    return values


def lbp_mse(observed, truth, hidden, link, lbp_options=None) -> float:
    """MSE against the truth of the beliefs LBP gives with these tables."""
    obs, tru = check_pair(observed, truth)
    result = infer(obs, hidden, link, **check_lbp_options(lbp_options))
    return mse(result.beliefs, tru)


def _valid(table):
    return np.all(table >= 0) and np.all(table.max(axis=1) > 0)


def learn_thesis(
    observed,
    truth,
    hidden=DEFAULT_HIDDEN,
    link=DEFAULT_LINK,
    *,
    alpha: float = 0.01,
    min_alpha: float = 0.01,
    max_rounds: int = 200,
    lbp_options: dict | None = None,
    progress: bool = True,
) -> LearningResult:
    """The thesis's coordinate search on the 8 table entries, minimising LBP's MSE against the truth.

    Each entry in turn is stepped by +alpha, else -alpha, keeping a step that lowers the MSE; when a round over the 8
    improves nothing, alpha halves; the search stops when alpha falls below ``min_alpha`` (by default at the first
    round without gain) or after ``max_rounds``. ``observed``, ``truth``: grids (OccupancyGrid or [y, x] arrays),
    truth 0/1; ``hidden``, ``link``: the starting tables; ``lbp_options``: for :func:`crfmap.crf.inference.lbp.infer`
    (the thesis's: ``{"schedule": "thesis", "max_iter": 2}``).

    >>> rng = np.random.default_rng(0)
    >>> truth = (rng.uniform(size=(8, 8)) < 0.3).astype(float)
    >>> obs = np.clip(truth + rng.normal(0, 0.3, truth.shape), 0, 1)
    >>> r = learn_thesis(obs, truth, max_rounds=3, progress=False)
    >>> bool(r.mse_after <= r.mse_before)
    True
    """
    obs, tru = check_pair(observed, truth)
    alpha = check_number("alpha", alpha, low=0.0, low_open=True)
    min_alpha = check_number("min_alpha", min_alpha, low=0.0, low_open=True)
    check_int("max_rounds", max_rounds, low=1)
    tables = np.concatenate([check_table(hidden, "hidden").ravel(), check_table(link, "link").ravel()])
    opts = check_lbp_options(lbp_options)

    def score(t):
        return lbp_mse(obs, tru, t[:4].reshape(2, 2), t[4:].reshape(2, 2), opts)

    best = score(tables)
    before = best
    trace = [{"step": 0, "entry": "start", "value": float("nan"), "alpha": alpha, "mse": best, "accepted": True}]
    step = 0
    from tqdm.auto import tqdm

    bar = tqdm(total=max_rounds, desc="learning (thesis)", disable=not progress, leave=False)
    try:
        for _ in range(max_rounds):
            improved = False
            for i, name in enumerate(ENTRY_NAMES):
                for sign in (+1.0, -1.0):
                    trial = tables.copy()
                    trial[i] += sign * alpha
                    if not (_valid(trial[:4].reshape(2, 2)) and _valid(trial[4:].reshape(2, 2))):
                        continue
                    value = score(trial)
                    step += 1
                    accepted = value < best
                    trace.append({"step": step, "entry": name, "value": float(trial[i]), "alpha": alpha,
                                  "mse": value, "accepted": bool(accepted)})
                    if accepted:
                        tables, best, improved = trial, value, True
                        break
            bar.update(1)
            bar.set_postfix(mse=f"{best:.5f}", alpha=alpha)
            if not improved:
                alpha /= 2.0
                if alpha < min_alpha:
                    break
    finally:
        bar.close()
    return LearningResult(tables[:4].reshape(2, 2), tables[4:].reshape(2, 2), before, best, trace, "thesis")


def _log_entries(hidden, link, floor):
    """The 8 entries as logs, zero entries lifted to ``floor`` times their table's largest entry."""
    H, L = check_table(hidden, "hidden"), check_table(link, "link")
    H = np.maximum(H, floor * H.max())
    L = np.maximum(L, floor * L.max())
    return np.log(np.concatenate([H.ravel(), L.ravel()]))


def _tables(theta):
    e = np.exp(theta)
    return e[:4].reshape(2, 2), e[4:].reshape(2, 2)


def learn_gradient(
    observed,
    truth,
    hidden=DEFAULT_HIDDEN,
    link=DEFAULT_LINK,
    *,
    steps: int = 60,
    step_size: float = 0.5,
    min_step: float = 1e-3,
    delta: float = 1e-3,
    floor: float = 1e-3,
    lbp_options: dict | None = None,
    progress: bool = True,
) -> LearningResult:
    """Minimise LBP's MSE against the truth by gradient descent on the log-entries (central differences of width
    ``delta`` through converged LBP).

    Zero entries are lifted to ``floor`` times their table's largest entry. Each step moves ``step_size`` (log units)
    along the normalised gradient; a step that lowers the MSE is kept and the size grows by 1.5, else it halves; the
    search stops when the size falls below ``min_step`` or after ``steps`` steps.
    """
    obs, tru = check_pair(observed, truth)
    H0, L0 = check_table(hidden, "hidden"), check_table(link, "link")
    check_int("steps", steps, low=1)
    step_size = check_number("step_size", step_size, low=0.0, low_open=True)
    min_step = check_number("min_step", min_step, low=0.0, low_open=True)
    delta = check_number("delta", delta, low=0.0, low_open=True)
    floor = check_number("floor", floor, low=0.0, low_open=True, high=1.0)
    opts = check_lbp_options(lbp_options)
    before = lbp_mse(obs, tru, H0, L0, opts)
    theta = _log_entries(H0, L0, floor)

    def score(th):
        return lbp_mse(obs, tru, *_tables(th), opts)

    best = score(theta)
    trace = [{"step": 0, "mse": best, "step_size": step_size, "accepted": True}]
    from tqdm.auto import tqdm

    bar = tqdm(range(1, steps + 1), desc="learning (gradient)", disable=not progress, leave=False)
    for k in bar:
        grad = np.zeros(8)
        for i in range(8):
            e = np.zeros(8)
            e[i] = delta
            grad[i] = (score(theta + e) - score(theta - e)) / (2 * delta)
        norm = np.linalg.norm(grad)
        if norm == 0:
            break
        while step_size >= min_step:
            trial = theta - step_size * grad / norm
            value = score(trial)
            accepted = value < best
            trace.append({"step": k, "mse": value, "step_size": step_size, "accepted": bool(accepted)})
            if accepted:
                theta, best = trial, value
                step_size *= 1.5
                break
            step_size *= 0.5
        bar.set_postfix(mse=f"{best:.5f}", step=f"{step_size:.3g}")
        if step_size < min_step:
            break
    bar.close()
    if best >= before:  # lifting zero entries cost more than the search won: keep the start
        H, L = rescale(check_table(hidden, "hidden"), check_table(link, "link"))
        return LearningResult(H, L, before, before, trace, "gradient")
    H, L = rescale(*_tables(theta))
    return LearningResult(H, L, before, best, trace, "gradient")


def _neighbour_counts(truth_occupied):
    """For every cell, how many of its 4-neighbours are occupied and how many empty in the truth."""
    t = truth_occupied.astype(np.int64)
    exists = np.ones_like(t)
    occ = np.zeros_like(t)
    n = np.zeros_like(t)
    occ[:, 1:] += t[:, :-1]
    n[:, 1:] += exists[:, :-1]
    occ[:, :-1] += t[:, 1:]
    n[:, :-1] += exists[:, 1:]
    occ[1:, :] += t[:-1, :]
    n[1:, :] += exists[:-1, :]
    occ[:-1, :] += t[1:, :]
    n[:-1, :] += exists[1:, :]
    return occ, n - occ


def pseudolikelihood(observed, truth, hidden, link, mask=None):
    """(mean log pseudo-likelihood of the truth, its gradient (8,) w.r.t. the log of the 8 entries).

    Cell i's conditional: ``P(x_i | x_N(i), o_i) ∝ phi_i(x_i) * prod_j hidden[x_i, x_j]`` with
    ``phi_i(c) = link[c, 0] * o_i + link[c, 1] * (1 - o_i)``.
    """
    obs, tru = check_pair(observed, truth)
    return _pl_value_grad(_pl_terms(obs, tru, mask), check_table(hidden, "hidden"), check_table(link, "link"))


def _pl_terms(obs, tru, mask):
    """What :func:`pseudolikelihood` needs of the grids alone (the same at every step of a fit)."""
    x = tru > 0.5
    n_occ, n_emp = _neighbour_counts(x)
    keep = check_mask(mask, x.shape)
    o = obs[keep]
    n_occ, n_emp, xk = n_occ[keep], n_emp[keep], x[keep]
    state = np.where(xk, 0, 1)  # index 0 = occupied
    onehot = np.stack([state == 0, state == 1]).astype(float)
    return {"o": o, "n_occ": n_occ, "n_emp": n_emp, "state": state, "cells": np.arange(state.size), "onehot": onehot,
            "pb": np.stack([o, 1 - o])}


def _pl_value_grad(terms, H, L):
    """:func:`pseudolikelihood`'s (value, gradient) from :func:`_pl_terms` and checked tables."""
    o, n_occ, n_emp, state = terms["o"], terms["n_occ"], terms["n_emp"], terms["state"]
    logH = np.log(np.maximum(H, 1e-300))
    phi = np.stack([L[0, 0] * o + L[0, 1] * (1 - o), L[1, 0] * o + L[1, 1] * (1 - o)])  # (2, n)
    # log score of each state c: log phi(c) + n_occ * log H[c, occ] + n_emp * log H[c, emp]
    s = np.log(np.maximum(phi, 1e-300)) + n_occ * logH[:, 0:1] + n_emp * logH[:, 1:2]
    smax = s.max(axis=0)
    logz = smax + np.log(np.exp(s[0] - smax) + np.exp(s[1] - smax))
    post = np.exp(s - logz)  # (2, n) model conditional
    value = np.mean(s[state, terms["cells"]] - logz)
    resid = terms["onehot"] - post  # d value / d s(c), per cell
    grad = np.zeros(8)
    # d s(c) / d log H[a, b] = [c == a] * count(b)
    for a in range(2):
        grad[2 * a + 0] = np.mean(resid[a] * n_occ)
        grad[2 * a + 1] = np.mean(resid[a] * n_emp)
    # d s(c) / d log L[a, b] = [c == a] * L[a, b] * p_b / phi(c), p_0 = o (occupied), p_1 = 1 - o
    pb = terms["pb"]
    for a in range(2):
        for b in range(2):
            grad[4 + 2 * a + b] = np.mean(resid[a] * L[a, b] * pb[b] / np.maximum(phi[a], 1e-300))
    return float(value), grad


def rescale(hidden, link):
    """Rescale tables to the defaults' scales (hidden max 10, link max 1): LBP is unchanged."""
    H = check_table(hidden, "hidden")
    L = check_table(link, "link")
    return H * (10.0 / H.max()), L * (1.0 / L.max())


def learn_pseudolikelihood(
    observed,
    truth,
    hidden=DEFAULT_HIDDEN,
    link=DEFAULT_LINK,
    *,
    steps: int = 500,
    learning_rate: float = 0.1,
    tol: float = 1e-8,
    floor: float = 1e-3,
    mask=None,
    lbp_options: dict | None = None,
    progress: bool = True,
) -> LearningResult:
    """Maximise the pseudo-likelihood of the truth by gradient ascent on the log-entries (Adam); zero entries are
    lifted as in :func:`learn_gradient`. ``mse_before``/``mse_after``: LBP's MSE with the starting and learned tables
    under ``lbp_options``, to compare with the other learners."""
    obs, tru = check_pair(observed, truth)
    check_int("steps", steps, low=1)
    learning_rate = check_number("learning_rate", learning_rate, low=0.0, low_open=True)
    tol = check_number("tol", tol, low=0.0)
    floor = check_number("floor", floor, low=0.0, low_open=True, high=1.0)
    opts = check_lbp_options(lbp_options)
    theta = _log_entries(hidden, link, floor)
    m = np.zeros(8)
    v = np.zeros(8)
    b1, b2, eps = 0.9, 0.999, 1e-8
    trace = []
    last = -np.inf
    from tqdm.auto import tqdm

    terms = _pl_terms(obs, tru, mask)  # the grids' part, once: each step only changes the tables
    for t in tqdm(range(1, steps + 1), desc="learning (pseudo-likelihood)", disable=not progress, leave=False):
        H, L = _tables(theta)
        value, grad = _pl_value_grad(terms, check_table(H, "hidden"), check_table(L, "link"))
        trace.append({"step": t - 1, "objective": value})
        if abs(value - last) < tol:
            break
        last = value
        m = b1 * m + (1 - b1) * grad
        v = b2 * v + (1 - b2) * grad**2
        theta = theta + learning_rate * (m / (1 - b1**t)) / (np.sqrt(v / (1 - b2**t)) + eps)
    H, L = rescale(*_tables(theta))
    return LearningResult(H, L, lbp_mse(obs, tru, hidden, link, opts), lbp_mse(obs, tru, H, L, opts), trace,
                          "pseudo-likelihood")
