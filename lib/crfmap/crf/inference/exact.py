"""Exact marginals of a small grid CRF by enumerating every joint state (the test reference).

Only for tiny grids (at most :data:`MAX_CELLS` cells): the work grows as 2**cells.
"""
from __future__ import annotations

import numpy as np

from crfmap.errors import InputError
from crfmap.grid import check_probability_array
from crfmap.crf.model.potentials import check_pairing, check_table, DEFAULT_HIDDEN, DEFAULT_LINK, is_symmetric, link_unary

MAX_CELLS = 22


def lattice_edges(shape, region=None):
    """Edges (a, b) of the 4-neighbour lattice as flat indices, a = west/south end.

    With ``region``, only edges whose both ends are in the mask.
    """
    h, w = shape
    idx = np.arange(h * w).reshape(h, w)
    horizontal = np.stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()], axis=1)
    vertical = np.stack([idx[:-1, :].ravel(), idx[1:, :].ravel()], axis=1)
    edges = np.concatenate([horizontal, vertical])
    if region is not None:
        mask = np.asarray(region, bool).ravel()
        edges = edges[mask[edges[:, 0]] & mask[edges[:, 1]]]
    return edges


def exact_marginals(observed, hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK, *, pairing="receiver", region=None) -> np.ndarray:
    """P(occupied) of every cell under the grid CRF, by brute force.

    The joint is ``prod_i phi_i(x_i) * prod_(a,b) hidden[x_a, x_b]`` over lattice edges
    (a = west/south end), with ``phi_i`` the observed node's message through ``link``.
    Under ``pairing="receiver"`` the table must be symmetric (otherwise no joint exists).
    With ``region``, only edges inside the mask are kept (cells outside stay independent).

    >>> exact_marginals(np.array([[0.8]])).round(3).tolist()
    [[0.8]]
    """
    p = check_probability_array(observed, "observed")
    hidden = check_table(hidden, "hidden")
    check_pairing(pairing)
    if pairing == "receiver" and not is_symmetric(hidden):
        raise InputError("hidden", "a non-symmetric table under the thesis's receiver pairing "
                         "defines no joint distribution; use pairing='oriented'")
    n = p.size
    if n > MAX_CELLS:
        raise InputError("observed", f"{n} cells is too many to enumerate (at most {MAX_CELLS})")
    u = link_unary(p, link).ravel()
    # states[s, i] = 1 if cell i is occupied in joint state s
    states = ((np.arange(2**n)[:, None] >> np.arange(n)[None, :]) & 1).astype(bool)
    with np.errstate(divide="ignore"):  # zero weights stay exactly zero (log 0 = -inf): hard evidence
        log_w = np.where(states, np.log(u), np.log(1 - u)).sum(axis=1)
        log_t = np.log(hidden)
    for a, b in lattice_edges(p.shape, region):
        # table rows/cols: index 0 = occupied, 1 = empty
        log_w += log_t[(~states[:, a]).astype(int), (~states[:, b]).astype(int)]
    if not np.isfinite(log_w.max()):
        raise InputError("observed", "contradictory hard evidence: no joint state has positive probability")
    w = np.exp(log_w - log_w.max())
    marg = (w[:, None] * states).sum(axis=0) / w.sum()
    return marg.reshape(p.shape)
