"""A reader follows ``infer`` to the numba kernel that updates a message in at most MAX_HOPS Python calls
(PLAIN_HOPS for the plain schedules: ``infer -> run_schedule -> the schedule's iteration -> kernel``, the iteration
being the schedule's entry in the registry ``crfmap.crf.inference.schedules.PLAIN_RUNNERS``).

Every numba dispatcher that Python code of ``crfmap.crf`` calls is wrapped (in the namespace it
is looked up in) by a counter of the Python frames between the ``infer`` call and it. A hop is
one call: ``infer -> solve -> PackedBlock.run -> _pass`` is three. Frames of
:mod:`crfmap.crf.threads` do not count: ``run_all(kernel, calls, threads)`` names the kernel it
runs where it is called and only shares the calls out over threads.
"""
import sys

import numpy as np
import pytest
from numba.core.dispatcher import Dispatcher

import crfmap.crf.engine.messages  # noqa: F401  (every module whose kernels infer may call is loaded)
import crfmap.crf.engine.packed  # noqa: F401
import crfmap.crf.engine.solve  # noqa: F401
import crfmap.crf.inference.schedules  # noqa: F401
import crfmap.crf.model.evidence  # noqa: F401
import crfmap.crf.threads
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.schedules import Checkerboard, Flooding, Sweep, Thesis

MAX_HOPS = 3
PLAIN_HOPS = 4
THREADS_SOURCE = crfmap.crf.threads.__file__
MESSAGE_UPDATES = {"_pass", "_send_rows",
                   "_sweep_along_rows", "_sweep_along_columns", "_pull_iteration"}  # the kernels that update messages


def _called_by_kernels(module):
    """Names the module's own numba kernels refer to (those must stay dispatchers: a kernel compiles against them)."""
    names = set()
    for value in vars(module).values():
        if isinstance(value, Dispatcher):
            names |= set(value.py_func.__code__.co_names)
    return names


def _count_hops(monkeypatch):
    hops = {}

    def wrap(name, dispatcher):
        def counted(*args):
            frame, n = sys._getframe(1), 1
            while frame is not None and frame.f_code is not infer.__code__:
                n += frame.f_code.co_filename != THREADS_SOURCE
                frame = frame.f_back
            if frame is not None:
                hops[name] = max(hops.get(name, 0), n)
            return dispatcher(*args)
        return counted

    for module_name, module in list(sys.modules.items()):
        if not module_name.startswith("crfmap.crf.") or module is None:
            continue
        inner = _called_by_kernels(module)
        for name, value in list(vars(module).items()):
            if isinstance(value, Dispatcher) and name not in inner:
                monkeypatch.setattr(module, name, wrap(name, value))
    return hops


RNG = np.random.default_rng(5)
SMALL = RNG.uniform(0.05, 0.95, (20, 30))
LARGE = RNG.uniform(0.05, 0.95, (256, 200))  # enough senders and rows for the parallel pass
HARD = SMALL.copy()
HARD[3, 4] = 1.0  # hard evidence: the fused start falls back to the general path


@pytest.mark.parametrize("call", [
    lambda: infer(SMALL, max_iter=20),
    lambda: infer(HARD, max_iter=20),
    lambda: infer(LARGE, max_iter=20, threads=2),
    lambda: infer(SMALL, max_iter=20, region=SMALL > 0.3),
    lambda: infer(SMALL, max_iter=20, messages=np.full((4, 20, 30), 0.4)),
    lambda: infer(SMALL, max_iter=20, init="coarse"),
    lambda: infer(SMALL, max_iter=5, schedule=Checkerboard(kernel="plain")),
    lambda: infer(SMALL, max_iter=5, schedule=Flooding(damping=0.2)),
    lambda: infer(SMALL, max_iter=5, schedule=Sweep()),
    lambda: infer(SMALL, max_iter=2, schedule=Thesis(start="upper-left"), region=SMALL > 0.3),
], ids=["fused", "hard-evidence", "parallel", "region", "warm", "coarse", "plain", "flooding", "sweep", "thesis"])
def test_infer_reaches_the_message_update_in_at_most_three_hops(monkeypatch, call, request):
    hops = _count_hops(monkeypatch)
    call()
    updates = {name: n for name, n in hops.items() if name in MESSAGE_UPDATES}
    assert updates, f"no message-update kernel was reached: {hops}"
    plain = request.node.callspec.id in ("plain", "flooding", "sweep", "thesis")
    assert max(updates.values()) <= (PLAIN_HOPS if plain else MAX_HOPS), f"Python hops from infer to each kernel: {hops}"
