"""THE BASELINE of ``crfmap bench``: checkerboard LBP in vectorised NumPy (see :mod:`crfstudy.bench.suite`).

Written for the benchmark, as well as NumPy allows, so crfmap's kernels are measured against a
fair opponent: same model, schedule and floors, whole-array operations, float32.
"""
from __future__ import annotations

import numpy as np

from crfmap.crf.engine import packed as F
from crfmap.crf.engine.messages import MESSAGE_FLOOR
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK, directional_tables, link_unary


class NumpyCheckerboard:
    """THE BASELINE: checkerboard LBP in vectorised NumPy, one odds ratio per message.

    Same model, schedule and floors as :func:`crfmap.crf.inference.lbp.infer` (cells with even x + y send,
    then the others); each half-sweep is four strided sub-lattices (even/odd rows) updated
    with whole-array operations: ``r' = (t00 R + t01) / (t10 R + t11)`` with R the sender's
    cavity odds. Messages are ``m[d, y, x]`` as in :mod:`crfmap.crf.inference._plain_kernels`, as odds.

    A good NumPy implementation: float32, no Python loop over cells, chunks of about
    CHUNK_CELLS cells of a sub-lattice at a time so the temporaries stay in cache.

    >>> nb = NumpyCheckerboard(np.array([[0.9, 0.5, 0.9]]))
    >>> nb.iterate(20)
    >>> bool(nb.beliefs()[0, 1] > 0.5)
    True
    """

    CHUNK_CELLS = 1 << 16

    def __init__(self, observed, hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK, dtype=np.float32, pairing="receiver"):
        observed = np.asarray(observed, np.float64)
        self.h, self.w = observed.shape
        self.dtype = np.dtype(dtype)
        u = np.clip(link_unary(observed, link), MESSAGE_FLOOR, 1.0 - MESSAGE_FLOOR)
        self.U = (u / (1.0 - u)).astype(self.dtype)
        self.m = np.ones((4, self.h, self.w), self.dtype)
        tables = directional_tables(hidden, pairing)
        tables = tables / tables.max()
        self.t = [tuple(self.dtype.type(v) for v in t.ravel()) for t in tables]
        co = F.odds_coefficients(tables, np.float64, MESSAGE_FLOOR)
        self.clamp = co[9] != 0
        self.lo = self.dtype.type(MESSAGE_FLOOR / (1.0 - MESSAGE_FLOOR))
        self.hi = self.dtype.type((1.0 - MESSAGE_FLOOR) / MESSAGE_FLOOR)

    def _message(self, d, R):
        t00, t01, t10, t11 = self.t[d]
        r = (t00 * R + t01) / (t10 * R + t11)
        return np.clip(r, self.lo, self.hi, out=r) if self.clamp else r

    def _send(self, ry, cx, i0, i1):
        """Cells in rows ry + 2i (i0 <= i < i1) and columns cx, cx + 2, ... send their 4 messages."""
        m, w = self.m, self.w
        rows = slice(ry + 2 * i0, ry + 2 * i1, 2)
        U = self.U[rows, cx::2]
        r0, r1, r2, r3 = (m[d, rows, cx::2] for d in range(4))
        p = U * r2 * r3  # cavity odds without the east and west messages
        q = U * r0 * r1  # without the north and south ones
        nc = U.shape[1]
        ne = len(range(cx + 1, w, 2))  # senders with an east neighbour
        if ne:
            m[0, rows, cx + 1::2] = self._message(0, p[:, :ne] * r0[:, :ne])
        if cx == 0:  # the sender at x = 0 has no west neighbour
            if nc > 1:
                m[1, rows, 1::2][:, :nc - 1] = self._message(1, p[:, 1:] * r1[:, 1:])
        else:
            m[1, rows, 0::2][:, :nc] = self._message(1, p * r1)
        # north: sender row ry + 2i -> row ry + 2i + 1, if inside the grid
        n_north = min(i1, len(range(ry + 1, self.h, 2))) - i0
        if n_north > 0:
            m[2, ry + 1 + 2 * i0:ry + 1 + 2 * (i0 + n_north):2, cx::2] = self._message(2, q[:n_north] * r2[:n_north])
        # south: sender row ry + 2i -> row ry + 2i - 1, if inside the grid
        first = 1 if (ry == 0 and i0 == 0) else 0
        if i1 - i0 > first:
            y0 = ry + 2 * (i0 + first) - 1
            m[3, y0:ry + 2 * i1 - 1:2, cx::2] = self._message(3, q[first:] * r3[first:])

    def iterate(self, n=1):
        """n checkerboard iterations (colour 0 = even x + y sends, then colour 1)."""
        for _ in range(n):
            for colour in (0, 1):
                for ry in (0, 1):
                    rows = len(range(ry, self.h, 2))
                    chunk = max(4, self.CHUNK_CELLS // self.w)  # row chunks keep temporaries in cache
                    for i0 in range(0, rows, chunk):
                        self._send(ry, (colour + ry) % 2, i0, min(i0 + chunk, rows))

    def beliefs(self) -> np.ndarray:
        b = self.U.astype(np.float64) * np.prod(self.m.astype(np.float64), axis=0)
        return b / (1.0 + b)
