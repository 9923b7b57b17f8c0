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

Bounded LBP (sec. 3.4.4): pass ``region`` (a boolean [y, x] mask, e.g. from :func:`disc_region`):
only cells in it send messages; every other message keeps its value (warm-start ``messages``
to carry them between calls). Cells outside a region never influence anything unless they
sent messages before.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from . import _lbp_kernels as K
from .errors import InputError
from .grid import OccupancyGrid, check_probability_array
from .potentials import (
    DEFAULT_HIDDEN,
    DEFAULT_LINK,
    check_pairing,
    check_table,
    directional_tables,
    link_unary,
    message_coefficients,
)

SCHEDULES = ("checkerboard", "flooding", "sweep", "thesis")

# Messages and observations are kept in [MESSAGE_FLOOR, 1 - MESSAGE_FLOOR]: products of five
# factors then stay far above float32's smallest normal (1e-38), hard evidence (P = 0 or 1, or a
# table with zeros) stays finite, and contradicting hard evidence gives 0.5 rather than 0/0 = NaN.
MESSAGE_FLOOR = 1e-6


@dataclass
class LBPResult:
    """What :func:`infer` returns.

    Attributes
    ----------
    beliefs : OccupancyGrid
        P(occupied) of every hidden cell, with the input grid's metadata.
    iterations : int
        Iterations done (one iteration updates every message once; for ``"thesis"`` one pass).
    max_change : ndarray
        The largest message change at every iteration (length ``iterations``).
    converged : bool
        Whether the last change fell below ``tol``.
    messages : ndarray
        The final messages, shape (4, H, W); pass them back as ``messages=`` to warm-start.
    seconds : float
        Wall time of the iterations (compilation excluded after the first call).
    """

    beliefs: OccupancyGrid
    iterations: int
    max_change: np.ndarray
    converged: bool
    messages: np.ndarray = field(repr=False)
    seconds: float = 0.0
    schedule: str = "checkerboard"

    def summary(self) -> str:
        last = f"{self.max_change[-1]:.2e}" if len(self.max_change) else "n/a"
        state = "converged" if self.converged else "not converged"
        return f"{self.schedule}: {self.iterations} iterations, {state} (last max message change {last})"


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


def _as_grid(grid, name="grid") -> OccupancyGrid:
    if isinstance(grid, OccupancyGrid):
        return grid
    return OccupancyGrid(check_probability_array(grid, name))


def initial_messages(shape, dtype=np.float64) -> np.ndarray:
    """Uniform messages (0.5) for a grid of ``shape`` = (H, W)."""
    return np.full((4,) + tuple(shape), 0.5, dtype=dtype)


def disc_region(grid, center, radius) -> np.ndarray:
    """Boolean [y, x] mask of cells whose centres lie within ``radius`` [m] of ``center`` (x, y) [m].

    >>> g = OccupancyGrid(np.full((5, 5), 0.5))
    >>> int(disc_region(g, (2.5, 2.5), 1.0).sum())
    5
    """
    g = _as_grid(grid)
    ys, xs = np.mgrid[0 : g.height, 0 : g.width]
    wx, wy = g.cell_to_world(xs, ys)
    return (wx - center[0]) ** 2 + (wy - center[1]) ** 2 <= radius * radius


def near_known(grid, margin: int) -> np.ndarray:
    """Boolean [y, x] mask of cells within ``margin`` cells (Chebyshev distance) of an observed cell.

    With the default coupling the CRF is in its ordered phase: a large never-observed area far
    from any observation does not stay at 0.5 under LBP but takes the state of its border. Passing
    this mask as ``region`` (and keeping the input outside it) fills gaps and occlusions up to
    ``margin`` cells deep and leaves the unexplored outside unknown.

    >>> m = near_known(np.array([[0.5, 0.5, 0.5, 0.9]]), 1)
    >>> m.astype(int).tolist()
    [[0, 0, 1, 1]]
    """
    g = _as_grid(grid)
    if not (isinstance(margin, (int, np.integer)) and margin >= 0):
        raise InputError("margin", f"must be a non-negative whole number of cells, got {margin!r}")
    mask = g.known()
    # a separable max-filter: dilate rows, then columns, by margin cells
    for axis in (0, 1):
        out = mask.copy()
        for shift in range(1, int(margin) + 1):
            if shift >= mask.shape[axis]:
                break
            sl_a = [slice(None)] * 2
            sl_b = [slice(None)] * 2
            sl_a[axis], sl_b[axis] = slice(shift, None), slice(None, -shift)
            out[tuple(sl_a)] |= mask[tuple(sl_b)]
            out[tuple(sl_b)] |= mask[tuple(sl_a)]
        mask = out
    return mask


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
) -> LBPResult:
    """Run loopy belief propagation on a grid's CRF.

    Parameters
    ----------
    grid : OccupancyGrid or 2-D array of P(occupied) in [0, 1], indexed [y, x]
    hidden, link : 2x2 tables (rows C1 C0, columns N1 N0); see :mod:`crfmap.potentials`
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

    Returns
    -------
    LBPResult

    Examples
    --------
    >>> r = infer(np.array([[0.9, 0.5, 0.9]]), max_iter=50, tol=1e-9)
    >>> bool(r.beliefs.probability[0, 1] > 0.5), r.converged
    (True, True)
    """
    g = _as_grid(grid)
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

    shape = g.shape
    unary = np.clip(link_unary(g.probability, link), MESSAGE_FLOOR, 1.0 - MESSAGE_FLOOR).astype(dtype)
    coef = message_coefficients(directional_tables(hidden, pairing)).astype(dtype)

    if messages is None:
        msg = initial_messages(shape, dtype)
    else:
        msg = np.asarray(messages)
        if msg.shape != (4,) + shape:
            raise InputError("messages", f"expected shape {(4,) + shape} for this grid, got {msg.shape}")
        if not np.all(np.isfinite(msg)) or msg.min() < 0 or msg.max() > 1:
            raise InputError("messages", "must be finite probabilities in [0, 1]")
        msg = np.clip(msg, MESSAGE_FLOOR, 1.0 - MESSAGE_FLOOR).astype(dtype, copy=True)
        # slots with no neighbour behind them must stay uniform
        msg[0, :, 0] = msg[1, :, -1] = msg[2, 0, :] = msg[3, -1, :] = 0.5

    if region is None:
        active = np.ones((1, 1), dtype=np.bool_)
        use_active = False
        y0, y1 = 0, shape[0]
    else:
        active = np.asarray(region)
        if active.shape != shape:
            raise InputError("region", f"mask shape {active.shape} does not match the grid {shape}")
        active = active.astype(np.bool_)
        use_active = True
        rows = np.flatnonzero(active.any(axis=1))
        y0, y1 = (int(rows[0]), int(rows[-1]) + 1) if rows.size else (0, 0)

    floor = float(MESSAGE_FLOOR)
    damping = float(damping)
    changes = []
    previous_threads = None
    if threads is not None:
        import numba

        previous_threads = numba.get_num_threads()
        numba.set_num_threads(int(threads))
    try:
        t0 = time.perf_counter()
        if schedule == "flooding":
            new = msg.copy()
        if schedule == "thesis":
            corner = {"lower-left": (0, 0), "lower-right": (0, shape[1] - 1),
                      "upper-left": (shape[0] - 1, 0), "upper-right": (shape[0] - 1, shape[1] - 1)}
            if start not in corner:
                raise InputError("start", f"must be one of {', '.join(corner)}, got {start!r}")
            sy, sx = corner[start]
            if use_active and not active[sy, sx]:
                cells = np.argwhere(active)
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
                order = K._bfs_order(shape[0], shape[1], active, use_active, sy, sx)
                c = K._pull_iteration(unary, msg, coef, active, use_active, order, floor, damping)
                if order.size:  # the next pass starts where this one ended (sec. 2.6.2)
                    sy, sx = divmod(int(order[-1]), shape[1])
            changes.append(float(c))
            if c < tol:
                break
        beliefs = np.empty(shape, dtype=np.float64)
        K._beliefs(unary, msg, beliefs)
        seconds = time.perf_counter() - t0
    finally:
        if previous_threads is not None:
            import numba

            numba.set_num_threads(previous_threads)

    max_change = np.asarray(changes, dtype=np.float64)
    converged = bool(max_change.size and max_change[-1] < tol)
    return LBPResult(
        beliefs=g.with_probability(np.clip(beliefs, 0.0, 1.0)),
        iterations=len(changes),
        max_change=max_change,
        converged=converged,
        messages=msg,
        seconds=seconds,
        schedule=schedule,
    )
