"""The fast kernels' side of :func:`crfmap.crf.lbp.infer`: packing, iterating, unpacking.

Whole grid from uniform messages (the common call) costs one trip through memory before the
iterations: :meth:`crfmap.crf.packed.PackedBlock.start_uniform` reads the observations once,
writes the observation odds and the messages after the first half-sweep (so no ones-fill of
the message planes), and counts on the way the cells a caller's grid check and the hard
evidence need (:func:`needs_checked_grid`). Warm starts, hard evidence and regions take the
general path: uniform planes, then the unary, messages, clamps or the region's box.
"""
from __future__ import annotations

import time

import numpy as np

from crfmap.crf import _lbp_kernels as K
from crfmap.crf.evidence import _forced, certain_states, clamp_messages, implied_messages
from crfmap.crf.messages import floored, initial_messages
from crfmap.crf.packed import PackedBlock, plane_width
from crfmap.crf.potentials import link_unary
from crfmap.crf.workspace import beliefs_buffer, packed_arrays
from crfmap.grid import check_probability_array

FREEZE = 0.01  # tiles that moved by less than FREEZE * tol pause (see crfmap.crf.packed.PackedBlock.run)


def run_packed(packed, max_iter, tol, threads, block, freeze=None, warm=True) -> list:
    """Run the fast kernel on a :class:`crfmap.crf.packed.PackedBlock` until ``tol`` or ``max_iter``.

    ``freeze`` None means ``FREEZE * tol``; ``warm`` False (uniform start messages) starts with
    blocks of ``block`` iterations, since such a run never stops after one. Returns the
    per-iteration largest message changes (NaN where not measured).
    """
    if freeze is None:
        freeze = FREEZE * tol
    return packed.run(max_iter, tol, threads, block=block, freeze=freeze, first=1 if warm else block)


def fused_start_applies(grid, tables, max_iter, block, region, messages) -> bool:
    """Whether :func:`infer_fast` may pack ``grid`` with the first half-sweep and check it on the way:
    a C-ordered float64 2-D array, whole grid, uniform start, a first pass of >= 2 iterations,
    and tables under which no observation-free certainty exists."""
    return (isinstance(grid, np.ndarray) and grid.dtype == np.float64 and grid.ndim == 2 and grid.size > 0
            and grid.flags.c_contiguous and region is None and messages is None and min(max_iter, block) >= 2
            and not np.any(_forced(tables) == -2))


def infer_fast(prob, tables, link, floor, max_iter, tol, active, messages, dtype, threads, block, freeze, states,
               fused=False):
    """Checkerboard LBP on the fast kernels; returns (beliefs, messages, changes, timings, states).

    ``floor``: the message floor; ``active``: the region or None; ``states``: the certain cells
    (:mod:`crfmap.crf.evidence`) or None. With ``fused`` (see :func:`fused_start_applies`;
    ``states`` not computed yet) ``prob`` is checked here: a bad grid raises
    :class:`crfmap.errors.InputError`, certain cells take the general path, and the returned
    ``states`` are the ones found.
    """
    shape = prob.shape
    if active is not None:
        beliefs, msg, changes = _infer_bounded(prob, tables, link, floor, max_iter, tol, active, messages, dtype,
                                               threads, block, freeze, states)
        return beliefs, msg, changes, {}, states
    t = [time.perf_counter()]
    wp = plane_width(shape[1])  # buffers of the last call of this shape when free: no page faults
    arrays = packed_arrays((2, 4, shape[0] + 2, wp), (2, shape[0] + 2, wp), dtype)
    packed = PackedBlock(shape[0], shape[1], dtype, tables, floor, arrays, fill=not fused)
    if fused:
        bad, certain = packed.start_uniform(prob, link, threads)
        if bad:
            check_probability_array(prob, "grid")  # raises, naming what is wrong
            raise AssertionError("the packing's grid check and check_probability_array disagree")
        if certain:  # hard evidence: the general path, which may then reuse these buffers
            packed = arrays = None
            states = certain_states(prob, link, tables)
            return infer_fast(prob, tables, link, floor, max_iter, tol, None, None, dtype, threads, block, freeze,
                              states)
    else:
        packed.set_unary(prob, link)
        if messages is not None:
            packed.set_messages(np.ascontiguousarray(messages))
        if states is not None:
            packed.clamp(states, implied_messages(tables))
    t.append(time.perf_counter())
    changes = (run_packed(packed, max_iter, tol, threads, block, freeze, warm=messages is not None)
               if packed.active_cells else [0.0][:max_iter])  # every cell clamped: nothing to do
    t.append(time.perf_counter())
    beliefs = packed.beliefs(beliefs_buffer(shape))
    packed.un = None  # the result keeps only the packed messages
    # unpacked when read; only senders' slots are unpacked under clamps, so the others start as clamped
    msg = lambda: packed.messages(np.empty((4,) + shape, dtype) if states is None else  # noqa: E731
                                  clamp_messages(states, tables, initial_messages(shape, dtype)))
    t.append(time.perf_counter())
    return beliefs, msg, changes, dict(zip(("pack", "iterate", "unpack"), np.diff(t).tolist())), states


def _infer_bounded(prob, tables, link, floor, max_iter, tol, active, messages, dtype, threads, block, freeze, states):
    """Bounded LBP: only the bounding box of the region plus a one-cell halo (the receivers) is packed."""
    shape = prob.shape
    msg = initial_messages(shape, dtype) if messages is None else floored(messages, dtype, shape, floor)
    if states is not None:
        clamp_messages(states, tables, msg, active)
        active = active & (states < 0)
    rows = np.flatnonzero(active.any(axis=1))
    changes = []
    if rows.size:
        cols = np.flatnonzero(active.any(axis=0))
        y0, y1 = max(int(rows[0]) - 1, 0), min(int(rows[-1]) + 2, shape[0])
        x0, x1 = max(int(cols[0]) - 1, 0), min(int(cols[-1]) + 2, shape[1])
        packed = PackedBlock(y1 - y0, x1 - x0, dtype, tables, floor)
        packed.set_unary(prob, link, y0, x0)
        packed.set_messages(msg, y0, x0)
        packed.set_mask(active, y0, x0)
        changes = run_packed(packed, max_iter, tol, threads, block, freeze)
        packed.messages(msg, y0, x0)
    else:
        changes = [0.0] if max_iter > 0 else []
    unary = np.clip(link_unary(prob, link), floor, 1.0 - floor)
    beliefs = np.empty(shape, dtype=np.float64)
    K._beliefs(unary, msg, beliefs)
    return beliefs, msg, changes
