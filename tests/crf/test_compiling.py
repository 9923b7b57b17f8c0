"""The one-line note before numba compiles LBP kernels (an empty cache), and only then."""
import numpy as np
from numba import njit

from crfmap.crf.inference.schedules import Checkerboard
from crfmap.crf.engine import messages as M
from crfmap.crf.inference import _plain_kernels as K
from crfmap.crf.inference.compiling import announce, MESSAGE, needs_compiling
from crfmap.crf.inference.lbp import infer


def test_note_for_a_kernel_not_yet_compiled_and_not_after(capsys):
    @njit
    def plus_one(x):  # no disk cache, never called: must compile
        return x + 1

    assert needs_compiling(plus_one)
    assert announce(plus_one)
    assert capsys.readouterr().err == MESSAGE + "\n"
    plus_one(1)
    assert not announce(plus_one)
    assert capsys.readouterr().err == ""


def test_no_note_once_infer_has_run(capsys):
    infer(np.full((4, 4), 0.6), max_iter=2, schedule=Checkerboard(kernel="plain"))
    capsys.readouterr()
    assert not needs_compiling(K._send_rows) and not needs_compiling(M._beliefs)
    infer(np.full((4, 4), 0.6), max_iter=2, schedule=Checkerboard(kernel="plain"))
    assert capsys.readouterr().err == ""
