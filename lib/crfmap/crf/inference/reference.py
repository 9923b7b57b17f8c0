"""A textbook LBP, independent of the fast kernels: the reference to compare them with.

Pure Python, explicit two-state messages ``m[x_receiver]`` (unnormalised products, then
normalised), a dictionary of directed edges, synchronous (flooding) updates: slow and obviously
correct. It shares no code with :mod:`crfmap.crf.inference._plain_kernels`; the tests and the toolbox comparison
(notebook 04) use it as the independent implementation.
"""
from __future__ import annotations

import numpy as np


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
