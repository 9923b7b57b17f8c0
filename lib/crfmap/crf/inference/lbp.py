"""Loopy belief propagation on an occupancy grid's CRF (thesis sec. 2.6, 3.3, 3.4): :func:`infer`.

The CRF has one binary hidden node per cell (4-neighbour edges, potential ``hidden``) and one observed node per cell
holding the grid's P(occupied), which sends its hidden node one message through ``link``. :func:`infer` checks its
input, clamps hard evidence (:mod:`crfmap.crf.model.evidence`), runs sum-product LBP with normalised messages on the
schedule asked for (the checkerboard without damping on the fast engine, :mod:`crfmap.crf.engine`: the plain kernel's
iterations to rounding) and returns the beliefs with the convergence diagnostics.

Bounded LBP (sec. 3.4.4): with ``region`` (e.g. :func:`crfmap.crf.inference.regions.disc_region`) only the cells in
it send; every other message keeps its value (warm-start ``messages`` to carry them between calls)."""
from __future__ import annotations

import time
import warnings

import numpy as np
import numba

from crfmap.checks import check_mask, check_number
from crfmap.crf.engine import solve as engine
from crfmap.crf.engine.messages import MESSAGE_FLOOR, check_messages
from crfmap.crf.engine.packed import PASS_ITERATIONS, fast_tables_ok
from crfmap.crf.inference import _plain_kernels as K
from crfmap.crf.inference.compiling import announcing, compile_timer
from crfmap.crf.inference.multiscale import COARSE_TOL_FACTOR, INITS, coarse_messages
from crfmap.crf.inference.result import LBPResult, result_grid
from crfmap.crf.inference.schedules import run_schedule, schedule_settings
from crfmap.crf.model.evidence import certain_states, clamp_beliefs
from crfmap.crf.model.potentials import (
    DEFAULT_HIDDEN,
    DEFAULT_LINK,
    check_pairing,
    check_table,
    check_table_fits,
    directional_tables,
    message_coefficients,
)
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid, as_grid, check_probability_array


def message(table, sender_p) -> float:
    """P(receiver occupied) of one message through a 2x2 table from a sender at P(occupied) = sender_p (thesis eq. 1,
    Table 1).

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


def check_float_dtype(dtype) -> np.dtype:
    """``dtype`` as np.float32 or np.float64; InputError naming ``dtype`` for anything else (None, 'abc', int).

    >>> check_float_dtype("float32")
    dtype('float32')
    """
    try:
        checked = np.dtype(dtype) if dtype is not None else None
    except (TypeError, ValueError):
        checked = None
    if checked is None or checked not in (np.dtype(np.float32), np.dtype(np.float64)):  # (dtype == None is True)
        raise InputError("dtype", f"must be np.float32 or np.float64, got {dtype!r}")
    return checked


def warn_near_certain(probability, name: str = "grid") -> int:
    """Warn (once per call) when cells have P within :data:`MESSAGE_FLOOR` of 0 or 1 without being 0 or 1; their count.

    LBP reads such a cell as MESSAGE_FLOOR away from certain, which under a strong coupling can change the result by
    far more than the floor; exactly 0 or 1 is hard evidence, and exact.

    >>> warn_near_certain(np.array([[0.0, 0.3, 1.0]]))
    0
    """
    p = np.asarray(probability)
    if p.size == 0 or (p.min() >= MESSAGE_FLOOR and p.max() <= 1 - MESSAGE_FLOOR):
        return 0
    near = int(np.count_nonzero(((p > 0) & (p < MESSAGE_FLOOR)) | ((p > 1 - MESSAGE_FLOOR) & (p < 1))))
    if near:
        warnings.warn(f"{name}: {near} cell(s) have P within {MESSAGE_FLOOR:g} of 0 or 1 without being 0 or 1; LBP "
                      f"reads them as {MESSAGE_FLOOR:g} from certain (give exactly 0 or 1 for hard evidence)",
                      stacklevel=3)
    return near


def infer(
    grid,
    hidden=DEFAULT_HIDDEN,
    link=DEFAULT_LINK,
    *,
    schedule="checkerboard",
    max_iter: int = 1000,
    tol: float = 1e-5,
    region=None,
    messages=None,
    pairing: str = "receiver",
    dtype=np.float64,
    threads: int | None = None,
    init: str = "uniform",
) -> LBPResult:
    """Run loopy belief propagation on a grid's CRF; returns an :class:`LBPResult`.

    ``grid``: an OccupancyGrid or a 2-D array of P(occupied) in [0, 1], indexed [y, x]. ``hidden``, ``link``: 2x2 tables
    (:mod:`crfmap.crf.model.potentials`). ``schedule``: a name or settings of :mod:`crfmap.crf.inference.schedules`.
    Iterations stop after ``max_iter`` (the thesis used 2 with ``schedule="thesis"``) or once an iteration's largest
    message change is below ``tol``. ``region``: a boolean [y, x] mask of the senders (bounded LBP). ``messages``:
    a (4, H, W) warm start (e.g. ``previous_result.messages``). ``pairing``: ``"receiver"`` (thesis) or ``"oriented"``.
    ``threads``: None for numba's default. ``dtype``: np.float64 or np.float32 (bounded LBP in float64 iterates in
    float32 first: :mod:`crfmap.crf.engine.solve`). ``init``: ``"uniform"`` start messages or ``"coarse"``-to-fine
    (:mod:`crfmap.crf.inference.multiscale`; ``seconds`` includes the coarse levels, ``iterations`` counts the full
    grid's only).

    >>> r = infer(np.array([[0.9, 0.5, 0.9]]), max_iter=50, tol=1e-9)
    >>> bool(r.beliefs.probability[0, 1] > 0.5), r.converged
    (True, True)
    """
    if isinstance(grid, np.ma.MaskedArray):  # the fused path reads the data under the mask: refuse masked cells
        grid = check_probability_array(grid, "grid")
    settings = schedule_settings(schedule)
    hidden = check_table(hidden, "hidden")
    link = check_table(link, "link")
    pairing = check_pairing(pairing)
    dtype = check_float_dtype(dtype)
    hidden = check_table_fits(hidden, dtype, "hidden")  # in the dtype the kernels compute in
    link = check_table_fits(link, dtype, "link")
    if isinstance(max_iter, (bool, np.bool_)) or not (isinstance(max_iter, (int, np.integer)) and max_iter >= 0):
        raise InputError("max_iter", f"must be a non-negative integer, got {max_iter!r}")
    tol = check_number("tol", tol, low=0.0)
    freeze = getattr(settings, "freeze", None)
    if freeze is not None and not (freeze < tol or freeze == 0):
        raise InputError("freeze", f"must be None or a number in [0, tol), got {freeze!r}")
    if threads is not None and not (isinstance(threads, (int, np.integer)) and threads >= 1):
        raise InputError("threads", f"must be a positive integer or None, got {threads!r}")
    if init not in INITS:
        raise InputError("init", f"must be one of {', '.join(INITS)}, got {init!r}")
    if init == "coarse" and (messages is not None or region is not None):
        raise InputError("init", '"coarse" starts the whole grid without messages: drop messages= and region=')
    tables = directional_tables(hidden, pairing)
    use_fast = settings.uses_engine and fast_tables_ok(tables)
    if settings.uses_engine and settings.kernel == "fast" and not use_fast:
        raise InputError("kernel", "the fast kernels need east/north and west/south to share a table")
    block = PASS_ITERATIONS if getattr(settings, "block", None) is None else settings.block
    given = isinstance(grid, OccupancyGrid)  # checked when made; an array is checked while packed (fused)
    fused = use_fast and init == "uniform" and engine.fused_start_applies(
        grid.probability if given else grid, tables, max_iter, block, region, messages)
    g = result_grid(_BARE_GRID, grid) if fused and not given else as_grid(grid)
    warn_near_certain(g.probability)
    coarse_seconds = None
    if init == "coarse":
        t0 = time.perf_counter()
        messages, _ = coarse_messages(g.probability, lambda p, m: infer(
            p, hidden, link, schedule=settings, max_iter=max_iter, tol=tol * COARSE_TOL_FACTOR, messages=m,
            pairing=pairing, dtype=dtype, threads=threads))
        coarse_seconds = time.perf_counter() - t0 if messages is not None else None

    shape = g.shape
    if messages is not None:
        messages = check_messages(messages, shape)
    active = None
    if region is not None:
        active = check_mask("region", region, shape)
    # hard evidence: certain cells are clamped (never updated, sending what their state implies)
    states = None if fused else certain_states(g.probability, link, tables, active)  # fused: found while packing
    sending = states if max_iter else None  # clamped cells send from the first iteration on
    senders = active if sending is None else (sending < 0 if active is None else active & (sending < 0))

    previous_threads = numba.get_num_threads()
    n_threads = previous_threads if threads is None else min(int(threads), numba.config.NUMBA_NUM_THREADS)
    numba.set_num_threads(n_threads)
    try:
        t0 = time.perf_counter()
        timings = {}
        with announcing(), compile_timer() as compiled:  # a compile says so as it starts
            if use_fast:
                prob = np.ascontiguousarray(g.probability, dtype=np.float64)
                out = engine.solve(prob, tables, link, max_iter=max_iter, tol=tol, dtype=dtype, threads=n_threads,
                                   region=active, messages=messages, states=sending, fused=fused, block=block,
                                   freeze=freeze, floor=MESSAGE_FLOOR)
                beliefs, msg, changes, timings = out.beliefs, out.messages, out.changes, out.timings
                states = out.states if fused else states  # fused: the certain cells the packing found
            else:
                beliefs, msg, changes = run_schedule(settings, g.probability, tables, link, max_iter, tol, senders,
                                                     messages, dtype, MESSAGE_FLOOR, (sending, active))
        if states is not None:
            clamp_beliefs(states, beliefs)
        # the first call's compile is not LBP time: reported apart (timings["compile"])
        seconds = time.perf_counter() - t0 - compiled.seconds + (coarse_seconds or 0.0)
    finally:
        numba.set_num_threads(previous_threads)
    if compiled.seconds > 0:
        timings["compile"] = compiled.seconds

    max_change = np.asarray(changes, dtype=np.float64)
    converged = bool(max_change.size and max_change[-1] < tol)
    if not use_fast:  # the fast kernels' b / (1 + b) lies in [0, 1] already
        np.clip(beliefs, 0.0, 1.0, out=beliefs)
    if coarse_seconds is not None:
        timings["coarse"] = coarse_seconds
    return LBPResult(
        beliefs=result_grid(g, beliefs),
        iterations=len(max_change),
        max_change=max_change,
        converged=converged,
        messages=msg,
        seconds=seconds,
        schedule=settings.name,
        kernel="fast" if use_fast else "plain",
        timings=timings,
    )
