"""What this machine can do at most, measured in the same run as the kernels (``crfmap bench``'s machine rows).

- ``memory-bandwidth``: a streaming triad (:func:`memory_bandwidth`); its
  ``bound_mcells_per_second`` is the rate at which one trip through memory per iteration would saturate it,
  the bound temporal blocking is measured against.
- ``division-throughput``: float32 divisions per second with the operands in L1, each thread on its own
  arrays. The fast kernel's message update costs :data:`DIVISIONS_PER_CELL` divisions a cell (one per message
  sent, :mod:`crfmap.crf.engine._message_update`), so ``ceiling_mcells_per_second`` is what the kernel could
  reach if it did nothing but divide: a compute ceiling no blocking raises.

>>> rows, bounds, ceilings = machine_rows((1,), mbytes=8)
>>> [r["method"] for r in rows], sorted(bounds) == sorted(ceilings) == [1]
(['memory-bandwidth', 'division-throughput'], True)
>>> 0 < ceilings[1] == rows[1]["ceiling_mcells_per_second"]
True
"""
from __future__ import annotations

import time

import numpy as np
from numba import njit, prange

from crfstudy.bench.common import BYTES_PER_CELL_PASS, record
from crfmap.crf.threads import run_all

DIVISIONS_PER_CELL = 4  # a cell sends four messages, each one division (the kernel's docstring)
_DIVISION_ELEMENTS = 2048  # per thread: 3 arrays of 8 KB, in L1
_DIVISION_SWEEPS = 4000


@njit(parallel=True, cache=True)
def _triad(a, b, c, s):
    for i in prange(a.shape[0]):
        a[i] = b[i] + s * c[i]


def memory_bandwidth(threads, mbytes=256, repeats=5) -> float:
    """Streaming bandwidth [GB/s]: a = b + s c over float64 arrays of ``mbytes`` each (3 streams)."""
    import numba

    n = mbytes * (1 << 20) // 8
    a, b, c = np.zeros(n), np.ones(n), np.ones(n)
    previous = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        _triad(a, b, c, 0.5)
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            _triad(a, b, c, 0.5)
            times.append(time.perf_counter() - t)
    finally:
        numba.set_num_threads(previous)
    return 3 * a.nbytes / min(times) / 1e9


# the kernels' flags (fastmath as in the message update; no zero-divisor check), so the loop vectorises as theirs
@njit(nogil=True, cache=True, fastmath={"nnan", "ninf", "nsz", "contract"}, error_model="numpy")
def _divide(a, b, out, sweeps):
    for _ in range(sweeps):
        for i in range(a.shape[0]):
            out[i] = a[i] / b[i]


def division_rate(threads, repeats=5) -> float:
    """Float32 divisions per second [G/s] summed over ``threads`` threads, each dividing its own arrays."""
    rng = np.random.default_rng(0)
    jobs = [(rng.uniform(0.5, 2.0, _DIVISION_ELEMENTS).astype(np.float32),
             rng.uniform(0.5, 2.0, _DIVISION_ELEMENTS).astype(np.float32),
             np.empty(_DIVISION_ELEMENTS, np.float32), _DIVISION_SWEEPS) for _ in range(threads)]
    _divide(*jobs[0][:3], 1)  # compile or load
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        run_all(_divide, jobs, threads)
        best = min(best, time.perf_counter() - t)
    return threads * _DIVISION_ELEMENTS * _DIVISION_SWEEPS / best / 1e9


def machine_rows(threads, mbytes):
    """(records, {threads: one-pass bound [Mcell/s]}, {threads: division ceiling [Mcell/s]}), float32."""
    rows, bounds, ceilings = [], {}, {}
    for th in threads:
        bw = memory_bandwidth(th, mbytes)
        bounds[th] = bw * 1e3 / BYTES_PER_CELL_PASS["float32"]
        rows.append(record("memory-bandwidth", None, None, th, None, gbytes_per_second=bw, mbytes_per_array=mbytes,
                           bound_mcells_per_second={k: bw * 1e3 / v for k, v in BYTES_PER_CELL_PASS.items()},
                           note="STREAM-style triad a = b + s c, 3 x 8 bytes per element counted "
                           "(write-allocate traffic not counted)"))
    for th in threads:
        rate = division_rate(th)
        ceilings[th] = rate * 1e3 / DIVISIONS_PER_CELL
        rows.append(record("division-throughput", None, np.float32, th, None, gdivisions_per_second=rate,
                           divisions_per_cell=DIVISIONS_PER_CELL, ceiling_mcells_per_second=ceilings[th],
                           note="float32 a / b in L1, each thread its own arrays; ceiling: the kernel's rate if "
                           "it only divided"))
    return rows, bounds, ceilings
