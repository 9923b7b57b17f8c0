"""Coarse-to-fine start for LBP: solve a 2x downsampled grid, upsample its messages as the warm start.

``infer(grid, init="coarse")`` halves the grid (:func:`downsample`) down to about :data:`COARSE_MIN_SIDE` cells a side,
runs LBP there from uniform messages, and warm-starts each finer level from the coarser (:func:`upsample_messages`).

Where LBP has a single fixed point (couplings below critical) the start changes only the path, not the beliefs. In
the ordered phase LBP has several fixed points and the start picks one (``crfmap bench``'s ``converge-start`` row and
notebook 09 measure what it costs and saves).

>>> import numpy as np
>>> downsample(np.array([[0.0, 1.0, 0.9], [1.0, 0.0, 0.5]])).round(3).tolist()
[[0.5, 0.988]]
>>> upsample_messages(np.arange(8.0).reshape(4, 1, 2), (2, 3))[2].tolist()
[[4.0, 4.0, 5.0], [4.0, 4.0, 5.0]]
"""
from __future__ import annotations

import numpy as np

COARSE_MIN_SIDE = 64  # [cells] levels stop halving once a side would drop below this
COARSE_TOL_FACTOR = 1.0  # coarse levels stop at this times the caller's tol (they only seed the next level)
PROBABILITY_FLOOR = 1e-6  # P clipped to [floor, 1 - floor] before combining log-odds
INITS = ("uniform", "coarse")


def downsample(probability) -> np.ndarray:
    """Each 2x2 block's evidence as one cell's: P whose log-odds is the sum of the four cells' (P clipped to
    [PROBABILITY_FLOOR, 1 - PROBABILITY_FLOOR] first), shape (ceil(H / 2), ceil(W / 2)); an odd last row or column
    counts twice. The block as one spin, the strong-coupling limit: the mean of P instead washes thin walls out, and
    the ordered phase then settles the fine grid on an all-empty fixed point."""
    p = np.clip(np.asarray(probability, dtype=np.float64), PROBABILITY_FLOOR, 1.0 - PROBABILITY_FLOOR)
    h, w = p.shape
    hh, ww = (h + 1) // 2, (w + 1) // 2
    padded = np.pad(np.log(p / (1.0 - p)), ((0, 2 * hh - h), (0, 2 * ww - w)), mode="edge")
    return 1.0 / (1.0 + np.exp(-padded.reshape(hh, 2, ww, 2).sum(axis=(1, 3))))


def upsample_messages(messages, shape) -> np.ndarray:
    """Messages (4, h, w) of a coarse grid onto a fine grid of ``shape``: fine (y, x) takes coarse (y // 2, x // 2)."""
    h, w = shape
    m = np.asarray(messages)
    return np.ascontiguousarray(m.repeat(2, axis=1).repeat(2, axis=2)[:, :h, :w])


def levels(shape, min_side=COARSE_MIN_SIDE) -> int:
    """How many times the grid can be halved before a side drops below ``min_side``."""
    n, (h, w) = 0, shape
    while min(h, w) >= 2 * min_side:
        h, w, n = (h + 1) // 2, (w + 1) // 2, n + 1
    return n


def coarse_messages(probability, solve, min_side=COARSE_MIN_SIDE):
    """(warm-start messages for ``probability`` from its coarser levels or None if it is too small to halve, the
    coarse levels' results, coarsest first); ``solve(probability, messages)`` runs LBP on one level."""
    n = levels(np.shape(probability), min_side)
    if n == 0:
        return None, []
    pyramid = [np.asarray(probability)]
    for _ in range(n):
        pyramid.append(downsample(pyramid[-1]))
    messages, results = None, []
    for p in pyramid[:0:-1]:  # coarsest first, the finest level is the caller's
        if messages is not None:
            messages = upsample_messages(messages, p.shape)
        result = solve(p, messages)
        results.append(result)
        messages = result.messages
    return upsample_messages(messages, np.shape(probability)), results
