"""What a navigation stack does with a map: nav2's reading of it, scored on a scan split.

nav2 reads not P(occupied) but the trinary map ``crfmap infer`` writes, loaded by map_server and made lethal / free /
unknown by the costmap's static layer. :func:`nav2_classes` composes exactly those rules
(:func:`crfmap.io.nav2_values.nav2_values`, :mod:`crfmap.io.nav2_costmap`), so a cell is lethal here when it is lethal
in the written file; every row's P (peers' too) goes through them.

:func:`nav_scores` scores that reading against the second half of a :class:`ScanSplit`, per group of
:data:`crfmap.assess.scansplit.GROUPS` (all counts: :data:`COUNTS`). ``lethal_recall``, ``miss_rate`` (dangerous
misses) and ``unknown_rate`` are the shares of the held-out occupied cells (``split.labels()``) called lethal, *free*
and unknown (they add up to 1); ``far_miss_rate`` the share called free and farther than ``cover_radius`` from every
lethal cell (a hole the costmap's inflation leaves open), ``far_miss_share`` their share of the misses.
``lethal_precision`` is the share of held-out occupied cells among the held-out observed cells called lethal,
``free_error`` among those called free (in ``unseen``: how often a never-observed cell the map turned free is a wall).
``ghost_rate`` is the share called lethal of the cells the second half passed at least :data:`GHOST_PASSES` times
and never hit. ``face_offset`` is the mean distance [cells] from the held-out *face* cells (:func:`held_out_face`) to
the map's nearest lethal cell, capped at :data:`FACE_CAP` (farther is a missed wall): near 0 when the lethal cells
sit on the observed face, about 1 for a wall one cell back. ``auc`` and ``nll`` are scikit-learn's (P clipped to
:data:`crfmap.assess.scansplit.LOG_FLOOR`, as the scan split's log-loss).

Each ratio gets an interval, and one of its paired difference to the ``reference`` row, from the resamples of
:func:`crfmap.assess.scansplit.score` (a ratio resampled as the ratio of its block sums). Per map (``"map"``, no
interval): ``unknown_free``, the cells the first half never observed that the map calls free
(``unknown_free_observed`` of them the second half observed, ``unknown_free_occupied`` of those occupied), and
:func:`wall_shape`.

>>> from crfmap.assess.scansplit import ScanSplit
>>> sp = ScanSplit(first_hits=np.array([[0, 3, 0, 0]]), first_passes=np.array([[2, 0, 0, 0]]),
...                second_hits=np.array([[0, 2, 1, 0]]), second_passes=np.array([[3, 0, 0, 2]]))
>>> nav2_values(np.array([[0.2, 0.9, 0.5, 0.6]])).tolist()
[[0, 100, -1, -1]]
>>> s = nav_scores(sp, {"raw": sp.raw_probability()}, n_boot=0)
>>> s["raw"]["all"]["lethal_recall"], s["raw"]["all"]["ghost_rate"], s["raw"]["map"]["thickness"]
(0.5, 0.0, 1.0)
"""
from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from crfmap.assess.scansplit import (DEFAULT_BLOCK, GROUPS, LOG_FLOOR, ScanSplit, block_resamples, check_probability,
                                     check_scoring,
                                     percentile_interval, score)
from crfmap.errors import InputError
from crfmap.io.nav2_costmap import LETHAL_OBSTACLE, NO_INFORMATION, static_layer_costs
from crfmap.io.nav2_loader import DEFAULT_LOADER
from crfmap.io.nav2_values import nav2_values

COVER_RADIUS = 0.5  # [m] a dangerous miss farther than this from every lethal cell is a hole inflation leaves open
GHOST_PASSES = 2  # a held-out free cell passed at least this often and never hit: a lethal call there is a ghost
FACE_CAP = 3.0  # [cells] a held-out wall face farther than this from every lethal cell counts this far (a miss)
NAV_METRICS = ("lethal_recall", "lethal_precision", "miss_rate", "far_miss_rate", "far_miss_share", "unknown_rate",
               "ghost_rate", "free_error", "face_offset", "auc", "nll")
# each ratio as (numerator, denominator) of per-cell counts; the bootstrap resamples both as block sums
RATIOS = {"lethal_recall": ("lethal_hits", "occupied"), "lethal_precision": ("lethal_hits", "lethal"),
          "miss_rate": ("misses", "occupied"), "far_miss_rate": ("far_misses", "occupied"),
          "far_miss_share": ("far_misses", "misses"), "unknown_rate": ("unknown_walls", "occupied"),
          "ghost_rate": ("ghosts", "ghost_candidates"), "free_error": ("misses", "free"),
          "face_offset": ("face_offset_cells", "face_cells")}
COUNTS = ("occupied", "lethal", "lethal_hits", "misses", "far_misses", "unknown_walls", "ghost_candidates", "ghosts",
          "free", "face_cells", "face_offset_cells")
MAP_METRICS = ("unknown_free", "unknown_free_observed", "unknown_free_occupied", "lethal_cells", "skeleton_m",
               "thickness", "components", "components_per_10m")


def nav2_classes(probability, loader: str = DEFAULT_LOADER) -> tuple:
    """(lethal, free) boolean [y, x] masks of the costmap's static layer on :func:`nav2_values` (else unknown).

    >>> lethal, free = nav2_classes(np.array([[0.9, 0.1, 0.5]]))
    >>> lethal.tolist(), free.tolist()
    ([[True, False, False]], [[False, True, False]])
    """
    values = nav2_values(probability, loader)
    costs = static_layer_costs(np.arange(-1, 101, dtype=np.int8))[values.astype(np.int16) + 1]
    lethal = costs == LETHAL_OBSTACLE
    return lethal, ~lethal & (costs != NO_INFORMATION)


def skeleton_length(skeleton) -> float:
    """Length [cells] of a one-cell-wide skeleton: its 8-neighbour steps plus one cell per 8-connected piece.

    A side step is 1, a corner step sqrt 2 unless the two cells share a side neighbour on the skeleton (an L's
    corner, already two side steps). A piece's two half-cell ends add one cell: a line of n cells is n long.

    >>> skeleton_length(np.eye(3, dtype=bool)), skeleton_length(np.ones((1, 5), bool))
    (3.8284271247461903, 5.0)
    """
    s = np.asarray(skeleton, dtype=bool)
    if s.ndim != 2:
        raise InputError("skeleton", f"expected a 2-D [y, x] mask, got shape {s.shape}")
    if not s.any():
        return 0.0
    side = int(np.sum(s[:, 1:] & s[:, :-1])) + int(np.sum(s[1:, :] & s[:-1, :]))
    a, b, c, d = s[:-1, :-1], s[:-1, 1:], s[1:, :-1], s[1:, 1:]  # the four cells of every 2x2 square
    corner = int(np.sum(a & d & ~b & ~c)) + int(np.sum(b & c & ~a & ~d))
    pieces = ndimage.label(s, structure=np.ones((3, 3), bool))[1]
    return float(side + math.sqrt(2) * corner + pieces)


def wall_shape(lethal, resolution: float) -> dict:
    """Thickness and continuity of a map's lethal cells (boolean [y, x]) on ``resolution`` [m] cells.

    ``thickness``: lethal cells over the length [cells] of their skeleton (:func:`skeleton_length` of scikit-image's
    ``skeletonize``): a one-cell wall is 1. ``components``: 8-connected lethal pieces; ``components_per_10m``: per
    10 m of skeleton (fewer: more continuous walls). NaN without lethal cells.

    >>> wall = np.zeros((5, 12), bool); wall[2, 1:11] = True
    >>> s = wall_shape(wall, 0.05)
    >>> s["thickness"], s["components"], round(s["components_per_10m"], 3)
    (1.0, 1, 20.0)
    """
    from skimage.morphology import skeletonize

    lethal = np.asarray(lethal)
    if lethal.ndim != 2 or lethal.dtype != bool:
        raise InputError("lethal", f"expected a 2-D boolean [y, x] mask, got {lethal.dtype} of shape {lethal.shape}")
    if not (isinstance(resolution, (int, float, np.floating, np.integer)) and math.isfinite(resolution)
            and resolution > 0):
        raise InputError("resolution", f"must be a positive cell size in metres, got {resolution!r}")
    cells = int(lethal.sum())
    components = int(ndimage.label(lethal, structure=np.ones((3, 3), bool))[1])
    length = skeleton_length(skeletonize(lethal)) if cells else 0.0  # [cells]
    metres = length * float(resolution)
    return {"lethal_cells": cells, "skeleton_m": metres, "components": components,
            "thickness": cells / length if length > 0 else float("nan"),
            "components_per_10m": components / (metres / 10.0) if metres > 0 else float("nan")}


def _far_from_lethal(lethal, resolution, radius):
    """Boolean [y, x]: farther than ``radius`` [m] from the nearest lethal cell centre (all True without one)."""
    if not lethal.any():
        return np.ones(lethal.shape, bool)
    return ndimage.distance_transform_edt(~lethal, sampling=resolution) > radius


def cell_counts(split: ScanSplit, lethal, free, far) -> dict:
    """Per-cell indicators {count name: [y, x]} of :data:`COUNTS` for one map's classes on ``split`` (held-out observed
    cells only); ``far``: cells beyond the cover radius of every lethal cell."""
    observed = split.group("all")
    occupied = split.labels()
    candidates = observed & (split.second_passes >= GHOST_PASSES) & (split.second_hits == 0)
    unknown = ~lethal & ~free
    face = held_out_face(split)
    offset = np.minimum(ndimage.distance_transform_edt(~lethal), FACE_CAP) if lethal.any() else FACE_CAP
    return {"occupied": occupied, "lethal": lethal & observed, "lethal_hits": lethal & occupied,
            "misses": free & occupied, "far_misses": free & occupied & far, "unknown_walls": unknown & occupied,
            "ghost_candidates": candidates, "ghosts": candidates & lethal, "free": free & observed,
            "face_cells": face, "face_offset_cells": np.where(face, offset, 0.0)}


def held_out_face(split: ScanSplit) -> np.ndarray:
    """Boolean [y, x]: held-out occupied cells with a held-out free cell among their four side neighbours.

    >>> from crfmap.assess.scansplit import ScanSplit
    >>> z = np.zeros((1, 4), int)
    >>> held_out_face(ScanSplit(z, z, np.array([[0, 2, 2, 0]]), np.array([[3, 0, 0, 0]]))).tolist()
    [[False, True, False, False]]
    """
    occupied = split.labels()
    free = split.group("all") & ~occupied
    return occupied & ndimage.binary_dilation(free, structure=ndimage.generate_binary_structure(2, 1))


def _ratio(num, den):
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1), np.nan)


def _sklearn_scores(p, y):
    """(ROC AUC, NLL) of P against 0/1 labels by scikit-learn; NaN AUC when one class is missing."""
    from sklearn.metrics import log_loss, roc_auc_score

    if y.size == 0:
        return float("nan"), float("nan")
    y = y.astype(np.int8)  # integer labels: scikit-learn's label checks are faster on them
    auc = float(roc_auc_score(y, p)) if 0 < y.sum() < y.size else float("nan")
    nll = float(log_loss(y, np.clip(p, LOG_FLOOR, 1 - LOG_FLOOR), labels=[0, 1]))
    return auc, nll


def nav_scores(split: ScanSplit, predictions: dict, n_boot: int = 200, block: int = DEFAULT_BLOCK, seed: int = 0,
               reference: str | None = "raw", level: float = 0.95, cover_radius: float = COVER_RADIUS,
               loader: str = DEFAULT_LOADER, scores: dict | None = None) -> dict:
    """nav2's reading of each map ``{name: [y, x] P}`` scored against the split's second half.

    Returns ``{name: {group: {metric: value, metric + "_ci": (lo, hi), metric + "_diff": name minus reference,
    metric + "_diff_ci": (lo, hi), count: int, ...}, "map": {...}}}`` with the metrics of the module doc
    (``n_boot=0``: no intervals). ``auc`` and ``nll`` take :func:`crfmap.assess.scansplit.score`'s intervals: pass
    its result as ``scores`` if computed already (same ``n_boot``, ``block``, ``seed``, ``reference``).

    >>> from crfmap.assess.scansplit import ScanSplit
    >>> sp = ScanSplit(*(np.random.default_rng(0).integers(0, 3, (8, 8)) for _ in range(4)))
    >>> s = nav_scores(sp, {"raw": sp.raw_probability()}, n_boot=20, block=4)
    >>> lo, hi = s["raw"]["seen"]["lethal_recall_ci"]
    >>> bool(lo <= s["raw"]["seen"]["lethal_recall"] <= hi), s["raw"]["seen"]["lethal_recall_diff_ci"]
    (True, (0.0, 0.0))
    """
    if not isinstance(split, ScanSplit):
        raise InputError("split", f"expected a ScanSplit, got {type(split).__name__}")
    check_scoring(predictions, reference, n_boot, block)
    if not (isinstance(cover_radius, (int, float)) and math.isfinite(cover_radius) and cover_radius >= 0):
        raise InputError("cover_radius", f"must be a non-negative distance in metres, got {cover_radius!r}")
    probs = {name: check_probability(p, split.shape, name) for name, p in predictions.items()}
    if scores is None:
        scores = score(split, probs, n_boot=n_boot, block=block, seed=seed, reference=reference, level=level,
                       metrics=("auc", "logloss"))
    resamples = block_resamples(split, n_boot=n_boot, block=block, seed=seed)
    labels = split.labels()
    never_seen = (split.first_hits + split.first_passes) == 0
    out, boot = {}, {}
    for name, p in probs.items():
        lethal, free = nav2_classes(p, loader)
        far = _far_from_lethal(lethal, split.resolution, cover_radius)
        indicators = cell_counts(split, lethal, free, far)
        turned = never_seen & free
        out[name] = {"map": {"unknown_free": int(turned.sum()),
                             "unknown_free_observed": int((turned & split.group("all")).sum()),
                             "unknown_free_occupied": int((turned & labels).sum()),
                             **wall_shape(lethal, split.resolution)}}
        boot[name] = {}
        for group in GROUPS:
            r = resamples[group]
            # per-block sums of every count: the point estimate is their total, a resample their weighted total
            sums = np.stack([np.bincount(r.inverse, weights=indicators[c][r.mask], minlength=r.n_blocks)
                             for c in COUNTS]).reshape(len(COUNTS), r.n_blocks)
            totals = sums.sum(axis=1)
            entry = {c: (float(t) if c == "face_offset_cells" else int(round(t))) for c, t in zip(COUNTS, totals)}
            total = dict(zip(COUNTS, totals))
            for m, (num, den) in RATIOS.items():
                entry[m] = float(_ratio(total[num], total[den]))
            entry["auc"], entry["nll"] = _sklearn_scores(p[r.mask], r.labels)
            out[name][group] = entry
            if r.draws is not None and n_boot:
                # einsum, not BLAS: a product this small gains nothing from threads, and BLAS threads spin on a busy machine
                resampled = dict(zip(COUNTS, np.einsum("kb,nb->kn", sums, r.draws)))
                boot[name][group] = {m: _ratio(resampled[num], resampled[den]) for m, (num, den) in RATIOS.items()}
    for name in probs:
        for group in GROUPS:
            entry = out[name][group]
            for m, theirs in (("auc", "auc"), ("nll", "logloss")):  # score()'s intervals: the same resamples
                for suffix in ("_ci", "_diff_ci"):
                    if theirs + suffix in scores[name][group]:
                        entry[m + suffix] = scores[name][group][theirs + suffix]
            if group in boot[name]:
                for m in RATIOS:
                    entry[m + "_ci"] = percentile_interval(boot[name][group][m], level)
            if reference is None:
                continue
            for m in NAV_METRICS:
                entry[m + "_diff"] = entry[m] - out[reference][group][m]
                if m in RATIOS and group in boot[name]:
                    entry[m + "_diff_ci"] = percentile_interval(boot[name][group][m] - boot[reference][group][m],
                                                                level)
        if reference is not None:
            shape = out[name]["map"]
            for m in MAP_METRICS:
                shape[m + "_diff"] = shape[m] - out[reference]["map"][m]
    return out


__all__ = ["COVER_RADIUS", "GHOST_PASSES", "FACE_CAP", "NAV_METRICS", "MAP_METRICS", "nav2_classes",
           "skeleton_length", "wall_shape", "cell_counts", "held_out_face", "nav_scores"]
