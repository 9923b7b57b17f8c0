"""Online mapping rows of ``crfmap bench``: the Intel lab log scan by scan (see :mod:`crfstudy.bench.suite`)."""
from __future__ import annotations

import time

import numpy as np

from crfstudy.bench.common import EQUALITY_TABLE, INTEL, ONLINE_MARGIN, median_time, record
from crfmap.crf.inference.lbp import infer
from crfmap.crf.model.potentials import DEFAULT_HIDDEN
from crfmap.data import data_file, have_data
from crfmap.mapping.builder import build_grid
from crfmap.io.carmen import read_carmen
from crfmap.mapping.online import OnlineMapper


def bench_online(quick=False, progress=False, final_tol=None):
    """Scan-by-scan mapping of the Intel lab log at 5 cm, and its final map against an offline run.

    ``final_tol``: the largest message change at which both final maps stop (default 1e-7, quick
    1e-5); the record keeps it beside their largest difference.
    """
    if not have_data(INTEL):
        return [record("online-intel", note=f"skipped: {INTEL} not found")]
    scans = read_carmen(data_file(INTEL)).scans
    out = []
    build_grid(scans, 0.05)
    t_build = median_time(lambda: build_grid(scans, 0.05), 3)
    grid = build_grid(scans, 0.05)
    out.append(record("builder-intel", grid.width, None, 1, None, seconds=t_build, scans=len(scans),
                      beams=int(scans.ranges.shape[1]), shape=list(grid.shape)))
    duration = float(scans.stamps[-1] - scans.stamps[0])
    for method, margin in (("online-intel", None), ("online-intel-margin", ONLINE_MARGIN)):
        mapper = OnlineMapper.for_scans(scans, 0.05, margin=margin)
        mapper.integrate(scans.ranges[0], scans.laser_poses[0])  # compile / load the kernels
        mapper = OnlineMapper.for_scans(scans, 0.05, margin=margin)
        t0 = time.perf_counter()
        per_scan = mapper.run(scans, progress=progress)
        total = time.perf_counter() - t0
        out.append(record(method, grid.width, np.float32, 1, None, scans=len(scans),
                          ms_per_scan_median=1e3 * float(np.median(per_scan)),
                          ms_per_scan_p90=1e3 * float(np.percentile(per_scan, 90)),
                          seconds_total=total, log_seconds=duration, real_time_factor=duration / total,
                          radius_m=mapper.radius, max_iter_per_scan=mapper.max_iter, margin_cells=margin,
                          table=DEFAULT_HIDDEN.tolist()))
    # the final map against an offline converged run, with a table for which LBP converges here
    tol = final_tol or (1e-5 if quick else 1e-7)
    n = 150 if quick else len(scans)
    part = scans if n == len(scans) else scans.head(n)
    t0 = time.perf_counter()
    mapper = OnlineMapper.for_scans(part, 0.05, hidden=EQUALITY_TABLE)
    mapper.run(part)
    final = mapper.finish(tol=tol, max_iter=20000)
    total = time.perf_counter() - t0
    offline = infer(build_grid(part, 0.05), EQUALITY_TABLE, tol=tol, max_iter=20000, dtype=np.float32)
    out.append(record("online-intel-final", grid.width, np.float32, None, None, scans=n, tol=tol,
                      table=EQUALITY_TABLE.tolist(), finish_iterations=final.iterations,
                      offline_iterations=offline.iterations, seconds_total=total,
                      real_time_factor=float(part.stamps[-1] - part.stamps[0]) / total,
                      max_abs_difference=float(np.abs(final.beliefs.probability - offline.beliefs.probability).max()),
                      observations_equal_builder=bool(np.array_equal(mapper.observations().probability,
                                                                      build_grid(part, 0.05).probability))))
    return out

