"""What a CRF refinement must beat: simple ways to clean a grid, all as [y, x] P(occupied) arrays.

Window filters over the observed cells, a grey closing (which closes wall gaps one or two cells wide), the exact MAP
labelling by a graph cut, and :func:`all_baselines`: these with the raw, log-odds and thesis rows of a scan split.

>>> p = np.array([[0.9, 0.5, 0.9], [0.1, 0.1, 0.1]])
>>> window_mean(p).round(3).tolist()
[[0.367, 0.42, 0.367], [0.367, 0.42, 0.367]]
>>> grey_closing(np.array([[0.9, 0.1, 0.9]])).tolist()
[[0.9, 0.9, 0.9]]
"""
from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy import ndimage

from crfmap.errors import InputError
from crfmap.assess.mincut import graph_cut_map
from crfmap.grid import UNKNOWN
from crfmap.crf.presets import get_preset

_WINDOW = np.ones((3, 3))  # the 3x3 window of the window filters


def _check(p):
    p = np.asarray(getattr(p, "probability", p), dtype=np.float64)
    if p.ndim != 2 or p.size == 0:
        raise InputError("grid", f"expected a non-empty 2-D grid of P(occupied), got shape {p.shape}")
    return p


def window_mean(grid) -> np.ndarray:
    """Mean P of the observed (P != 0.5) cells in each cell's 3x3 window; 0.5 where there are none."""
    p = _check(grid)
    known = p != UNKNOWN
    # sums of the window in row-major order from 0, cells outside the grid adding 0 (unobserved): one correlation
    total = ndimage.correlate(np.where(known, p, 0.0), _WINDOW, mode="constant", cval=0.0)
    n = ndimage.correlate(known.astype(np.float64), _WINDOW, mode="constant", cval=0.0)
    return np.where(n > 0, total / np.maximum(n, 1), UNKNOWN)


def window_median(grid) -> np.ndarray:
    """Median P of the observed cells in each cell's 3x3 window (np.nanmedian's value); 0.5 where there are none.

    >>> window_median(np.array([[0.9, 0.1, 0.2]])).round(3).tolist()
    [[0.5, 0.2, 0.15]]
    """
    p = _check(grid)
    # no scipy filter skips unknown cells (generic_filter with np.nanmedian does, 15x slower; np.nanmedian over the
    # windows 8x slower): sort each window, NaN (unknown) last, and take the middle of its n known values
    padded = np.pad(np.where(p == UNKNOWN, np.nan, p), 1, constant_values=np.nan)
    win = np.sort(sliding_window_view(padded, _WINDOW.shape).reshape(p.shape + (_WINDOW.size,)), axis=-1)
    n = np.isfinite(win).sum(axis=-1)
    low = np.take_along_axis(win, (np.maximum(n - 1, 0) // 2)[..., None], axis=-1)[..., 0]
    high = np.take_along_axis(win, (n // 2)[..., None], axis=-1)[..., 0]
    return np.where(n > 0, np.where(n % 2 == 1, high, (low + high) / 2), UNKNOWN)


def grey_closing(grid) -> np.ndarray:
    """3x3 grey-level closing of P: dilation (maximum) then erosion (minimum); edges replicate."""
    return ndimage.grey_closing(_check(grid), size=_WINDOW.shape, mode="nearest")


def graph_cut(observation, hidden, region=None) -> np.ndarray:
    """Exact MAP labelling (1.0 occupied, 0.0 free) of the CRF with unary ``observation`` and a symmetric attractive
    ``hidden`` (:func:`crfmap.assess.mincut.graph_cut_map`). Outside ``region`` (boolean mask): the observation.

    >>> graph_cut(np.array([[0.9, 0.45, 0.9]]), [[10, 1], [1, 10]]).tolist()
    [[1.0, 1.0, 1.0]]
    """
    u = _check(observation)
    labels, _ = graph_cut_map(u, hidden, np.eye(2))
    out = np.asarray(labels, dtype=np.float64)
    if region is not None:
        out = np.where(region, out, u)
    return out


def _logodds(split, raw, thesis_max_iter):
    """The Probabilistic Robotics log-odds update of the first half's scans (None without them)."""
    if split.first_scans is None:
        return None
    from crfmap.mapping.builder import build_grid

    return build_grid(split.first_scans, split.resolution, bounds=split.bounds, model="logodds").probability


def _thesis(split, raw, thesis_max_iter):
    return get_preset("thesis").refine(raw, max_iter=thesis_max_iter).beliefs.probability


def _graphcut(split, raw, thesis_max_iter):
    return graph_cut(raw, get_preset("thesis").hidden)


# name -> function(split, raw grid, thesis_max_iter) -> [y, x] P, or None for this split; a new baseline is one entry
BASELINE_ROWS = {
    "raw": lambda split, raw, _: raw,
    "logodds": _logodds,
    "mean3x3": lambda split, raw, _: window_mean(raw),
    "median3x3": lambda split, raw, _: window_median(raw),
    "closing3x3": lambda split, raw, _: grey_closing(raw),
    "thesis": _thesis,
    "graphcut": _graphcut,
}
BASELINES = tuple(BASELINE_ROWS)


def all_baselines(split, thesis_max_iter: int = 1000, names=BASELINES) -> dict:
    """{name: P} of the baselines ``names`` (:data:`BASELINE_ROWS`) for a scan split's first half: ``raw`` always,
    ``logodds`` only with ``split.first_scans``."""
    unknown = [n for n in names if n not in BASELINE_ROWS]
    if unknown:
        raise InputError("baselines", f"unknown baseline(s) {', '.join(unknown)}; known: {', '.join(BASELINES)}")
    raw = split.raw_probability()
    out = {"raw": raw}
    for name in BASELINES:
        if name != "raw" and name in names:
            value = BASELINE_ROWS[name](split, raw, thesis_max_iter)
            if value is not None:
                out[name] = value
    return out
