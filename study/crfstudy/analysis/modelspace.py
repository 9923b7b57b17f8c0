"""The model space the thesis left as future work, scored by scan-split validation.

- :func:`symmetric_tables`: every (coupling J, link strength K) pair of a phase diagram, the
  hidden table [[e^2J, 1], [1, e^2J]] and link [[e^2K, 1], [1, e^2K]] applied to the raw grid,
  LBP near observations (as the certainty preset), scored on the second half.
- :func:`fit_scaled`: the certainty preset's coupling and evidence scale chosen by the scan-split
  Brier score of one recording (to apply to the others: transfer); :func:`scaled_scores` every
  candidate's score.
- :func:`fit_pseudolikelihood`: hidden and link tables learned by pseudo-likelihood with the
  second half's labels as the truth.

>>> from crfmap.assess.scansplit import ScanSplit
>>> rng = np.random.default_rng(0)
>>> sp = ScanSplit(*(rng.integers(0, 3, (16, 16)) for _ in range(4)))
>>> d = symmetric_tables(sp, [0.0, 0.3], [0.5, 1.0], margin=2)
>>> d["brier"].shape, bool(np.all(np.isfinite(d["brier"])))
((2, 2), True)
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from crfmap.assess.scansplit import score
from crfstudy.analysis.coordinate import split_brier
from crfmap.crf.presets import coupling_table, get_preset
from crfmap.crf.inference.lbp import infer
from crfmap.assess.learning import learn_pseudolikelihood

CERTAINTY = "certainty"  # the model whose space is mapped (the gated default is this model plus its evidence gate)


def _near(split, margin):
    preset = get_preset(CERTAINTY) if margin is None else replace(get_preset(CERTAINTY), margin=margin)
    return preset.region(split.first_hits + split.first_passes > 0)


def table_refine(split, coupling, link_strength, margin=None, max_iter=1000, tol=1e-5, dtype=np.float64):
    """(beliefs, LBPResult) of the raw grid with symmetric tables of coupling J and link strength K.

    ``tol`` and ``dtype`` go to :func:`crfmap.crf.inference.lbp.infer` (float32 moves half the bytes; its
    beliefs differ from float64's by about 1e-6).
    """
    return _refine(split.raw_probability(), _near(split, margin), coupling, link_strength, max_iter=max_iter, tol=tol,
                   dtype=dtype)


def _refine(raw, region, coupling, link_strength, max_iter=1000, tol=1e-5, dtype=np.float64):
    """:func:`table_refine` given the split's raw grid and LBP region (the same for every table of a diagram)."""
    result = infer(raw, coupling_table(coupling), coupling_table(link_strength), region=region, max_iter=max_iter,
                   tol=tol, dtype=dtype)
    return np.where(region, result.beliefs.probability, raw), result


def symmetric_tables(split, couplings, link_strengths, margin=None, group="all", progress=False, keep=(),
                     **options) -> dict:
    """Phase diagram: Brier score, wall recall and convergence for every (J, K), arrays [J, K].

    ``out["beliefs"]`` keeps the refined grids of the best pair and of the (J, K) pairs in ``keep``
    (so a caller scoring them again does not run LBP again); ``options`` go to :func:`table_refine`.
    """
    from tqdm.auto import tqdm

    shape = (len(couplings), len(link_strengths))
    out = {k: np.full(shape, np.nan) for k in ("brier", "wall_recall", "converged", "iterations")}
    keep = {(float(j), float(k)) for j, k in keep}
    kept, best_beliefs = {}, (np.inf, None, None)
    pairs = [(i, j) for i in range(shape[0]) for j in range(shape[1])]
    raw, region = split.raw_probability(), _near(split, margin)
    for i, j in tqdm(pairs, desc="phase diagram", disable=not progress, leave=False):
        beliefs, result = _refine(raw, region, couplings[i], link_strengths[j], **options)
        s = score(split, {"p": beliefs}, n_boot=0, groups=(group,), metrics=("brier", "wall_recall"))["p"][group]
        out["brier"][i, j], out["wall_recall"][i, j] = s["brier"], s["wall_recall"]
        out["converged"][i, j], out["iterations"][i, j] = result.converged, result.iterations
        pair = (float(couplings[i]), float(link_strengths[j]))
        if pair in keep:
            kept[pair] = beliefs
        if s["brier"] < best_beliefs[0]:  # first of equal scores, as nanargmin below
            best_beliefs = (s["brier"], pair, beliefs)
    out["couplings"], out["link_strengths"] = np.asarray(couplings, float), np.asarray(link_strengths, float)
    best = np.unravel_index(np.nanargmin(out["brier"]), shape)
    out["best"] = (float(couplings[best[0]]), float(link_strengths[best[1]]))
    if best_beliefs[1] == out["best"]:
        kept[out["best"]] = best_beliefs[2]
    out["beliefs"] = kept
    return out


def scaled_preset(coupling, scale, base=CERTAINTY):
    """The certainty preset with coupling J and every evidence weight multiplied by ``scale``."""
    p = get_preset(base)
    return replace(p, hidden=coupling_table(coupling), occupied=tuple(scale * v for v in p.occupied),
                   free=tuple(scale * v for v in p.free))


def scaled_scores(split, couplings, scales, dtype=np.float32) -> dict:
    """{(J, scale): scan-split Brier score (all cells)} of :func:`scaled_preset` on ``split``, J outer.

    LBP in ``dtype`` (float32: half the bytes; the scores move by about 1e-8).
    """
    out = {}
    for j in couplings:
        for s in scales:
            b = scaled_preset(j, s).refine(hits=split.first_hits, passes=split.first_passes,
                                           dtype=dtype).beliefs.probability
            out[(float(j), float(s))] = split_brier(split, b)
    return out


def fit_scaled(split, couplings, scales, scores=None) -> tuple:
    """(J, scale) of :func:`scaled_preset` with the lowest scan-split Brier score on ``split``.

    ``scores``: the :func:`scaled_scores` of this split, if already computed (the first of equal
    scores wins, in the order J outer, scale inner).
    """
    scores = scores if scores is not None else scaled_scores(split, couplings, scales)
    return min(scores, key=scores.get)


def fit_pseudolikelihood(split, steps=300):
    """(hidden, link) learned by pseudo-likelihood: raw grid of the first half, second-half labels as truth."""
    mask = split.group("all")
    truth = split.labels().astype(float)
    r = learn_pseudolikelihood(split.raw_probability(), truth, mask=mask, steps=steps, progress=False,
                               lbp_options={"max_iter": 1})
    return r.hidden, r.link
