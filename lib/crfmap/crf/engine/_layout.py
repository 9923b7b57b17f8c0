"""Numba kernels converting between the probability layout of :mod:`crfmap.crf.engine.messages` and the red/black
odds planes of :mod:`crfmap.crf.engine._message_update` (private; used by :mod:`crfmap.crf.engine.packed`).

Kernels over rows take their band ``[r0, r1)`` last and release the GIL, for :func:`crfmap.crf.threads.over_rows`.
All take ``error_model="numpy"``: under numba's default every division checks for a zero divisor (to raise
ZeroDivisionError), so no loop with one vectorises; a zero divisor gives inf or NaN, as in NumPy."""
from __future__ import annotations

import numpy as np
from numba import njit



@njit(inline="always", cache=True, error_model="numpy")
def unary_odds(p, link, floor):
    """Odds of the message an observation P(occupied) = p sends through ``link`` = (l00, l01, l10, l11), floored."""
    return _odds(link[0] * p + link[1] * (1.0 - p), link[2] * p + link[3] * (1.0 - p), floor)


@njit(inline="always", cache=True, error_model="numpy")
def _odds(occ, emp, floor):
    """:func:`unary_odds` from the two link sums, occupied and empty."""
    hi = (1.0 - floor) / floor  # the odds of P = 1 - floor (a loop invariant)
    r = occ / emp if emp > 0 else (hi if occ > 0 else 1.0)  # one division: P = occ / (occ + emp) as odds
    return min(max(r, 1.0 / hi), hi)


@njit(nogil=True, cache=True, error_model="numpy")
def _pack_unary(prob, y0, x0, h, w, link, floor, un, r0, r1):
    """Observation odds of cells [y0, y0 + h) x [x0, x0 + w) of ``prob`` into planes ``un``."""
    for y in range(r0, r1):
        for c in range(2):  # colour by colour: unit-stride writes, so the divisions vectorise
            off = (y + c) & 1
            for k in range(1, ((w - off + 1) >> 1) + 1):
                un[c, y + 1, k] = unary_odds(prob[y0 + y, x0 + 2 * k - 2 + off], link, floor)


@njit(nogil=True, cache=True, error_model="numpy")
def _pack_messages(msg_p, y0, x0, h, w, floor, out, r0, r1):
    """Probability messages [4, y, x] of the block into odds planes ``out`` (floored; a slot with no neighbour
    behind it in the whole grid uniform)."""
    grid_h, grid_w = msg_p.shape[1], msg_p.shape[2]
    for y in range(r0, r1):
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


@njit(nogil=True, cache=True, error_model="numpy")
def _unpack_messages(packed, y0, x0, h, w, act, use_act, out, r0, r1):
    """Odds planes back into probability messages ``out[4, y0 + y, x0 + x]``; with ``use_act`` only the slots of
    active senders (the others did not change, and a round trip through odds would perturb them by rounding)."""
    for y in range(r0, r1):
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


@njit(nogil=True, cache=True, error_model="numpy")
def _beliefs_packed(un, packed, h, w, out, r0, r1):
    """P(occupied) of every cell of the block: observation odds times its four message odds."""
    for y in range(r0, r1):
        _beliefs_row(un, packed, y, w, out)


# not inlined, and no fastmath: the fused beliefs of the last pass (crf.engine._message_update) call this same
# compiled row, so they are bit for bit these (inlined, the caller's contract flag could fuse 1 + b into an FMA)
@njit(nogil=True, cache=True, error_model="numpy")
def _beliefs_row(un, packed, y, w, out):
    """P(occupied) of the cells of row y: observation odds times its four message odds."""
    ce = y & 1  # colour of the even columns; cells 2m and 2m + 1 both sit at plane index m + 1
    co = 1 - ce
    for m in range(w >> 1):  # unit-stride reads of both planes, pairs of adjacent writes
        k = m + 1
        b = float(un[ce, y + 1, k]) * float(packed[ce, 0, y + 1, k]) * float(packed[ce, 1, y + 1, k])
        b = b * float(packed[ce, 2, y + 1, k]) * float(packed[ce, 3, y + 1, k])
        out[y, 2 * m] = b / (1.0 + b)
        b = float(un[co, y + 1, k]) * float(packed[co, 0, y + 1, k]) * float(packed[co, 1, y + 1, k])
        b = b * float(packed[co, 2, y + 1, k]) * float(packed[co, 3, y + 1, k])
        out[y, 2 * m + 1] = b / (1.0 + b)
    if w & 1:
        k = (w >> 1) + 1
        b = float(un[ce, y + 1, k]) * float(packed[ce, 0, y + 1, k]) * float(packed[ce, 1, y + 1, k])
        b = b * float(packed[ce, 2, y + 1, k]) * float(packed[ce, 3, y + 1, k])
        out[y, w - 1] = b / (1.0 + b)


@njit(cache=True, error_model="numpy")
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


@njit(nogil=True, cache=True, error_model="numpy")
def _fill_ones(rows, r0, r1):
    """rows[r0:r1, :] = 1 (``rows``: planes seen as rows; on threads, so each first touches its share of fresh memory)."""
    for i in range(r0, r1):
        rows[i, :] = 1


@njit(nogil=True, cache=True, error_model="numpy")
def _pack_clamped(state, implied_odds, msg, act, r0, r1):
    """Cells with ``state`` >= 0 (certain) stop sending (``act`` 0) and their four messages become
    ``implied_odds[d, state]``; the others send (``act`` 1). Whole grid, as :func:`crfmap.crf.model.evidence.clamp_messages`."""
    h, w = state.shape
    for y in range(r0, r1):
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


@njit(nogil=True, cache=True, error_model="numpy")
def _pack_mask(mask, y0, x0, h, w, out, r0, r1):
    for y in range(r0, r1):
        for x in range(w):
            out[(x + y) & 1, y + 1, (x >> 1) + 1] = 1 if mask[y0 + y, x0 + x] else 0


@njit(inline="always", cache=True, error_model="numpy")
def _start_row(prob, y, link, floor, co, fu, un):
    """Row y's observation odds into ``un``; returns (cells outside [0, 1] or not finite, cells the link makes
    certain), counted in the same loop."""
    w = prob.shape[1]
    wp = un.shape[2]
    one = co[8]
    bad = 0
    certain = 0
    for x in range(w):
        p = prob[y, x]
        bad += np.int64(not ((p >= 0.0) & (p <= 1.0)))  # NaN fails both; & (not and): no branches
        occ = link[0] * p + link[1] * (1.0 - p)
        emp = link[2] * p + link[3] * (1.0 - p)
        certain += np.int64(((emp == 0.0) & (occ > 0.0)) | ((occ == 0.0) & (emp > 0.0)))
        fu[x] = _odds(occ, emp, floor)
    # cells 2m and 2m + 1 sit at plane index m + 1 of colours ce and 1 - ce: one unit-stride loop over the pairs
    # (a loop per colour reading every other odds vectorised poorly)
    ce = y & 1
    cq = 1 - ce
    for m in range(w >> 1):
        un[ce, y + 1, m + 1] = fu[2 * m]
        un[cq, y + 1, m + 1] = fu[2 * m + 1]
    if w & 1:
        un[ce, y + 1, (w >> 1) + 1] = fu[w - 1]
    for c in range(2):
        un[c, y + 1, 0] = one
        for k in range(((w - ((y + c) & 1) + 1) >> 1) + 1, wp):
            un[c, y + 1, k] = one
    return bad, certain


@njit(nogil=True, cache=True, error_model="numpy")  # no fastmath: the grid check must see NaN
def _pack_start(prob, link, floor, co, un, msg, stats, b):
    """Row block ``b`` of ``stats.shape[0]`` (independent: threads may run them at once) of a whole grid from uniform
    messages: observation odds into ``un`` and, of the message slots, only those no neighbour ever sends into and the
    ghost rows (1); the first pass (``uniform_start``) writes every other slot before anything reads it. Counts into
    ``stats[b]``: cells outside [0, 1] or not finite, and cells the link makes certain (hard evidence)."""
    h, w = prob.shape
    wp = un.shape[2]
    nblocks = stats.shape[0]
    one = co[8]
    r0 = b * h // nblocks
    r1 = (b + 1) * h // nblocks
    fu = np.empty(w, un.dtype)  # one row of observation odds
    bad = 0
    certain = 0
    for y in range(r0, r1):
        nb, nc = _start_row(prob, y, link, floor, co, fu, un)
        bad += nb
        certain += nc
        for c in range(2):  # slots no neighbour sends into: x = 0 (west), x = w - 1 (east), rows 0 and h - 1
            if (y + c) & 1 == 0:
                msg[c, 0, y + 1, 1] = one
            if (w - 1 + y + c) & 1 == 0:
                msg[c, 1, y + 1, (w - 1) // 2 + 1] = one
            if y == 0:
                for k in range(wp):
                    msg[c, 2, 1, k] = one
            if y == h - 1:
                for k in range(wp):
                    msg[c, 3, h, k] = one
    stats[b, 0] = bad
    stats[b, 1] = certain
    if b == 0:  # the ghost rows
        for c in range(2):
            for k in range(wp):
                un[c, 0, k] = one
                un[c, h + 1, k] = one
                for d in range(4):
                    msg[c, d, 0, k] = one
                    msg[c, d, h + 1, k] = one
