"""The kernel tests also run with numba's JIT off (``make kernel-coverage``: NUMBA_DISABLE_JIT=1 under pytest-cov),
so coverage sees the kernels' lines. Then every kernel is a plain Python function, about a thousand times slower:

- nothing compiles (numba fires no compile event), so no compile notice is printed;
- the tests that inspect numba dispatchers (hops, the compile notice) are skipped;
- a test that runs for more than :data:`CPU_BUDGET` seconds of CPU time (a large grid in pure Python) is skipped
  there and then, with its name in the skip reason, so the target ends in minutes (CPU time, not wall clock: a
  busy machine does not change what is skipped).

With the JIT on (``make test``) this file changes nothing.
"""
import signal
from pathlib import Path

import numba
import pytest

JIT_OFF = bool(numba.config.DISABLE_JIT)
DISPATCHER_TESTS = {"test_hops.py", "test_compiling.py"}  # they read dispatchers' signatures and overloads
CPU_BUDGET = 20.0  # [s] of CPU time per test with the JIT off; the kernel tests take well under 1 s with it on
HERE = Path(__file__).resolve().parent


def pytest_collection_modifyitems(config, items):
    if not JIT_OFF:
        return
    skip = pytest.mark.skip(reason="inspects numba dispatchers; with NUMBA_DISABLE_JIT=1 kernels are plain functions")
    for item in items:
        if HERE in item.path.parents and item.path.name in DISPATCHER_TESTS:
            item.add_marker(skip)


@pytest.fixture(autouse=True)
def _plain_python_kernels(request, monkeypatch):
    if not JIT_OFF:
        yield
        return
    def too_slow(signum, frame):
        pytest.skip(f"{request.node.name}: over {CPU_BUDGET:g} s of CPU as plain Python (NUMBA_DISABLE_JIT=1)")

    previous = signal.signal(signal.SIGPROF, too_slow)
    signal.setitimer(signal.ITIMER_PROF, CPU_BUDGET)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, previous)
