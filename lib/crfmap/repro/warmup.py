"""Warm numba's on-disk cache once, so no entry point pays for compiling the LBP kernels again.

``make test`` and ``make reproduce`` run ``python -m crfmap.repro.warmup`` first: it runs
``crfmap infer`` on a tiny grid with every schedule, in float64 and float32 and with ``--margin``,
which compiles (or loads) what those calls need into the cache every entry point of the
environment shares (``NUMBA_CACHE_DIR``, set for the shell by make, for the command line by the
venv's ``crfmap_numba_cache.pth`` and for Jupyter by the kernel spec; see the Makefile). With a warm
cache it takes a second or two.

In a Jupyter kernel, :func:`announce_if_cold` (called when a notebook imports
:mod:`crfmap.repro.report`, i.e. in its first code cell) prints "compiling kernels (first run only)"
and warms the cache there, so the pause happens where the message is, not on a silent later cell.
"""
from __future__ import annotations

import contextlib
import io
import os
import sys
import tempfile
import time
from pathlib import Path

KERNEL_MODULES = ("crf/_lbp_fast.py", "crf/_lbp_kernels.py")  # numba modules with cache=True the LBP calls use
LIBRARY = Path(__file__).resolve().parents[1]


def cache_dir() -> Path | None:
    """Numba's cache folder (``NUMBA_CACHE_DIR``); None means numba's default beside the sources."""
    value = os.environ.get("NUMBA_CACHE_DIR")
    return Path(value) if value else None


def is_cold() -> bool:
    """Whether a kernel module has no cache index newer than its source (so its first call compiles)."""
    for relative in KERNEL_MODULES:
        source = LIBRARY / relative
        if not source.is_file():
            continue
        where = cache_dir() or source.parent / "__pycache__"
        indexes = list(where.rglob(f"{source.stem}.*.nbi")) if where.is_dir() else []
        if not indexes or max(p.stat().st_mtime for p in indexes) < source.stat().st_mtime:
            return True
    return False


def _stamp() -> Path:
    return (cache_dir() or LIBRARY / "crf" / "__pycache__") / "crfmap-warmed.stamp"


def is_warm() -> bool:
    """Whether :func:`warm` ran since the last change to the code ``crfmap infer`` runs (then it has nothing to do)."""
    sources = [*(LIBRARY / "crf").glob("*.py"), LIBRARY / "cli.py", LIBRARY / "commands" / "infer.py"]
    stamp = _stamp()
    return stamp.is_file() and stamp.stat().st_mtime > max(p.stat().st_mtime for p in sources if p.is_file())


def warm(verbose: bool = True) -> float:
    """Run ``crfmap infer`` on a tiny grid with every schedule and dtype; returns the seconds it took."""
    import numpy as np

    from crfmap.cli import main
    from crfmap.crf.lbp import SCHEDULES

    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="crfmap-warmup-") as tmp:
        grid = Path(tmp) / "grid.npy"
        rng = np.random.default_rng(0)
        np.save(grid, rng.uniform(0.0, 1.0, (12, 10)))
        runs = [[s] for s in SCHEDULES] + [[s, "--float32"] for s in SCHEDULES] + [["checkerboard", "--margin", "2"]]
        for run in runs:
            argv = ["infer", str(grid), str(Path(tmp) / "out.npy"), "--schedule", *run]
            with contextlib.redirect_stdout(io.StringIO()):  # one line per call would drown the message
                status = main(argv)
            if status != 0:
                raise RuntimeError(f"warm-up call `crfmap {' '.join(argv)}` failed")
    seconds = time.perf_counter() - start
    _stamp().parent.mkdir(parents=True, exist_ok=True)
    _stamp().touch()
    if verbose:
        print(f"numba kernels ready in {seconds:.1f} s (cache: {cache_dir() or 'beside the sources'})")
    return seconds


def announce_if_cold() -> None:
    """In a Jupyter kernel with a cold cache: say so and compile now (the notebook's first cell)."""
    if "ipykernel" not in sys.modules or not is_cold():
        return
    print("compiling kernels (first run only; numba caches them on disk) ...", flush=True)
    warm(verbose=True)


if __name__ == "__main__":
    if is_warm():
        print(f"numba cache already warm ({cache_dir() or 'beside the sources'})")
    else:
        if is_cold():
            print("compiling kernels (first run only) ...", flush=True)
        warm(verbose=True)
