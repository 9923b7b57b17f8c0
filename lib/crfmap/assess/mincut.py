"""The exact MAP labelling of the grid CRF by a graph cut (PyMaxflow): a baseline beside LBP and a check of it.

With a symmetric attractive hidden table the CRF's energy is submodular, so a Boykov-Kolmogorov cut finds its exact
minimum. PyMaxflow is optional (the ``compare`` extra); :func:`graph_cut_map` imports it when called.
"""
from __future__ import annotations

import numpy as np

from crfmap.crf.engine.messages import MESSAGE_FLOOR
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK, check_table, link_unary
from crfmap.errors import InputError


def floored_unary(observed, link=DEFAULT_LINK):
    """P(occupied) each hidden cell gets from its observation, floored as crfmap.crf.inference.lbp.infer floors it."""
    return np.clip(link_unary(observed, link), MESSAGE_FLOOR, 1.0 - MESSAGE_FLOOR)


def potts_weight(hidden=DEFAULT_HIDDEN) -> tuple:
    """(w, shift, constant) so that -log hidden[s_a, s_b] = constant + shift * (x_a + x_b) + w [x_a != x_b].

    x = 1 for occupied. Needs a symmetric table with positive entries and w >= 0 (attractive: see the module doc).

    >>> [round(v, 4) for v in potts_weight([[10, 1], [1, 10]])]  # log 10, 0, -log 10
    [2.3026, 0.0, -2.3026]
    """
    t = check_table(hidden, "hidden")
    if t[0, 1] != t[1, 0] or np.any(t <= 0):
        raise InputError("hidden", f"the graph cut needs a symmetric table with positive entries, got {t.tolist()}")
    occ, mixed, free = -np.log(t[0, 0]), -np.log(t[0, 1]), -np.log(t[1, 1])
    w = mixed - 0.5 * (occ + free)
    if w < 0:
        raise InputError("hidden", f"not attractive (t01^2 > t00 t11): the energy is not submodular, {t.tolist()}")
    return float(w), float(0.5 * (occ - free)), float(free)


def graph_cut_map(observed, hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK) -> tuple:
    """Exact MAP labelling with PyMaxflow: (occupied[y, x] bool, energy from the flow).

    Sink side = occupied: a cell on the sink side pays its source capacity (its occupied cost)."""
    import maxflow

    u = floored_unary(observed, link)
    h, w = u.shape
    weight, shift, constant = potts_weight(hidden)
    degree = np.full((h, w), 4.0)
    degree[0, :] -= 1
    degree[-1, :] -= 1
    degree[:, 0] -= 1
    degree[:, -1] -= 1
    cost_occ = -np.log(u) + shift * degree
    cost_free = -np.log1p(-u)
    low = np.minimum(cost_occ, cost_free)  # capacities must be >= 0
    g = maxflow.Graph[float]()
    nodes = g.add_grid_nodes((h, w))
    right_and_up = np.array([[0, 0, 0], [0, 0, 1], [0, 1, 0]])  # each edge once, then both ways
    g.add_grid_edges(nodes, weights=weight, structure=right_and_up, symmetric=True)
    g.add_grid_tedges(nodes, cost_occ - low, cost_free - low)
    flow = g.maxflow()
    n_edges = h * (w - 1) + w * (h - 1)
    return g.get_grid_segments(nodes), float(flow + low.sum() + constant * n_edges)
