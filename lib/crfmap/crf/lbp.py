"""Loopy belief propagation on an occupancy grid's CRF (thesis sec. 2.6, 3.3, 3.4).

The CRF has one binary hidden node per cell (4-neighbour edges, potential ``hidden``) and one
observed node per cell holding the grid's P(occupied), which sends its hidden node one message
through ``link``. :func:`infer` runs sum-product LBP with normalised messages and returns the
beliefs P(occupied) as a grid plus the convergence diagnostics.

Schedules:

- ``"checkerboard"`` (default): red cells send, then black cells. Parallel, in place, and in our
  runs convergent where flooding oscillates.
- ``"flooding"``: every message from the previous iteration's messages (synchronous). Can
  oscillate on strong couplings; ``damping`` (0..1, weight of the old message) tames it.
- ``"sweep"``: four directional sweeps (thesis sec. 2.6.2): information crosses the grid per sweep.
- ``"thesis"``: breadth-first from a corner cell, each visited cell pulling fresh messages from
  its neighbours, in place (Listing 5); every iteration restarts from the last cell visited
  (sec. 2.6.2). ``max_iter=2`` is the thesis's setting.

Kernels: the checkerboard schedule (without damping) runs on the fast kernels of
:mod:`crfmap.crf._lbp_fast` by default (``kernel="auto"``): messages as odds ratios in red/black
planes, float32 SIMD, several iterations per trip through memory. They give the plain
kernel's iterations (to rounding) but measure the largest message change only on the last
iteration of each block of up to ``block`` iterations (blocks grow 1, 2, 4, ... so a warm
start still stops at once); the other entries of ``max_change`` are NaN, and a run may do up
to ``block - 1`` iterations more than the plain kernel before it sees ``tol``. On large grids,
tiles whose messages stopped moving (by more than ``freeze``, default ``tol / 100``) pause until
a neighbouring tile moves; a run ends only after an iteration of every cell moved no message by
``tol``, and ``freeze=0`` pauses only tiles that did not move at all (the plain iterations
exactly). ``kernel="plain"`` runs the reference kernels of :mod:`crfmap.crf._lbp_kernels`.

Bounded LBP (sec. 3.4.4): pass ``region`` (a boolean [y, x] mask, e.g. from :func:`disc_region`):
only cells in it send messages; every other message keeps its value (warm-start ``messages``
to carry them between calls). Cells outside a region never influence anything unless they
sent messages before.
"""
from __future__ import annotations

import time
import numpy as np

from crfmap.crf import _lbp_kernels as K
from crfmap.crf.compiling import announce_lbp
from crfmap.crf.evidence import certain_states, clamp_beliefs, clamp_messages
from crfmap.crf.fastpath import FREEZE, fused_start_applies, infer_fast, run_packed  # noqa: F401  (re-exported)
from crfmap.crf.messages import check_messages, floored, initial_messages
from crfmap.crf.multiscale import COARSE_TOL_FACTOR, INITS, coarse_messages
from crfmap.crf.packed import fast_tables_ok
from crfmap.crf.result import LBPResult, result_grid
from crfmap.errors import InputError
from crfmap.crf.regions import disc_region, near_known  # noqa: F401  (re-exported)
from crfmap.grid import OccupancyGrid, check_probability_array
from crfmap.crf.potentials import (
    DEFAULT_HIDDEN,
    DEFAULT_LINK,
    check_pairing,
    check_table,
    directional_tables,
    link_unary,
    message_coefficients,
)

SCHEDULES = ("checkerboard", "flooding", "sweep", "thesis")
KERNELS = ("auto", "fast", "plain")
DEFAULT_BLOCK = 16  # iterations per pass of the fast kernel (temporal blocking depth)
# Fast kernel: tiles whose messages moved by less than FREEZE * tol stop iterating until a
# neighbouring tile moves (see crfmap.crf.packed.PackedBlock.run); convergence is always
# decided by an iteration of every cell. FREEZE lives in crfmap.crf.fastpath.

# Messages and observations are kept in [MESSAGE_FLOOR, 1 - MESSAGE_FLOOR]: products of five
# factors then stay far above float32's smallest normal (1e-38), hard evidence (P = 0 or 1, or a
# table with zeros) stays finite, and contradicting hard evidence gives 0.5 rather than 0/0 = NaN.
MESSAGE_FLOOR = 1e-6


def message(table, sender_p) -> float:
    """P(receiver occupied) of one message through a 2x2 table from a sender at P(occupied) = sender_p.

    Thesis eq. 1 / Table 1:

    >>> round(message([[0.9, 0.1], [0.1, 0.9]], 0.8), 6)
    0.74
    """
    t = check_table(table, "table")
    c = message_coefficients(t[None])[0]
    p = float(sender_p)
    if not 0.0 <= p <= 1.0:
        raise InputError("sender_p", f"must be a probability in [0, 1], got {sender_p!r}")
    return float(K._message(p, 0.5, 0.5, 0.5, c[0], c[1], c[2], c[3], 0.0, 0.0, 0.0))


_BARE_GRID = OccupancyGrid(np.zeros((1, 1)))  # default metadata, for arrays checked while packed


def _as_grid(grid, name="grid") -> OccupancyGrid:
    if isinstance(grid, OccupancyGrid):
        return grid
    return OccupancyGrid(check_probability_array(grid, name))


def infer(
    grid,
    hidden=DEFAULT_HIDDEN,
    link=DEFAULT_LINK,
    *,
    schedule: str = "checkerboard",
    max_iter: int = 1000,
    tol: float = 1e-5,
    damping: float = 0.0,
    region=None,
    messages=None,
    pairing: str = "receiver",
    dtype=np.float64,
    start: str = "lower-left",
    threads: int | None = None,
    kernel: str = "auto",
    block: int = DEFAULT_BLOCK,
    freeze: float | None = None,
    init: str = "uniform",
) -> LBPResult:
    """Run loopy belief propagation on a grid's CRF.

    Parameters
    ----------
    grid : OccupancyGrid or 2-D array of P(occupied) in [0, 1], indexed [y, x]
    hidden, link : 2x2 tables (rows C1 C0, columns N1 N0); see :mod:`crfmap.crf.potentials`
    schedule : "checkerboard", "flooding", "sweep" or "thesis"
    max_iter : int
        Stop after this many iterations (the thesis used 2 with ``schedule="thesis"``).
    tol : float
        Stop once the largest message change of an iteration is below ``tol``.
    damping : float in [0, 1)
        New message = (1 - damping) * update + damping * old.
    region : boolean [y, x] mask or None
        Bounded LBP: only these cells send messages.
    messages : (4, H, W) array or None
        Warm start (e.g. ``previous_result.messages``); uniform when None.
    pairing : "receiver" (thesis) or "oriented" (proper pairwise CRF for non-symmetric tables)
    dtype : np.float64 or np.float32
    start : "lower-left", "lower-right", "upper-left", "upper-right"
        Corner where the ``"thesis"`` schedule begins.
    threads : int or None
        Numba threads for the parallel schedules (None: numba's default).
    kernel : "auto", "fast" or "plain"
        "auto" runs the fast kernels whenever they apply (checkerboard, no damping).
    block : int
        Fast kernel: at most this many iterations per trip through memory; the message change
        is measured on the last iteration of each block.
    freeze : float or None
        Fast kernel: tiles (``TILE_ROWS`` x ``TILE_COLS`` cells, :mod:`crfmap.crf.packed`) whose
        messages moved by at most this stop iterating until a neighbouring tile moves; None
        means ``FREEZE * tol``, 0 freezes only tiles that did not move at all (exactly the
        plain iterations). The result has always
        passed an iteration of every cell that moved no message by ``tol``.
    init : "uniform" or "coarse"
        Start messages when ``messages`` is None: uniform, or coarse-to-fine
        (:mod:`crfmap.crf.multiscale`: the grid halved recursively, each level solved with
        these arguments and its messages upsampled as the next level's warm start). Same
        fixed point where LBP has one; in the ordered phase it may reach another. ``seconds``
        includes the coarse levels (also ``timings["coarse"]``); ``iterations`` counts the
        full grid's only.

    Returns
    -------
    LBPResult

    Examples
    --------
    >>> r = infer(np.array([[0.9, 0.5, 0.9]]), max_iter=50, tol=1e-9)
    >>> bool(r.beliefs.probability[0, 1] > 0.5), r.converged
    (True, True)
    """
    if schedule not in SCHEDULES:
        raise InputError("schedule", f"must be one of {', '.join(SCHEDULES)}, got {schedule!r}")
    hidden = check_table(hidden, "hidden")
    link = check_table(link, "link")
    pairing = check_pairing(pairing)
    dtype = np.dtype(dtype)
    if dtype not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise InputError("dtype", f"must be float32 or float64, got {dtype}")
    if not (isinstance(max_iter, (int, np.integer)) and max_iter >= 0):
        raise InputError("max_iter", f"must be a non-negative integer, got {max_iter!r}")
    if not (np.isfinite(tol) and tol >= 0):
        raise InputError("tol", f"must be a non-negative number, got {tol!r}")
    if not (0.0 <= damping < 1.0):
        raise InputError("damping", f"must be in [0, 1), got {damping!r}")
    if kernel not in KERNELS:
        raise InputError("kernel", f"must be one of {', '.join(KERNELS)}, got {kernel!r}")
    if not (isinstance(block, (int, np.integer)) and block >= 1):
        raise InputError("block", f"must be a positive integer, got {block!r}")
    if freeze is not None and not (np.isfinite(freeze) and 0 <= freeze and (freeze < tol or freeze == 0)):
        raise InputError("freeze", f"must be None or a number in [0, tol), got {freeze!r}")
    if threads is not None and not (isinstance(threads, (int, np.integer)) and threads >= 1):
        raise InputError("threads", f"must be a positive integer or None, got {threads!r}")
    if init not in INITS:
        raise InputError("init", f"must be one of {', '.join(INITS)}, got {init!r}")
    if init == "coarse" and (messages is not None or region is not None):
        raise InputError("init", '"coarse" starts the whole grid without messages: drop messages= and region=')
    tables = directional_tables(hidden, pairing)
    fast_ok = schedule == "checkerboard" and damping == 0.0 and fast_tables_ok(tables)
    if kernel == "fast" and not fast_ok:
        raise InputError("kernel", "the fast kernels run the checkerboard schedule without damping only")
    use_fast = fast_ok and kernel != "plain"
    # the common call (a float64 array, whole grid, uniform start) is checked while it is packed
    given = isinstance(grid, OccupancyGrid)  # checked when made; an array is checked while packed (fused)
    fused = use_fast and init == "uniform" and fused_start_applies(grid.probability if given else grid, tables,
                                                                   max_iter, block, region, messages)
    g = result_grid(_BARE_GRID, grid) if fused and not given else _as_grid(grid)
    coarse_seconds = None
    if init == "coarse":
        t0 = time.perf_counter()
        messages, _ = coarse_messages(g.probability, lambda p, m: infer(
            p, hidden, link, schedule=schedule, max_iter=max_iter, tol=tol * COARSE_TOL_FACTOR, damping=damping, messages=m,
            pairing=pairing, dtype=dtype, start=start, threads=threads, kernel=kernel, block=block, freeze=freeze))
        coarse_seconds = time.perf_counter() - t0 if messages is not None else None

    shape = g.shape
    if messages is not None:
        messages = check_messages(messages, shape)
    active = None
    if region is not None:
        active = np.asarray(region)
        if active.shape != shape:
            raise InputError("region", f"mask shape {active.shape} does not match the grid {shape}")
        active = active.astype(np.bool_, copy=False)
    # hard evidence: certain cells are clamped (never updated, sending what their state implies)
    states = None if fused else certain_states(g.probability, link, tables, active)  # fused: found while packing
    sending = states if max_iter else None  # clamped cells send from the first iteration on
    senders = active if sending is None else (sending < 0 if active is None else active & (sending < 0))

    import numba

    previous_threads = numba.get_num_threads()
    n_threads = previous_threads if threads is None else min(int(threads), numba.config.NUMBA_NUM_THREADS)
    announce_lbp(use_fast, schedule, g.probability.size, n_threads, bool(fused))
    numba.set_num_threads(n_threads)
    try:
        t0 = time.perf_counter()
        if use_fast:
            prob = np.ascontiguousarray(g.probability, dtype=np.float64)
            out = infer_fast(prob, tables, link, MESSAGE_FLOOR, max_iter, tol, active, messages, dtype, n_threads,
                             block, freeze, sending, fused)
            states = out[4] if fused else states  # fused: the certain cells the packing found
        else:
            out = _infer_plain(g, hidden, link, schedule, max_iter, tol, damping, senders, messages, pairing,
                               dtype, start, (sending, active))
        beliefs, msg, changes = out[:3]
        if states is not None:
            clamp_beliefs(states, beliefs)
        seconds = time.perf_counter() - t0 + (coarse_seconds or 0.0)
    finally:
        numba.set_num_threads(previous_threads)

    max_change = np.asarray(changes, dtype=np.float64)
    converged = bool(max_change.size and max_change[-1] < tol)
    if not use_fast:  # the fast kernels' b / (1 + b) lies in [0, 1] already
        np.clip(beliefs, 0.0, 1.0, out=beliefs)
    timings = out[3] if len(out) > 3 else {}
    if coarse_seconds is not None:
        timings["coarse"] = coarse_seconds
    return LBPResult(
        beliefs=result_grid(g, beliefs),
        iterations=len(max_change),
        max_change=max_change,
        converged=converged,
        messages=msg,
        seconds=seconds,
        schedule=schedule,
        kernel="fast" if use_fast else "plain",
        timings=timings,
    )


def _infer_plain(g, hidden, link, schedule, max_iter, tol, damping, active, messages, pairing, dtype, start, clamped):
    """The reference kernels of :mod:`crfmap.crf._lbp_kernels`; returns (beliefs, messages, changes).

    ``active``: the senders; ``clamped``: (certain states or None, the region or None).
    """
    shape = g.shape
    unary = np.clip(link_unary(g.probability, link), MESSAGE_FLOOR, 1.0 - MESSAGE_FLOOR).astype(dtype)
    tables = directional_tables(hidden, pairing)
    coef = message_coefficients(tables).astype(dtype)
    msg = initial_messages(shape, dtype) if messages is None else floored(messages, dtype, shape, MESSAGE_FLOOR)
    if clamped[0] is not None:
        clamp_messages(clamped[0], tables, msg, clamped[1])
    # the thesis's walk visits the region (clamped cells included); only ``active`` cells send
    walk = clamped[1]
    if active is None:
        active = np.ones((1, 1), dtype=np.bool_)
        use_active = False
        y0, y1 = 0, shape[0]
    else:
        use_active = True
        rows = np.flatnonzero(active.any(axis=1))
        y0, y1 = (int(rows[0]), int(rows[-1]) + 1) if rows.size else (0, 0)
    floor = float(MESSAGE_FLOOR)
    damping = float(damping)
    changes = []
    if schedule == "flooding":
        new = msg.copy()
    if schedule == "thesis":
        corner = {"lower-left": (0, 0), "lower-right": (0, shape[1] - 1),
                  "upper-left": (shape[0] - 1, 0), "upper-right": (shape[0] - 1, shape[1] - 1)}
        if start not in corner:
            raise InputError("start", f"must be one of {', '.join(corner)}, got {start!r}")
        sy, sx = corner[start]
        use_walk = walk is not None
        walk = walk if use_walk else np.ones((1, 1), np.bool_)
        if use_walk and not walk[sy, sx]:
            cells = np.argwhere(walk)
            if cells.size:
                sy, sx = (int(v) for v in cells[0])
    for _ in range(max_iter):
        if schedule == "checkerboard":
            c = K._checkerboard_iteration(unary, msg, coef, active, use_active, y0, y1, floor, damping)
        elif schedule == "flooding":
            c = K._flooding_iteration(unary, msg, new, coef, active, use_active, y0, y1, floor, damping)
            msg, new = new, msg
            new[...] = msg  # slots not written this round (inactive senders) keep their values
        elif schedule == "sweep":
            c = K._sweep_iteration(unary, msg, coef, active, use_active, y0, y1, floor, damping)
        else:
            order = K._bfs_order(shape[0], shape[1], walk, use_walk, sy, sx)
            c = K._pull_iteration(unary, msg, coef, active, use_active, order, floor, damping)
            if order.size:  # the next pass starts where this one ended (sec. 2.6.2)
                sy, sx = divmod(int(order[-1]), shape[1])
        changes.append(float(c))
        if c < tol:
            break
    beliefs = np.empty(shape, dtype=np.float64)
    K._beliefs(unary, msg, beliefs)
    return beliefs, msg, changes
