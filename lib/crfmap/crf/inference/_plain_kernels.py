"""The plain schedules' message updates: numba kernels of LBP on a 4-connected binary lattice (private).

``unary[y, x]``: the floored P(occupied) the observed layer tells each hidden cell; ``msg``: the layout of
:mod:`crfmap.crf.engine.messages`; ``coef[d]``: :func:`crfmap.crf.model.potentials.message_coefficients`, one
division an update; ``active[y, x]``: cells allowed to send (``use_active`` False ignores it). Every kernel returns
the largest change of any message it wrote."""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(inline="always")
def _message(u, ma, mb, mc, c0, c1, c2, c3, floor, damping, old):
    a = u * ma * mb * mc
    b = (1.0 - u) * (1.0 - ma) * (1.0 - mb) * (1.0 - mc)
    m = (c0 * a + c1 * b) / (c2 * a + c3 * b)
    if damping > 0.0:
        m = (1.0 - damping) * m + damping * old
    if m < floor:
        m = floor
    elif m > 1.0 - floor:
        m = 1.0 - floor
    return m


@njit(inline="always")
def _send_all(y, x, unary, src, dst, coef, floor, damping):
    """Write all four messages cell (y, x) sends (read from ``src``, written to ``dst``); return max change."""
    h, w = unary.shape
    u = unary[y, x]
    m0 = src[0, y, x]
    m1 = src[1, y, x]
    m2 = src[2, y, x]
    m3 = src[3, y, x]
    change = 0.0
    if x + 1 < w:
        old = src[0, y, x + 1]
        m = _message(u, m0, m2, m3, coef[0, 0], coef[0, 1], coef[0, 2], coef[0, 3], floor, damping, old)
        dst[0, y, x + 1] = m
        change = max(change, abs(m - old))
    if x > 0:
        old = src[1, y, x - 1]
        m = _message(u, m1, m2, m3, coef[1, 0], coef[1, 1], coef[1, 2], coef[1, 3], floor, damping, old)
        dst[1, y, x - 1] = m
        change = max(change, abs(m - old))
    if y + 1 < h:
        old = src[2, y + 1, x]
        m = _message(u, m0, m1, m2, coef[2, 0], coef[2, 1], coef[2, 2], coef[2, 3], floor, damping, old)
        dst[2, y + 1, x] = m
        change = max(change, abs(m - old))
    if y > 0:
        old = src[3, y - 1, x]
        m = _message(u, m0, m1, m3, coef[3, 0], coef[3, 1], coef[3, 2], coef[3, 3], floor, damping, old)
        dst[3, y - 1, x] = m
        change = max(change, abs(m - old))
    return change


# Kernels over a band of rows (or columns) take it as [r0, r1) last and release the GIL, for over_rows.


@njit(nogil=True, cache=True)
def _send_rows(unary, msg, dst, coef, active, use_active, parity, y0, floor, damping, r0, r1):
    """Cells of rows [y0 + r0, y0 + r1) send from ``msg`` into ``dst``: those with (x + y) % 2 == parity
    (a checkerboard half, ``dst`` is ``msg``: in place, race-free as a half only reads the other
    half's slots), or every cell with ``parity`` -1 (flooding: ``dst`` a second array, synchronous)."""
    w = unary.shape[1]
    step = 1 if parity < 0 else 2
    c = 0.0
    for y in range(y0 + r0, y0 + r1):
        for x in range(0 if parity < 0 else (parity + y) & 1, w, step):
            if use_active and not active[y, x]:
                continue
            c = max(c, _send_all(y, x, unary, msg, dst, coef, floor, damping))
    return c


@njit(nogil=True, cache=True)
def _sweep_along_rows(unary, msg, coef, active, use_active, d, y0, floor, damping, r0, r1):
    """The east-bound (d = 0) or west-bound (d = 1) sweep of rows [y0 + r0, y0 + r1), each row in order along d
    (rows are independent: a row's messages of direction d depend only on that row's)."""
    w = unary.shape[1]
    change = 0.0
    for y in range(y0 + r0, y0 + r1):
        for i in range(w - 1):
            x = i if d == 0 else w - 1 - i
            if use_active and not active[y, x]:
                continue
            to = x + 1 if d == 0 else x - 1
            old = msg[d, y, to]
            m = _message(unary[y, x], msg[d, y, x], msg[2, y, x], msg[3, y, x],
                         coef[d, 0], coef[d, 1], coef[d, 2], coef[d, 3], floor, damping, old)
            msg[d, y, to] = m
            change = max(change, abs(m - old))
    return change


@njit(nogil=True, cache=True)
def _sweep_along_columns(unary, msg, coef, active, use_active, d, y0, y1, floor, damping, r0, r1):
    """The north-bound (d = 2) or south-bound (d = 3) sweep of columns [r0, r1), rows of [y0, y1) in order along d."""
    h = unary.shape[0]
    change = 0.0
    if d == 2:
        start, stop, step = max(y0, 0), min(y1, h - 1), 1
    else:
        start, stop, step = min(y1, h) - 1, max(y0, 1) - 1, -1
    for y in range(start, stop, step):
        to = y + step
        for x in range(r0, r1):
            if use_active and not active[y, x]:
                continue
            old = msg[d, to, x]
            m = _message(unary[y, x], msg[0, y, x], msg[1, y, x], msg[d, y, x],
                         coef[d, 0], coef[d, 1], coef[d, 2], coef[d, 3], floor, damping, old)
            msg[d, to, x] = m
            change = max(change, abs(m - old))
    return change


@njit(cache=True)
def _pull_iteration(unary, msg, coef, active, use_active, order, floor, damping):
    """The thesis's schedule (Listing 5): visit cells in ``order``; at each, recompute the
    messages its neighbours send it from their current state, in place."""
    h, w = unary.shape
    change = 0.0
    for k in range(order.shape[0]):
        idx = order[k]
        y = idx // w
        x = idx - y * w
        # from the west neighbour (travelling east, slot 0 here)
        if x > 0 and (not use_active or active[y, x - 1]):
            old = msg[0, y, x]
            m = _message(unary[y, x - 1], msg[0, y, x - 1], msg[2, y, x - 1], msg[3, y, x - 1],
                         coef[0, 0], coef[0, 1], coef[0, 2], coef[0, 3], floor, damping, old)
            msg[0, y, x] = m
            change = max(change, abs(m - old))
        # from the east neighbour (travelling west, slot 1)
        if x + 1 < w and (not use_active or active[y, x + 1]):
            old = msg[1, y, x]
            m = _message(unary[y, x + 1], msg[1, y, x + 1], msg[2, y, x + 1], msg[3, y, x + 1],
                         coef[1, 0], coef[1, 1], coef[1, 2], coef[1, 3], floor, damping, old)
            msg[1, y, x] = m
            change = max(change, abs(m - old))
        # from the south neighbour (travelling north, slot 2)
        if y > 0 and (not use_active or active[y - 1, x]):
            old = msg[2, y, x]
            m = _message(unary[y - 1, x], msg[0, y - 1, x], msg[1, y - 1, x], msg[2, y - 1, x],
                         coef[2, 0], coef[2, 1], coef[2, 2], coef[2, 3], floor, damping, old)
            msg[2, y, x] = m
            change = max(change, abs(m - old))
        # from the north neighbour (travelling south, slot 3)
        if y + 1 < h and (not use_active or active[y + 1, x]):
            old = msg[3, y, x]
            m = _message(unary[y + 1, x], msg[0, y + 1, x], msg[1, y + 1, x], msg[3, y + 1, x],
                         coef[3, 0], coef[3, 1], coef[3, 2], coef[3, 3], floor, damping, old)
            msg[3, y, x] = m
            change = max(change, abs(m - old))
    return change


@njit(cache=True)
def _bfs_order(h, w, active, use_active, start_y, start_x):
    """Breadth-first order of cells from a start cell over 4-neighbours (within ``active``)."""
    seen = np.zeros((h, w), np.bool_)
    order = np.empty(h * w, np.int64)
    head = 0
    tail = 0
    if use_active and not active[start_y, start_x]:
        return order[:0]
    order[tail] = start_y * w + start_x
    tail += 1
    seen[start_y, start_x] = True
    while head < tail:
        idx = order[head]
        head += 1
        y = idx // w
        x = idx - y * w
        for k in range(4):
            ny, nx = y, x
            if k == 0:
                nx = x + 1
            elif k == 1:
                ny = y + 1
            elif k == 2:
                nx = x - 1
            else:
                ny = y - 1
            if ny < 0 or nx < 0 or ny >= h or nx >= w or seen[ny, nx]:
                continue
            if use_active and not active[ny, nx]:
                continue
            seen[ny, nx] = True
            order[tail] = ny * w + nx
            tail += 1
    return order[:tail]
