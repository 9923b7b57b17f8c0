"""How the Hilbert map's constants were chosen: scan-split scores over a grid of settings (Intel only).

Apart from :mod:`crfmap.assess.peers` because it scores (scansplit), which itself scores the peers.
"""
from __future__ import annotations

import time

from crfmap.assess.peers import hilbert_row


def hilbert_search(split, configs, progress=False) -> list:
    """Scan-split scores of the Hilbert map for each (feature_spacing, length_scale, free_spacing) [m] in ``configs``.

    How :mod:`crfmap.mapping.hilbert`'s constants were chosen, on the Intel log only (its record:
    :data:`HILBERT_SEARCH_INTEL`).
    """
    from crfmap.assess.scansplit import score  # scansplit imports peers: here, not at the top

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
