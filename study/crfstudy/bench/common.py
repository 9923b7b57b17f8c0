"""What every benchmark shares: the constants, the input grids, one record's keys and the median timer
(the machine's limits: :mod:`crfstudy.bench.machine`). The suite (:mod:`crfstudy.bench.suite`) and its rows (baseline, external, online)
import from here, never from each other."""
from __future__ import annotations

import time

import numpy as np

from crfmap.world.scenes import noisy_image
from crfmap.world.office import office_floor

SIZES = (256, 512, 1024, 2048, 4096, 8192)
QUICK_SIZES = (128, 256)
CONVERGE_SIZES = (256, 512, 1024, 2048, 4096)
QUICK_CONVERGE_SIZES = (128, 256)
CONVERGE_TOL = 1e-4
BYTES_PER_CELL_PASS = {"float32": 36, "float64": 72}  # read 4 messages + observation, write 4 messages
GENERAL_TABLE = np.array([[3.0, 0.7], [1.3, 2.5]])  # non-symmetric (receiver pairing)
EQUALITY_TABLE = np.array([[2.0, 1.0], [1.0, 2.0]])  # LBP converges on the Intel grid with it
INTEL = "carmen/intel-corrected.log.gz"
EXTERNAL_MAX_SIZE = 512  # PGMax / PyMaxflow rows (when installed) up to this size: PGMax needs GBs beyond
ONLINE_MARGIN = 3  # [cells] the online run near observations only (OnlineMapper margin)


# --- inputs ---------------------------------------------------------------------------


def bench_grid(size, seed=0, kind="uniform") -> np.ndarray:
    """An observed grid of ``size`` x ``size`` cells.

    ``"uniform"``: P ~ U(0, 1) (throughput does not depend on the data); ``"office"``: a
    procedural office floor at 5 cm (:func:`crfmap.world.office.office_floor`) seen with flip noise
    0.2 (P = 0.8 or 0.2): LBP with [[10, 1], [1, 10]] needs ~300 iterations at 2048 x 2048.
    """
    if kind == "uniform":
        return np.random.default_rng(seed).uniform(0.0, 1.0, (size, size))

    side = max(size, 128)  # an office needs a few metres; small grids are a corner of one
    scene = office_floor(side * 0.05, side * 0.05, 0.05, seed=seed)
    return noisy_image(scene.truth, 0.2, seed=seed, model="flip").probability[:size, :size].copy()


# --- records ----------------------------------------------------------------------------------------


def record(method, size=None, dtype=None, threads=None, seconds_per_iteration=None, **extra) -> dict:
    """One benchmark result with the keys every record has."""
    mcells = None
    if seconds_per_iteration and size:
        mcells = size * size / seconds_per_iteration / 1e6
    out = dict(method=method, size=size, dtype=None if dtype is None else np.dtype(dtype).name, threads=threads,
               seconds_per_iteration=seconds_per_iteration, mcells_per_second=mcells)
    out.update(extra)
    return out


def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def with_threads(threads, fn):
    import numba

    previous = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        return fn()
    finally:
        numba.set_num_threads(previous)


WORK = 2e8  # cell updates per timed repeat (quick: QUICK_WORK)
QUICK_WORK = 2e7


