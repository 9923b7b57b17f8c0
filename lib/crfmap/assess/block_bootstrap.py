"""The spatial-block bootstrap's pieces for :mod:`crfmap.assess.scansplit` (private): block ids and sums, resample
draws, and the compiled AUC of every resample at once.

>>> _block_ids((2, 3), 2).tolist()
[[0, 0, 1], [0, 0, 1]]
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _auc_resampled(y, inverse, starts, draws):  # pragma: no cover - compiled; tested against _Scorer._auc
    """:meth:`crfmap.assess.scansplit._Scorer._auc` for every row of block weights ``draws``, cells sorted by P.

    Each resample's sums are added in the order of one resample at a time (the same numbers, bit for bit), but the
    innermost loop runs over independent resamples, not along one long chain of additions.
    """
    n_boot, n, n_runs = draws.shape[0], y.size, starts.size
    weights = np.ascontiguousarray(draws.T)  # [block, resample]
    total, neg_below = np.zeros(n_boot), np.zeros(n_boot)
    n_pos, n_neg = np.zeros(n_boot), np.zeros(n_boot)
    pos_g, neg_g = np.empty(n_boot), np.empty(n_boot)
    for r in range(n_runs):
        end = starts[r + 1] if r + 1 < n_runs else n
        pos_g[:] = 0.0
        neg_g[:] = 0.0
        for i in range(starts[r], end):
            yi, ni = y[i], 1.0 - y[i]
            w = weights[inverse[i]]
            for k in range(n_boot):
                pos_g[k] += w[k] * yi
                neg_g[k] += w[k] * ni
        for k in range(n_boot):
            total[k] += pos_g[k] * (neg_below[k] + 0.5 * neg_g[k])
            neg_below[k] += neg_g[k]
            n_pos[k] += pos_g[k]
            n_neg[k] += neg_g[k]
    out = np.empty(n_boot)
    for k in range(n_boot):
        out[k] = total[k] / (n_pos[k] * n_neg[k]) if n_pos[k] > 0 and n_neg[k] > 0 else np.nan
    return out


def _block_ids(shape, block):
    yy, xx = np.indices(shape)
    nbx = -(-shape[1] // block)
    return (yy // block) * nbx + xx // block


def _block_counts(y, inverse, n_blocks):
    """(cells, walls) per block: the sums of :class:`_Scorer` that do not depend on the prediction."""
    return (np.bincount(inverse, weights=np.ones(len(y)), minlength=n_blocks),
            np.bincount(inverse, weights=y, minlength=n_blocks))


def _draws(rng, n_blocks, n_boot):
    """[n_boot, n_blocks] block weights: how often each block was drawn in each resample (advances ``rng``)."""
    return np.array([np.bincount(rng.integers(0, n_blocks, n_blocks), minlength=n_blocks)
                     for _ in range(n_boot)], dtype=np.float64).reshape(-1, n_blocks)
