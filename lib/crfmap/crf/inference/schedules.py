"""LBP schedules, each with the settings that apply to it only, and the plain kernels that run them.

Pass one as ``infer(grid, schedule=...)``: a name (its settings' defaults) or a settings object.

- :class:`Checkerboard` (``"checkerboard"``, the default): red cells send, then black cells; parallel, in place.
  Runs on the fast engine (:mod:`crfmap.crf.engine`) unless ``kernel="plain"`` or ``damping`` asks for the plain one.
- :class:`Flooding` (``"flooding"``): every message from the previous iteration's (synchronous). Can oscillate on
  strong couplings; ``damping`` tames it.
- :class:`Sweep` (``"sweep"``): four directional sweeps (thesis sec. 2.6.2): information crosses the grid per sweep.
- :class:`Thesis` (``"thesis"``): breadth-first from a corner cell, each visited cell pulling fresh messages from its
  neighbours, in place (Listing 5); every iteration restarts from the last cell visited. One thread.

``damping`` (in [0, 1), the weight of the old message) applies to the plain kernels. An option given to a schedule
or kernel it does not apply to is refused (:class:`crfmap.errors.InputError`).

>>> Thesis(start="upper-left").name, Checkerboard().uses_engine
('thesis', True)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crfmap.checks import check_settings, check_number
from crfmap.crf.engine.messages import beliefs_from_messages, floored, initial_messages
from crfmap.crf.engine.progress import passed
from crfmap.crf.inference import _plain_kernels as K
from crfmap.crf.model.evidence import clamp_messages
from crfmap.crf.model.potentials import link_unary, message_coefficients
from crfmap.crf.threads import over_rows
from crfmap.errors import InputError

KERNELS = ("auto", "fast", "plain")
CORNERS = ("lower-left", "lower-right", "upper-left", "upper-right")


def _check_damping(damping):
    if check_number("damping", damping, low=0.0, high=1.0) == 1.0:
        raise InputError("damping", f"must be in [0, 1), got {damping!r}")


@dataclass(frozen=True)
class Checkerboard:
    """Red cells send, then black ones. ``block`` and ``freeze`` apply to the fast engine only; a run ends only after
    an iteration of every cell moved no message by ``tol``."""

    kernel: str = "auto"  # "auto" (the fast engine unless damping), "fast" or "plain"
    damping: float = 0.0  # plain kernel only
    # iterations per trip through memory at most (None: crfmap.crf.engine.packed.PASS_ITERATIONS); the message
    # change is measured on the last of each pass, the others are NaN in max_change
    block: int | None = None
    # tiles whose messages moved by at most this pause until a neighbouring tile moves (None: packed.FREEZE * tol;
    # 0: only tiles that did not move at all, exactly the plain iterations); below tol
    freeze: float | None = None
    name = "checkerboard"

    def __post_init__(self):
        if self.kernel not in KERNELS:
            raise InputError("kernel", f"must be one of {', '.join(KERNELS)}, got {self.kernel!r}")
        _check_damping(self.damping)
        if self.kernel == "fast" and self.damping != 0.0:
            raise InputError("damping", "the fast kernel runs without damping; use kernel='plain' (or 'auto')")
        if self.block is not None and not (isinstance(self.block, (int, np.integer)) and self.block >= 1):
            raise InputError("block", f"must be a positive integer, got {self.block!r}")
        if self.freeze is not None and not (np.isfinite(self.freeze) and self.freeze >= 0):
            raise InputError("freeze", f"must be None or a non-negative number below tol, got {self.freeze!r}")
        if not self.uses_engine:
            why = "kernel='plain'" if self.kernel == "plain" else "damping runs the plain kernel"
            for option in ("block", "freeze"):
                if getattr(self, option) is not None:
                    raise InputError(option, f"applies to the fast kernel only ({why})")

    @property
    def uses_engine(self) -> bool:
        """Whether this runs on the fast engine."""
        return self.kernel != "plain" and self.damping == 0.0


@dataclass(frozen=True)
class _Damped:
    """A schedule of the plain kernels whose one option is ``damping`` in [0, 1)."""

    damping: float = 0.0
    uses_engine = False

    def __post_init__(self):
        _check_damping(self.damping)


@dataclass(frozen=True)
class Flooding(_Damped):
    """Every cell sends from the previous iteration's messages; ``damping`` in [0, 1)."""

    name = "flooding"


@dataclass(frozen=True)
class Sweep(_Damped):
    """Four directional sweeps per iteration; ``damping`` in [0, 1)."""

    name = "sweep"


@dataclass(frozen=True)
class Thesis:
    """The thesis's breadth-first pull schedule from the corner ``start`` (one of :data:`CORNERS`)."""

    start: str = "lower-left"
    damping: float = 0.0
    name = "thesis"
    uses_engine = False

    def __post_init__(self):
        if self.start not in CORNERS:
            raise InputError("start", f"must be one of {', '.join(CORNERS)}, got {self.start!r}")
        _check_damping(self.damping)


SETTINGS = {s.name: s for s in (Checkerboard, Flooding, Sweep, Thesis)}
SCHEDULES = tuple(SETTINGS)


def schedule_settings(schedule):
    """The settings object of ``schedule``: a name (its defaults) or a settings object, else InputError."""
    return check_settings("schedule", schedule, SETTINGS,
                          f"must be one of {', '.join(SCHEDULES)} or their settings (Checkerboard(...), ...)")


@dataclass
class _PlainRun:
    """What a plain schedule's iteration works on."""

    unary: np.ndarray
    msg: np.ndarray
    coef: np.ndarray
    active: np.ndarray
    use_active: bool
    y0: int
    y1: int
    floor: float
    damping: float
    walk: np.ndarray | None  # the thesis's walk: the region (None: every cell)
    scratch: dict  # a schedule's own state between iterations


def _checkerboard_iteration(settings, r):
    return max(max(over_rows(K._send_rows, r.y1 - r.y0, r.unary, r.msg, r.msg, r.coef, r.active, r.use_active,
                             parity, r.y0, r.floor, r.damping), default=0.0) for parity in (0, 1))


def _flooding_iteration(settings, r):
    new = r.scratch.setdefault("new", r.msg.copy())
    c = max(over_rows(K._send_rows, r.y1 - r.y0, r.unary, r.msg, new, r.coef, r.active, r.use_active, -1, r.y0,
                      r.floor, r.damping), default=0.0)
    r.msg[...] = new  # ``new`` keeps them too: slots not written next round (inactive senders) keep their values
    return c


def _sweep_iteration(settings, r):
    shape = r.unary.shape
    return max([max(over_rows(K._sweep_along_rows, r.y1 - r.y0, r.unary, r.msg, r.coef, r.active, r.use_active, d,
                              r.y0, r.floor, r.damping), default=0.0) for d in (0, 1)]
               + [max(over_rows(K._sweep_along_columns, shape[1], r.unary, r.msg, r.coef, r.active, r.use_active, d,
                                r.y0, r.y1, r.floor, r.damping), default=0.0) for d in (2, 3)])


def _thesis_iteration(settings, r):
    shape = r.unary.shape
    if "start" not in r.scratch:
        corner = {"lower-left": (0, 0), "lower-right": (0, shape[1] - 1),
                  "upper-left": (shape[0] - 1, 0), "upper-right": (shape[0] - 1, shape[1] - 1)}
        sy, sx = corner[settings.start]
        use_walk = r.walk is not None
        walk = r.walk if use_walk else np.ones((1, 1), np.bool_)
        if use_walk and not walk[sy, sx]:
            cells = np.argwhere(walk)
            if cells.size:
                sy, sx = (int(v) for v in cells[0])
        r.scratch.update(start=(sy, sx), walk=walk, use_walk=use_walk)
    sy, sx = r.scratch["start"]
    order = K._bfs_order(shape[0], shape[1], r.scratch["walk"], r.scratch["use_walk"], sy, sx)
    c = K._pull_iteration(r.unary, r.msg, r.coef, r.active, r.use_active, order, r.floor, r.damping)
    if order.size:
        r.scratch["start"] = divmod(int(order[-1]), shape[1])
    return c


# name -> one iteration of the plain schedule: a new schedule is its settings class, one entry here, and its kernels
PLAIN_RUNNERS = {
    "checkerboard": _checkerboard_iteration,
    "flooding": _flooding_iteration,
    "sweep": _sweep_iteration,
    "thesis": _thesis_iteration,
}


def run_schedule(settings, probability, tables, link, max_iter, tol, senders, messages, dtype, floor, clamped):
    """A plain schedule from start to end: (beliefs, messages, changes). ``senders``: the cells that send or None
    (all); ``clamped``: (certain states or None, the region or None)."""
    shape = probability.shape
    unary = np.clip(link_unary(probability, link), floor, 1.0 - floor).astype(dtype)
    coef = message_coefficients(tables).astype(dtype)
    msg = initial_messages(shape, dtype) if messages is None else floored(messages, dtype, shape, floor)
    if clamped[0] is not None:
        clamp_messages(clamped[0], tables, msg, clamped[1])
    if senders is None:
        active, use_active, y0, y1 = np.ones((1, 1), dtype=np.bool_), False, 0, shape[0]
    else:
        active, use_active = senders, True
        rows = np.flatnonzero(active.any(axis=1))
        y0, y1 = (int(rows[0]), int(rows[-1]) + 1) if rows.size else (0, 0)
    # the thesis's walk visits the region (clamped cells included); only senders send
    run = _PlainRun(unary, msg, coef, active, use_active, y0, y1, float(floor), float(settings.damping), clamped[1], {})
    iteration = PLAIN_RUNNERS[settings.name]
    changes = []
    for _ in range(max_iter):
        c = iteration(settings, run)
        changes.append(float(c))
        passed(len(changes), max_iter, c)
        if c < tol:
            break
    return beliefs_from_messages(unary, msg), msg, changes
