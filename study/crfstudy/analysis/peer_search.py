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
constants they chose (:data:`crfmap.assess.peers.OCTOMAP_SEARCH_INTEL`,
:data:`crfmap.assess.peers.HILBERT_SEARCH_INTEL`).

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
from crfstudy.analysis.coordinate import SearchResult, coordinate_descent
from crfstudy.analysis.preset_search import TRAINING, TRAINING_RESOLUTION

# OctoMap's four constants, as probabilities like OctoMap's own setters (setProbHit, setClampingThresMin, ...)
OCTOMAP_GRID = {
    "p_hit": (0.55, 0.6, 0.65, 0.7, 0.8, 0.9),
    "p_miss": (0.1, 0.2, 0.3, 0.4, 0.45),
    "clamp_min": (0.001, 0.005, 0.01, 0.02, 0.05, 0.1192),
    "clamp_max": (0.971, 0.99, 0.999, 0.9999, 0.99999, 0.999999),
}
OCTOMAP_START = {"p_hit": octomap.P_HIT, "p_miss": octomap.P_MISS, "clamp_min": octomap.CLAMP_MIN,
                 "clamp_max": octomap.CLAMP_MAX}  # the library's defaults, the row's constants before this search
# the Hilbert map's three lengths [m]; the first grid (2026-12-02, crfmap.assess.peers.HILBERT_SEARCH_INTEL_FIRST)
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
        {"grid": "crfmap.assess.peers.HILBERT_SEARCH_INTEL_FIRST (18 hand-picked settings, 2026-12-02)",
         "best": {"feature_spacing": 0.075, "length_scale": 0.03, "free_spacing": 0.075}, "best_brier": 0.0279,
         "configurations": 18, "edge": ["length_scale"]},
        {"grid": {"length_scale": [0.015, 0.02, 0.025, 0.03, 0.0375], "feature_spacing": [0.05, 0.06, 0.075, 0.09, 0.1],
                  "free_spacing": [0.05, 0.06, 0.075, 0.09, 0.1]},
         "best": {"feature_spacing": 0.075, "length_scale": 0.025, "free_spacing": 0.05}, "best_brier": 0.0225795,
         "configurations": 21, "edge": ["free_spacing"]},
    ),
}
HILBERT_DETAILS = ("seconds", "brier_unseen", "logloss_all", "auc_all", "wall_recall")  # recorded beside Brier
CACHES = {"octomap": Path(__file__).with_name("peer_search_octomap_intel.json"),
          "hilbert": Path(__file__).with_name("peer_search_hilbert_intel.json")}


def _brier(split, p) -> float:
    from crfmap.assess.scansplit import score  # scansplit imports peers: here, not at the top

    return score(split, {"p": p}, n_boot=0, groups=("all",), metrics=("brier",))["p"]["all"]["brier"]


def octomap_brier(split, constants: dict) -> float:
    """Scan-split Brier score (all cells) of OctoMap's map of the split's first half with ``constants``."""
    return _brier(split, octomap_row(split, **constants))


def octomap_search(split, grid: dict | None = None, start: dict | None = None, max_rounds: int = 10,
                   progress: bool = False) -> SearchResult:
    """The preset's coordinate search over OctoMap's constants (default :data:`OCTOMAP_GRID` from :data:`OCTOMAP_START`)."""
    grid = OCTOMAP_GRID if grid is None else grid
    _check_names(grid, OCTOMAP_GRID)
    return coordinate_descent(lambda c: octomap_brier(split, c), grid, OCTOMAP_START if start is None else start,
                              order=OCTOMAP_GRID, max_rounds=max_rounds, progress=progress, desc="OctoMap search")


def hilbert_search(split, configs, progress=False) -> list:
    """Scan-split scores of the Hilbert map for each (feature_spacing, length_scale, free_spacing) [m] in ``configs``."""
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
    from crfmap.assess.scansplit import scan_split
    from crfmap.io.recordings import load_recording
    from crfmap.data import data_file

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
    from crfstudy.analysis.coordinate import check_or_write

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
