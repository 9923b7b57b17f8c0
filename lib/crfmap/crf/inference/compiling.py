"""Say so when numba starts compiling kernels (an empty cache: tens of seconds of silence otherwise), and measure how
long compiling took, so it is never reported as the time of the work itself.

Both listen to :mod:`numba.core.event`: "numba:compile" fires only while a kernel is compiled, never when it is loaded
from the disk cache; "numba:compiler_lock" around both.

>>> import io
>>> with announcing(io.StringIO()) as note, compile_timer() as compiled:
...     pass
>>> note.said, compiled.seconds
(False, 0.0)
"""
from __future__ import annotations

import contextlib
import sys
import time

from numba.core import event

MESSAGE = "compiling LBP kernels (first run only)..."


class Announcer(event.Listener):
    """Prints :data:`MESSAGE` (one line) when numba starts the first compile inside an :func:`announcing` block."""

    def __init__(self, stream=None):
        self.stream = stream
        self.said = False

    def on_start(self, event):
        if not self.said:  # a kernel compiles its callees within its own compile: one note for all
            self.said = True
            print(MESSAGE, file=self.stream or sys.stderr, flush=True)

    def on_end(self, event):
        pass


@contextlib.contextmanager
def announcing(stream=None):
    """Print :data:`MESSAGE` (``stream``, default stderr) once if numba compiles a kernel in the block (``.said``)."""
    announcer = Announcer(stream)
    with event.install_listener("numba:compile", announcer):
        yield announcer


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
    """Measure the time numba spends on kernels inside the block (``.seconds``): compiling them or (``loading``)
    loading them from the disk cache too. Nested timers each see the whole time of their own block."""
    timer = CompileTime()
    with event.install_listener("numba:compiler_lock" if loading else "numba:compile", timer):
        yield timer
