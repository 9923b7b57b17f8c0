"""The message update of the fast engine: checkerboard LBP kernels on odds-ratio red/black planes (private).

A cell's four messages are :func:`_four`, a row of one colour sends in :func:`_send`, and a pass of several
iterations is :func:`_pass` (:func:`_trapezoid` on every band of rows, then the inverted ones between bands), the only
kernel Python calls to iterate. Same schedule and fixed point as :func:`crfmap.crf.inference._plain_kernels._send_rows`
(cells with (x + y) even send, then the others), laid out for SIMD and for cache:

- **Odds, not probabilities.** A binary message is one odds ratio r = P/(1-P). A sender's cavity odds are ``R = U *
  r_a * r_b * r_c`` (U the observation's odds) and the message through a table t (rows receiver, columns sender) is
  ``r' = (t00 R + t01) / (t10 R + t11)``: half the multiplies of the probability form, and one division.
- **Red/black planes.** ``msg[c, d, 1 + y, 1 + k]`` is slot d (as in :mod:`crfmap.crf.engine.messages`) of the cell
  in row y with colour c = (x + y) & 1 and x = 2k + ((y + c) & 1): a colour's cells are contiguous, so a half-sweep
  is a unit-stride loop that vectorises. Rows 0 and H + 1 and the first and last columns are ghosts that absorb
  messages sent off the grid.
- **Temporal blocking.** A *pass* runs T iterations (2T half-sweeps, "phases") over bands of rows: every band runs a
  trapezoid that shrinks by one row per phase at each inner edge (a wavefront, so only ~2T + 2 rows are live, in
  cache), then the inverted trapezoids between bands finish. Every (phase, row) is computed once, after the three
  rows it depends on, so a pass equals T plain iterations.
- **Measured changes.** A message's change in probability, ``|r' - r| / ((1 + r)(1 + r'))``, costs four more
  divisions, so it is measured only on the iterations asked for (by default the last of each pass).

``act`` (bounded LBP) holds 1 where a cell may send; ``lo_k, hi_k`` bound the plane indices of each row's active
cells so a small region costs little. The arrays and the Python driver live in :mod:`crfmap.crf.engine.packed`."""
from __future__ import annotations

import numpy as np
from numba import njit, prange, types
from numba.extending import overload

from crfmap.crf.engine._layout import _beliefs_row

FASTMATH = {"nnan", "ninf", "nsz", "contract"}  # no NaN/inf ever occur (floors); lets min/max vectorise
# ``act`` of a pass in which every cell may send: its dtype (bool, where a mask is uint8) tells the kernels at
# compile time, so a first call compiles the row loops of its case only (whole grid or bounded), not all five
NO_MASK = np.zeros((2, 1, 1), np.bool_)


def _masked(act):
    """Whether ``act`` is a mask (uint8) rather than :data:`NO_MASK` (bool); a constant where compiled."""
    return act.dtype == np.uint8


def _is_mask_type(act) -> bool:
    """Whether numba type ``act`` is that of a mask (uint8 array), not of :data:`NO_MASK`."""
    return isinstance(act, types.Array) and act.dtype == types.uint8


@overload(_masked, inline="always")
def _masked_compiled(act):
    return (lambda act: True) if _is_mask_type(act) else (lambda act: False)


# --- one cell, the four messages -------------------------------------------------------------


@njit(inline="always", cache=True, fastmath=FASTMATH, error_model="numpy")
def _four_unclamped(U, r0, r1, r2, r3, a0, a1, a2, a3, b0, b1, b2, b3):
    """Odds of the messages a cell sends east, west, north, south (tables a: E/N, b: W/S), unclamped: as is for
    tables whose messages cannot leave [lo, hi] (all entries positive)."""
    p = U * r2 * r3
    q = U * r0 * r1
    R = p * r0
    mE = (a0 * R + a1) / (a2 * R + a3)
    R = p * r1
    mW = (b0 * R + b1) / (b2 * R + b3)
    R = q * r2
    mN = (a0 * R + a1) / (a2 * R + a3)
    R = q * r3
    mS = (b0 * R + b1) / (b2 * R + b3)
    return mE, mW, mN, mS


@njit(inline="always", cache=True, fastmath=FASTMATH, error_model="numpy")
def _four(U, r0, r1, r2, r3, a0, a1, a2, a3, b0, b1, b2, b3, lo, hi):
    """Odds of the messages a cell sends east, west, north, south (tables a: E/N, b: W/S), kept in [lo, hi]."""
    mE, mW, mN, mS = _four_unclamped(U, r0, r1, r2, r3, a0, a1, a2, a3, b0, b1, b2, b3)
    return (min(max(mE, lo), hi), min(max(mW, lo), hi), min(max(mN, lo), hi), min(max(mS, lo), hi))


@njit(inline="always", cache=True, fastmath=FASTMATH, error_model="numpy")
def _dp(new, old, one):
    """|P(new) - P(old)| of two odds."""
    return abs(new - old) / ((one + old) * (one + new))


# --- one row of one colour ---------------------------------------------------------------------


def _send(msg, un, act, c, y, k0, n, co, lo, hi, measure, w_n, w_s, cb, ty):
    """Cells k0 <= k < k0 + n of colour c in row y send (all have east and west neighbours). With ``measure`` the
    largest change per column is max-accumulated into ``cb[ty]``; ``w_n``, ``w_s`` (1 or 0) drop the north/south
    message of the top/bottom row, which goes nowhere. Unsigned indices and no slices keep the loops vectorised.
    Compiled, ``act``'s type picks the rows (:func:`_send_compiled`); this is that choice in plain Python."""
    send = _send_masked if _masked(act) else _send_whole
    send(msg, un, act, c, y, k0, n, co, lo, hi, measure, w_n, w_s, cb, ty)


# inlined, as the row loop always was: called once per segment instead, bounded LBP on a real map ran ~25% slower
@overload(_send, inline="always")
def _send_compiled(msg, un, act, c, y, k0, n, co, lo, hi, measure, w_n, w_s, cb, ty):
    # chosen while typing: a pass compiles (and a first call waits for) the row loops of its case only
    return _send_masked if _is_mask_type(act) else _send_whole


@njit(inline="always", cache=True)
def _sent(msg, o, y, y1, j, east, west, mE, mW, mN, mS):
    """A cell at plane index j of stored row y1 = y + 1 has sent: its messages into the slots of its east and west
    neighbours (plane indices ``east``, ``west`` in the other colour ``o``) and of those in the rows above and below."""
    msg[o, 0, y1, east] = mE
    msg[o, 1, y1, west] = mW
    msg[o, 2, y1 + 1, j] = mN
    msg[o, 3, y, j] = mS


@njit(inline="always", cache=True)
def _row_columns(c, y, k0):
    """(the other colour, the stored row, the stored column of cell k0 (column 0 is a ghost), its east and its
    west neighbour's column in the other plane) of a row's cells from k0 on."""
    j0 = np.uint64(k0 + 1)
    e0 = j0 + np.uint64((y + c) & 1)
    return 1 - c, y + 1, j0, e0, e0 - np.uint64(1)


def _send_whole(msg, un, act, c, y, k0, n, co, lo, hi, measure, w_n, w_s, cb, ty):
    """:func:`_send` where every cell may send."""
    o, y1, j0, e0, w0 = _row_columns(c, y, k0)
    a0, a1, a2, a3 = co[0], co[1], co[2], co[3]
    b0, b1, b2, b3 = co[4], co[5], co[6], co[7]
    one = co[8]
    zero = one - one
    if not measure and co[9] == zero:
        # the hot loop: a table with positive entries never sends a message outside [lo, hi]
        for i in range(n):
            ui = np.uint64(i)
            j = j0 + ui
            mE, mW, mN, mS = _four_unclamped(un[c, y1, j], msg[c, 0, y1, j], msg[c, 1, y1, j], msg[c, 2, y1, j],
                                             msg[c, 3, y1, j], a0, a1, a2, a3, b0, b1, b2, b3)
            _sent(msg, o, y, y1, j, e0 + ui, w0 + ui, mE, mW, mN, mS)
    elif not measure:
        for i in range(n):
            ui = np.uint64(i)
            j = j0 + ui
            mE, mW, mN, mS = _four(un[c, y1, j], msg[c, 0, y1, j], msg[c, 1, y1, j], msg[c, 2, y1, j],
                                   msg[c, 3, y1, j], a0, a1, a2, a3, b0, b1, b2, b3, lo, hi)
            _sent(msg, o, y, y1, j, e0 + ui, w0 + ui, mE, mW, mN, mS)
    else:
        for i in range(n):
            ui = np.uint64(i)
            j = j0 + ui
            mE, mW, mN, mS = _four(un[c, y1, j], msg[c, 0, y1, j], msg[c, 1, y1, j], msg[c, 2, y1, j],
                                   msg[c, 3, y1, j], a0, a1, a2, a3, b0, b1, b2, b3, lo, hi)
            d = _dp(mE, msg[o, 0, y1, e0 + ui], one)
            msg[o, 0, y1, e0 + ui] = mE
            d = max(d, _dp(mW, msg[o, 1, y1, w0 + ui], one))
            msg[o, 1, y1, w0 + ui] = mW
            d = max(d, w_n * _dp(mN, msg[o, 2, y1 + 1, j], one))
            msg[o, 2, y1 + 1, j] = mN
            d = max(d, w_s * _dp(mS, msg[o, 3, y, j], one))
            msg[o, 3, y, j] = mS
            cc = cb[ty, j]
            cb[ty, j] = cc + max(d - cc, zero)  # max(cc, d) without a masked store (slow on AMD)


def _send_masked(msg, un, act, c, y, k0, n, co, lo, hi, measure, w_n, w_s, cb, ty):
    """:func:`_send` in bounded LBP: only cells with ``act`` 1 send, the others' messages keep their values."""
    o, y1, j0, e0, w0 = _row_columns(c, y, k0)
    a0, a1, a2, a3 = co[0], co[1], co[2], co[3]
    b0, b1, b2, b3 = co[4], co[5], co[6], co[7]
    one = co[8]
    zero = one - one
    if not measure:  # apart from the measured loop, every old message loaded first: only so does it vectorise
        # (a select with a load of the old value, or one helper shared with the loop below, ran far slower)
        for i in range(n):
            ui = np.uint64(i)
            j = j0 + ui
            mE, mW, mN, mS = _four(un[c, y1, j], msg[c, 0, y1, j], msg[c, 1, y1, j], msg[c, 2, y1, j],
                                   msg[c, 3, y1, j], a0, a1, a2, a3, b0, b1, b2, b3, lo, hi)
            on = act[c, y1, j] != 0
            oE = msg[o, 0, y1, e0 + ui]
            oW = msg[o, 1, y1, w0 + ui]
            oN = msg[o, 2, y1 + 1, j]
            oS = msg[o, 3, y, j]
            msg[o, 0, y1, e0 + ui] = mE if on else oE
            msg[o, 1, y1, w0 + ui] = mW if on else oW
            msg[o, 2, y1 + 1, j] = mN if on else oN
            msg[o, 3, y, j] = mS if on else oS
    else:
        for i in range(n):
            ui = np.uint64(i)
            j = j0 + ui
            mE, mW, mN, mS = _four(un[c, y1, j], msg[c, 0, y1, j], msg[c, 1, y1, j], msg[c, 2, y1, j],
                                   msg[c, 3, y1, j], a0, a1, a2, a3, b0, b1, b2, b3, lo, hi)
            on = act[c, y1, j] != 0
            oE = msg[o, 0, y1, e0 + ui]
            oW = msg[o, 1, y1, w0 + ui]
            oN = msg[o, 2, y1 + 1, j]
            oS = msg[o, 3, y, j]
            mE = mE if on else oE
            mW = mW if on else oW
            mN = mN if on else oN
            mS = mS if on else oS
            _sent(msg, o, y, y1, j, e0 + ui, w0 + ui, mE, mW, mN, mS)
            d = max(max(_dp(mE, oE, one), _dp(mW, oW, one)),
                    max(w_n * _dp(mN, oN, one), w_s * _dp(mS, oS, one)))
            cc = cb[ty, j]
            cb[ty, j] = cc + max(d - cc, zero)


@njit(inline="always", cache=True, fastmath=FASTMATH, error_model="numpy")
def _uniform_row(msg, un, y, w, co, lo, hi):
    """The red cells of row y send from uniform incoming messages, without loading them: the first half-sweep of a
    whole-grid run from uniform messages (so the packing writes no message plane: one trip through memory fewer)."""
    o, y1, j0, e0, w0 = _row_columns(0, y, 0)
    a0, a1, a2, a3 = co[0], co[1], co[2], co[3]
    b0, b1, b2, b3 = co[4], co[5], co[6], co[7]
    one = co[8]
    zero = one - one
    n = (w - (y & 1) + 1) >> 1
    if co[9] == zero:  # as in _send_whole: a table with positive entries never leaves [lo, hi]
        for i in range(n):
            ui = np.uint64(i)
            j = j0 + ui
            mE, mW, mN, mS = _four_unclamped(un[0, y1, j], one, one, one, one, a0, a1, a2, a3, b0, b1, b2, b3)
            _sent(msg, o, y, y1, j, e0 + ui, w0 + ui, mE, mW, mN, mS)
    else:
        for i in range(n):
            ui = np.uint64(i)
            j = j0 + ui
            mE, mW, mN, mS = _four(un[0, y1, j], one, one, one, one, a0, a1, a2, a3, b0, b1, b2, b3, lo, hi)
            _sent(msg, o, y, y1, j, e0 + ui, w0 + ui, mE, mW, mN, mS)


@njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def _cell(msg, un, act, c, y, k, h, w, co, lo, hi):
    """One cell sends, whatever neighbours it has (grid edges); returns the largest change."""
    off = (y + c) & 1
    x = 2 * k + off
    o = 1 - c
    one = co[8]
    if _masked(act) and act[c, y + 1, k + 1] == 0:
        return one - one
    mE, mW, mN, mS = _four(un[c, y + 1, k + 1], msg[c, 0, y + 1, k + 1], msg[c, 1, y + 1, k + 1],
                           msg[c, 2, y + 1, k + 1], msg[c, 3, y + 1, k + 1],
                           co[0], co[1], co[2], co[3], co[4], co[5], co[6], co[7], lo, hi)
    d = one - one
    if x + 1 < w:
        d = max(d, _dp(mE, msg[o, 0, y + 1, k + off + 1], one))
        msg[o, 0, y + 1, k + off + 1] = mE
    if x > 0:
        d = max(d, _dp(mW, msg[o, 1, y + 1, k + off], one))
        msg[o, 1, y + 1, k + off] = mW
    if y + 1 < h:
        d = max(d, _dp(mN, msg[o, 2, y + 2, k + 1], one))
        msg[o, 2, y + 2, k + 1] = mN
    if y > 0:
        d = max(d, _dp(mS, msg[o, 3, y, k + 1], one))
        msg[o, 3, y, k + 1] = mS
    return d


@njit(inline="always", cache=True, fastmath=FASTMATH, error_model="numpy")
def _segment(msg, un, act, c, y, k0, k1, h, w, co, lo, hi, measure, cb, ty):
    """Cells k0 <= k < k1 of colour c in row y send; measured changes go to ``cb[ty, k + 1]``."""
    if k1 <= k0:
        return
    one = co[8]
    zero = one - one
    first, last, w_n, w_s = 0, 0, one, one  # unmeasured: messages sent off the grid land in ghost slots nobody reads
    if measure:
        # the change of a message sent off the grid must not count, so the cells at x = 0 (no west
        # neighbour) and x = w - 1 (no east neighbour) go one by one
        off = (y + c) & 1
        first = 1 if (off == 0 and k0 == 0) else 0
        last = 1 if 2 * (k1 - 1) + off == w - 1 else 0
        if first == 1:
            d = _cell(msg, un, act, c, y, k0, h, w, co, lo, hi)
            cb[ty, k0 + 1] = max(cb[ty, k0 + 1], d)
        if last == 1 and (k1 - 1 > k0 or first == 0):
            d = _cell(msg, un, act, c, y, k1 - 1, h, w, co, lo, hi)
            cb[ty, k1] = max(cb[ty, k1], d)
        w_n = one if y + 1 < h else zero
        w_s = one if y > 0 else zero
    n = k1 - last - (k0 + first)
    if n > 0:  # one call site: the row loops are inlined (and compiled) once
        _send(msg, un, act, c, y, k0 + first, n, co, lo, hi, measure, w_n, w_s, cb, ty)


@njit(inline="always", cache=True, fastmath=FASTMATH, error_model="numpy")
def _phase_row(msg, un, act, lo_k, hi_k, segs, nseg, tile_h, c, y, h, w, co, lo, hi, measure, cb):
    """Colour c of row y sends: the cells of the row's active segments (one row of a half-sweep)."""
    ty = y // tile_h
    off = (y + c) & 1
    for s in range(nseg[ty]):
        k0 = max((segs[ty, s, 0] - off + 1) >> 1, lo_k[c, y])
        k1 = min((segs[ty, s, 1] - off + 1) >> 1, hi_k[c, y])
        _segment(msg, un, act, c, y, k0, k1, h, w, co, lo, hi, measure, cb, ty)


# not inlined: both trapezoids call this one compiled loop of rows (inlining them twice doubled the compile time),
# once per wavefront step or gap phase (a call per row cost more). No branch on which trapezoid calls: LLVM would
# unswitch the loop on it, compiling the rows twice
@njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def _phase_rows(msg, un, act, lo_k, hi_k, segs, nseg, tile_h, h, w, co, lo, hi, measure_from, cb, count, j_from, dj,
                y_from, dy, y0, y1, ylo, yhi, uniform_start):
    """Phase j_from + t dj on row y_from + t dy for 0 <= t < count, rows kept in [y0, y1) shrunk by j at inner edges
    (edges at ``ylo`` / ``yhi`` do not shrink): one wavefront step of a band or one phase of a gap. With
    ``uniform_start`` phase 0 sends from uniform messages (:func:`_uniform_row`; whole grid, unmeasured)."""
    for t in range(count):
        j = j_from + t * dj
        y = y_from + t * dy
        lo_row = y0 + j if y0 > ylo else ylo
        hi_row = y1 - j if y1 < yhi else yhi
        if y < lo_row or y >= hi_row:
            continue
        if uniform_start and j == 0:
            _uniform_row(msg, un, y, w, co, lo, hi)
        else:
            _phase_row(msg, un, act, lo_k, hi_k, segs, nseg, tile_h, j & 1, y, h, w, co, lo, hi,
                       (j >> 1) >= measure_from, cb)


# --- passes ----------------------------------------------------------------------------------
# Rows are cut into tiles of tile_h rows; in each row tile, only the cells of the segments segs[ty, :nseg[ty]] (column
# ranges [x0, x1)) send: the others are frozen. Changes are max-accumulated per column into cb[row tile, :] (threads
# never share a row tile: band edges are multiples of tile_h) and give the largest change per tile.


@njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def _trapezoid(msg, un, act, lo_k, hi_k, segs, nseg, tile_h, h, w, co, lo, hi, y0, y1, ylo, yhi, phases, measure_from,
               cb, uniform_start, gap, bel, with_beliefs):
    """The trapezoid of the band on rows [y0, y1) (``gap`` False), or the inverted one around the band edge y1.

    Band: phase j covers the band's rows shrunk by j at inner edges (edges at ``ylo`` / ``yhi``, the first / last
    row with senders, do not shrink). At step s, phase j works on row s - j: the rows it needs were finished by phase
    j - 1 one step earlier, still in cache. Gap: phase j on rows [y1 - j, y1 + j), for 1 <= j < phases.

    ``with_beliefs`` (the whole grid sends): each row's beliefs go into ``bel`` once it and its two neighbours
    finished the last phase, while in cache: a band does rows [y0 + phases, y1 - phases) (from ylo / to yhi at the
    grid's edges), the gap the rows between, after its last phase."""
    blo = y0 + phases if y0 > ylo else ylo
    bhi = y1 - phases if y1 < yhi else yhi
    # one call site of the rows: each would hold its own compiled copy of them
    for u in range(1 if gap else y0, phases if gap else y1 + phases):
        y_from = max(y1 - u, ylo) if gap else u
        count = min(y1 + u, yhi) - y_from if gap else phases
        _phase_rows(msg, un, act, lo_k, hi_k, segs, nseg, tile_h, h, w, co, lo, hi, measure_from, cb, count,
                    u if gap else 0, 0 if gap else 1, y_from, 1 if gap else -1,
                    ylo if gap else y0, yhi if gap else y1, ylo, yhi, uniform_start)
        if with_beliefs and not gap and blo <= u - phases < bhi:
            _beliefs_row(un, msg, u - phases, w, bel)
    if with_beliefs and gap:
        for y in range(max(y1 - phases, ylo), min(y1 + phases, yhi)):
            _beliefs_row(un, msg, y, w, bel)


# a parfor even for one band on one thread: numba compiles the trapezoids' code inside its parallel region to run
# faster than the same functions called directly; one parallel loop for both stages: a shorter compile
@njit(parallel=True, cache=True, fastmath=FASTMATH, error_model="numpy")
def _pass(msg, un, act, lo_k, hi_k, segs, nseg, tile_h, h, w, co, lo, hi, edges, iterations, measure_from, cb,
          uniform_start, stage, bel, with_beliefs):
    """Stage ``stage`` (0: every band's trapezoid, on numba's threads; 1: the inverted ones between bands) of
    ``iterations`` checkerboard iterations over the bands of rows between ``edges``; rows outside [edges[0], edges[-1])
    must hold no sender. Iterations from ``measure_from`` on are measured (max-accumulated into ``cb``);
    ``uniform_start``: the red cells' first half-sweep loads no message. ``with_beliefs`` (every cell sends): the
    beliefs after the pass into ``bel`` [h, w], row by row while in cache."""
    phases = 2 * iterations
    nb = edges.shape[0] - 1
    for b in prange(nb - stage):
        _trapezoid(msg, un, act, lo_k, hi_k, segs, nseg, tile_h, h, w, co, lo, hi, edges[b], edges[b + 1], edges[0],
                   edges[nb], phases, measure_from, cb, uniform_start, stage == 1, bel, with_beliefs)
    return 0


@njit(cache=True)
def _tile_max(cb, tile_w, w, out):
    """out[ty, tx] = largest change in tile (ty, tx), from the per-column maxima ``cb[ty, :]``."""
    for ty in range(out.shape[0]):
        for tx in range(out.shape[1]):
            k0 = (tx * tile_w) >> 1
            k1 = min(((tx + 1) * tile_w + 1) >> 1, (w + 1) >> 1)
            m = 0.0
            for k in range(k0, k1):
                v = cb[ty, k + 1]
                if v > m:
                    m = v
            out[ty, tx] = m
