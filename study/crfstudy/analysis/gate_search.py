"""The search that chose the gated preset's coupling J and never-observed prior pi (issue 38), rerunnable.

The gated preset (:mod:`crfmap.crf.presets`) is the certainty model at coupling J followed by an evidence gate
(:mod:`crfmap.crf.model.gating`) whose ``unobserved_prior`` pi gives never-observed cells the building's rate. Both
were chosen on the two choosing recordings only (Intel and ACES), over three splits each (the even/odd scan split,
temporal halves, blocks of 50 scans: :mod:`crfstudy.splits`), on the grid J in :data:`COUPLINGS` x pi in
:data:`PRIORS`, each by the score of what it shapes (:func:`best`). J shapes the map nav2 reads (LBP's beliefs, then
the gate's decision from them): it is chosen by the held-out log-loss with occupied cells weighted 3x (a dangerous
miss, a wall called free, is the costlier error for a planner). pi moves only never-observed cells off wall lines,
which the gate always reads unknown, so it changes no decision: it is chosen, at that J, by the held-out Brier score,
the probabilities' own score (a cost weight there would only bias the probability). The certainty model's other constants stay as the certainty
preset's search chose them (:mod:`crfstudy.analysis.preset_search`). The cached result
(``gate_search_intel_aces.json``) holds every grid point's scores; ``python -m crfstudy.analysis.gate_search`` reruns
the search (about a minute: 4 couplings x 6 splits of LBP, then the gate per prior) and ``--check`` compares it with
the cache.
"""
from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from crfmap.assess.scansplit import scan_split
from crfstudy.splits import scan_blocks, split_by, temporal_halves
from crfmap.crf.presets import coupling_table, get_preset
from crfmap.data import data_file
from crfmap.io.recordings import load_recording
from crfmap.io.atomic import atomic_path

RECORDINGS = {"intel": "carmen/intel-corrected.log.gz", "aces": "carmen/aces-corrected.log.gz"}
RESOLUTION = 0.05  # [m]
SCAN_BLOCK = 50  # scans per block of the block split
COUPLINGS = (0.25, 0.30, 0.33, 0.35)  # J: the certainty preset's 0.35 (on the Bethe point atanh(1/3)) and below
PRIORS = (0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5)  # pi: 0.5 is no prior
OCCUPIED_WEIGHT = 3.0  # a held-out occupied cell's weight in the log-loss (misses the costlier error)
LOG_FLOOR = 1e-6
CACHE = Path(__file__).with_name("gate_search_intel_aces.json")


def training_splits(recordings=RECORDINGS, resolution=RESOLUTION) -> dict:
    """{(recording, split kind): ScanSplit}: the even/odd scan split, temporal halves and scan blocks of each."""
    out = {}
    for name, relative in recordings.items():
        scans = load_recording(data_file(relative)).scans
        n = len(scans)
        out[(name, "scan")] = scan_split(scans, resolution)
        out[(name, "temporal")] = split_by(scans, temporal_halves(n), resolution)
        out[(name, "blocks")] = split_by(scans, scan_blocks(n, SCAN_BLOCK), resolution)
    return out


def weighted_logloss(probability, split, weight=OCCUPIED_WEIGHT) -> float:
    """Held-out log-loss over every cell the second half observed, occupied cells weighted ``weight``.

    >>> from crfmap.assess.scansplit import ScanSplit
    >>> sp = ScanSplit(*(np.array([[1, 0]]),) * 4)
    >>> round(weighted_logloss(np.array([[0.9, 0.5]]), sp), 4)   # one occupied cell, P 0.9
    0.1054
    """
    mask = split.group("all")
    y = split.labels()[mask].astype(np.float64)
    p = np.clip(np.asarray(probability, dtype=np.float64)[mask], LOG_FLOOR, 1 - LOG_FLOOR)
    loss = -(y * np.log(p) + (1 - y) * np.log1p(-p))
    w = np.where(y == 1, weight, 1.0)
    return float((w * loss).sum() / w.sum())


def search(splits, couplings=COUPLINGS, priors=PRIORS, gate=None) -> list:
    """Every grid point's scores: [{"J", "pi", "weighted_logloss", "brier", "iterations", per split brier}], with
    the mean over ``splits`` of the weighted log-loss (the rule) and of the Brier score (information)."""
    base = get_preset("certainty")
    gate = gate or get_preset("gated").gate
    rows = []
    for coupling in couplings:
        preset = replace(base, hidden=coupling_table(coupling))
        beliefs = {key: preset.refine(hits=s.first_hits, passes=s.first_passes) for key, s in splits.items()}
        for prior in priors:
            g = replace(gate, unobserved_prior=prior)
            row = {"J": coupling, "pi": prior, "iterations": max(r.iterations for r in beliefs.values())}
            wll, brier = [], []
            for key, s in splits.items():
                # the beliefs the preset reports (the prior, not the gate's nav2 decision): probabilities to score
                q = g.beliefs_and_map(beliefs[key].beliefs.probability, hits=s.first_hits, passes=s.first_passes)[0]
                mask = s.group("all")
                b = float(np.mean((q[mask] - s.labels()[mask]) ** 2))
                row[f"brier_{key[0]}_{key[1]}"] = b
                wll.append(weighted_logloss(q, s))
                brier.append(b)
            row["weighted_logloss"], row["brier"] = float(np.mean(wll)), float(np.mean(brier))
            rows.append(row)
    return rows


def best(rows) -> dict:
    """The grid point the rules choose: J of the lowest mean weighted log-loss, then at that J the pi of the lowest
    mean Brier score (see the module doc).

    >>> best([{"J": 0.3, "pi": 0.2, "weighted_logloss": 0.2, "brier": 0.03},
    ...       {"J": 0.3, "pi": 0.3, "weighted_logloss": 0.1, "brier": 0.04},
    ...       {"J": 0.35, "pi": 0.3, "weighted_logloss": 0.3, "brier": 0.01}])["pi"]
    0.2
    """
    coupling = min(rows, key=lambda r: r["weighted_logloss"])["J"]
    return min((r for r in rows if r["J"] == coupling), key=lambda r: r["brier"])


def load_cached(path=CACHE) -> dict:
    return json.loads(Path(path).read_text())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crfstudy.analysis.gate_search", description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare a rerun with the cached result, write nothing")
    args = parser.parse_args(argv)
    rows = search(training_splits())
    chosen = best(rows)
    print(f"chosen: J = {chosen['J']}, pi = {chosen['pi']} (weighted log-loss {chosen['weighted_logloss']:.5f}, "
          f"Brier {chosen['brier']:.5f}, {chosen['iterations']} LBP iterations at most)")
    if args.check:
        cached = load_cached()
        same = all(abs(a["weighted_logloss"] - b["weighted_logloss"]) < 1e-9 for a, b in zip(rows, cached["rows"]))
        print("cache agrees" if same and cached["best"] == {"J": chosen["J"], "pi": chosen["pi"]} else "cache DIFFERS")
        return 0 if same else 1

    with atomic_path(CACHE) as tmp:  # a search interrupted or a full disk leaves the old cache whole
        Path(tmp).write_text(json.dumps({"rule": "J: lowest mean held-out log-loss, occupied cells weighted "
                                                 f"{OCCUPIED_WEIGHT:g}x; pi at that J: lowest mean held-out Brier; over "
                                                 f"{sorted(RECORDINGS)} x (scan, temporal, blocks)",
                                         "best": {"J": chosen["J"], "pi": chosen["pi"]},
                                         "rows": rows}, indent=1) + "\n")
    print(f"written {CACHE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
