"""Running ``nogil`` numba kernels on several threads: row bands over Python threads instead of numba's parfor.

A ``parallel=True`` kernel takes two to three times as long to compile as the same loop compiled serially, and that
compile is the wait of a first ``crfmap infer``. So crfmap's kernels are serial ``@njit(nogil=True)`` functions over
a range of rows (or a list of jobs), run here on a persistent pool per thread count, the calling thread doing one
share itself, ``threads`` at a time (:func:`thread_count`).

>>> import numpy as np
>>> from numba import njit
>>> @njit(nogil=True)
... def _row_sums(a, out, r0, r1):
...     for y in range(r0, r1):
...         out[y] = a[y].sum()
>>> a = np.arange(12.0).reshape(6, 2); out = np.zeros(6)
>>> over_rows(_row_sums, 6, a, out, threads=2, min_rows=1)
[None, None]
>>> out.tolist()
[1.0, 5.0, 9.0, 13.0, 17.0, 21.0]
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numba

_pools: dict = {}
_lock = threading.Lock()


def _forget_pools_after_fork():
    """A forked child has none of its parent's threads: it must not wait on the parent's pools."""
    global _lock
    _pools.clear()
    _lock = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pools_after_fork)


def thread_count(threads=None) -> int:
    """``threads`` as a whole number >= 1 (None: numba's current thread count)."""
    if threads is None:
        threads = numba.get_num_threads()
    return max(1, int(threads))


def _pool(workers: int) -> ThreadPoolExecutor:
    with _lock:
        pool = _pools.get(workers)
        if pool is None:
            pool = _pools[workers] = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="crfmap-kernel")
        return pool


def _run_group(kernel, calls):
    return [kernel(*args) for args in calls]


def run_all(kernel, calls, threads=None) -> list:
    """``kernel(*args)`` for every ``args`` of ``calls`` on ``threads`` threads, the caller's included; results in order.
    Thread t runs calls t, t + threads, ... (so the bands at the grid's edges go to different threads); a thread
    stops at its first failing call, raised here after every thread finished."""
    calls = list(calls)
    n = min(thread_count(threads), len(calls))
    if n <= 1:
        return _run_group(kernel, calls)
    pool = _pool(n - 1)
    pending = [pool.submit(_run_group, kernel, calls[t::n]) for t in range(1, n)]
    groups = []  # bound before the try: a failing call of this thread's own is then what gets raised
    try:
        groups.append(_run_group(kernel, calls[0::n]))
    finally:
        groups += [future.result() for future in pending]  # every thread done before anything is raised or read
    out = [None] * len(calls)
    for t, results in enumerate(groups):
        out[t::n] = results
    return out


def row_bands(rows: int, threads=None, min_rows: int = 64) -> list:
    """[(r0, r1), ...]: ``rows`` cut into one band per thread, none shorter than ``min_rows`` (at least one band)."""
    n = max(1, min(thread_count(threads), rows // max(1, min_rows)))
    return [(b * rows // n, (b + 1) * rows // n) for b in range(n)]


def over_rows(kernel, rows, *args, threads=None, min_rows: int = 64) -> list:
    """``kernel(*args, r0, r1)`` over bands of ``[0, rows)`` on ``threads`` threads (see :func:`row_bands`); the results."""
    return run_all(kernel, [args + band for band in row_bands(rows, threads, min_rows)], threads)
