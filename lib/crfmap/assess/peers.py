"""Published alternatives as scan-split rows: OctoMap's update and Bayesian Hilbert maps.

Each peer maps the first half's scans (``split.first_scans``) on the split's grid; the rows are
scored like every other row (:func:`crfmap.assess.scansplit.score`).

- ``octomap``: :func:`crfmap.mapping.octomap.octomap_grid` with OctoMap's defaults;
- ``hilbert``: :func:`crfmap.mapping.hilbert.hilbert_grid` with the constants chosen on the Intel log.

:func:`peer_rows` returns the predictions and each peer's wall time (a benchmark number:
it says how long a map took on this machine, nothing more).
"""
from __future__ import annotations

import time

from crfmap.errors import InputError

PEERS = ("octomap", "hilbert")


def octomap_row(split, **options):
    """OctoMap's clamped log-odds map of the split's first half, [y, x] P(occupied)."""
    from crfmap.mapping.octomap import octomap_grid

    return octomap_grid(_scans(split), split.resolution, bounds=split.bounds, **options).probability


def hilbert_row(split, progress=False, **options):
    """The Bayesian Hilbert map of the split's first half queried at its cell centres, [y, x] P(occupied)."""
    from crfmap.mapping.hilbert import hilbert_grid

    p = hilbert_grid(_scans(split), split.resolution, split.bounds, progress=progress, **options).probability
    if p.shape != split.shape:  # pragma: no cover - both follow the builder's rounding
        raise InputError("hilbert", f"grid {p.shape} does not match the split's {split.shape}")
    return p


_ROWS = {"octomap": octomap_row, "hilbert": hilbert_row}


def _scans(split):
    if split.first_scans is None or split.bounds is None:
        raise InputError(split.source or "scan split", "the peers need the first half's scans and the grid's bounds "
                         "(make the split with crfmap.assess.scansplit.scan_split)")
    return split.first_scans


def peer_rows(split, methods=PEERS, progress=False) -> tuple[dict, dict]:
    """({name: [y, x] P}, {name: seconds}) of the peers ``methods`` on a scan split."""
    unknown = [m for m in methods if m not in _ROWS]
    if unknown:
        raise InputError("methods", f"unknown peer(s) {', '.join(unknown)}; known: {', '.join(PEERS)}")
    predictions, seconds = {}, {}
    for name in methods:
        start = time.perf_counter()
        predictions[name] = _ROWS[name](split, progress=progress) if name == "hilbert" else _ROWS[name](split)
        seconds[name] = time.perf_counter() - start
    return predictions, seconds


def hilbert_search(split, configs, progress=False) -> list:
    """Scan-split scores of the Hilbert map for each (feature_spacing, length_scale, free_spacing) [m] in ``configs``.

    How :mod:`crfmap.mapping.hilbert`'s constants were chosen, on the Intel log only (its record:
    :data:`HILBERT_SEARCH_INTEL`).
    """
    from crfmap.assess.scansplit import score

    rows = []
    for spacing, scale, free in configs:
        start = time.perf_counter()
        p = hilbert_row(split, progress=progress, feature_spacing=spacing, length_scale=scale, free_spacing=free)
        s = score(split, {"h": p}, n_boot=0)["h"]
        rows.append({"feature_spacing": spacing, "length_scale": scale, "free_spacing": free,
                     "seconds": time.perf_counter() - start, "brier_all": s["all"]["brier"],
                     "brier_unseen": s["unseen"]["brier"], "logloss_all": s["all"]["logloss"],
                     "auc_all": s["all"]["auc"], "wall_recall": s["all"]["wall_recall"]})
    return rows
