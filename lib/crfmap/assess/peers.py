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

# How crfmap.mapping.hilbert's constants were chosen: peer_search.hilbert_search on the Intel log's scan split at 5 cm
# (even scans fit, odd scans score; nothing else seen), 2026-12-02. Columns: feature spacing [m], length
# scale [m], free-point spacing [m], Brier (all observed cells), log-loss, AUC, wall recall, fit seconds
# (on a shared, loaded 2-core machine). Rule: the lowest Brier among fits under a minute on Intel here.
HILBERT_SEARCH_COLUMNS = ("feature_spacing", "length_scale", "free_spacing", "brier_all", "logloss_all", "auc_all",
                          "wall_recall", "seconds")
HILBERT_SEARCH_INTEL = (
    (0.25, 0.25, 0.25, 0.0731, 0.981, 0.705, 0.311, 40),
    (0.25, 0.125, 0.25, 0.0890, 1.016, 0.936, 0.698, 17),
    (0.2, 0.2, 0.2, 0.0636, 0.851, 0.737, 0.314, 37),
    (0.15, 0.15, 0.15, 0.0555, 0.739, 0.788, 0.314, 74),
    (0.15, 0.1125, 0.15, 0.0582, 0.755, 0.927, 0.499, 24),
    (0.15, 0.075, 0.15, 0.0547, 0.576, 0.966, 0.769, 17),
    (0.1, 0.1, 0.1, 0.0486, 0.642, 0.855, 0.325, 46),
    (0.1, 0.1, 0.2, 0.0769, 1.028, 0.924, 0.711, 17),
    (0.1, 0.075, 0.1, 0.0446, 0.565, 0.952, 0.535, 27),
    (0.1, 0.075, 0.05, 0.0531, 0.691, 0.896, 0.109, 86),
    (0.1, 0.05, 0.1, 0.0371, 0.364, 0.977, 0.791, 14),
    (0.1, 0.05, 0.15, 0.0545, 0.606, 0.975, 0.895, 22),
    (0.1, 0.04, 0.1, 0.0344, 0.246, 0.982, 0.866, 19),
    (0.1, 0.03, 0.1, 0.0340, 0.146, 0.981, 0.907, 26),
    (0.075, 0.0562, 0.075, 0.0384, 0.476, 0.962, 0.554, 57),
    (0.075, 0.0375, 0.075, 0.0307, 0.280, 0.981, 0.779, 39),
    (0.075, 0.03, 0.075, 0.0279, 0.177, 0.985, 0.838, 20),  # chosen
    (0.05, 0.0375, 0.05, 0.0343, 0.411, 0.967, 0.538, 158),
)


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
