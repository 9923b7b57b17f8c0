"""Closed-loop rows of ``crfmap bench``: one exploration run of a generated office floor per onboard map kind.

Each row is one seeded run of :func:`crfstudy.closed_loop.exploration.explore` (notebook 11's setting: a 12 x 10 m
floor at 0.1 m, robot radius 0.2 m), after a short run that compiles or loads the kernels: its wall time, the time
spent mapping and planning, and what the run did (scans, coverage, collisions), so the speed of an onboard map is
read beside what it cost the robot.
"""
from __future__ import annotations

import time

from crfstudy.bench.common import record
from crfmap.world.office import office_floor
from crfstudy.closed_loop.exploration import ExploreSettings, explore
from crfstudy.closed_loop.onboard import ONBOARD_MAPS

FLOOR = (12.0, 10.0)  # [m] notebook 11's floor
RESOLUTION = 0.1  # [m]


def bench_closed_loop(quick=False, seed=0) -> list:
    """One record per onboard map kind (``closed-loop-<kind>``); ``quick``: the raw grid and the online CRF only."""
    scene = office_floor(*FLOOR, RESOLUTION, seed=seed)
    kinds = ["raw", "online-crf"] if quick else list(ONBOARD_MAPS)
    out = []
    for kind in kinds:
        explore(scene, kind, ExploreSettings(max_scans=2), seed=seed)  # compile / load the kernels first
        t0 = time.perf_counter()
        run = explore(scene, kind, ExploreSettings(), seed=seed)
        seconds = time.perf_counter() - t0
        s = run.summary()
        out.append(record(f"closed-loop-{kind}", seconds=seconds, scans=s["scans"], coverage=s["coverage"],
                          collisions=s["collisions"], plans_into_walls=s["plans_into_walls"],
                          map_seconds=s["map_seconds"], plan_seconds=s["plan_seconds"],
                          note=f"office floor {FLOOR[0]:g} x {FLOOR[1]:g} m at {RESOLUTION:g} m, seed {seed}: one "
                               f"exploration to {ExploreSettings().coverage_goal:.0%} coverage"))
    return out
