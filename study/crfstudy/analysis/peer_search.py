"""How the peers' constants were chosen: the certainty preset's search rule, on the same recording and split.

Both peers (:mod:`crfmap.assess.peers`) are this project's implementations: OctoMap's update
(:mod:`crfmap.mapping.octomap`, checked against the real OctoMap library through octomap-python on the same
rays: ``tests/mapping/test_octomap.py::test_matches_the_octomap_library``) and the Bayesian Hilbert map
(:mod:`crfmap.mapping.hilbert`, the authors' BHM2D update rewritten sparse). Their constants are chosen the
way the certainty preset's are (:mod:`crfstudy.analysis.preset_search`): the coordinate search of
:func:`crfstudy.analysis.coordinate.coordinate_descent` (strict improvement, whole rounds until one changes
nothing) by the scan-split Brier score on all observed cells of Intel at 5 cm (even scans map, odd
scans score; nothing else seen), each constant on a grid of 5-6 values as the preset's 4-5, starting
from the values used before the search (OctoMap's library defaults; the Hilbert map's earlier choice).
A grid is wide enough when every chosen value has a grid value on either side
(:meth:`~crfstudy.analysis.coordinate.SearchResult.interior`); a grid whose choice sat on an edge was
widened there and the search rerun (:data:`EARLIER` records the dropped grids and their choices).

- OctoMap (:data:`OCTOMAP_GRID`): P(hit), P(miss) and the clamping bounds; a map takes ~0.05 s.
- The Hilbert map (:data:`HILBERT_GRID`): feature spacing, length scale and free-point spacing [m];
  a fit takes 1-7 s here (every scan of Intel's first half). Each fit's seconds are recorded; no fit
  is excluded for its time.

The results are kept in :data:`CACHES` (``python -m crfstudy.analysis.peer_search octomap|hilbert``
reruns one and rewrites its file; ``--check`` reruns it and compares), and copied as tables beside the
constants' records here (:data:`OCTOMAP_SEARCH_INTEL`, :data:`HILBERT_SEARCH_INTEL`).

>>> import numpy as np
>>> from crfmap.assess.scansplit import scan_split
>>> from crfmap.recording import ScanSet
>>> rng = np.random.default_rng(0)
>>> poses = np.column_stack([rng.uniform(1.8, 2.2, 8), rng.uniform(1.8, 2.2, 8), rng.uniform(-3, 3, 8)])
>>> scans = ScanSet(rng.uniform(0.5, 1.5, (8, 40)).astype(np.float32), -1.5, 0.075, 0.1, 5.0, poses, np.arange(8.0))
>>> r = octomap_search(scan_split(scans, 0.1), grid={"p_hit": (0.6, 0.7, 0.8), "p_miss": (0.3, 0.4)})
>>> r.configurations, r.converged, r.best_brier < r.trace[0]["brier"]
(6, True, True)
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from crfmap.assess.peers import hilbert_row, octomap_row
from crfmap.errors import InputError
from crfmap.mapping import octomap
from crfstudy.analysis.coordinate import SearchResult, check_or_write, coordinate_descent, split_brier
from crfstudy.analysis.preset_search import TRAINING, TRAINING_RESOLUTION
from crfmap.assess.scansplit import score, scan_split
from crfmap.io.recordings import load_recording
from crfmap.data import data_file

# OctoMap's four constants, as probabilities like OctoMap's own setters (setProbHit, setClampingThresMin, ...)
OCTOMAP_GRID = {
    "p_hit": (0.55, 0.6, 0.65, 0.7, 0.8, 0.9),
    "p_miss": (0.1, 0.2, 0.3, 0.4, 0.45),
    "clamp_min": (0.001, 0.005, 0.01, 0.02, 0.05, 0.1192),
    "clamp_max": (0.971, 0.99, 0.999, 0.9999, 0.99999, 0.999999),
}
OCTOMAP_START = {"p_hit": octomap.P_HIT, "p_miss": octomap.P_MISS, "clamp_min": octomap.CLAMP_MIN,
                 "clamp_max": octomap.CLAMP_MAX}  # the library's defaults, the row's constants before this search
# the Hilbert map's three lengths [m]; the first grid (2026-12-02, HILBERT_SEARCH_INTEL_FIRST)
# chose length scale 0.03 at its smallest value: this one reaches below it and around the chosen spacings
HILBERT_GRID = {
    "length_scale": (0.015, 0.02, 0.025, 0.03, 0.0375),
    "feature_spacing": (0.05, 0.06, 0.075, 0.09, 0.1),
    "free_spacing": (0.025, 0.035, 0.05, 0.06, 0.075, 0.09),
}
HILBERT_START = {"feature_spacing": 0.075, "length_scale": 0.03, "free_spacing": 0.075}  # the first grid's choice
# the grids searched before the ones above, each dropped because its choice sat on an edge (the same rule, the same
# split; their best, Brier and configurations as the search printed them)
EARLIER = {
    "octomap": (
        {"grid": {"p_hit": [0.55, 0.6, 0.65, 0.7, 0.8, 0.9], "p_miss": [0.1, 0.2, 0.3, 0.4, 0.45],
                  "clamp_min": [0.02, 0.05, 0.1192, 0.2, 0.3], "clamp_max": [0.6, 0.7, 0.8, 0.9, 0.971, 0.99]},
         "best": {"p_hit": 0.7, "p_miss": 0.3, "clamp_min": 0.02, "clamp_max": 0.99}, "best_brier": 0.0274247,
         "configurations": 37, "edge": ["clamp_min", "clamp_max"]},
        {"grid": {"p_hit": [0.55, 0.6, 0.65, 0.7, 0.8, 0.9], "p_miss": [0.1, 0.2, 0.3, 0.4, 0.45],
                  "clamp_min": [0.001, 0.005, 0.01, 0.02, 0.05, 0.1192],
                  "clamp_max": [0.9, 0.971, 0.99, 0.997, 0.999, 0.9999]},
         "best": {"p_hit": 0.8, "p_miss": 0.2, "clamp_min": 0.005, "clamp_max": 0.9999}, "best_brier": 0.0263280,
         "configurations": 72, "edge": ["clamp_max"]},
    ),
    "hilbert": (
        # (the cache's record names where the table stood then; it is :data:`HILBERT_SEARCH_INTEL_FIRST` now)
        {"grid": "crfmap.assess.peers.HILBERT_SEARCH_INTEL_FIRST (18 hand-picked settings, 2026-12-02)",
         "best": {"feature_spacing": 0.075, "length_scale": 0.03, "free_spacing": 0.075}, "best_brier": 0.0279,
         "configurations": 18, "edge": ["length_scale"]},
        {"grid": {"length_scale": [0.015, 0.02, 0.025, 0.03, 0.0375], "feature_spacing": [0.05, 0.06, 0.075, 0.09, 0.1],
                  "free_spacing": [0.05, 0.06, 0.075, 0.09, 0.1]},
         "best": {"feature_spacing": 0.075, "length_scale": 0.025, "free_spacing": 0.05}, "best_brier": 0.0225795,
         "configurations": 21, "edge": ["free_spacing"]},
    ),
}
OCTOMAP_SEARCH_COLUMNS = ("p_hit", "p_miss", "clamp_min", "clamp_max", "brier_all")
# the search's profile through the chosen values: each constant over its grid, the others at the chosen values
OCTOMAP_SEARCH_INTEL = (
    (0.8, 0.2, 0.005, 0.9999, 0.0263280),  # chosen
    (0.55, 0.2, 0.005, 0.9999, 0.0379656),
    (0.6, 0.2, 0.005, 0.9999, 0.0345712),
    (0.65, 0.2, 0.005, 0.9999, 0.0315979),
    (0.7, 0.2, 0.005, 0.9999, 0.0291624),
    (0.9, 0.2, 0.005, 0.9999, 0.0267903),
    (0.8, 0.1, 0.005, 0.9999, 0.0292066),
    (0.8, 0.3, 0.005, 0.9999, 0.0271602),
    (0.8, 0.4, 0.005, 0.9999, 0.0417298),
    (0.8, 0.45, 0.005, 0.9999, 0.0711153),
    (0.8, 0.2, 0.001, 0.9999, 0.0264140),
    (0.8, 0.2, 0.01, 0.9999, 0.0263340),
    (0.8, 0.2, 0.02, 0.9999, 0.0265234),
    (0.8, 0.2, 0.05, 0.9999, 0.0282323),
    (0.8, 0.2, 0.1192, 0.9999, 0.0383555),
    (0.8, 0.2, 0.005, 0.971, 0.0267676),
    (0.8, 0.2, 0.005, 0.99, 0.0265503),
    (0.8, 0.2, 0.005, 0.999, 0.0263624),
    (0.8, 0.2, 0.005, 0.99999, 0.0263284),
    (0.8, 0.2, 0.005, 0.999999, 0.0263289),
)

# How crfmap.mapping.hilbert's constants were first chosen: hilbert_search on the Intel log's scan split at 5 cm
# (even scans fit, odd scans score; nothing else seen), 2026-12-02. Columns: feature spacing [m], length
# scale [m], free-point spacing [m], Brier (all observed cells), log-loss, AUC, wall recall, fit seconds
# (on a shared, loaded 2-core machine). Rule then: the lowest Brier among fits under a minute on Intel here. Its
# choice, length scale 0.03, was the grid's smallest: HILBERT_SEARCH_INTEL is the search that replaced it.
HILBERT_SEARCH_COLUMNS = ("feature_spacing", "length_scale", "free_spacing", "brier_all", "logloss_all", "auc_all",
                          "wall_recall", "seconds")
HILBERT_SEARCH_INTEL_FIRST = (
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
    (0.075, 0.03, 0.075, 0.0279, 0.177, 0.985, 0.838, 20),  # chosen then
    (0.05, 0.0375, 0.05, 0.0343, 0.411, 0.967, 0.538, 158),
)


# How crfmap.mapping.hilbert's constants are chosen now: hilbert_coordinate_search, the
# preset's coordinate search by scan-split Brier (all observed cells) on Intel at 5 cm from the first grid's choice
# (cache study/crfstudy/analysis/peer_search_hilbert_intel.json), 2026-12-04. Rows in the order scored, columns
# HILBERT_SEARCH_COLUMNS; seconds are each fit's on a shared 2-core machine (1-7 s: no fit is excluded for its time).
# Its first grid (free spacing 0.05-0.1) chose free spacing 0.05, its edge; this one reaches 0.025. The chosen lengths
# have grid values on either side. Lower Brier than the first choice (0.0226 against 0.0279), at lower wall recall
# (0.735 against 0.838): denser free points pull thin walls down. Read by nav2 on Intel (`crfmap evaluate`): lethal
# recall 81.4 -> 66.7 %, precision 71.0 -> 81.1 %, dangerous misses 11.9 -> 14.7 %, walls 3.41 -> 2.44 cells thick.
HILBERT_SEARCH_INTEL = (
    (0.075, 0.03, 0.075, 0.0279, 0.177, 0.985, 0.838, 2.6),  # start: the first grid's choice
    (0.075, 0.015, 0.075, 0.0698, 0.258, 0.953, 0.845, 1.4),
    (0.075, 0.02, 0.075, 0.0286, 0.110, 0.978, 0.865, 2.1),
    (0.075, 0.025, 0.075, 0.0269, 0.122, 0.985, 0.861, 1.8),
    (0.075, 0.0375, 0.075, 0.0307, 0.280, 0.981, 0.779, 1.8),
    (0.05, 0.025, 0.075, 0.0294, 0.268, 0.986, 0.854, 2.4),
    (0.06, 0.025, 0.075, 0.0279, 0.193, 0.986, 0.858, 3.3),
    (0.09, 0.025, 0.075, 0.0271, 0.103, 0.980, 0.857, 2.9),
    (0.1, 0.025, 0.075, 0.0292, 0.106, 0.979, 0.843, 1.2),
    (0.075, 0.025, 0.025, 0.0309, 0.133, 0.972, 0.420, 6.8),
    (0.075, 0.025, 0.035, 0.0252, 0.100, 0.980, 0.582, 3.9),
    (0.075, 0.025, 0.05, 0.0226, 0.087, 0.984, 0.735, 3.0),  # chosen
    (0.075, 0.025, 0.06, 0.0235, 0.095, 0.985, 0.805, 3.1),
    (0.075, 0.025, 0.09, 0.0312, 0.159, 0.984, 0.895, 2.4),
    (0.075, 0.015, 0.05, 0.0667, 0.249, 0.939, 0.742, 2.0),
    (0.075, 0.02, 0.05, 0.0239, 0.089, 0.975, 0.761, 3.3),
    (0.075, 0.03, 0.05, 0.0255, 0.144, 0.982, 0.680, 3.4),
    (0.075, 0.0375, 0.05, 0.0317, 0.289, 0.975, 0.563, 4.1),
    (0.05, 0.025, 0.05, 0.0263, 0.225, 0.982, 0.720, 4.1),
    (0.06, 0.025, 0.05, 0.0245, 0.147, 0.984, 0.725, 4.5),
    (0.09, 0.025, 0.05, 0.0234, 0.084, 0.977, 0.732, 5.2),
    (0.1, 0.025, 0.05, 0.0252, 0.089, 0.978, 0.719, 3.0),
)

HILBERT_DETAILS = ("seconds", "brier_unseen", "logloss_all", "auc_all", "wall_recall")  # recorded beside Brier
CACHES = {"octomap": Path(__file__).with_name("peer_search_octomap_intel.json"),
          "hilbert": Path(__file__).with_name("peer_search_hilbert_intel.json")}


def octomap_brier(split, constants: dict) -> float:
    """Scan-split Brier score (all cells) of OctoMap's map of the split's first half with ``constants``."""
    return split_brier(split, octomap_row(split, **constants))


def octomap_search(split, grid: dict | None = None, start: dict | None = None, max_rounds: int = 10,
                   progress: bool = False) -> SearchResult:
    """The preset's coordinate search over OctoMap's constants (default :data:`OCTOMAP_GRID` from :data:`OCTOMAP_START`)."""
    grid = OCTOMAP_GRID if grid is None else grid
    _check_names(grid, OCTOMAP_GRID)
    return coordinate_descent(lambda c: octomap_brier(split, c), grid, OCTOMAP_START if start is None else start,
                              order=OCTOMAP_GRID, max_rounds=max_rounds, progress=progress, desc="OctoMap search")


def hilbert_search(split, configs, progress=False) -> list:
    """Scan-split scores of the Hilbert map for each (feature_spacing, length_scale, free_spacing) [m] in ``configs``."""
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


def hilbert_coordinate_search(split, grid: dict | None = None, start: dict | None = None, max_rounds: int = 10,
                              progress: bool = False) -> SearchResult:
    """The preset's coordinate search over the Hilbert map's lengths (default :data:`HILBERT_GRID`).

    Each trace entry also holds the fit's :data:`HILBERT_DETAILS` (seconds, log-loss, AUC, ...).
    """
    grid = HILBERT_GRID if grid is None else grid
    _check_names(grid, HILBERT_GRID)
    details = {}

    def brier(c):
        row = hilbert_search(split, [(c["feature_spacing"], c["length_scale"], c["free_spacing"])])[0]
        details[tuple(sorted(c.items()))] = {k: row[k] for k in HILBERT_DETAILS}
        return row["brier_all"]

    result = coordinate_descent(brier, grid, HILBERT_START if start is None else start, order=HILBERT_GRID,
                                max_rounds=max_rounds, progress=progress, desc="Hilbert search")
    for entry in result.trace:
        entry.update(details[tuple(sorted((k, entry[k]) for k in HILBERT_START))])
    return result


def _check_names(grid, known):
    unknown = set(grid) - set(known)
    if unknown:
        raise InputError("grid", f"unknown constant(s) {sorted(unknown)}; expected some of {', '.join(known)}")


SEARCHES = {"octomap": octomap_search, "hilbert": hilbert_coordinate_search}


def load_cached(peer: str, path: Path | None = None) -> dict:
    """The cached search of ``peer`` on Intel (:meth:`SearchResult.as_dict` plus ``recording``, ``interior``, ...)."""
    if peer not in CACHES:
        raise InputError("peer", f"unknown peer {peer!r}; expected one of {', '.join(CACHES)}")
    target = CACHES[peer] if path is None else Path(path)
    try:
        return json.loads(target.read_text())
    except (OSError, ValueError) as e:
        raise InputError(target, f"cannot read the cached {peer} search ({e})") from None


def training_split():
    """Intel's scan split at 5 cm (even scans map, odd scans score): the preset's training split."""
    return scan_split(load_recording(data_file(TRAINING)).scans, TRAINING_RESOLUTION)


def run_training_search(peer: str, progress: bool = True) -> dict:
    """The full search of ``peer`` on the training split, as its cache holds it."""
    if peer not in SEARCHES:
        raise InputError("peer", f"unknown peer {peer!r}; expected one of {', '.join(SEARCHES)}")
    started = time.perf_counter()
    result = SEARCHES[peer](training_split(), progress=progress)
    return {**result.as_dict(), "interior": result.interior(), "earlier": EARLIER[peer], "recording": TRAINING,
            "resolution_m": TRAINING_RESOLUTION, "split": "even/odd scans",
            "search_seconds": round(time.perf_counter() - started, 1)}


def main(argv=None) -> int:
    """``python -m crfstudy.analysis.peer_search octomap|hilbert [--check]``: rerun one search, (re)write or check its cache."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if not (1 <= len(argv) <= 2 and argv[0] in SEARCHES and argv[1:] in ([], ["--check"])):
        print("usage: python -m crfstudy.analysis.peer_search octomap|hilbert [--check]", file=sys.stderr)
        return 2
    peer = argv[0]
    try:
        result = run_training_search(peer)
    except InputError as e:  # the data missing included
        print(f"crfmap peer search: {e}", file=sys.stderr)
        return 2
    return check_or_write(result, CACHES[peer], load_cached(peer) if argv[1:] == ["--check"] else None,
                          f"{peer} search", f", interior {result['interior']}")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
