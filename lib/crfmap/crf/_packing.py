"""Numba kernels converting between the probability layout of :mod:`crfmap.crf._lbp_kernels` and the
red/black odds planes of :mod:`crfmap.crf._lbp_fast` (private; used by :mod:`crfmap.crf.packed`)."""
from __future__ import annotations

import numpy as np
from numba import njit, prange


# --- layout conversion -------------------------------------------------------------------------


@njit(inline="always", cache=True)
def unary_odds(p, link, floor):
    """Odds of the message an observation P(occupied) = p sends through ``link`` (floored).

    ``link`` = (l00, l01, l10, l11); as :func:`crfmap.crf.potentials.link_unary`.
    """
    occ = link[0] * p + link[1] * (1.0 - p)
    emp = link[2] * p + link[3] * (1.0 - p)
    tot = occ + emp
    u = occ / tot if tot > 0 else 0.5
    u = min(max(u, floor), 1.0 - floor)
    return u / (1.0 - u)


@njit(parallel=True, cache=True)
def _pack_unary(prob, y0, x0, h, w, link, floor, un):
    """Observation odds of cells [y0, y0 + h) x [x0, x0 + w) of ``prob`` into planes ``un``."""
    for y in prange(h):
        for c in range(2):  # colour by colour: unit-stride writes, so the divisions vectorise
            off = (y + c) & 1
            for k in range(1, ((w - off + 1) >> 1) + 1):
                un[c, y + 1, k] = unary_odds(prob[y0 + y, x0 + 2 * k - 2 + off], link, floor)


@njit(parallel=True, cache=True)
def _pack_messages(msg_p, y0, x0, h, w, floor, out):
    """Probability messages [4, y, x] of the block into odds planes ``out`` (floored).

    A slot with no neighbour behind it in the whole grid stays uniform (odds 1).
    """
    grid_h, grid_w = msg_p.shape[1], msg_p.shape[2]
    for y in prange(h):
        gy = y0 + y
        for x in range(w):
            gx = x0 + x
            c = (x + y) & 1
            for d in range(4):
                m = min(max(msg_p[d, gy, gx], floor), 1.0 - floor)
                r = m / (1.0 - m)
                if (d == 0 and gx == 0) or (d == 1 and gx == grid_w - 1) or (d == 2 and gy == 0) or (d == 3 and gy == grid_h - 1):
                    r = 1.0
                out[c, d, y + 1, (x >> 1) + 1] = r


@njit(parallel=True, cache=True)
def _unpack_messages(packed, y0, x0, h, w, act, use_act, out):
    """Odds planes back into probability messages ``out[4, y0 + y, x0 + x]``.

    With ``use_act`` only slots whose sender is an active cell of the block are written (the
    others did not change, and a round trip through odds would perturb them by rounding).
    """
    for y in prange(h):
        for x in range(w):
            c = (x + y) & 1
            for d in range(4):
                if use_act:
                    sy = y + (1 if d == 3 else (-1 if d == 2 else 0))
                    sx = x + (1 if d == 1 else (-1 if d == 0 else 0))
                    if sy < 0 or sy >= h or sx < 0 or sx >= w or act[(sx + sy) & 1, sy + 1, (sx >> 1) + 1] == 0:
                        continue
                r = packed[c, d, y + 1, (x >> 1) + 1]
                out[d, y0 + y, x0 + x] = r / (1.0 + r)


@njit(parallel=True, cache=True)
def _beliefs_packed(un, packed, h, w, out):
    """P(occupied) of every cell of the block: observation odds times its four message odds."""
    for y in prange(h):
        for c in range(2):  # colour by colour: unit-stride reads
            off = (y + c) & 1
            for k in range(1, ((w - off + 1) >> 1) + 1):
                b = float(un[c, y + 1, k]) * float(packed[c, 0, y + 1, k]) * float(packed[c, 1, y + 1, k])
                b = b * float(packed[c, 2, y + 1, k]) * float(packed[c, 3, y + 1, k])
                out[y, 2 * k - 2 + off] = b / (1.0 + b)


@njit(cache=True)
def _active_extents(act, h, w, lo_k, hi_k):
    """Per colour and row, the plane-index range [lo, hi) holding its active cells."""
    for c in range(2):
        for y in range(h):
            off = (y + c) & 1
            n = (w - off + 1) >> 1
            lo = n
            hi = 0
            for k in range(n):
                if act[c, y + 1, k + 1] != 0:
                    if k < lo:
                        lo = k
                    hi = k + 1
            lo_k[c, y] = lo if hi > 0 else 0
            hi_k[c, y] = hi


@njit(parallel=True, cache=True)
def _fill_ones(planes):
    """planes[...] = 1 over the last two axes in parallel (first touch of fresh memory on every thread)."""
    flat = planes.reshape(-1, planes.shape[-2], planes.shape[-1])
    for i in prange(flat.shape[0] * flat.shape[1]):
        flat[i // flat.shape[1], i % flat.shape[1], :] = 1


@njit(parallel=True, cache=True)
def _pack_clamped(state, implied_odds, msg, act):
    """Cells with ``state`` >= 0 (certain) stop sending (``act`` 0) and their four messages become
    ``implied_odds[d, state]``; the others send (``act`` 1). Whole grid, as :func:`crfmap.crf.evidence.clamp_messages`."""
    h, w = state.shape
    for y in prange(h):
        for x in range(w):
            s = state[y, x]
            act[(x + y) & 1, y + 1, (x >> 1) + 1] = 1 if s < 0 else 0
            if s < 0:
                continue
            if x + 1 < w:
                msg[(x + 1 + y) & 1, 0, y + 1, ((x + 1) >> 1) + 1] = implied_odds[0, s]
            if x > 0:
                msg[(x - 1 + y) & 1, 1, y + 1, ((x - 1) >> 1) + 1] = implied_odds[1, s]
            if y + 1 < h:
                msg[(x + y + 1) & 1, 2, y + 2, (x >> 1) + 1] = implied_odds[2, s]
            if y > 0:
                msg[(x + y - 1) & 1, 3, y, (x >> 1) + 1] = implied_odds[3, s]


@njit(parallel=True, cache=True)
def _pack_mask(mask, y0, x0, h, w, out):
    for y in prange(h):
        for x in range(w):
            out[(x + y) & 1, y + 1, (x >> 1) + 1] = 1 if mask[y0 + y, x0 + x] else 0
