"""The fast engine's one entry, :func:`solve`: pack a grid, iterate checkerboard LBP, unpack the result.

Three paths. The whole grid from uniform messages (the common call) is packed, checked and searched for hard evidence
in one trip through memory (:meth:`~crfmap.crf.engine.packed.PackedBlock.start_uniform`, :func:`fused_start_applies`).
A region from uniform messages without hard evidence (every preset's call) packs only the region's bounding box plus a
one-cell halo (the receivers): outside it the belief is the floored observation, and the messages are unpacked when
first read; in float64 with tol >= :data:`MIXED_MIN_TOL` it iterates in float32 first (faster), then in float64 from
those messages to the same stopping rule (the result differs from a float64-only run by about tol, as two runs
stopped at tol from different starts do). Warm starts, hard evidence and other regions take the general path."""
from __future__ import annotations

import time
from typing import Callable, NamedTuple

import numpy as np

from crfmap.crf.engine.messages import MESSAGE_FLOOR, beliefs_from_messages, floored, initial_messages
from crfmap.crf.engine.packed import PASS_ITERATIONS, PackedBlock, plane_width
from crfmap.crf.engine.workspace import beliefs_buffer, packed_arrays
from crfmap.crf.model.evidence import certain_states, clamp_messages, forced_states, implied_messages
from crfmap.crf.model.potentials import link_unary
from crfmap.grid import check_probability_array


MIXED_MIN_TOL = 1e-6  # float32 resolves message changes to ~1e-8 in P: far below this, so its phase always ends


class EngineResult(NamedTuple):

    beliefs: np.ndarray  # float64 [y, x] P(occupied), certain cells not yet set to their state
    messages: np.ndarray | Callable  # (4, H, W) probability messages, or a function unpacking them on first read
    changes: list  # the largest message change per iteration (NaN where not measured)
    timings: dict  # seconds of "pack", "iterate", "unpack" (whole grid only; else empty)
    states: np.ndarray | None  # the certain cells (crfmap.crf.model.evidence), found while packing when fused


def fused_start_applies(grid, tables, max_iter, block, region, messages) -> bool:
    """Whether :func:`solve` may pack ``grid`` in one trip and check it on the way: a C-ordered float64 2-D array, whole
    grid, uniform start, a first pass of >= 2 iterations, tables under which no observation-free certainty exists."""
    return (isinstance(grid, np.ndarray) and grid.dtype == np.float64 and grid.ndim == 2 and grid.size > 0
            and grid.flags.c_contiguous and region is None and messages is None and min(max_iter, block) >= 2
            and not np.any(forced_states(tables) == -2))


def solve(prob, tables, link, *, max_iter, tol, dtype, threads, region=None, messages=None, states=None,
          fused=False, block=PASS_ITERATIONS, freeze=None, floor=MESSAGE_FLOOR) -> EngineResult:
    """Checkerboard LBP on the fast kernels, as :func:`crfmap.crf.inference.lbp.infer` calls it. ``prob``: float64
    [y, x] observations; ``tables``: the four directional tables; ``region``: the senders or None; ``messages``: a
    warm start or None; ``states``: the certain cells or None; ``block``, ``freeze``: as in
    :meth:`~crfmap.crf.engine.packed.PackedBlock.run`. With ``fused`` (``states`` not computed yet) a bad ``prob``
    raises :class:`crfmap.errors.InputError`, and the returned ``states`` are the certain cells found."""
    shape = prob.shape
    t = [time.perf_counter()]
    if region is not None and messages is None and states is None:  # the presets' call: the lean bounded path
        mixed = np.dtype(dtype) == np.float64 and tol >= MIXED_MIN_TOL and max_iter >= 2
        beliefs, packed, box = _bounded_uniform_block(prob, tables, link, floor, region,
                                                      np.float32 if mixed else dtype)
        if packed is None:
            return EngineResult(beliefs, lambda: initial_messages(shape, dtype), [0.0][:max_iter], {}, None)
        changes = packed.run(max_iter - 1 if mixed else max_iter, tol, threads, block=block, freeze=freeze, first=block,
                             confirm_settled=not mixed)  # float64 confirms
        if mixed:  # float64 from float32's messages, at least one iteration, until one moves none by tol
            packed = packed.widened(tables, prob, link, box[0], box[2])
            changes += packed.run(max_iter - len(changes), tol, threads, block=block, freeze=freeze)
        return EngineResult(*_bounded_uniform_result(beliefs, packed, box, dtype), changes, {}, None)
    if region is not None:
        msg, packed, corner = _bounded_block(prob, tables, link, floor, region, messages, dtype, states)
        changes = [0.0][:max_iter] if packed is None else packed.run(max_iter, tol, threads, block=block,
                                                                      freeze=freeze)
        if packed is not None:
            packed.messages(msg, *corner)
        unary = np.clip(link_unary(prob, link), floor, 1.0 - floor)
        return EngineResult(beliefs_from_messages(unary, msg), msg, changes, {}, states)
    packed, states = _whole_block(prob, tables, link, floor, messages, dtype, threads, states, fused)
    t.append(time.perf_counter())
    beliefs = beliefs_buffer(shape)  # the last pass writes them when it can (PackedBlock.run)
    changes = (packed.run(max_iter, tol, threads, block=block, freeze=freeze,
                          first=1 if messages is not None else block, beliefs=beliefs)
               if packed.active_cells else [0.0][:max_iter])  # every cell clamped: nothing to do
    t.append(time.perf_counter())
    if not packed.beliefs_written:  # also when every cell is clamped (no pass ran)
        packed.beliefs(beliefs)
    packed.un = None  # the result keeps only the packed messages
    # unpacked when read; only senders' slots are unpacked under clamps, so the others start as clamped
    msg = lambda: packed.messages(np.empty((4,) + shape, dtype) if states is None else  # noqa: E731
                                  clamp_messages(states, tables, initial_messages(shape, dtype)))
    t.append(time.perf_counter())
    return EngineResult(beliefs, msg, changes, dict(zip(("pack", "iterate", "unpack"), np.diff(t).tolist())), states)


def _whole_block(prob, tables, link, floor, messages, dtype, threads, states, fused):
    """The packed whole grid, ready to iterate, and the certain cells (found while packing when ``fused``)."""
    shape = prob.shape
    wp = plane_width(shape[1])  # buffers of the last call of this shape when free: no page faults
    arrays = packed_arrays((2, 4, shape[0] + 2, wp), (2, shape[0] + 2, wp), dtype)
    packed = PackedBlock(shape[0], shape[1], dtype, tables, floor, arrays, fill=not fused)
    if fused:
        bad, certain = packed.start_uniform(prob, link, threads)
        if bad:
            check_probability_array(prob, "grid")  # raises, naming what is wrong
            raise AssertionError("the packing's grid check and check_probability_array disagree")
        if not certain:
            return packed, states
        # hard evidence: the general path, which may then reuse these buffers
        packed = arrays = None
        states = certain_states(prob, link, tables)
        return _whole_block(prob, tables, link, floor, None, dtype, threads, states, False)
    packed.set_unary(prob, link)
    if messages is not None:
        packed.set_messages(np.ascontiguousarray(messages))
    if states is not None:
        packed.clamp(states, implied_messages(tables))
    return packed, states


def _packed_box(prob, tables, link, floor, active, dtype):
    """(the packed box of the senders plus a one-cell halo, with uniform messages, the box's observations and
    senders; the box (y0, y1, x0, x1)), or (None, None) if no cell sends."""
    rows = np.flatnonzero(active.any(axis=1))
    if not rows.size:
        return None, None
    cols = np.flatnonzero(active.any(axis=0))
    y0, y1 = max(int(rows[0]) - 1, 0), min(int(rows[-1]) + 2, prob.shape[0])
    x0, x1 = max(int(cols[0]) - 1, 0), min(int(cols[-1]) + 2, prob.shape[1])
    packed = PackedBlock(y1 - y0, x1 - x0, dtype, tables, floor)
    packed.set_unary(prob, link, y0, x0)
    packed.set_mask(active, y0, x0)
    return packed, (y0, y1, x0, x1)


def _bounded_uniform_block(prob, tables, link, floor, active, dtype):
    """Bounded LBP from uniform messages without hard evidence: (the beliefs outside the senders' box, which are the
    floored observations, the packed box or None if no cell sends, the box (y0, y1, x0, x1))."""
    beliefs = link_unary(prob, link)
    np.clip(beliefs, floor, 1.0 - floor, out=beliefs)
    return (beliefs,) + _packed_box(prob, tables, link, floor, active, dtype)


def _bounded_uniform_result(beliefs, packed, box, dtype):
    """(beliefs, messages) of an iterated :func:`_bounded_uniform_block`: the box's beliefs from its packed planes;
    the whole grid's messages unpacked when first read."""
    y0, y1, x0, x1 = box
    beliefs[y0:y1, x0:x1] = packed.beliefs()
    packed.un = None  # the result keeps only the box's messages (and its mask: the slots they fill)
    shape = beliefs.shape
    return beliefs, lambda: packed.messages(initial_messages(shape, dtype), y0, x0)


def _bounded_block(prob, tables, link, floor, active, messages, dtype, states):
    """(the whole grid's probability messages, the packed box around the senders or None if there are none,
    the box's lower-left cell (y0, x0))."""
    shape = prob.shape
    msg = initial_messages(shape, dtype) if messages is None else floored(messages, dtype, shape, floor)
    if states is not None:
        clamp_messages(states, tables, msg, active)
        active = active & (states < 0)
    packed, box = _packed_box(prob, tables, link, floor, active, dtype)
    if packed is None:
        return msg, None, (0, 0)
    packed.set_messages(msg, box[0], box[2])
    return msg, packed, (box[0], box[2])
