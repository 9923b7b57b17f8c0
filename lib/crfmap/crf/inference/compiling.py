"""Say so when a call is about to compile numba kernels (an empty cache: tens of seconds of silence otherwise),
and measure how long compiling took, so it is never reported as the time of the work itself.

A dispatcher needs compiling when it has no compiled signature in this process and numba's
on-disk cache holds no entry for its current source. Checking costs one small file read per
dispatcher, once per process. :func:`compile_timer` measures the time spent holding numba's
compiler lock (compiling, or loading a compiled kernel from the disk cache) within a block.

>>> from crfmap.crf.inference import _plain_kernels as K
>>> isinstance(needs_compiling(K._send_rows), bool)
True
>>> with compile_timer() as compiled:
...     pass
>>> compiled.seconds
0.0
"""
from __future__ import annotations

import contextlib
import sys
import time

from numba.core import event

MESSAGE = "compiling LBP kernels (first run only)..."
_checked = set()  # dispatchers known to be compiled or cached in this process
_announced = set()  # (fast, schedule, parallel) calls already announced


def needs_compiling(dispatcher) -> bool:
    """Whether calling ``dispatcher`` will compile it (not compiled here, nothing in the disk cache)."""
    if not hasattr(dispatcher, "signatures"):  # NUMBA_DISABLE_JIT=1: a plain function, which never compiles
        return False
    if dispatcher.signatures or id(dispatcher) in _checked:
        return False
    try:  # numba's cache index: empty when missing or written for another version of the source
        cached = bool(dispatcher._cache._cache_file._load_index())
    except Exception:  # no cache (cache=False, no locator) or another numba layout: assume a compile
        cached = False
    if cached:
        _checked.add(id(dispatcher))
    return not cached


def announce(*dispatchers, stream=None) -> bool:
    """Print :data:`MESSAGE` (one line, stderr) if any of ``dispatchers`` will compile; returns whether it did."""
    if not any([needs_compiling(d) for d in dispatchers]):
        return False
    print(MESSAGE, file=stream or sys.stderr, flush=True)
    return True


def announce_lbp(fast: bool, schedule: str, cells: int = 0, threads: int = 1, fused: bool = False) -> bool:
    """:func:`announce` for the kernels one :func:`crfmap.crf.inference.lbp.infer` call on ``cells`` cells runs.

    ``fused``: the call packs in one trip and fills no message plane
    (:meth:`crfmap.crf.engine.packed.PackedBlock.start_uniform`) instead of filling and packing the planes apart.
    """
    from crfmap.crf.engine import _layout as L
    from crfmap.crf.engine import _message_update as F
    from crfmap.crf.engine import messages as M
    from crfmap.crf.engine import packed as P
    from crfmap.crf.inference.schedules import plain_kernels

    key = (fast, schedule, cells >= P.SERIAL_CELLS and threads > 1, fused)
    if key in _announced:  # a kernel the call may skip (e.g. one thread's pass on a large grid) stays
        return False  # uncompiled: say it once per process, not on every call
    if fast:  # the kernels every such call runs
        kernels = ((L._pack_start,) if fused else (L._fill_ones, L._pack_unary)) + (L._beliefs_packed, F._pass)
        if cells >= P.SPARSE_CELLS:  # only such grids measure changes tile by tile: a smaller one never compiles it
            kernels += (F._tile_max,)
    else:
        kernels = plain_kernels(schedule) + (M._beliefs,)
    said = announce(*kernels)
    if said:
        _announced.add(key)
    return said


class CompileTime(event.Listener):
    """Seconds numba spent compiling or loading cached kernels inside a :func:`compile_timer` block (``seconds``)."""

    def __init__(self):
        self.seconds = 0.0
        self._depth = 0
        self._start = 0.0

    def on_start(self, event):  # nested acquisitions of the (re-entrant) lock count once
        if self._depth == 0:
            self._start = time.perf_counter()
        self._depth += 1

    def on_end(self, event):
        self._depth -= 1
        if self._depth == 0:
            self.seconds += time.perf_counter() - self._start


@contextlib.contextmanager
def compile_timer(loading=True):
    """Measure the time numba spends on kernels inside the block (``.seconds``).

    ``loading`` True: the time it holds its compiler lock, compiling kernels or loading them from the
    disk cache (all time that is not the work itself); False: compiling only. Nested timers each see
    the whole time of their own block.
    """
    timer = CompileTime()
    with event.install_listener("numba:compiler_lock" if loading else "numba:compile", timer):
        yield timer
