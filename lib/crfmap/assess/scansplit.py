"""Scan-split validation: does a refined map predict what the robot observes next? (no hand labels)

A real recording has no ground truth, but many scans of each place. Its scans are split in two interleaved halves
(even and odd by default): the grid is built and refined from the *first* half only, and each cell's P(occupied) is
scored against the *second* half. Each second-half beam that returns counts one hit in its end cell and one pass in
every cell it crosses; an observed cell is labelled occupied when ``hits2 >= passes2``, else free, and counts once.

:func:`score` reports three groups of second-half cells: ``"all"`` it observed; ``"seen"``, those the first half also
observed (the map had evidence there); ``"unseen"``, those the first half never observed (the raw grid says 0.5 there:
only filling-in can help).

Metrics: the Brier score (mean squared error against the 0/1 label), log-loss (P clipped to [LOG_FLOOR,
1 - LOG_FLOOR]), AUC (ties count one half) and wall recall (the share of occupied-labelled cells with P > 0.5).
Intervals come from a *spatial-block bootstrap*: squares of ``block`` x ``block`` cells are resampled with
replacement (single cells are correlated with their neighbours). Predictions scored together share the resamples, so
:func:`score` also gives intervals of the paired difference to a reference; :func:`block_resamples` hands the same
draws to other scorers (:mod:`crfmap.assess.navigation`).

>>> split = ScanSplit(first_hits=np.array([[0, 3, 0]]), first_passes=np.array([[2, 0, 0]]),
...                   second_hits=np.array([[0, 2, 1]]), second_passes=np.array([[3, 0, 0]]))
>>> split.labels().astype(int).tolist(), split.group("unseen").astype(int).tolist()
([[0, 1, 1]], [[0, 0, 1]])
>>> s = score(split, {"raw": split.raw_probability()}, n_boot=0)
>>> round(s["raw"]["all"]["brier"], 4), s["raw"]["unseen"]["brier"]
(0.0941, 0.25)
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from crfmap.assess.block_bootstrap import _auc_resampled, _block_counts, _block_ids, _draws
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.mapping.builder import arctan_probability, count_hits, scan_bounds

GROUPS = ("all", "seen", "unseen")
METRICS = ("brier", "logloss", "auc", "wall_recall")
LOG_FLOOR = 1e-6  # P is clipped to [LOG_FLOOR, 1 - LOG_FLOOR] for the log-loss
DEFAULT_BLOCK = 16  # [cells] side of a bootstrap square (0.8 m at 5 cm cells)


def split_scans(scans, parity: int):
    """The scans with index % 2 == parity, as a new ScanSet (same sensor, same frame).

    >>> from crfmap.recording import ScanSet
    >>> s = ScanSet(np.ones((5, 2), np.float32), 0.0, 0.1, 0.1, 5.0, np.zeros((5, 3)), np.arange(5.0))
    >>> split_scans(s, 1).stamps.tolist()
    [1.0, 3.0]
    """
    if parity not in (0, 1):
        raise InputError("parity", f"must be 0 (even scans) or 1 (odd scans), got {parity!r}")
    keep = slice(parity, None, 2)
    return replace(scans, ranges=np.asarray(scans.ranges)[keep], laser_poses=np.asarray(scans.laser_poses)[keep],
                   stamps=np.asarray(scans.stamps)[keep])


@dataclass
class ScanSplit:
    """Hit counts ([y, x] int arrays on one grid) of a recording's two halves of scans: ``first_*`` build the map,
    ``second_*`` only score it; ``first_scans``/``second_scans`` (optional, set by :func:`scan_split`) keep each half's
    ScanSet for what needs the scans themselves."""

    first_hits: np.ndarray
    first_passes: np.ndarray
    second_hits: np.ndarray
    second_passes: np.ndarray
    resolution: float = 1.0
    origin: tuple = (0.0, 0.0, 0.0)
    bounds: tuple | None = None  # (xmin, ymin, xmax, ymax) [m] given to the builder
    source: str = ""
    first_scans: object = field(default=None, repr=False)
    second_scans: object = field(default=None, repr=False)

    def __post_init__(self):
        arrays = [np.asarray(a) for a in (self.first_hits, self.first_passes, self.second_hits, self.second_passes)]
        shape = arrays[0].shape
        if len(shape) != 2 or arrays[0].size == 0 or any(a.shape != shape for a in arrays):
            raise InputError(self.source or "scan split", f"hit counts must be four non-empty 2-D arrays of one "
                             f"shape, got {[a.shape for a in arrays]}")
        if any(not np.issubdtype(a.dtype, np.integer) or (a < 0).any() for a in arrays):
            raise InputError(self.source or "scan split", "hit counts must be non-negative integers")
        self.first_hits, self.first_passes, self.second_hits, self.second_passes = arrays

    @property
    def shape(self):
        return self.first_hits.shape

    def labels(self) -> np.ndarray:
        """Boolean [y, x]: the second half calls the cell occupied (hits >= passes, hits > 0)."""
        return (self.second_hits >= self.second_passes) & (self.second_hits > 0)

    def group(self, name: str) -> np.ndarray:
        """Boolean [y, x] mask of the cells scored in group ``name`` (see :data:`GROUPS`)."""
        observed2 = (self.second_hits + self.second_passes) > 0
        seen1 = (self.first_hits + self.first_passes) > 0
        if name == "all":
            return observed2
        if name == "seen":
            return observed2 & seen1
        if name == "unseen":
            return observed2 & ~seen1
        raise InputError("group", f"must be one of {', '.join(GROUPS)}, got {name!r}")

    def raw_probability(self) -> np.ndarray:
        """The first half's grid with the thesis's arctan model (as :func:`crfmap.mapping.build_grid`)."""
        return arctan_probability(self.first_hits, self.first_passes)


def scan_split(scans, resolution: float, parity: int = 0, bounds=None, progress: bool = False) -> ScanSplit:
    """Count the hits of the ``parity`` half (even scans: 0) and of the other half on one grid:
    :func:`crfmap.mapping.build_grid`'s of all the scans, unless ``bounds`` (xmin, ymin, xmax, ymax) [m].

    >>> from crfmap.recording import ScanSet
    >>> r = np.array([[0.36], [0.26]], np.float32)
    >>> s = ScanSet(r, 0.0, 0.0, 0.1, 5.0, np.array([[0.05, 0.05, 0.0]] * 2), np.zeros(2))
    >>> sp = scan_split(s, 0.1, bounds=(0, 0, 0.5, 0.1))
    >>> sp.first_hits.tolist(), sp.second_hits.tolist()
    ([[0, 0, 0, 0, 1]], [[0, 0, 0, 1, 0]])
    """
    if len(scans) < 2:
        raise InputError(getattr(scans, "source", "") or "scans", f"need at least 2 scans to split, got {len(scans)}")
    if bounds is None:
        xmin, ymin, xmax, ymax = scan_bounds(scans)
        xmin = round(math.floor(xmin / resolution) * resolution, 9)
        ymin = round(math.floor(ymin / resolution) * resolution, 9)
        bounds = (xmin, ymin, xmax, ymax)
    first = split_scans(scans, parity)
    second = split_scans(scans, 1 - parity)
    h1, e1 = count_hits(first, resolution, bounds=bounds, progress=progress)
    h2, e2 = count_hits(second, resolution, bounds=bounds, progress=progress)
    return ScanSplit(h1, e1, h2, e2, resolution=float(resolution), origin=(float(bounds[0]), float(bounds[1]), 0.0),
                     bounds=tuple(float(b) for b in bounds), source=getattr(scans, "source", ""), first_scans=first,
                     second_scans=second)


class _Scorer:
    """The metrics of one prediction on one group of cells, fast under block resampling: Brier, log-loss and recall
    are sums, kept per bootstrap block (all resamples at once are one matrix product); the AUC sorts once (only when
    asked for) and reweights the sorted cells per resample in a compiled loop."""

    def __init__(self, p, y, inverse, n_blocks, auc=True, logloss=True, counts=None):
        """``logloss=False``: its sums stay 0; ``counts``: the (cells, walls) sums per block, if known."""
        cells, walls = counts if counts is not None else _block_counts(y, inverse, n_blocks)
        if logloss:
            q = np.clip(p, LOG_FLOOR, 1 - LOG_FLOOR)
            loss = np.bincount(inverse, weights=-(y * np.log(q) + (1 - y) * np.log(1 - q)), minlength=n_blocks)
        else:
            loss = np.zeros(n_blocks)
        self.sums = np.stack([cells, np.bincount(inverse, weights=(p - y) ** 2, minlength=n_blocks), loss, walls,
                              np.bincount(inverse, weights=y * (p > 0.5), minlength=n_blocks)])
        self.with_auc = auc
        if auc:
            order = np.argsort(p, kind="stable")
            self.y, self.inverse = y[order], inverse[order]
            self.starts = np.concatenate([[0], np.flatnonzero(np.diff(p[order])) + 1])  # runs of equal P

    def metrics(self, block_weights=None) -> dict:
        s = self.sums.sum(axis=1) if block_weights is None else self.sums @ block_weights
        n, walls = s[0], s[3]
        if n <= 0:
            return dict.fromkeys(METRICS, float("nan"))
        out = {"brier": float(s[1] / n), "logloss": float(s[2] / n),
               "wall_recall": float(s[4] / walls) if walls > 0 else float("nan")}
        if self.with_auc:
            w = np.ones(len(self.y)) if block_weights is None else block_weights[self.inverse]
            out["auc"] = self._auc(w)
        return out

    def resampled(self, draws) -> dict:
        """{metric: array over resamples} for block weights ``draws`` [n_boot, n_blocks]."""
        s = self.sums @ draws.T  # [5, n_boot]
        n, walls = s[0], s[3]
        with np.errstate(divide="ignore", invalid="ignore"):
            out = {"brier": np.where(n > 0, s[1] / n, np.nan), "logloss": np.where(n > 0, s[2] / n, np.nan),
                   "wall_recall": np.where((n > 0) & (walls > 0), s[4] / walls, np.nan)}
        if self.with_auc:
            out["auc"] = _auc_resampled(self.y, self.inverse, self.starts.astype(np.int64), draws)
        return out

    def _auc(self, w):
        """Mann-Whitney AUC: a wall beats every free cell with lower P, ties count one half."""
        pos, neg = w * self.y, w * (1 - self.y)
        n_pos, n_neg = pos.sum(), neg.sum()
        if n_pos <= 0 or n_neg <= 0:
            return float("nan")
        pos_g, neg_g = np.add.reduceat(pos, self.starts), np.add.reduceat(neg, self.starts)
        neg_below = np.cumsum(neg_g) - neg_g
        return float(np.sum(pos_g * (neg_below + 0.5 * neg_g)) / (n_pos * n_neg))


def _layout(split, block) -> dict:
    """{group: (mask, labels, block ids, each cell's block index, (cells, walls) per block)} in ``block``-cell squares.

    Cached on the split, remade when its count arrays (by identity) or ``block`` change: scoring many predictions one
    :func:`score` call at a time finds the cells and blocks once.
    """
    counts = (split.first_hits, split.first_passes, split.second_hits, split.second_passes)
    kept = split.__dict__.get("_layout")  # (the count arrays it was made from, block, layout)
    if kept is not None and kept[1] == block and all(a is b for a, b in zip(kept[0], counts)):
        return kept[2]
    labels = split.labels().astype(np.float64)
    blocks = _block_ids(split.shape, block)
    layout = {}
    for group in GROUPS:
        mask = split.group(group)
        uniq, inverse = np.unique(blocks[mask], return_inverse=True)
        layout[group] = (mask, labels[mask], uniq, inverse, _block_counts(labels[mask], inverse, len(uniq)))
    split.__dict__["_layout"] = (counts, int(block), layout)  # one at a time: a split is scored in one block size
    return layout


def check_probability(pred, shape, name) -> np.ndarray:
    """``pred`` (an array or OccupancyGrid) as a float [y, x] array of P in [0, 1] of ``shape``, else InputError.

    >>> check_probability([[0.2, 1.0]], (1, 2), "map").tolist()
    [[0.2, 1.0]]
    """
    p = pred.probability if isinstance(pred, OccupancyGrid) else np.asarray(pred, dtype=np.float64)
    p = getattr(p, "probability", p)
    if p.shape != shape:
        raise InputError(name, f"prediction shape {p.shape} does not match the split's grid {shape}")
    if not np.all(np.isfinite(p)) or p.min() < 0 or p.max() > 1:
        raise InputError(name, "predictions must be probabilities in [0, 1]")
    return p


def check_scoring(predictions: dict, reference, n_boot, block) -> None:
    """The arguments every paired scoring of a split shares (:func:`score`, the navigation metrics), checked."""
    if not predictions:
        raise InputError("predictions", "nothing to score")
    if reference is not None and reference not in predictions:
        raise InputError("reference", f"{reference!r} is not one of the predictions")
    if not (isinstance(n_boot, (int, np.integer)) and n_boot >= 0):
        raise InputError("n_boot", f"must be a non-negative integer, got {n_boot!r}")
    if not (isinstance(block, (int, np.integer)) and block >= 1):
        raise InputError("block", f"must be a positive integer, got {block!r}")


def score(split: ScanSplit, predictions: dict, n_boot: int = 200, block: int = DEFAULT_BLOCK, seed: int = 0,
          reference: str | None = None, level: float = 0.95, groups=GROUPS, metrics=METRICS) -> dict:
    """Score predictions ``{name: [y, x] P(occupied)}`` against the second half, with intervals.

    Returns ``{name: {group: {metric: value, metric + "_ci": (lo, hi), ...}}}``; with a ``reference`` name, also
    ``metric + "_diff"`` (name minus reference) and its paired interval ``metric + "_diff_ci"``. ``n_boot=0`` skips
    the intervals; ``groups`` and ``metrics`` limit the work (without ``"auc"`` nothing is sorted).

    >>> sp = ScanSplit(*(np.random.default_rng(0).integers(0, 3, (8, 8)) for _ in range(4)))
    >>> s = score(sp, {"raw": sp.raw_probability()}, n_boot=0, groups=("all",), metrics=("brier",))
    >>> list(s["raw"]), sorted(s["raw"]["all"])
    (['all'], ['brier', 'cells', 'walls'])
    """
    check_scoring(predictions, reference, n_boot, block)
    unknown = [g for g in groups if g not in GROUPS] + [m for m in metrics if m not in METRICS]
    if unknown or not groups or not metrics:
        raise InputError("groups/metrics", f"must be non-empty subsets of {GROUPS} and {METRICS}, "
                         f"got {unknown or 'none'}")
    probs = {name: check_probability(p, split.shape, name) for name, p in predictions.items()}
    resamples = block_resamples(split, n_boot=n_boot, block=block, seed=seed)
    out = {name: {} for name in probs}
    for group in groups:
        mask, y, inverse, draws = (getattr(resamples[group], k) for k in ("mask", "labels", "inverse", "draws"))
        boot = {}
        for name, p in probs.items():
            scorer = _Scorer(p[mask], y, inverse, resamples[group].n_blocks, auc="auc" in metrics,
                             logloss="logloss" in metrics, counts=resamples[group].counts)
            values = scorer.metrics()
            out[name][group] = dict({m: values[m] for m in metrics}, cells=int(mask.sum()), walls=int(y.sum()))
            boot[name] = scorer.resampled(draws) if draws is not None and n_boot else {}
        for name in probs:
            entry = out[name][group]
            for m in metrics:
                if boot[name]:
                    entry[m + "_ci"] = percentile_interval(boot[name][m], level)
                if reference is not None:
                    entry[m + "_diff"] = entry[m] - out[reference][group][m]
                    if boot[name]:
                        entry[m + "_diff_ci"] = percentile_interval(boot[name][m] - boot[reference][m], level)
    return out


@dataclass(frozen=True)
class GroupBlocks:
    """One group's cells cut into bootstrap blocks, and the block resamples :func:`score` draws for it."""

    mask: np.ndarray  # [y, x] bool: the group's cells; every per-cell array below is in ``p[mask]`` order
    labels: np.ndarray  # float 0/1 per cell: the second half calls it occupied
    inverse: np.ndarray  # each cell's block index, 0 .. n_blocks - 1
    n_blocks: int
    counts: tuple  # (cells, walls) per block
    draws: np.ndarray | None  # [n_boot, n_blocks]: how often each block was drawn; None when the group is empty


def block_resamples(split: ScanSplit, n_boot: int = 200, block: int = DEFAULT_BLOCK, seed: int = 0) -> dict:
    """``{group: GroupBlocks}``: the spatial-block resamples :func:`score` uses (the same seed, the same draws), so
    anything scored with them is paired with :func:`score`'s intervals.

    >>> sp = ScanSplit(*(np.random.default_rng(0).integers(0, 3, (8, 8)) for _ in range(4)))
    >>> r = block_resamples(sp, n_boot=3, block=4)
    >>> r["all"].draws.shape, int(r["all"].draws.sum(axis=1)[0]) == r["all"].n_blocks
    ((3, 4), True)
    """
    layout = _layout(split, block)
    rng = np.random.default_rng(seed)
    out = {}
    for group in GROUPS:  # every group draws, asked for or not: the same seed gives the same intervals
        mask, y, uniq, inverse, counts = layout[group]
        draws = _draws(rng, len(uniq), n_boot) if len(uniq) else None  # a block's weight: how often it was drawn
        out[group] = GroupBlocks(mask, y, inverse, len(uniq), counts, draws)
    return out


def percentile_interval(values, level: float = 0.95) -> tuple:
    """The central ``level`` percentile interval of the finite ``values`` (NaN, NaN if none).

    >>> percentile_interval(np.arange(101.0), 0.5)
    (25.0, 75.0)
    """
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return (float("nan"), float("nan"))
    alpha = (1 - level) / 2
    return (float(np.quantile(v, alpha)), float(np.quantile(v, 1 - alpha)))
