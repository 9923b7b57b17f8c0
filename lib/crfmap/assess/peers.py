"""Published alternatives as scan-split rows: OctoMap's update and Bayesian Hilbert maps.

Both are this project's implementations, not the authors' programs (:mod:`crfmap.mapping.octomap`, checked cell by cell
against the OctoMap library; :mod:`crfmap.mapping.hilbert`, from the authors' BHM2D update). Each maps the split's first
half (``split.first_scans``) on the split's grid and is scored like every other row. Their constants were chosen on
Intel's scan split by the certainty preset's rule (a coordinate search by the Brier score, every chosen value interior
to its grid; ``crfstudy.analysis.peer_search`` keeps the records), then fixed for every recording. The wall times
:func:`peer_rows` returns are benchmark numbers of this machine.
"""
from __future__ import annotations

import time

from crfmap.errors import InputError


# chosen on Intel (see the module doc); Brier over all observed cells, most of them free, favours freeing cells fast
OCTOMAP_INTEL = {"p_hit": 0.8, "p_miss": 0.2, "clamp_min": 0.005, "clamp_max": 0.9999}


def octomap_row(split, progress=False, **options):
    """OctoMap's clamped log-odds map of the split's first half, [y, x] P(occupied).

    ``options`` (``p_hit``, ``p_miss``, ``clamp_min``, ``clamp_max``) override :data:`OCTOMAP_INTEL`; ``progress`` is
    accepted like every row's (one pass over the scans: no bar)."""
    from crfmap.mapping.octomap import octomap_grid

    return octomap_grid(_scans(split), split.resolution, bounds=split.bounds, **{**OCTOMAP_INTEL, **options}).probability


def hilbert_row(split, progress=False, **options):
    """The Bayesian Hilbert map of the split's first half queried at its cell centres, [y, x] P(occupied)."""
    from crfmap.mapping.hilbert import hilbert_grid

    p = hilbert_grid(_scans(split), split.resolution, split.bounds, progress=progress, **options).probability
    if p.shape != split.shape:  # pragma: no cover - both follow the builder's rounding
        raise InputError("hilbert", f"grid {p.shape} does not match the split's {split.shape}")
    return p


def octomap_defaults_row(split, progress=False, **options):
    """OctoMap's update at the OctoMap library's own defaults, as users run it out of the box: tuned by Brier,
    ``octomap`` frees cells quickly and opens walls to nav2; scoring both rows, neither choice flatters the preset."""
    from crfmap.mapping.octomap import octomap_grid

    return octomap_grid(_scans(split), split.resolution, bounds=split.bounds, **options).probability


# name -> row function (split, progress=False, **options) -> [y, x] P; a new peer is one entry
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
        predictions[name] = _ROWS[name](split, progress=progress)
        seconds[name] = time.perf_counter() - start
    return predictions, seconds
