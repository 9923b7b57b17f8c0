"""The fast engine's data, :class:`PackedBlock`: a block of the grid in the red/black odds planes of
:mod:`crfmap.crf.engine._message_update`, converted to and from :mod:`crfmap.crf.engine.messages`, and its passes."""
from __future__ import annotations

import math

import numpy as np

from crfmap.crf.engine._layout import (
    _active_extents,
    _beliefs_packed,
    _fill_ones,
    _pack_clamped,
    _pack_mask,
    _pack_messages,
    _pack_start,
    _pack_unary,
    _unpack_messages,
)
from crfmap.crf.engine._message_update import NO_MASK, _pass, _tile_max
from crfmap.crf.engine.progress import passed
from crfmap.crf.threads import over_rows, run_all

PASS_ITERATIONS = 16  # iterations per pass at most (temporal blocking depth); each pass measures its last
SERIAL_CELLS = 1 << 15  # blocks with fewer senders run on one thread (no thread start-up per pass)
TILE_ROWS = 16  # [cells] tiles for measuring changes and freezing settled parts of the grid
TILE_COLS = 32  # [cells] narrow tiles freeze settled parts sooner (fewer cell updates on large noisy maps)
FREEZE = 0.01  # default freeze threshold, times tol: tiles that moved by less pause until a neighbour moves
SPARSE_FRACTION = 0.5  # iterate tile by tile once fewer tiles than this still move
SPARSE_CELLS = 1 << 18  # grids with fewer senders never freeze tiles (few tiles: freezing costs more than it saves)
NO_BELIEFS = np.zeros((1, 1))  # the beliefs argument of a pass that writes none


def odds_coefficients(tables, dtype, floor) -> np.ndarray:
    """(E/N table, W/S table) entries t00 t01 t10 t11 scaled to a largest of 1, then 1, and whether messages need
    the floor: a message through t has odds between t01/t11 and t00/t10; when both lie well inside the floored range
    the clamp never acts and the hot loop skips it (co[9] = 0). East and north must share a table, west and south
    the other (true of both pairings)."""
    tables = np.asarray(tables, dtype=np.float64)
    scale = tables.max()
    clamp = 0.0
    lo, hi = floor / (1.0 - floor), (1.0 - floor) / floor
    for t in (tables[0], tables[1]):
        if np.any(t <= 0):
            clamp = 1.0
        else:
            ends = (t[0, 1] / t[1, 1], t[0, 0] / t[1, 0])
            if min(ends) < 10.0 * lo or max(ends) > hi / 10.0:
                clamp = 1.0
    co = np.concatenate([tables[0].ravel() / scale, tables[1].ravel() / scale, [1.0, clamp]])
    return co.astype(dtype)


def fast_tables_ok(tables) -> bool:
    """Whether the fast kernels can run these directional tables (E = N and W = S)."""
    tables = np.asarray(tables)
    return bool(np.array_equal(tables[0], tables[2]) and np.array_equal(tables[1], tables[3]))


def plane_width(w) -> int:
    return (w + 1) // 2 + 2


def full_extents(h, w):
    """Plane-index ranges covering every cell of every row: lo = 0, hi = cells of that colour."""
    y = np.arange(h)
    lo = np.zeros((2, h), np.int64)
    hi = np.stack([(w - ((y + c) & 1) + 1) >> 1 for c in (0, 1)]).astype(np.int64)
    return lo, hi


class PackedBlock:
    """Odds messages and observations of a block of ``h x w`` cells in red/black planes. ``tables``: (4, 2, 2)
    directional tables; ``floor``: the message floor in probability; ``arrays`` (msg, un): planes to reuse (None: new
    ones); ``fill`` False leaves them undefined for :meth:`start_uniform` (True: uniform)."""

    def __init__(self, h, w, dtype, tables, floor, arrays=None, fill=True):
        self.h, self.w = int(h), int(w)
        self.dtype = np.dtype(dtype)
        wp = plane_width(self.w)
        self.msg, self.un = arrays if arrays is not None else (np.empty((2, 4, self.h + 2, wp), self.dtype),
                                                                np.empty((2, self.h + 2, wp), self.dtype))
        if fill:
            for planes in (self.msg, self.un):
                rows = planes.reshape(-1, planes.shape[-1])
                over_rows(_fill_ones, rows.shape[0], rows)
        self.co = odds_coefficients(tables, self.dtype, floor)
        self.floor = float(floor)
        self.lo = self.dtype.type(floor / (1.0 - floor))
        self.hi = self.dtype.type((1.0 - floor) / floor)
        self.act = np.zeros((2, 1, 1), np.uint8)
        self.use_act = False
        self.lo_k, self.hi_k = full_extents(self.h, self.w)
        self._extents_changed()
        self.cell_updates = 0  # cells that sent, summed over iterations (work done)
        self.beliefs_written = False  # whether the last pass of run() wrote the beliefs
        self.uniform_start = False  # the next pass's first half-sweep sends from uniform messages (start_uniform)

    # --- filling it ---------------------------------------------------------------------------
    def set_unary(self, probability, link, y0=0, x0=0):
        """Observation odds from P(occupied) ``probability[y0:y0+h, x0:x0+w]`` through ``link``."""
        link = np.asarray(link, np.float64).ravel()
        over_rows(_pack_unary, self.h, probability, y0, x0, self.h, self.w, link, self.floor, self.un)

    def start_uniform(self, probability, link, threads=1):
        """Whole-grid block from uniform messages in one trip: the observation odds and only the message slots no
        neighbour sends into; the next pass (at least two iterations of the whole grid) sends the red cells' first
        half-sweep from the odds alone. Returns (cells of ``probability`` outside [0, 1] or not finite, cells
        ``link`` makes certain): with either, the result must not be used."""
        link = np.asarray(link, np.float64).ravel()
        stats = np.zeros((max(1, min(4 * int(threads), self.h)), 2), np.int64)
        run_all(_pack_start, [(probability, link, self.floor, self.co, self.un, self.msg, stats, b)
                              for b in range(stats.shape[0])], threads)
        self.uniform_start = True
        return int(stats[:, 0].sum()), int(stats[:, 1].sum())

    def set_messages(self, messages, y0=0, x0=0):
        """Probability messages ``messages[4, y0:y0+h, x0:x0+w]`` (None: uniform)."""
        if messages is None:
            self.msg.fill(1.0)
        else:
            over_rows(_pack_messages, self.h, messages, y0, x0, self.h, self.w, self.floor, self.msg)

    def set_mask(self, mask, y0=0, x0=0):
        """Only cells with ``mask[y0 + y, x0 + x]`` send (None: all)."""
        if mask is None:
            self.act = np.zeros((2, 1, 1), np.uint8)
            self.use_act = False
            self.lo_k, self.hi_k = full_extents(self.h, self.w)
            self._extents_changed()
            return
        act = np.zeros((2, self.h + 2, plane_width(self.w)), np.uint8)
        over_rows(_pack_mask, self.h, mask, y0, x0, self.h, self.w, act)
        self.set_packed_mask(act)

    def clamp(self, state, implied):
        """Whole-grid block: certain cells (``state`` >= 0) send ``implied[d, state]`` (probabilities) for ever; call
        after :meth:`set_messages`."""
        p = np.clip(np.asarray(implied, np.float64), self.floor, 1.0 - self.floor)
        act = np.empty(self.un.shape, np.uint8)
        over_rows(_pack_clamped, state.shape[0], state, (p / (1.0 - p)).astype(self.dtype), self.msg, act)
        self.set_packed_mask(act)

    def set_packed_mask(self, act):
        """Only cells whose entry of ``act`` (red/black planes, shape of ``un``) is non-zero send; ``act`` is not
        copied: its owner may keep updating it between passes."""
        self.act = act
        self.use_act = True
        self.lo_k = np.zeros((2, self.h), np.int64)
        self.hi_k = np.zeros((2, self.h), np.int64)
        _active_extents(self.act, self.h, self.w, self.lo_k, self.hi_k)
        self._extents_changed()

    def set_rows(self, y0, x_from, x_to, act=None):
        """Only cells x_from[i] <= x < x_to[i] of row y0 + i send (e.g. a disc); with ``act`` (as in
        :meth:`set_packed_mask`) only those among them it marks (``active_cells`` counts the whole ranges)."""
        self.act = np.zeros((2, 1, 1), np.uint8) if act is None else act
        self.use_act = act is not None
        self.lo_k = np.zeros((2, self.h), np.int64)
        self.hi_k = np.zeros((2, self.h), np.int64)
        rows = y0 + np.arange(len(x_from))
        for c in (0, 1):
            off = (rows + c) & 1
            self.lo_k[c, rows] = (np.asarray(x_from) - off + 1) >> 1
            self.hi_k[c, rows] = np.maximum((np.asarray(x_to) - off + 1) >> 1, self.lo_k[c, rows])
        self._extents_changed()

    def _extents_changed(self):
        counts = (self.hi_k - self.lo_k).clip(0)
        rows = np.flatnonzero(counts.sum(axis=0) > 0)
        self.row_range = (int(rows[0]), int(rows[-1]) + 1) if rows.size else (0, 0)
        self.active_cells = int(counts.sum())

    def widened(self, tables, probability, link, y0=0, x0=0):
        """This block in float64: its messages (copied, ghosts included), its senders (shared), and ``tables`` and the
        observation odds of ``probability`` (as :meth:`set_unary`) in float64, not widened from float32."""
        wide = PackedBlock(self.h, self.w, np.float64, tables, self.floor,
                           (self.msg.astype(np.float64), np.empty(self.un.shape, np.float64)), fill=False)
        rows = wide.un.reshape(-1, wide.un.shape[-1])
        over_rows(_fill_ones, rows.shape[0], rows)  # the ghosts' observations
        wide.set_unary(probability, link, y0, x0)
        wide.act, wide.use_act, wide.lo_k, wide.hi_k = self.act, self.use_act, self.lo_k, self.hi_k
        wide._extents_changed()
        return wide

    # --- reading it ---------------------------------------------------------------------------
    def messages(self, out, y0=0, x0=0):
        """Write the probability messages into ``out[4, y0:y0+h, x0:x0+w]``."""
        over_rows(_unpack_messages, self.h, self.msg, y0, x0, self.h, self.w, self.act, self.use_act, out)
        return out

    def beliefs(self, out=None):
        out = np.empty((self.h, self.w), np.float64) if out is None else out
        over_rows(_beliefs_packed, self.h, self.un, self.msg, self.h, self.w, out)
        return out

    # --- running it -----------------------------------------------------------------------------
    def band_edges(self, iterations, threads):
        """Row edges of the bands a pass of ``iterations`` uses (one band: run serially). Inner edges are multiples of
        TILE_ROWS and bands are tall enough that neither two gap trapezoids nor two threads share a row tile."""
        ylo, yhi = self.row_range
        rows = yhi - ylo
        min_height = 4 * iterations + 2 * TILE_ROWS + 4
        if threads <= 1 or self.active_cells < SERIAL_CELLS or rows < 2 * min_height:
            return np.array([ylo, yhi], np.int64)
        # two bands per thread: edge bands (which shrink on one side only) pair with inner ones
        nb = 2 * threads if rows >= 2 * threads * min_height else threads
        inner = np.linspace(ylo, yhi, nb + 1)[1:-1]
        inner = (np.round(inner / TILE_ROWS) * TILE_ROWS).astype(np.int64)
        edges = np.concatenate([[ylo], inner, [yhi]]).astype(np.int64)
        if np.any(np.diff(edges) < min_height):
            return np.array([ylo, yhi], np.int64)
        return edges

    def tile_shape(self):
        return ((self.h + TILE_ROWS - 1) // TILE_ROWS, (self.w + TILE_COLS - 1) // TILE_COLS)

    def _segments(self, active):
        """Column ranges of the runs of active tiles in each row tile (all tiles if None)."""
        n_ty, n_tx = self.tile_shape()
        if active is None:
            if getattr(self, "_all_segments", None) is None or self._all_segments[0].shape[0] != n_ty:
                segs = np.zeros((n_ty, 1, 2), np.int64)
                segs[:, 0, 1] = self.w
                self._all_segments = (segs, np.ones(n_ty, np.int64), self.h * self.w)
            return self._all_segments
        segs = np.zeros((n_ty, (n_tx + 1) // 2, 2), np.int64)
        nseg = np.zeros(n_ty, np.int64)
        padded = np.zeros((n_ty, n_tx + 2), bool)
        padded[:, 1:-1] = active
        ty, t0 = np.nonzero(padded[:, 1:-1] & ~padded[:, :-2])  # row-major: the runs' starts and ends pair up
        t1 = np.nonzero(padded[:, 1:-1] & ~padded[:, 2:])[1]
        x0, x1 = t0 * TILE_COLS, np.minimum((t1 + 1) * TILE_COLS, self.w)
        rank = np.arange(ty.size) - np.searchsorted(ty, ty)  # each run's place in its row tile
        segs[ty, rank, 0], segs[ty, rank, 1] = x0, x1
        nseg += np.bincount(ty, minlength=n_ty)
        cells = int(((np.minimum((ty + 1) * TILE_ROWS, self.h) - ty * TILE_ROWS) * (x1 - x0)).sum())
        return segs, nseg, cells

    def run_pass(self, iterations, threads, measure=True, active=None, per_tile=True):
        """``iterations`` checkerboard iterations, only the tiles in ``active`` sending (None: all): the largest message
        change of the last (NaN if not ``measure``) and, with ``per_tile``, per tile (else None)."""
        args, stages, cb = self._pass_arguments(iterations, threads, measure, active)
        for stage in range(stages):
            _pass(*args, stage, NO_BELIEFS, False)
        return self._pass_change(cb, measure, per_tile)

    def _pass_arguments(self, iterations, threads, measure, active):
        """The arguments of :func:`_pass` for one pass but its stage, how many stages it has (1 with one band, else 2)
        and its per-column change buffer; counts its cell updates."""
        edges = self.band_edges(iterations, threads)
        segs, nseg, cells = self._segments(active)
        n_ty, n_tx = self.tile_shape()
        cb = np.zeros((n_ty, self.msg.shape[3]), self.dtype)
        measure_from = iterations - 1 if measure else iterations
        args = (self.msg, self.un, self.act if self.use_act else NO_MASK, self.lo_k, self.hi_k, segs, nseg, TILE_ROWS,
                self.h, self.w, self.co, self.lo, self.hi)
        if self.uniform_start and (iterations < 2 or active is not None or self.use_act):
            raise ValueError("the pass after start_uniform must run at least two iterations of the whole grid")
        uniform, self.uniform_start = self.uniform_start, False
        self.cell_updates += (self.active_cells if active is None else cells) * iterations
        return args + (edges, int(iterations), int(measure_from), cb, uniform), min(2, len(edges) - 1), cb

    def _pass_change(self, cb, measure, per_tile):
        """The largest change of a pass's measured iteration, and per tile (see :meth:`run_pass`)."""
        if not measure:
            return float("nan"), None
        if not per_tile:
            return float(cb.max()), None
        n_ty, n_tx = self.tile_shape()
        tiles = np.zeros((n_ty, n_tx))
        _tile_max(cb, TILE_COLS, self.w, tiles)
        return float(tiles.max()) if tiles.size else 0.0, tiles

    def run(self, max_iter, tol, threads, block=PASS_ITERATIONS, freeze=None, first=1, beliefs=None,
            confirm_settled=True):
        """Iterate until an iteration of *every* cell moves no message by ``tol`` or more; the per-iteration largest
        changes (NaN where not measured, and for the last if max_iter ends the run before it was confirmed).

        Passes of ``first``, 2 ``first``, 4 ``first``, ... ``block`` iterations, each measuring its last (``first`` 1
        after a warm start, which may stop at once; ``block`` from uniform messages: then two passes of ``block / 2``
        first). Once two passes measured, a pass is cut to the iterations their rate predicts to reach ``tol``.
        ``freeze`` (below ``tol``; None: ``FREEZE * tol``; 0 changes nothing): once fewer than SPARSE_FRACTION of the
        tiles moved by more than it, only those tiles and their four neighbours iterate; when they settle below
        ``tol``, one iteration of every cell decides (``confirm_settled`` False: the run ends unconfirmed, for a caller
        that confirms itself). ``beliefs`` (float64 [h, w], no mask): a whole-grid pass that is likely the last also
        writes the beliefs there while each row is in cache (:attr:`beliefs_written`: whether the last pass did)."""
        fusable = beliefs is not None and not self.use_act and self.row_range == (0, self.h) and self.h > 0
        self.beliefs_written = False
        confirm = False  # the whole-grid iteration after the moving tiles settled
        if freeze is None:
            freeze = FREEZE * tol
        changes = []
        size = max(1, int(first))
        # from uniform messages two half passes give the rate before a whole pass could run past tol (not for tol 0,
        # which runs to max_iter: each pass is one more trip through memory)
        halves = 2 if size >= block >= 4 and tol > 0 else 0
        size = block // 2 if halves else size
        sparse = freeze is not None and (freeze < tol or freeze == 0) and self.active_cells >= SPARSE_CELLS
        active = None
        measured = []  # (iterations done, change) after each pass: the rate of convergence
        while len(changes) < max_iter:
            n = min(size, block, max_iter - len(changes))
            predicted = _iterations_to_tol(*measured[-2:], tol) if len(measured) >= 2 else 1 << 30
            n = min(n, predicted)  # the last pass stops near tol, not up to block - 1 iterations beyond it
            last = n == max_iter - len(changes) or n == predicted or confirm  # likely the last pass
            self.beliefs_written = with_beliefs = fusable and active is None and last
            args, stages, cb = self._pass_arguments(n, threads, True, active)
            for stage in range(stages):  # the bands, then the gaps between them
                _pass(*args, stage, beliefs if with_beliefs else NO_BELIEFS, with_beliefs)
            change, per_tile = self._pass_change(cb, True, sparse)
            confirm = False
            changes.extend([float("nan")] * (n - 1) + [change])
            passed(len(changes), max_iter, change)  # a watcher's bar (crfmap infer on a terminal); Ctrl-C lands here
            whole_grid = active is None
            measured.append((len(changes), change))
            halves -= 1
            size = size if halves > 0 else 2 * size
            if change < tol:
                if active is None or not confirm_settled:
                    break  # an iteration of every cell moved no message by tol (or the caller confirms)
                active, size, confirm = None, 1, True  # the moving tiles settled: one full iteration decides
                continue
            if sparse:
                moving = per_tile > freeze
                active = _dilate(moving) if moving.mean() < SPARSE_FRACTION else None
        if changes and not whole_grid and changes[-1] < tol:
            # max_iter ran out before an iteration of every cell confirmed the settled tiles
            changes[-1] = float("nan")
        return changes


def _iterations_to_tol(earlier, later, tol):
    """Iterations after ``later`` until the largest change falls below ``tol`` if it keeps shrinking at the rate
    it did from ``earlier`` (each an (iterations done, change) pair); a large number where it did not shrink."""
    (i0, c0), (i1, c1) = earlier, later
    if not (0.0 < c1 < c0 and i1 > i0 and tol > 0.0):
        return 1 << 30
    rate = math.log(c1 / c0) / (i1 - i0)  # log of the factor per iteration, < 0
    return max(1, math.ceil(math.log(tol / c1) / rate)) if c1 >= tol else 1


def _dilate(mask):
    """The mask grown by one tile in the four directions."""
    out = mask.copy()
    out[1:] |= mask[:-1]
    out[:-1] |= mask[1:]
    out[:, 1:] |= mask[:, :-1]
    out[:, :-1] |= mask[:, 1:]
    return out
