"""Named CRF configurations, model and solver together: the one source of settings for every path.

- ``"thesis"``: the thesis's tables (hidden [[10, 1], [1, 10]], identity link, whole grid), to reproduce the
  thesis. Its coupling J = ln(10) / 2 = 1.15 is far above the square lattice's critical ln(1 + sqrt 2) / 2 = 0.44:
  in this ordered phase LBP erases thin walls and gives never-seen space the state of its border.
- ``"certainty"``: a cell's observation follows its signed evidence ``x = hits - passes``: P(occupied) =
  ``sigmoid(l)`` with ``l = min(a + b (x - 1), limit)`` for x > 0 (``(a, b) = occupied``: the first net hit is worth
  a, each further one b), ``l = -min(c + d (|x| - 1), limit)`` for x < 0 (``(c, d) = free``), l = 0 for x = 0. A
  wall hit 20 times says ``sigmoid(limit)`` and neighbours cannot vote it away (their pull is at most 4 * 2J <
  limit); a cell seen once yields. J is below the critical value, so information spreads only a few cells, and LBP
  runs only within ``margin`` cells of an observation: space far from every observation stays 0.5 (unknown).
- ``"gated"`` (:data:`DEFAULT_PRESET`): the certainty model at J = 0.30, below LBP's own critical coupling (the Bethe
  value atanh(1/3) = 0.347), then an :class:`~crfmap.crf.model.gating.EvidenceGate` for what a robot does with the
  map (``certainty`` opens walls and thickens them; its two outputs: :mod:`crfmap.crf.model.gating`).

``temperature`` T (default 1: no change) tempers the whole refined map, ``P' = sigmoid(logit(P) / T)``
(:func:`temper`); :func:`crfmap.assess.calibration.fit_temperature` fits it.

The scaled observation reaches LBP as a probability through the identity link. A map file holds P, not counts: the
preset reads the thesis's model backwards, ``x = tan(pi (P - 0.5))`` (exact for grids crfmap builds; P = 0 or 1, a
trinary map's free and occupied, gives the strongest observation; 0.5 gives none).

>>> p = get_preset("certainty")
>>> u = p.observation(hits=np.array([[20, 1, 0]]), passes=np.array([[0, 0, 0]]))
>>> [round(float(v), 3) for v in u[0]]
[0.968, 0.818, 0.5]
>>> bool(np.allclose(p.observation(probability=0.5 + np.arctan(np.array([[20.0, 1, 0]])) / np.pi), u))
True
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.regions import near_cells
from crfmap.crf.inference.schedules import SETTINGS
from crfmap.crf.model.gating import EvidenceGate
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK, check_pairing, check_table
from crfmap.crf.threads import over_rows
from crfmap.checks import check_int, check_mask, check_number, check_positive
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid

CRITICAL_COUPLING = math.log(1 + math.sqrt(2)) / 2  # square-lattice Ising, J_c = 0.4407
LOGIT_FLOOR = 1e-6  # P is clipped to [LOGIT_FLOOR, 1 - LOGIT_FLOOR] before its logit is tempered (logit(0) is -inf)
DEFAULT_PRESET = "gated"  # what every path runs by default: crfmap infer / evaluate, the node, the online mapper


def coupling_table(coupling: float) -> np.ndarray:
    """The symmetric hidden table [[a, 1], [1, a]] with a = exp(2 J) for Ising coupling J.

    >>> coupling_table(math.log(10) / 2).round(6).tolist()
    [[10.0, 1.0], [1.0, 10.0]]
    """
    j = float(coupling)
    if not (math.isfinite(j) and j >= 0):
        raise InputError("coupling", f"must be a non-negative number, got {coupling!r}")
    a = math.exp(2 * j)
    return np.array([[a, 1.0], [1.0, a]])


def table_coupling(hidden) -> float:
    """The Ising coupling J = ln(oo * ee / (oe * eo)) / 4 of a hidden table (inf if an entry is 0).

    >>> round(table_coupling([[10, 1], [1, 10]]), 4)
    1.1513
    """
    t = check_table(hidden, "hidden")
    if np.any(t <= 0):
        return float("inf")
    return float(math.log(t[0, 0] * t[1, 1] / (t[0, 1] * t[1, 0])) / 4)


def evidence_from_probability(probability) -> np.ndarray:
    """Signed evidence hits - passes that the thesis's arctan model turns into ``probability``.

    >>> evidence_from_probability(np.array([0.5 + np.arctan(3.0) / np.pi, 0.5, 1.0])).round(6).tolist()
    [3.0, 0.0, inf]
    """
    p = np.asarray(probability, dtype=np.float64)
    x = np.tan(np.pi * (p - 0.5))
    x = np.where(p >= 1.0, np.inf, np.where(p <= 0.0, -np.inf, x))
    return np.where(p == 0.5, 0.0, x)


def temper(probability, temperature: float) -> np.ndarray:
    """``sigmoid(logit(P) / T)``, P clipped to [LOGIT_FLOOR, 1 - LOGIT_FLOOR] first.

    >>> temper(np.array([0.5, 0.9]), 2.0).round(3).tolist()
    [0.5, 0.75]
    """
    t = check_positive("temperature", temperature)
    q = np.clip(np.asarray(probability, dtype=np.float64), LOGIT_FLOOR, 1 - LOGIT_FLOOR)
    return 1.0 / (1.0 + np.exp(-(np.log(q) - np.log1p(-q)) / t))


def check_margin(margin) -> int | None:
    """``margin`` [cells]: how far from an observation LBP runs, a whole number >= 0 or None (everywhere).

    >>> check_margin(2.5)
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: margin: expected an integer, got 2.5
    """
    return None if margin is None else check_int("margin", margin, low=0)


CACHE_SLOTS = 1024  # a power of two


@njit(cache=True, nogil=True)  # no fastmath: NumPy's operations, in its order
def _certainty_rows(values, from_probability, o0, o1, f0, f1, limit, out, r0, r1):
    """The certainty-scaled P(occupied) of rows [r0, r1) from the evidence x, or (``from_probability``) from a grid's
    P read back as x (:func:`evidence_from_probability`). NaN stays NaN."""
    # a cache of results keyed by a hash of the value: a map holds few distinct values, so most cells skip the tan
    # and exp. NaN never equals a key: it goes the long way
    keys = np.full(CACHE_SLOTS, np.nan)
    results = np.empty(CACHE_SLOTS)
    for y in range(r0, r1):
        for i in range(values.shape[1]):
            x = values[y, i]
            if (x == 0.5) if from_probability else (x == 0.0):
                out[y, i] = 0.5  # no evidence (most cells of a map): 1 / (1 + exp(-0)) without the tan and exp
                continue
            slot = np.int64(x * 1048576.0) & (CACHE_SLOTS - 1) if abs(x) < 1e12 else 0
            if keys[slot] == x:
                out[y, i] = results[slot]
                continue
            keys[slot] = x
            if from_probability:
                p = x
                if p >= 1.0:
                    x = np.inf
                elif p <= 0.0:
                    x = -np.inf
                else:
                    x = np.tan(np.pi * (p - 0.5))
            if x > 0:
                logit = min(o0 + o1 * (x - 1), limit) if o1 != 0 else min(o0, limit)  # o1 = 0: no inf * 0
            elif x < 0:
                logit = -(min(f0 + f1 * (-x - 1), limit) if f1 != 0 else min(f0, limit))
            else:
                logit = x * 0.0  # 0, or NaN for NaN
            results[slot] = out[y, i] = 1.0 / (1.0 + np.exp(-logit))


@dataclass(frozen=True)
class Preset:
    """One named CRF configuration (see the module docstring); the solver fields are what every path runs it with."""

    name: str
    purpose: str
    hidden: np.ndarray = field(repr=False)
    scaled: bool  # True: certainty-scaled observations (through the identity link); False: the grid's P through link
    occupied: tuple = (0.0, 0.0)  # log-odds of the first net hit, and of each further one
    free: tuple = (0.0, 0.0)  # the same for net passes
    limit: float = 0.0  # largest |log-odds| of one cell's observation
    margin: int | None = None  # infer only within this many cells of an observation (None: everywhere)
    link: np.ndarray = field(default_factory=lambda: DEFAULT_LINK.copy(), repr=False)  # observation-cell table
    pairing: str = "receiver"  # how a non-symmetric hidden table applies to an edge
    temperature: float = 1.0  # output P' = sigmoid(logit(P) / T) (see temper)
    tol: float = 1e-5  # stop when an iteration moves no message by more than this
    max_iter: int = 1000  # iteration limit
    schedule: str = "checkerboard"  # a name of crfmap.crf.inference.schedules.SETTINGS
    dtype: str = "float64"
    gate: EvidenceGate | None = None  # what each cell's own evidence lets nav2 read (crfmap.crf.model.gating)

    def __post_init__(self):
        # the model: every field a number of the kind it is read as (refine would take 2.5 cells or True silently)
        if not isinstance(self.scaled, (bool, np.bool_)):
            raise InputError("scaled", f"must be True or False, got {self.scaled!r}")
        for name in ("occupied", "free"):
            pair = getattr(self, name)
            if not (isinstance(pair, (tuple, list)) and len(pair) == 2):
                raise InputError(name, f"must be two log-odds (first net count, each further one), got {pair!r}")
        if self.gate is not None and not isinstance(self.gate, EvidenceGate):
            raise InputError("gate", f"must be None or an EvidenceGate, got {type(self.gate).__name__}")
        if self.schedule not in SETTINGS:
            raise InputError("schedule", f"must be one of {', '.join(SETTINGS)}, got {self.schedule!r}")
        if self.dtype not in ("float64", "float32"):
            raise InputError("dtype", f"must be 'float64' or 'float32', got {self.dtype!r}")
        checked = dict(
            temperature=check_positive("temperature", self.temperature), hidden=check_table(self.hidden, "hidden"),
            link=check_table(self.link, "link"), pairing=check_pairing(self.pairing),
            occupied=tuple(check_number("occupied", v, low=0.0) for v in self.occupied),
            free=tuple(check_number("free", v, low=0.0) for v in self.free),
            # inf is a valid limit (no cap on a cell's log-odds: the ablations' J = 0); NaN is not
            limit=check_number("limit", self.limit, low=0.0, infinite=True),
            margin=check_margin(self.margin), tol=check_number("tol", self.tol, low=0.0),
            max_iter=check_int("max_iter", self.max_iter, low=0))
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    def solver(self) -> dict:
        """The solver settings of this preset, as :func:`crfmap.crf.inference.lbp.infer` takes them.

        >>> get_preset("thesis").solver()
        {'tol': 1e-05, 'max_iter': 1000, 'schedule': 'checkerboard', 'dtype': 'float64'}
        """
        return {"tol": self.tol, "max_iter": self.max_iter, "schedule": self.schedule, "dtype": self.dtype}

    @property
    def coupling(self) -> float:
        return table_coupling(self.hidden)

    def observation(self, hits=None, passes=None, probability=None) -> np.ndarray:
        """P(occupied) each cell's observation gives its hidden cell, from counts or from a grid's P."""
        if (hits is None) != (passes is None) or (hits is None) == (probability is None):
            raise InputError("observation", "give hits and passes, or probability")
        if hits is not None:
            h, e = np.asarray(hits), np.asarray(passes)
            if h.shape != e.shape:
                raise InputError("passes", f"shape {e.shape} does not match hits {h.shape}")
            x = h.astype(np.float64) - e
            if not self.scaled:
                return 0.5 + np.arctan(x) / math.pi
        else:
            x = np.asarray(probability, np.float64)
            if not self.scaled:
                return x
        # one pass over the cells: NumPy's nine temporaries cost as long as several LBP passes
        rows = np.ascontiguousarray(x).reshape(-1, x.shape[-1] if x.ndim else 1)
        out = np.empty(rows.shape)
        if rows.size:
            over_rows(_certainty_rows, rows.shape[0], rows, hits is None, float(self.occupied[0]),
                      float(self.occupied[1]), float(self.free[0]), float(self.free[1]), float(self.limit), out)
        return out.reshape(x.shape)

    def region(self, observed) -> np.ndarray | None:
        """Cells LBP runs on: within ``margin`` cells of an observed cell (None: all)."""
        if self.margin is None:
            return None
        return near_cells(observed, int(self.margin))

    def refine(self, grid=None, hits=None, passes=None, within=None, **options):
        """Run LBP with this preset on counts (``hits``, ``passes``) or on a grid's P; an
        :class:`~crfmap.crf.inference.result.LBPResult`, ended through :meth:`finish`.

        Outside :meth:`region` the beliefs are the observation itself. ``within`` (a boolean mask, e.g. a bound
        around the robot) further limits the senders, as ``infer``'s ``region``; ``options`` override the solver
        fields in :func:`crfmap.crf.inference.lbp.infer`.

        >>> r = get_preset("certainty").refine(np.array([[0.5, 0.9, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]]))
        >>> r.converged, float(r.beliefs.probability[0, -1])
        (True, 0.5)
        """
        if grid is not None:
            g = grid if isinstance(grid, OccupancyGrid) else OccupancyGrid(np.asarray(grid, dtype=np.float64))
            if hits is not None or passes is not None:
                raise InputError("refine", "give a grid or counts, not both")
            unary = self.observation(probability=g.probability)
            observed = g.probability != 0.5
        else:
            if hits is None or passes is None:
                raise InputError("refine", "give a grid, or hits and passes")
            unary = self.observation(hits=hits, passes=passes)
            observed = (np.asarray(hits) + np.asarray(passes)) > 0
            g = OccupancyGrid(unary)
        own = region = self.region(observed)
        if within is not None:  # only these cells send messages, as infer's region
            within = check_mask("within", within, g.shape)
            region = within if own is None else own & within
        for key, value in self.solver().items():
            options.setdefault(key, value)
        result = infer(g.with_probability(unary), self.hidden, self.link, region=region, pairing=self.pairing, **options)
        if own is not None:  # outside the preset's region nothing was inferred: keep the observation
            np.copyto(result.beliefs.probability, unary, where=~own)  # the result's own array: checked, in [0, 1]
        # the gate reads each cell's own evidence everywhere: beyond the margin too a never-observed cell gets the prior
        if self.gate is None and self.temperature == 1.0:  # LBP's beliefs are the result
            return result
        beliefs, decided = self.finish(result.beliefs.probability, hits=hits, passes=passes,
                                       evidence_grid=g.probability, observed=observed)
        dtype = result.beliefs.probability.dtype
        result.beliefs = result.beliefs.with_probability(beliefs.astype(dtype))
        if decided is not None:
            result.gated = result.beliefs.with_probability(decided.astype(dtype))
        return result

    def finish(self, probability, hits=None, passes=None, evidence_grid=None, observed=None) -> tuple:
        """(beliefs, map for nav2 or None without a gate) of LBP's ``probability``: the gate's prior, the temperature
        (whole map), then the gate's decision. Each cell's evidence: ``hits`` and ``passes``, or a map file's P
        (``evidence_grid``) with the ``observed`` mask. :meth:`refine` and the online mapper end here."""
        tempered = None if self.temperature == 1.0 else (lambda p: temper(p, self.temperature))
        if self.gate is None:
            p = np.asarray(probability, dtype=np.float64)
            return (p if tempered is None else tempered(p)), None
        cells = dict(hits=hits, passes=passes) if hits is not None else dict(
            evidence=evidence_from_probability(evidence_grid), observed=observed)
        return self.gate.beliefs_and_map(probability, **cells, transform=tempered)


PRESETS = {
    "thesis": Preset(
        "thesis", "the thesis's tables (hidden [[10,1],[1,10]], identity link, whole grid): reproduce the thesis; "
        "ordered phase, erases thin walls and fills unseen space", DEFAULT_HIDDEN, scaled=False),
    "certainty": Preset(
        "certainty", "recommended: certainty-scaled observations (link strength follows hits - passes), coupling "
        "below critical, LBP only near observations: improves real maps, keeps walls, leaves unexplored space unknown",
        coupling_table(0.35), scaled=True, occupied=(1.5, 0.1), free=(0.75, 0.2), limit=6.0, margin=5),
    # Chosen on Intel and ACES's held-out splits (`python -m crfstudy.analysis.gate_search` reruns it): J by log-loss
    # with occupied cells weighted 3x (dangerous misses are the costlier error), pi at that J by Brier (pi moves no
    # decision); free_evidence = 3 read off the trade-off curves (notebook 12): 2 is the least that never frees a
    # cell the raw grid does not, 4 costs free cells and exploration.
    "gated": Preset(
        "gated", "recommended for navigation: the certainty model at J = 0.30 (below LBP's Bethe point), gated by "
        "each cell's own evidence: free only after three net passes (never a cell the raw grid does not call free), "
        "repeated or on-a-wall hits stay lethal, lone hits go, walls do not grow into unobserved space, "
        "never-observed cells at P = 0.15 (still unknown to nav2)",
        coupling_table(0.30), scaled=True, occupied=(1.5, 0.1), free=(0.75, 0.2), limit=6.0, margin=5,
        gate=EvidenceGate(free_evidence=3, lethal_evidence=2, line_hits=True, wall_lines=True, unobserved_prior=0.15)),
}


def get_preset(name: str = DEFAULT_PRESET) -> Preset:
    """The preset called ``name`` (see :data:`PRESETS`)."""
    try:
        return PRESETS[name]
    except KeyError:
        raise InputError("preset", f"must be one of {', '.join(PRESETS)}, got {name!r}") from None


def custom_preset(hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK, pairing="receiver", margin=None) -> Preset:
    """A preset of given tables: the grid's P through ``link``, LBP within ``margin`` cells of an observation.

    >>> custom_preset("4,1,1,4", margin=3).coupling.__round__(4), custom_preset().name
    (0.6931, 'custom')
    """
    return Preset("custom", "given tables", hidden, scaled=False, margin=margin, link=link, pairing=pairing)
