"""Hard evidence: the cells whose state is certain, the messages they send, and contradictions.

An observed P(occupied) of exactly 0 or 1 makes its hidden cell certain when the link gives the other hidden state
zero weight (identity link: P in {0, 1}); a link with no zero entry, or a P inside (0, 1), never does. A certain
cell's exact marginal is its state whatever its neighbours are, so :func:`crfmap.crf.inference.lbp.infer` *clamps*
it: its belief is exactly its state and it sends, every iteration, the message that state implies (the table's
column for it, normalised); it is never updated, so no floor lets neighbours overturn it.

A hidden table with a zero entry carries certainty on: if column ``t[:, s]`` has one zero, the neighbour of a cell
certain in state ``s`` is certain too (unit propagation; exact). Certainties that disagree, or a certain state whose
column is all zero, leave no joint state of positive weight: :class:`InputError` naming the cell. A state whose
column is all zero towards an existing neighbour is impossible. On a chain this is arc consistency, which finds
every certain cell and contradiction; on a loopy grid it may miss some (then the floors keep LBP finite).

>>> import numpy as np
>>> from crfmap.crf.model.potentials import directional_tables
>>> certain_states(np.array([[1.0, 0.5, 0.0]]), [[1, 0], [0, 1]], directional_tables([[10, 1], [1, 10]])).tolist()
[[1, -1, 0]]
"""
from __future__ import annotations

import numpy as np
from numba import njit

from crfmap.crf.threads import over_rows
from crfmap.errors import InputError

UNCERTAIN = -1  # state of a cell that is not certain (1 certainly occupied, 0 certainly empty)

# (dy, dx) of the neighbour each message direction reaches: east, west, north (+y), south (-y)
_STEPS = np.array([[0, 1], [0, -1], [1, 0], [-1, 0]], np.int64)


@njit(nogil=True, cache=True)
def _certain_from_observations(prob, link, out, write, r0, r1):
    """How many cells of rows [r0, r1) the link makes certain; with ``write``, their state into ``out`` (1 / 0
    certainly occupied / empty, UNCERTAIN elsewhere)."""
    w = prob.shape[1]
    n = 0
    for y in range(r0, r1):
        for x in range(w):
            p = prob[y, x]
            occ = link[0] * p + link[1] * (1.0 - p)
            emp = link[2] * p + link[3] * (1.0 - p)
            s = -1
            if emp == 0.0 and occ > 0.0:
                s = 1
            elif occ == 0.0 and emp > 0.0:
                s = 0
            if write:
                out[y, x] = s
            n += s >= 0
    return n


@njit(cache=True)
def _doubled(stack, top):
    """``stack`` copied into one twice its size (a loop: a slice assignment's shape check compiles for seconds)."""
    grown = np.empty(2 * top, np.int64)
    for k in range(top):
        grown[k] = stack[k]
    return grown


@njit(cache=True)
def _propagate(state, forced, senders, use_senders, steps):
    """Unit propagation of certainty through hidden tables with zeros (depth first, in place; ``forced``:
    :func:`forced_states`): (flat index of a contradicting cell, of the certain neighbour forcing it) or (-1, -1)."""
    h, w = state.shape
    stack = np.empty(1024, np.int64)
    top = 0
    for i in range(h * w):
        y, x = i // w, i % w
        if not use_senders or senders[y, x]:
            possible = 3  # bit s: state s is possible
            for d in range(4):
                ny, nx = y + steps[d, 0], x + steps[d, 1]
                if 0 <= ny < h and 0 <= nx < w:
                    for s in range(2):
                        if forced[d, s] == -2:
                            possible &= ~(1 << s)
            if possible == 0 or (state[y, x] >= 0 and not (possible >> state[y, x]) & 1):
                return i, -1
            if possible != 3:
                state[y, x] = possible >> 1  # 1 (only occupied possible) or 0
        if state[y, x] >= 0:
            if top == stack.shape[0]:
                stack = _doubled(stack, top)
            stack[top] = i
            top += 1
    while top > 0:
        top -= 1
        i = stack[top]
        y, x = i // w, i % w
        if use_senders and not senders[y, x]:
            continue
        s = state[y, x]
        for d in range(4):
            ny, nx = y + steps[d, 0], x + steps[d, 1]
            if ny < 0 or ny >= h or nx < 0 or nx >= w:
                continue
            f = forced[d, s]
            if f == -2:
                return i, -1
            if f < 0:
                continue
            r = state[ny, nx]
            if r == f:
                continue
            if r >= 0:
                return ny * w + nx, i
            state[ny, nx] = f
            if top == stack.shape[0]:
                stack = _doubled(stack, top)
            stack[top] = ny * w + nx
            top += 1
    return -1, -1


@njit(nogil=True, cache=True)
def _send_clamped(state, senders, use_senders, implied, steps, msg, r0, r1):
    """Write into ``msg`` (layout of :mod:`crfmap.crf.engine.messages`) the messages every certain sender implies."""
    h, w = state.shape
    for y in range(r0, r1):
        for x in range(w):
            s = state[y, x]
            if s < 0 or (use_senders and not senders[y, x]):
                continue
            for d in range(4):
                ny, nx = y + steps[d, 0], x + steps[d, 1]
                if 0 <= ny < h and 0 <= nx < w:
                    msg[d, ny, nx] = implied[d, s]


@njit(nogil=True, cache=True)
def _set_beliefs(state, beliefs, r0, r1):
    w = state.shape[1]
    for y in range(r0, r1):
        for x in range(w):
            if state[y, x] >= 0:
                beliefs[y, x] = state[y, x]


def _column(table, s):
    """(P(receiver occupied) of the message from a sender in state s, weight of both receiver states)."""
    col = np.asarray(table, np.float64)[:, 0 if s == 1 else 1]  # rows receiver, columns sender: index 0 occupied
    total = col.sum()
    return (col[0] / total if total > 0 else 0.5), col


def implied_messages(tables) -> np.ndarray:
    """``implied[d, s]``: P(receiver occupied) of the message a cell certain in state s sends in direction d."""
    return np.array([[_column(t, s)[0] for s in (0, 1)] for t in np.asarray(tables)], np.float64)


def forced_states(tables) -> np.ndarray:
    """``forced[d, s]``: the state the receiver must take (UNCERTAIN if none, -2 if the sender's state is impossible)."""
    out = np.full((4, 2), UNCERTAIN, np.int64)
    for d, t in enumerate(np.asarray(tables)):
        for s in (0, 1):
            col = _column(t, s)[1]
            if col[0] == 0 and col[1] == 0:
                out[d, s] = -2
            elif col[0] == 0:
                out[d, s] = 0
            elif col[1] == 0:
                out[d, s] = 1
    return out


def certain_states(probability, link, tables, senders=None, name="grid"):
    """Per cell 1 (certainly occupied), 0 (certainly empty) or UNCERTAIN (-1), as int8 [y, x]; None if none is certain.

    ``tables``: the four directional tables; certainty spreads only from ``senders`` (a boolean mask, None: all).
    Contradictory hard evidence raises :class:`InputError` naming ``name`` and the cell."""
    prob = np.ascontiguousarray(probability, dtype=np.float64)
    link = np.asarray(link, np.float64).ravel()
    forced = forced_states(tables)
    if not np.any(forced == -2) and sum(over_rows(_certain_from_observations, prob.shape[0], prob, link,
                                                  np.empty((1, 1), np.int8), False)) == 0:
        return None  # the common case: no state array (a full-size write into fresh memory)
    state = np.empty(prob.shape, np.int8)
    n = sum(over_rows(_certain_from_observations, prob.shape[0], prob, link, state, True))
    if np.any(forced != UNCERTAIN):
        use = senders is not None
        mask = np.ascontiguousarray(senders, dtype=np.bool_) if use else np.ones((1, 1), np.bool_)
        bad, by = _propagate(state, forced, mask, use, _STEPS)
        if bad >= 0:
            y, x = divmod(int(bad), prob.shape[1])
            why = "the state it must have is impossible next to its neighbours under the hidden table"
            if by >= 0:
                ny, nx = divmod(int(by), prob.shape[1])
                why = (f"certain neighbour (x={nx}, y={ny}) forces it {'empty' if state[y, x] == 1 else 'occupied'} "
                       f"through the hidden table's zero entries, but it is certainly "
                       f"{'occupied' if state[y, x] == 1 else 'empty'}")
            raise InputError(name, f"contradictory hard evidence (cells with P exactly 0 or 1, or a hidden table "
                             f"with zero entries) at cell (x={x}, y={y}): " + why)
    if n == 0 and not (state >= 0).any():
        return None
    return state


def clamp_messages(state, tables, msg, senders=None):
    """Set the messages every certain cell in ``senders`` (None: all) sends to the ones its state implies."""
    use = senders is not None
    mask = np.ascontiguousarray(senders, dtype=np.bool_) if use else np.ones((1, 1), np.bool_)
    over_rows(_send_clamped, state.shape[0], state, mask, use, implied_messages(tables).astype(msg.dtype), _STEPS, msg)
    return msg


def clamp_beliefs(state, beliefs):
    """Certain cells' beliefs become exactly their state (in place)."""
    over_rows(_set_beliefs, state.shape[0], state, beliefs)
    return beliefs
