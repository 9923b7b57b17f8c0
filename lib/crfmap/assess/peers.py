"""Published alternatives as scan-split rows: OctoMap's update and Bayesian Hilbert maps.

Both peers are this project's implementations, not the authors' programs: OctoMap's clamped
log-odds update rewritten on a 2-D grid (:mod:`crfmap.mapping.octomap`; its update is checked cell
by cell against the real OctoMap library, through octomap-python, on the same rays:
``tests/mapping/test_octomap.py::test_matches_the_octomap_library``) and the Bayesian Hilbert map
rewritten with sparse features from the authors' BHM2D update (:mod:`crfmap.mapping.hilbert`).

Each peer maps the first half's scans (``split.first_scans``) on the split's grid; the rows are
scored like every other row (:func:`crfmap.assess.scansplit.score`).

- ``octomap``: :func:`crfmap.mapping.octomap.octomap_grid` with :data:`OCTOMAP_INTEL` (not OctoMap's defaults);
- ``hilbert``: :func:`crfmap.mapping.hilbert.hilbert_grid` with its module's constants.

Both sets of constants were chosen on Intel's scan split (5 cm, even scans map, odd scans score)
by the certainty preset's own rule: a coordinate search by the Brier score on all observed cells,
each constant on a grid of 5-6 values, widened until every chosen value is interior
(``crfstudy.analysis.peer_search``, which keeps the records), then fixed for every recording.

:func:`peer_rows` returns the predictions and each peer's wall time (a benchmark number:
it says how long a map took on this machine, nothing more).
"""
from __future__ import annotations

import time

from crfmap.errors import InputError


# OctoMap's constants for the peer row, chosen on Intel (crfstudy.analysis.peer_search.octomap_search; cache
# study/crfstudy/analysis/peer_search_octomap_intel.json). The library's defaults (hit 0.7, miss 0.4, clamping
# 0.1192 / 0.971: crfmap.mapping.octomap.P_HIT, ...) score 0.0459581 there; three grids were searched (the first two
# chose a clamping bound on their edge), 72 configurations in the last one, 4 rounds. The upper clamp is flat above
# 0.999 (Brier within 4e-5): on this score OctoMap's upper clamp hardly matters once it is above 0.99. Scoring all 1080
# configurations of the last grid finds the same optimum. What the rule buys on Intel (`crfmap evaluate`): Brier
# 0.0460 -> 0.0263, ECE 0.142 -> 0.011, but AUC 0.9745 -> 0.9565 and, read by nav2, lethal recall 63.6 -> 54.2 % and
# dangerous misses 2.2 -> 24.3 % of the held-out occupied cells (raw grid 10.3 %): Brier over all observed cells,
# most of them free, favours a map that frees cells fast. (The gated default was chosen by log-loss with occupied
# cells weighted 3x; by that score the same search keeps hit / miss 0.7 / 0.4, its clamps on the grid's edges.)
OCTOMAP_INTEL = {"p_hit": 0.8, "p_miss": 0.2, "clamp_min": 0.005, "clamp_max": 0.9999}
# The search records (each constant over its grid, the scores) are the study's: crfstudy.analysis.peer_search.


def octomap_row(split, **options):
    """OctoMap's clamped log-odds map of the split's first half, [y, x] P(occupied).

    ``options`` (``p_hit``, ``p_miss``, ``clamp_min``, ``clamp_max``) override :data:`OCTOMAP_INTEL`.
    """
    from crfmap.mapping.octomap import octomap_grid

    return octomap_grid(_scans(split), split.resolution, bounds=split.bounds, **{**OCTOMAP_INTEL, **options}).probability


def hilbert_row(split, progress=False, **options):
    """The Bayesian Hilbert map of the split's first half queried at its cell centres, [y, x] P(occupied)."""
    from crfmap.mapping.hilbert import hilbert_grid

    p = hilbert_grid(_scans(split), split.resolution, split.bounds, progress=progress, **options).probability
    if p.shape != split.shape:  # pragma: no cover - both follow the builder's rounding
        raise InputError("hilbert", f"grid {p.shape} does not match the split's {split.shape}")
    return p


def octomap_defaults_row(split, **options):
    """OctoMap's update at the OctoMap library's own defaults (hit 0.7, miss 0.4, clamping 0.1192 / 0.971): the peer
    as users run it out of the box. Tuned by scan-split Brier (``octomap``) it frees cells quickly and opens walls
    to nav2; at its defaults a cell needs about four misses to read free. Both rows are scored, so neither choice
    flatters the preset."""
    from crfmap.mapping.octomap import octomap_grid

    return octomap_grid(_scans(split), split.resolution, bounds=split.bounds, **options).probability


# The registry of published peers: name -> row function (split, **options) -> [y, x] P. compare(), crfmap evaluate
# and the notebooks read their rows from here; a new peer is one function and one entry.
_ROWS = {"octomap": octomap_row, "octomap-defaults": octomap_defaults_row, "hilbert": hilbert_row}
PEERS = tuple(_ROWS)


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
