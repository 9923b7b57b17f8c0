"""Notebook 07's online section: map a log scan by scan with :class:`~crfmap.mapping.online.OnlineMapper`, time it,
summarise what LBP did while mapping, and check the end result against the offline pipeline
(:func:`~crfmap.mapping.builder.build_grid` of all the scans, then :func:`~crfmap.crf.inference.lbp.infer`).

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

from crfmap.crf.inference.lbp import infer
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK
from crfmap.errors import InputError
from crfmap.grid import UNKNOWN
from crfmap.mapping.builder import build_grid
from crfmap.mapping.online import OnlineMapper

FINAL_MAX_ITER = 20000  # LBP iterations allowed for the final (whole-grid) comparisons
# The cold offline run with the default tables on the near-observation region: its largest message change
# stalls at float32 rounding (~1e-7) within a few hundred iterations, and its state no longer changes
# (the same at 2000 as at 20000 iterations), so running it longer only costs time.
COLD_MAX_ITER = 2000


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


def versus_offline(scans, resolution, hidden, tol, max_iter=FINAL_MAX_ITER) -> tuple:
    """Online mapping with ``hidden`` then ``finish(tol)``, against ``build_grid`` + ``infer`` of the same scans.

    Returns (numbers, the offline observation grid). ``hidden`` should be a table for which
    offline LBP converges (else there is no fixed point to compare with).
    """
    t0 = time.perf_counter()
    mapper = OnlineMapper.for_scans(scans, resolution, hidden=hidden)
    mapper.run(scans)
    mapping_seconds = time.perf_counter() - t0
    final = mapper.finish(tol=tol, max_iter=max_iter)
    offline_grid = build_grid(scans, resolution)
    offline = infer(offline_grid, hidden, DEFAULT_LINK, tol=tol, max_iter=max_iter, dtype=np.float32)
    difference = np.abs(final.beliefs.probability - offline.beliefs.probability)
    observed = mapper.observations()
    numbers = {
        "hidden": hidden, "tol": tol,
        "observations_equal_builder": bool(np.array_equal(observed.probability, offline_grid.probability)),
        "same_grid": bool(observed.origin == offline_grid.origin and observed.shape == offline_grid.shape),
        "online_mapping_seconds": mapping_seconds, "finish_iterations": final.iterations,
        "finish_converged": final.converged, "finish_seconds": final.seconds,
        "offline_iterations": offline.iterations, "offline_converged": offline.converged,
        "offline_seconds": offline.seconds,
        "max_abs_belief_difference": float(difference.max()),
        "cells_differing_over_0.001": int(np.count_nonzero(difference > 1e-3)),
    }
    return numbers, offline_grid


def near_versus_offline(scans, resolution, offline_grid, hidden, mapper_near, tol, max_iter=FINAL_MAX_ITER,
                        cold_max_iter=COLD_MAX_ITER) -> dict:
    """Near observations only: ``finish()`` against ``infer(region=mapper.region())``, with ``hidden`` and the mapper's.

    ``mapper_near`` has already mapped ``scans`` with tables on the arctan grid (the thesis preset,
    ``preset="thesis"``, or custom tables) and a margin (it is finished here); a second mapper with
    the same margin maps them again with ``hidden``. The thesis's tables have no single fixed point,
    so for them we report the share of region cells on the same side of 0.5, and how far offline LBP
    warm-started from the online messages moves; the cold offline run with those tables stops after
    ``cold_max_iter`` iterations (its last measured message change is reported). Beliefs are
    compared inside the region: outside it the mapper reports the observation (unknown), as
    :meth:`crfmap.crf.presets.Preset.refine` does, where ``infer`` reports what the region sent.
    """
    if mapper_near.preset.scaled:
        raise InputError("mapper_near", f"the {mapper_near.preset.name} preset observes counts, not the arctan "
                         "grid infer() is given here: map with preset='thesis' or custom tables")
    margin = mapper_near.margin
    weak = OnlineMapper.for_scans(scans, resolution, hidden=hidden, margin=margin)
    weak.run(scans)
    final_weak = weak.finish(tol=tol, max_iter=max_iter)
    offline_weak = infer(offline_grid, hidden, DEFAULT_LINK, tol=tol, max_iter=max_iter, dtype=np.float32,
                         region=weak.region())
    final_default = mapper_near.finish(tol=tol, max_iter=max_iter)
    tables = mapper_near.hidden, mapper_near.link
    offline_default = infer(offline_grid, *tables, tol=tol, max_iter=cold_max_iter,
                            dtype=np.float32, region=mapper_near.region())
    warm_default = infer(offline_grid, *tables, tol=tol, max_iter=max_iter, dtype=np.float32,
                         region=mapper_near.region(), messages=mapper_near.messages())
    inside = mapper_near.region()
    return {
        "margin_cells": margin, "region_cells": int(inside.sum()),
        "weak_max_abs_belief_difference": float(np.abs(final_weak.beliefs.probability
                                                       - offline_weak.beliefs.probability)[weak.region()].max()),
        "weak_finish_iterations": final_weak.iterations, "weak_offline_iterations": offline_weak.iterations,
        "weak_converged": bool(final_weak.converged and offline_weak.converged),
        "default_finish_converged": final_default.converged,
        "default_offline_converged": offline_default.converged,
        "default_finish_iterations": final_default.iterations,
        "default_offline_iterations": offline_default.iterations,
        "default_offline_last_max_change": float(offline_default.max_change[np.isfinite(offline_default.max_change)][-1]),
        "default_same_state_fraction": float(np.mean((final_default.beliefs.probability[inside] > 0.5)
                                                     == (offline_default.beliefs.probability[inside] > 0.5))),
        "default_max_abs_difference_to_offline_warm_started_from_online": float(
            np.abs(final_default.beliefs.probability - warm_default.beliefs.probability)[inside].max()),
    }


def default_table_drift(offline_grid, tol, iterations=250) -> dict:
    """Offline LBP with the default tables, twice ``iterations`` (the second warm-started): what still moves.

    With [[10, 1], [1, 10]] the CRF is in its ordered phase and LBP does not settle on a large grid;
    the cells that move by more than 0.1 in the second half are mostly never-observed ones.
    """
    first_half = infer(offline_grid, DEFAULT_HIDDEN, DEFAULT_LINK, tol=tol, max_iter=iterations)
    second_half = infer(offline_grid, DEFAULT_HIDDEN, DEFAULT_LINK, tol=tol, max_iter=iterations,
                        messages=first_half.messages)
    drift = np.abs(second_half.beliefs.probability - first_half.beliefs.probability) > 0.1
    return {
        "iterations": first_half.iterations + second_half.iterations, "converged": second_half.converged,
        "last_max_change": float(second_half.max_change[np.isfinite(second_half.max_change)][-1]),
        f"cells_moving_over_0.1_in_last_{iterations}_iterations": int(drift.sum()),
        "of_which_never_observed": float((drift & ~offline_grid.known()).sum() / max(int(drift.sum()), 1)),
    }
