"""The one-line note as numba starts compiling LBP kernels (an empty cache), and only then; the compile time apart."""
import io

import numpy as np
from numba import njit

from crfmap.crf.engine import messages as M
from crfmap.crf.inference import _plain_kernels as K
from crfmap.crf.inference.compiling import announcing, MESSAGE
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.schedules import Checkerboard


def test_note_when_a_kernel_compiles_and_not_after():
    @njit
    def plus_one(x):  # no disk cache, never called: must compile
        return x + 1

    with announcing(first := io.StringIO()) as note:
        assert not note.said  # nothing compiled yet
        plus_one(1)
        plus_one(2)  # the same block: one note
    assert note.said and first.getvalue() == MESSAGE + "\n"
    with announcing(again := io.StringIO()) as note:
        plus_one(3)  # compiled: no note
    assert not note.said and again.getvalue() == ""
    plus_one(1.5)  # outside any block: a compile says nothing
    with announcing(other := io.StringIO()):
        plus_one(2.5)  # that signature is compiled now
    assert other.getvalue() == ""


def test_no_note_once_infer_has_run(capsys):
    infer(np.full((4, 4), 0.6), max_iter=2, schedule=Checkerboard(kernel="plain"))
    capsys.readouterr()
    assert K._send_rows.signatures and M._beliefs.signatures  # the kernels that infer ran are compiled here
    infer(np.full((4, 4), 0.6), max_iter=2, schedule=Checkerboard(kernel="plain"))
    assert capsys.readouterr().err == ""


def test_compile_timer_counts_a_compile_and_not_the_work():
    import time

    from crfmap.crf.inference.compiling import compile_timer

    @njit
    def total(x):  # no disk cache: its first call compiles
        s = 0.0
        for v in x:
            s += v
        return s

    t0 = time.perf_counter()
    with compile_timer() as kernels, compile_timer(loading=False) as compiling:
        total(np.ones(3))
    wall = time.perf_counter() - t0
    assert 0 < compiling.seconds <= kernels.seconds <= wall
    with compile_timer() as again:
        total(np.ones(10**6))  # compiled: only work
    assert again.seconds == 0.0


def test_infer_reports_lbp_time_without_the_compile():
    """A kernel infer has never called in this process compiles (or loads) inside the call: timings["compile"],
    kept out of seconds; a second call has nothing to compile."""
    import time

    grid = np.random.default_rng(1).uniform(0.0, 1.0, (9, 7))
    t0 = time.perf_counter()
    first = infer(grid, max_iter=3, schedule="sweep", dtype=np.float32)
    wall = time.perf_counter() - t0
    second = infer(grid, max_iter=3, schedule="sweep", dtype=np.float32)
    assert "compile" not in second.timings
    if "compile" in first.timings:  # (absent when an earlier test of this process already ran the sweep kernels)
        assert first.seconds + first.timings["compile"] <= wall
        assert first.seconds < first.timings["compile"]  # 63 cells: the kernels cost more than the LBP
