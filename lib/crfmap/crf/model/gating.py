"""Evidence gating: what a refined map may say to nav2 about a cell, given that cell's own evidence.

nav2 reads a map in three classes (map_saver's trinary, on v = rint(100 P)): lethal v >= 65 (P >= 0.65), free
v <= 20 (P <= 0.196), unknown between. LBP calls free a weakly observed cell (a wall face grazed by beams, a cell seen
once) next to free space, opening a wall for the planner, and grows walls into space no beam reached. An
:class:`EvidenceGate` lets the CRF's belief stand where the cell's own evidence x = hits - passes agrees with the
class it gives, and otherwise moves the belief just inside the nearest class the evidence allows:

- **free needs the cell's own passes**: a cell with x > -``free_evidence`` is raised to at least
  :data:`UNKNOWN_FLOOR`. With ``free_evidence`` >= 2 the refined map's free cells are a subset of the raw arctan
  grid's (P = 0.5 + atan(x) / pi <= 0.196 exactly when x <= -2).
- **repeatedly hit cells stay lethal**: a cell with x >= ``lethal_evidence`` keeps at least nav2's occupied
  threshold; so does (``line_hits``) a single net hit (x >= 1) with an observed-lethal cell among its eight
  neighbours, a hit on a wall line. An isolated single hit is left to the CRF: free neighbours vote it away, which
  removes a ghost (one stale or noisy return in passed space).
- **never-observed cells become lethal only on a wall line** (``wall_lines``): only if they close a one-cell gap
  between two observed-lethal cells on opposite sides (E-W, N-S or a diagonal); otherwise they are capped at
  :data:`UNKNOWN_CEILING`, so walls do not grow into the space behind them.
- **never-observed cells start from the building's rate, not 0.5**: ``unobserved_prior`` pi shifts the belief of a
  never-observed cell off every wall line in log-odds, ``logit(P') = logit(P) + logit(pi)`` (the belief that cell
  gets from an observation P = pi that does not travel on to its neighbours). Far fewer than half of such cells turn
  out occupied, while those in a wall's gap mostly are: they keep the CRF's belief. The floor above keeps them unknown
  to nav2; only their probability is calibrated. pi = 0.5 changes nothing.

Two outputs, since a probability and a decision answer different questions (:meth:`EvidenceGate.beliefs_and_map`):
the beliefs with the prior only (what a user scores or fuses: ``Preset.refine(...).beliefs``, a ``.npy``), and the
decision, the beliefs moved by the rules above (``LBPResult.nav2_map``: the map_server map the node publishes). A
belief kept from crossing a threshold is a safer decision, not a better probability, so it stays out of the beliefs.

>>> gate = EvidenceGate(unobserved_prior=0.25)
>>> p = np.array([[0.10, 0.10, 0.10, 0.90, 0.30]])
>>> hits, passes = np.array([[0, 0, 0, 3, 0]]), np.array([[5, 1, 0, 0, 0]])
>>> gate.beliefs_and_map(p, hits, passes)[0].round(3).tolist()   # the never-observed cells take the prior
[[0.1, 0.1, 0.036, 0.9, 0.125]]
>>> gate.apply(p, hits, passes).round(3).tolist()   # free kept, x = -1 and unseen raised, x = 3 kept
[[0.1, 0.21, 0.21, 0.9, 0.21]]
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from crfmap.errors import InputError

FREE_THRESHOLD = 0.196  # nav2 / map_saver (Jazzy): P <= this is free
OCCUPIED_THRESHOLD = 0.65  # nav2 / map_saver: P >= this is lethal
# The gate's bounds, inside the unknown band as map_saver writes it: P = 0.2 (v = 20) would be written free, 0.21 and
# 0.64 (v = 21, 64) are written unknown.
UNKNOWN_FLOOR = 0.21
UNKNOWN_CEILING = 0.64

LOGIT_FLOOR = 1e-9  # a belief is clipped to [LOGIT_FLOOR, 1 - LOGIT_FLOOR] before its logit takes the prior
EVIDENCE_DECIMALS = 6  # evidence read back from a map's P is rounded to this many decimals before it is compared

# (dy, dx) of one side of each opposite pair: east-west, north-south, and the two diagonals
_LINE_STEPS = ((0, 1), (1, 0), (1, 1), (1, -1))


def _shifted(mask, dy, dx):
    """``mask`` moved so that out[y, x] = mask[y + dy, x + dx] (False beyond the edge)."""
    h, w = mask.shape
    out = np.zeros_like(mask)
    ys, yd = (slice(dy, h), slice(0, h - dy)) if dy >= 0 else (slice(0, h + dy), slice(-dy, h))
    xs, xd = (slice(dx, w), slice(0, w - dx)) if dx >= 0 else (slice(0, w + dx), slice(-dx, w))
    out[yd, xd] = mask[ys, xs]
    return out


def wall_line_gaps(walls) -> np.ndarray:
    """Boolean [y, x]: cells with a ``walls`` cell on both opposite sides (E-W, N-S or a diagonal).

    >>> walls = np.array([[1, 0, 1], [0, 0, 0], [0, 0, 1]], bool)
    >>> wall_line_gaps(walls).astype(int).tolist()
    [[0, 1, 0], [0, 1, 1], [0, 0, 0]]
    """
    w = np.asarray(walls, dtype=bool)
    if w.ndim != 2:
        raise InputError("walls", f"must be a 2-D mask, got shape {w.shape}")
    gaps = np.zeros_like(w)
    for dy, dx in _LINE_STEPS:
        gaps |= _shifted(w, dy, dx) & _shifted(w, -dy, -dx)
    return gaps


def wall_neighbours(walls) -> np.ndarray:
    """Boolean [y, x]: cells with at least one ``walls`` cell among their eight neighbours (the cell itself not counted).

    >>> wall_neighbours(np.array([[1, 0, 0, 0]], bool)).astype(int).tolist()
    [[0, 1, 0, 0]]
    """
    w = np.asarray(walls, dtype=bool)
    if w.ndim != 2:
        raise InputError("walls", f"must be a 2-D mask, got shape {w.shape}")
    out = np.zeros_like(w)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dy or dx:
                out |= _shifted(w, dy, dx)
    return out


def _check_evidence_count(value, name):
    v = float(value) if not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating)) else -1
    if not (math.isfinite(v) and v >= 1):
        raise InputError(name, f"must be a number of net observations >= 1, got {value!r}")
    return v


@dataclass(frozen=True)
class EvidenceGate:
    """Which nav2 class a cell's own evidence allows (the rules: the module docstring)."""

    free_evidence: float = 2.0  # net passes (passes - hits) a cell needs before the map may call it free
    lethal_evidence: float = 2.0  # net hits that keep a cell lethal (math.inf: none)
    line_hits: bool = True  # a single net hit next to an observed-lethal cell stays lethal too
    wall_lines: bool = True  # never-observed cells may become lethal only in one-cell gaps of walls (False: never)
    unobserved_prior: float = 0.5  # P(occupied) of a never-observed cell before its neighbours' messages (0.5: none)

    def __post_init__(self):
        prior = self.unobserved_prior
        if isinstance(prior, bool) or not (isinstance(prior, (int, float, np.floating)) and 0 < prior < 1):
            raise InputError("unobserved_prior", f"must be a probability strictly between 0 and 1, got {prior!r}")
        _check_evidence_count(self.free_evidence, "free_evidence")
        if self.lethal_evidence != math.inf:
            _check_evidence_count(self.lethal_evidence, "lethal_evidence")

    def apply(self, probability, hits=None, passes=None, evidence=None, observed=None) -> np.ndarray:
        """The map for nav2, a new float64 [y, x] array: the second of :meth:`beliefs_and_map`. Give the cell counts
        (``hits``, ``passes``), or the signed ``evidence`` x (a map file's P read back by
        :func:`crfmap.crf.presets.evidence_from_probability`) with an ``observed`` mask (default x != 0)."""
        return self.beliefs_and_map(probability, hits, passes, evidence, observed)[1]

    def beliefs_and_map(self, probability, hits=None, passes=None, evidence=None, observed=None, transform=None):
        """(beliefs, map for nav2), new float64 [y, x] arrays: the beliefs with the never-observed prior, then
        ``transform`` of them (e.g. a preset's temperature; None: none), then the decision. Arguments: :meth:`apply`."""
        cells = self._cells(probability, hits, passes, evidence, observed)
        beliefs = self._calibrate(*cells)
        if transform is not None:
            beliefs = np.asarray(transform(beliefs), dtype=np.float64)
        return beliefs, self._decide(beliefs, *cells[1:])

    def _cells(self, probability, hits, passes, evidence, observed):
        """(P as a new float64 array, evidence x, seen mask, observed walls, never-observed cells off wall lines)."""
        p = np.array(probability, dtype=np.float64)
        if p.ndim != 2:
            raise InputError("probability", f"must be a 2-D grid, got shape {p.shape}")
        if (hits is None) != (passes is None) or (hits is None) == (evidence is None):
            raise InputError("gate", "give hits and passes, or evidence")
        if hits is not None:
            h, e = np.asarray(hits), np.asarray(passes)
            if h.shape != p.shape or e.shape != p.shape:
                raise InputError("hits", f"hits {h.shape} and passes {e.shape} must match the grid {p.shape}")
            x = h.astype(np.float64) - e
            seen = (h + e) > 0
        else:
            # a count read back from a map's P through tan is off by ~1e-9 (2 comes back as 1.9999999999)
            x = np.round(np.asarray(evidence, dtype=np.float64), EVIDENCE_DECIMALS)
            if x.shape != p.shape:
                raise InputError("evidence", f"shape {x.shape} does not match the grid {p.shape}")
            seen = (x != 0) if observed is None else np.asarray(observed, dtype=bool)
            if seen.shape != p.shape:
                raise InputError("observed", f"shape {seen.shape} does not match the grid {p.shape}")
        walls = seen & (x >= 1)  # what the raw arctan grid calls lethal (P >= 0.75 > 0.65)
        off_line = ~seen  # never observed, and (wall_lines) not in a gap of an observed wall
        if self.wall_lines:
            off_line &= ~wall_line_gaps(walls)
        return p, x, walls, off_line

    def _calibrate(self, p, x, walls, off_line):
        if self.unobserved_prior != 0.5:  # p is the gate's own copy (_cells): changed in place, on those cells only
            q = np.clip(p[off_line], LOGIT_FLOOR, 1 - LOGIT_FLOOR)
            shift = math.log(self.unobserved_prior / (1 - self.unobserved_prior))
            p[off_line] = 1 / (1 + np.exp(-(np.log(q) - np.log1p(-q) + shift)))
        return p

    def _decide(self, p, x, walls, off_line):
        p = p.copy()
        not_free = ~(x <= -self.free_evidence)
        np.maximum(p, UNKNOWN_FLOOR, out=p, where=not_free & (p < UNKNOWN_FLOOR))
        keep = x >= self.lethal_evidence
        if self.line_hits:
            keep |= walls & wall_neighbours(walls)
        np.maximum(p, OCCUPIED_THRESHOLD, out=p, where=keep)
        np.minimum(p, UNKNOWN_CEILING, out=p, where=off_line & (p > UNKNOWN_CEILING))
        return p
