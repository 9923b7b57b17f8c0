"""The slow, obviously correct references the fast kernels are checked against (the tests, notebooks 01, 02, 04).

- :func:`exact_marginals`: exact marginals of a small grid CRF by enumerating every joint state. Only for tiny
  grids (at most :data:`MAX_CELLS` cells): the work grows as 2**cells.
- :func:`reference_lbp`: a textbook LBP, independent of the fast kernels. Pure Python, explicit two-state
  messages ``m[x_receiver]`` (unnormalised products, then normalised), a dictionary of directed edges,
  synchronous (flooding) updates. It shares no code with crfmap's kernels; the tests and the toolbox comparison
  (notebook 04) use it as the independent implementation.
- :func:`crf_energy`: the energy a labelling has under the CRF, which the graph cut
  (:func:`crfmap.assess.mincut.graph_cut_map`) minimises: the tests' brute force and the benchmark compare by it.
"""
from __future__ import annotations

import numpy as np

from crfmap.assess.mincut import floored_unary
from crfmap.crf.model.potentials import check_pairing, check_table, DEFAULT_HIDDEN, DEFAULT_LINK, link_unary
from crfmap.errors import InputError
from crfmap.grid import check_probability_array

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
    if pairing == "receiver" and hidden[0, 1] != hidden[1, 0]:  # not symmetric
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



def lattice_neighbours(h, w):
    """{cell: [neighbour cells]} for the 4-neighbour lattice, cells as (y, x)."""
    nb = {}
    for y in range(h):
        for x in range(w):
            nb[(y, x)] = [(y + dy, x + dx) for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0))
                          if 0 <= y + dy < h and 0 <= x + dx < w]
    return nb


def edge_table(hidden, sender, receiver, pairing):
    """2x2 array t[x_receiver, x_sender] (index 0 occupied) used for the message sender -> receiver."""
    t = np.asarray(hidden, float)
    if pairing == "receiver":
        return t
    # oriented: psi(x_a, x_b) = t[x_a, x_b] with a the west/south end
    (sy, sx), (ry, rx) = sender, receiver
    sender_is_a = (sx < rx) or (sy < ry)
    return t.T if sender_is_a else t


def reference_lbp(observed, hidden, link, iterations, pairing="receiver", damping=0.0, tol=0.0):
    """Synchronous sum-product LBP with two-state messages; returns (beliefs, iterations done).

    Stops after ``iterations`` or once the largest change of a message's occupied share is
    below ``tol`` (when ``tol`` > 0).
    """
    p = np.asarray(observed, float)
    h, w = p.shape
    L = np.asarray(link, float)
    nb = lattice_neighbours(h, w)
    phi = {}
    for c in nb:
        v = np.array([L[0, 0] * p[c] + L[0, 1] * (1 - p[c]), L[1, 0] * p[c] + L[1, 1] * (1 - p[c])])
        phi[c] = v / v.sum()
    msg = {(s, r): np.array([0.5, 0.5]) for s in nb for r in nb[s]}
    done = 0
    for _ in range(iterations):
        new = {}
        change = 0.0
        for (s, r), old in msg.items():
            cav = phi[s].copy()
            for k in nb[s]:
                if k != r:
                    cav = cav * msg[(k, s)]
            t = edge_table(hidden, s, r, pairing)
            m = t @ cav  # m[x_r] = sum_{x_s} t[x_r, x_s] cav[x_s]
            m = m / m.sum()
            m = (1 - damping) * m + damping * old
            change = max(change, abs(m[0] - old[0]))
            new[(s, r)] = m
        msg = new
        done += 1
        if tol > 0 and change < tol:
            break
    beliefs = np.empty_like(p)
    for c in nb:
        b = phi[c].copy()
        for k in nb[c]:
            b = b * msg[(k, c)]
        beliefs[c] = b[0] / b.sum()
    return beliefs, done


def crf_energy(occupied, observed, hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK) -> float:
    """-log of the unnormalised CRF probability of a labelling (``occupied[y, x]`` boolean).

    Unary -log u or -log(1 - u) per cell, -log hidden[s_a, s_b] per 4-neighbour edge with
    s = 0 for occupied, 1 for free (the thesis layout; oriented pairing, a = west / south).

    >>> round(crf_energy(np.array([[True, True]]), np.array([[0.5, 0.5]])), 4)  # 2 log 2 - log 10
    -0.9163
    """
    occupied = np.asarray(occupied, bool)
    u = floored_unary(observed, link)
    if occupied.shape != u.shape:
        raise InputError("occupied", f"shape {occupied.shape} does not match the grid {u.shape}")
    cost = -np.log(check_table(hidden, "hidden"))
    s = np.where(occupied, 0, 1)
    unary = np.where(occupied, -np.log(u), -np.log1p(-u)).sum()
    pairwise = cost[s[:, :-1], s[:, 1:]].sum() + cost[s[:-1, :], s[1:, :]].sum()
    return float(unary + pairwise)
