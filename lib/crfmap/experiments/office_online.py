"""Notebook 07's online section: map a log scan by scan with :class:`~crfmap.mapping.online.OnlineMapper`, time it,
and summarise what LBP did while mapping.

>>> import numpy as np
>>> from crfmap.mapping.online import OnlineMapper
>>> from crfmap.recording import ScanSet
>>> scans = ScanSet(np.full((4, 3), 2.0, np.float32), -0.5, 0.5, 0.1, 5.0,
...                 np.tile([1.0, 1.0, 0.0], (4, 1)), np.arange(4.0))
>>> run = map_online(OnlineMapper.for_scans(scans, 0.25), scans, snapshot_at=[2])
>>> sorted(run.snapshots), len(run.updates)
([2, 4], 4)
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from crfmap.grid import UNKNOWN


@dataclass
class OnlineRun:
    """What :func:`map_online` saw: one update per scan, (observations, beliefs) snapshots, the busy time."""

    updates: list  # crfmap.mapping.online.ScanUpdate per scan
    snapshots: dict = field(default_factory=dict)  # scans integrated -> (observations, beliefs) OccupancyGrids
    busy_seconds: float = 0.0  # time spent in integrate(), the snapshots excluded


def map_online(mapper, scans, snapshot_at=()) -> OnlineRun:
    """Integrate ``scans`` one by one; snapshot the grids after each count in ``snapshot_at`` and at the end.

    Only ``mapper.integrate`` is timed (taking a snapshot is not part of mapping).
    """
    run = OnlineRun([])
    n = len(scans)
    wanted = {int(k) for k in snapshot_at} | {n}
    for i in range(n):
        t0 = time.perf_counter()
        run.updates.append(mapper.integrate(scans.ranges[i], scans.laser_poses[i]))
        run.busy_seconds += time.perf_counter() - t0
        if i + 1 in wanted:
            run.snapshots[i + 1] = (mapper.observations(), mapper.beliefs())
    return run


def online_numbers(mapper, run: OnlineRun, log_seconds) -> dict:
    """Speed (ms per scan, real-time factor = ``log_seconds`` / busy time) and what the beliefs did by the end.

    At the last snapshot: how many observed-occupied cells LBP keeps occupied, and how many
    never-observed cells it gave a state (moved more than 0.01 from 0.5), of which how many occupied.
    """
    per_scan = np.array([u.seconds for u in run.updates])  # [s]
    busy = run.busy_seconds
    out = {
        "margin_cells": mapper.margin, "radius_m": mapper.radius, "max_iter_per_scan": mapper.max_iter,
        "ms_per_scan_median": 1e3 * float(np.median(per_scan)),
        "ms_per_scan_p90": 1e3 * float(np.percentile(per_scan, 90)),
        "ms_per_scan_max": 1e3 * float(per_scan.max()), "seconds_total": busy, "real_time_factor": log_seconds / busy,
        "iterations_per_scan_median": float(np.median([u.iterations for u in run.updates])),
        "fraction_of_scans_settled": float(np.mean([u.converged for u in run.updates])),
        "disc_cells_median": float(np.median([u.cells for u in run.updates])),
    }
    observed_now, believed_now = run.snapshots[len(run.updates)]
    seen_occupied = observed_now.probability > 0.5
    never_seen = ~observed_now.known()
    given = never_seen & (np.abs(believed_now.probability - UNKNOWN) > 0.01)
    out["observed_occupied_cells"] = int(seen_occupied.sum())
    out["observed_occupied_fraction_still_occupied"] = float((believed_now.probability[seen_occupied] > 0.5).mean())
    out["never_observed_cells_given_a_state"] = int(np.count_nonzero(given))
    out["never_observed_fraction_made_occupied"] = (float((believed_now.probability[given] > 0.5).mean())
                                                    if given.any() else 0.0)
    return out
