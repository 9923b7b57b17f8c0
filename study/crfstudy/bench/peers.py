"""Published-peer rows of ``crfmap bench``: how long each method takes to map a recording (see :mod:`crfstudy.bench.suite`).

``peers-<recording>`` records, one per method (``octomap``, ``hilbert``, and the default preset's
refinement of the same half for scale): the wall time to map the even scans of each CARMEN log
present under ``$CRFMAP_DATA`` on the 5 cm scan-split grid (quick: Intel only, OctoMap and the preset).
The first call of each method is made beforehand so compilation is not timed.
"""
from __future__ import annotations

import time

from crfstudy.bench.common import record
from crfmap.data import data_file, have_data
from crfmap.assess.peers import PEERS, peer_rows
from crfmap.assess.scansplit import scan_split
from crfmap.crf.presets import DEFAULT_PRESET, get_preset
from crfmap.io.carmen import read_carmen

RECORDINGS = {"intel": "carmen/intel-corrected.log.gz", "aces": "carmen/aces-corrected.log.gz",
              "csail": "carmen/csail-corrected.log.gz", "fr101": "carmen/freiburg-101-corrected.log.gz"}


def bench_peers(quick=False, resolution=0.05):
    """One record per recording present and method: ``seconds`` to map the even scans, grid ``shape``."""
    names = ["intel"] if quick else list(RECORDINGS)
    methods = ["octomap"] if quick else list(PEERS)
    out = []
    warmed = False
    for name in names:
        if not have_data(RECORDINGS[name]):
            out.append(record(f"peers-{name}", note=f"skipped: {RECORDINGS[name]} not found"))
            continue
        split = scan_split(read_carmen(data_file(RECORDINGS[name])).scans, resolution)
        if not warmed:  # compile (or load) the kernels on a small part first
            small = scan_split(split.first_scans.head(4), resolution)
            peer_rows(small, methods)
            warmed = True
        _, seconds = peer_rows(split, methods)
        start = time.perf_counter()
        get_preset(DEFAULT_PRESET).refine(hits=split.first_hits, passes=split.first_passes)
        seconds[DEFAULT_PRESET] = time.perf_counter() - start
        for method, s in seconds.items():
            out.append(record(f"peers-{name}", None, None, 1, None, peer=method, seconds=s, shape=list(split.shape),
                              scans=len(split.first_scans.ranges)))
    return out
