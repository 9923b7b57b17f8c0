"""Checkerboard LBP kept alive between calls, for :class:`crfmap.mapping.online.OnlineMapper`: one whole grid of packed
messages that stays between scans, the observations of the cells a scan touched set in place, and warm-started runs
on a disc (rows with a column range each) or the whole grid. With a ``margin``, only cells within ``margin`` cells
(Chebyshev) of a cell whose observation was ever set send, as ``infer(region=near_known(grid, margin))`` would.

>>> import numpy as np
>>> lbp = IncrementalLBP(3, 4, [[10, 1], [1, 10]], [[1, 0], [0, 1]])
>>> lbp.set_observations(np.array([[1, 1]]), np.array([0.9]))
>>> changes = lbp.run(5, 1e-6, threads=1)
>>> bool(lbp.beliefs()[1, 1] > 0.9), bool(lbp.beliefs()[1, 2] > 0.5)
(True, True)
"""
from __future__ import annotations

import numpy as np
from numba import njit

from crfmap.crf.engine._layout import unary_odds
from crfmap.crf.engine.messages import MESSAGE_FLOOR
from crfmap.crf.engine.packed import PASS_ITERATIONS, PackedBlock, fast_tables_ok
from crfmap.crf.model.potentials import check_pairing, check_table, directional_tables
from crfmap.errors import InputError
from crfmap.grid import UNKNOWN


@njit(cache=True, nogil=True)
def _set_observations(cells, probability, link, floor, un, known, near, margin):
    """Observation odds of cells (x, y) = ``cells[i]`` from P(occupied) ``probability[i]`` into the planes ``un``; with
    ``margin`` >= 0, a cell set for the first time marks every cell within ``margin`` in the planes ``near``."""
    height, width = known.shape if margin >= 0 else (0, 0)
    for i in range(cells.shape[0]):
        x = cells[i, 0]
        y = cells[i, 1]
        un[(x + y) & 1, y + 1, (x >> 1) + 1] = unary_odds(probability[i], link, floor)
        if margin >= 0 and known[y, x] == 0:
            known[y, x] = 1
            for ny in range(max(y - margin, 0), min(y + margin + 1, height)):
                for nx in range(max(x - margin, 0), min(x + margin + 1, width)):
                    near[(nx + ny) & 1, ny + 1, (nx >> 1) + 1] = 1


class IncrementalLBP:
    """A whole grid of ``height x width`` cells on the fast engine, iterated a little at a time; every cell starts
    unknown with uniform messages. ``hidden``, ``link``, ``pairing``: as ``infer``'s; ``margin`` [cells]: as above."""

    def __init__(self, height, width, hidden, link, dtype=np.float32, pairing="receiver", margin=None):
        hidden = check_table(hidden, "hidden")
        self.link = check_table(link, "link")
        tables = directional_tables(hidden, check_pairing(pairing))
        if not fast_tables_ok(tables):  # pragma: no cover - both pairings qualify
            raise InputError("pairing", "the fast engine needs east/north and west/south to share tables")
        if margin is not None and not (isinstance(margin, (int, np.integer)) and margin >= 0):
            raise InputError("margin", f"must be None or a non-negative whole number of cells, got {margin!r}")
        self.height, self.width = int(height), int(width)
        self.margin = None if margin is None else int(margin)
        self._link = np.ascontiguousarray(self.link.ravel())
        self._packed = PackedBlock(self.height, self.width, dtype, tables, MESSAGE_FLOOR)
        self._packed.set_unary(np.full((self.height, self.width), UNKNOWN), self.link)
        # with a margin: cells ever set, and the cells near them (the only senders), packed
        self._known = np.zeros((self.height, self.width) if margin is not None else (0, 0), np.uint8)
        self._near = np.zeros(self._packed.un.shape if margin is not None else (2, 1, 1), np.uint8)

    @property
    def dtype(self) -> np.dtype:
        return self._packed.dtype

    @property
    def senders(self) -> int:
        """Cells the last :meth:`run` let send (counting whole row ranges under a margin)."""
        return self._packed.active_cells

    def set_observations(self, cells, probability) -> None:
        """Cells (x, y) = ``cells[i]`` (int64 (n, 2)) now observe P(occupied) = ``probability[i]``."""
        _set_observations(cells, probability, self._link, MESSAGE_FLOOR, self._packed.un, self._known, self._near,
                          -1 if self.margin is None else self.margin)

    def run(self, max_iter, tol, threads, rows=None, block=PASS_ITERATIONS) -> list:
        """LBP until ``tol`` or ``max_iter``, warm-started; returns the per-iteration largest changes (NaN: not measured).
        ``rows`` ``(y0, x_from, x_to)``: only cells x_from[i] <= x < x_to[i] of row y0 + i send (None: all)."""
        packed = self._packed
        if rows is not None:
            packed.set_rows(*rows, act=None if self.margin is None else self._near)
        elif self.margin is None:
            packed.set_mask(None)
        else:
            packed.set_packed_mask(self._near)
        return packed.run(max_iter, tol, threads, block=block)

    def beliefs(self) -> np.ndarray:
        """float64 [y, x] P(occupied) of every cell now."""
        return self._packed.beliefs()

    def messages(self) -> np.ndarray:
        """The messages now as probabilities, shape (4, H, W) (the layout of :mod:`crfmap.crf.engine.messages`)."""
        return self._packed.messages(np.full((4, self.height, self.width), 0.5, self._packed.dtype))
