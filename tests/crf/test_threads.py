"""Row bands on Python threads (crfmap.crf.threads): every row once, results in order, errors raised, kernels nogil."""
import sys
import time

import numba
import numpy as np
import pytest
from numba import njit
from numba.core.dispatcher import Dispatcher

from crfmap.crf.threads import over_rows, row_bands, run_all


@njit(nogil=True, cache=False)
def _mark(rows, r0, r1):
    for y in range(r0, r1):
        rows[y] += 1
    return r1 - r0


@pytest.mark.parametrize("rows, threads, min_rows", [(0, 2, 64), (1, 2, 64), (127, 2, 64), (128, 2, 64),
                                                     (1000, 3, 64), (1000, 8, 1), (5, 1, 1)])
def test_bands_cover_every_row_once(rows, threads, min_rows):
    bands = row_bands(rows, threads, min_rows)
    assert len(bands) <= threads and bands[0][0] == 0 and bands[-1][1] == rows
    assert all(a[1] == b[0] for a, b in zip(bands, bands[1:]))
    assert all(r1 - r0 >= min(min_rows, rows) for r0, r1 in bands)
    marks = np.zeros(rows, np.int64)
    assert sum(over_rows(_mark, rows, marks, threads=threads, min_rows=min_rows)) == rows
    assert np.all(marks == 1)


def test_results_come_back_in_call_order_on_any_thread_count():
    calls = [(k,) for k in range(7)]
    for threads in (1, 2, 3, 8):
        assert run_all(lambda k: k * k, calls, threads) == [k * k for k in range(7)]


@pytest.mark.parametrize("failing, error, others", [
    (1, ValueError, [0, 2]),  # thread 1 (calls 1, 3) stops at its first failing call; thread 0 finishes its own
    (0, KeyError, [1, 3]),  # the calling thread's own call: its exception, not a failure of the clean-up, is raised
])
def test_an_error_in_any_call_is_raised_after_every_thread_finished(failing, error, others):
    """A thread stops at its first failing call (its later calls do not run); the others finish theirs."""
    finished = []

    def work(k):
        if k == failing:
            raise error(f"call {k} failed")
        time.sleep(0.05)
        finished.append(k)

    with pytest.raises(error, match=f"call {failing} failed"):
        run_all(work, [(k,) for k in range(4)], 2)  # thread 0 (the caller): calls 0, 2; thread 1: calls 1, 3
    assert sorted(finished) == others


@pytest.mark.skipif(bool(numba.config.DISABLE_JIT), reason="inspects numba dispatchers; NUMBA_DISABLE_JIT=1 leaves none")
def test_every_row_band_kernel_releases_the_gil():
    """Kernels taking a band (r0, r1) last are run on threads: compiled nogil, or the threads would take turns."""
    import crfmap.crf.engine._layout
    import crfmap.crf.engine.messages
    import crfmap.crf.inference._plain_kernels
    import crfmap.crf.model.evidence  # noqa: F401

    banded = []
    for name, module in list(sys.modules.items()):
        if not name.startswith("crfmap.crf.") or module is None:
            continue
        for value in vars(module).values():
            if isinstance(value, Dispatcher) and value.py_func.__code__.co_varnames[
                    value.py_func.__code__.co_argcount - 2:value.py_func.__code__.co_argcount] == ("r0", "r1"):
                banded.append(value)
                assert value.targetoptions.get("nogil"), f"{value.py_func.__qualname__} is not compiled nogil=True"
    assert len(banded) >= 10  # the packing, beliefs, evidence and plain-schedule kernels


def _child_runs_bands(queue):
    queue.put(run_all(lambda k: k + 1, [(k,) for k in range(4)], 2))


def test_a_forked_child_runs_bands_on_threads_of_its_own():
    """After fork the parent's pool threads do not exist in the child: its calls must not wait on them."""
    import multiprocessing

    run_all(lambda k: k, [(0,), (1,)], 2)  # the parent's pool exists
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_child_runs_bands, args=(queue,))
    child.start()
    child.join(60)  # a hang guard, not a timing: the child needs well under a second
    alive = child.is_alive()
    if alive:
        child.kill()
    assert not alive and child.exitcode == 0
    assert queue.get(timeout=5) == [1, 2, 3, 4]
