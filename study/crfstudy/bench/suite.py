"""How fast crfmap's LBP runs, measured against a vectorised NumPy baseline in the same run.

:func:`run` yields one record (a dict) per measurement; ``crfmap bench`` prints them (``--json``:
one JSON object per line). Every record has ``method``, ``size`` (cells per side, or None),
``dtype``, ``threads``, ``seconds_per_iteration`` and ``mcells_per_second`` (None where they do
not apply); convergence records add ``iterations`` and ``seconds_to_converge``. Times are
medians over ``repeats``; the first call of each kernel (JIT compilation or loading numba's
cache) is timed apart, in ``compile`` records.

Methods:

- ``numpy-baseline``: THE BASELINE, :class:`NumpyCheckerboard`, written here: the same
  checkerboard schedule, one odds ratio per message, float32, whole-array NumPy operations.
- ``crfmap-fast``: the fast kernels (:mod:`crfmap.crf.engine._message_update`), blocks of ``block`` iterations
  per trip through memory; ``-general`` with a non-symmetric table, ``-bounded`` on a disc
  (bounded LBP) covering about half the grid; ``crfmap-infer``: :func:`crfmap.crf.inference.lbp.infer`
  end to end (packing, iterations, beliefs, unpacking).
- ``crfmap-plain``: the reference kernels (:mod:`crfmap.crf.inference._plain_kernels`), small grids only.
- ``memory-bandwidth``: a streaming triad over 2 x 256 MB; ``bound_mcells_per_second`` is the
  rate at which one pass per iteration (36 bytes per cell in float32) would saturate it.
  ``division-throughput``: float32 divisions per second; ``ceiling_mcells_per_second``, the kernel's rate if
  it only did its four divisions a cell (:mod:`crfstudy.bench.machine`).
- ``converge``: noisy office floors (flip noise 0.2), table [[10, 1], [1, 10]], until the
  largest message change is below 1e-4: fast kernel with frozen tiles (default), exact
  (``freeze=0``), and the plain kernel on small grids, with the largest belief difference.
- ``online-intel`` / ``online-intel-margin`` / ``online-intel-final`` / ``builder-intel``: the
  Intel lab log at 5 cm (when the data is present): scan-by-scan mapping (LBP on a 4 m disc; with
  ``-margin`` only its cells near observations), the final map against an offline run.
- ``peers-<recording>`` (with the online rows): wall time of the published peers (OctoMap's update,
  Bayesian Hilbert maps) and the default preset on each CARMEN log's even scans (:mod:`crfstudy.bench.peers`).
- ``memory``: peak resident memory of :func:`crfmap.crf.inference.lbp.infer` per cell, in a child process.
- ``pgmax-bp`` / ``pymaxflow-map``: when installed, PGMax's LBP and a PyMaxflow graph cut on the
  same model (:mod:`crfstudy.bench.external`); a "not installed" record otherwise.
- ``jit-compile``: the first calls of :func:`crfmap.crf.inference.lbp.infer` in a new process, with an empty
  numba cache (compilation; not in quick runs, nor with ``cold=False``) and with the package's cache.
- issue 13's goals (``goals=True``, :mod:`crfstudy.bench.goals`): ``infer-vs-kernel`` (per size),
  ``start-cold`` / ``start-warm`` / ``start-env``, ``explorer-redraw`` / ``explorer-scene-change``,
  ``reproduce`` (read from the last run's record) and ``converge-start`` (4096², quick 256²).
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
import tempfile

import numpy as np

from crfmap.crf.engine import packed as F
from crfmap.crf.engine.messages import MESSAGE_FLOOR
from crfmap.errors import InputError
from crfmap.crf.engine.packed import PASS_ITERATIONS
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.schedules import Checkerboard
from crfstudy.bench.baseline import NumpyCheckerboard
from crfstudy.bench.machine import machine_rows
from crfstudy.bench.common import (
    SIZES,
    QUICK_SIZES,
    CONVERGE_SIZES,
    QUICK_CONVERGE_SIZES,
    CONVERGE_TOL,
    GENERAL_TABLE,
    EXTERNAL_MAX_SIZE,
    bench_grid,
    record,
    median_time,
    with_threads,
    WORK,
    QUICK_WORK,
)
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK, directional_tables
from crfstudy.bench import goals as G

PLAIN = Checkerboard(kernel="plain")  # the reference kernels


def _iterations_for(size, block, work=WORK):
    """Iterations per timed repeat: about ``work`` cell updates, a multiple of ``block``."""
    return max(block, int(round(work / (size * size) / block)) * block)


def bench_fast(size, dtype, threads, repeats, hidden=DEFAULT_HIDDEN, bounded=False, block=PASS_ITERATIONS,
               method="crfmap-fast", work=WORK):
    """Throughput of the fast kernel: passes of ``block`` iterations, the last of each measured."""
    obs = bench_grid(size)
    packed = F.PackedBlock(size, size, dtype, directional_tables(hidden), MESSAGE_FLOOR)
    packed.set_unary(obs, DEFAULT_LINK)
    if bounded:  # a disc of radius size / 2.5 around the centre: about half the cells
        r = size / 2.5
        ys = np.arange(size)
        half = np.sqrt(np.clip(r * r - (ys + 0.5 - size / 2) ** 2, 0.0, None))
        x_from = np.ceil(size / 2 - half - 0.5).clip(0, size).astype(np.int64)
        x_to = np.maximum((np.floor(size / 2 + half - 0.5) + 1).clip(0, size).astype(np.int64), x_from)
        packed.set_rows(0, x_from, x_to)
    cells = packed.active_cells
    n = _iterations_for(size, block, work)

    def go():
        for _ in range(n // block):
            packed.run_pass(block, threads, measure=True, per_tile=False)

    t0 = time.perf_counter()
    with_threads(threads, lambda: packed.run_pass(1, threads, measure=True, per_tile=False))
    first = time.perf_counter() - t0
    seconds = with_threads(threads, lambda: median_time(go, repeats)) / n
    rec = record(method, size, dtype, threads, seconds, iterations_timed=n, block=block, first_call_seconds=first)
    rec["mcells_per_second"] = cells / seconds / 1e6  # cells that actually send
    rec["cells"] = cells
    return rec


def bench_baseline(size, repeats, dtype=np.float32):
    nb = NumpyCheckerboard(bench_grid(size), dtype=dtype)
    n = max(1, min(8, int(2e7 / (size * size))))
    nb.iterate(1)
    seconds = median_time(lambda: nb.iterate(n), repeats) / n
    return record("numpy-baseline", size, dtype, 1, seconds, iterations_timed=n,
                  note="vectorised NumPy checkerboard, odds ratios (the baseline)")


def bench_plain(size, repeats, threads):
    obs = bench_grid(size)
    infer(obs, max_iter=1, tol=0.0, schedule=PLAIN, dtype=np.float32, threads=threads)
    n = 4
    seconds = median_time(lambda: infer(obs, max_iter=n, tol=0.0, schedule=PLAIN, dtype=np.float32,
                                         threads=threads), repeats) / n
    return record("crfmap-plain", size, np.float32, threads, seconds, iterations_timed=n)


def bench_infer(size, dtype, threads, repeats, block=PASS_ITERATIONS, work=WORK):
    obs = bench_grid(size)
    n = _iterations_for(size, block, work)
    seconds = median_time(lambda: infer(obs, max_iter=n, tol=0.0, dtype=dtype, threads=threads,
                                        schedule=Checkerboard(block=block)),
                           repeats) / n
    return record("crfmap-infer", size, dtype, threads, seconds, iterations_timed=n,
                  note="infer() end to end: packing, iterations, beliefs, unpacking")


def agreement(size=96, iterations=7, seed=1) -> dict:
    """Largest belief difference between the baseline and crfmap after the same iterations."""
    obs = bench_grid(size, seed)
    nb = NumpyCheckerboard(obs, dtype=np.float64)
    nb.iterate(iterations)
    fast = infer(obs, max_iter=iterations, tol=0.0, dtype=np.float64)
    plain = infer(obs, max_iter=iterations, tol=0.0, dtype=np.float64, schedule=PLAIN)
    return record("agreement", size, np.float64, None, None, iterations=iterations,
                  max_difference_baseline_vs_fast=float(np.abs(nb.beliefs() - fast.beliefs.probability).max()),
                  max_difference_plain_vs_fast=float(np.abs(plain.beliefs.probability - fast.beliefs.probability).max()))


def bench_converge(size, threads, with_plain=False, tol=CONVERGE_TOL, runs=2):
    """Time to convergence on the noisy office floor, with and without frozen tiles (best of ``runs``)."""
    obs = bench_grid(size, kind="office")
    out = []
    exact = infer(obs, tol=tol, max_iter=5000, dtype=np.float32, threads=threads,
                  schedule=Checkerboard(freeze=0.0))
    fast = min((infer(obs, tol=tol, max_iter=5000, dtype=np.float32, threads=threads) for _ in range(max(runs, 1))),
               key=lambda r: r.seconds)
    diff = float(np.abs(fast.beliefs.probability - exact.beliefs.probability).max())
    for name, r in (("converge", fast), ("converge-exact", exact)):
        out.append(record(f"crfmap-{name}", size, np.float32, threads, r.seconds / max(r.iterations, 1),
                          iterations=r.iterations, seconds_to_converge=r.seconds, converged=r.converged,
                          tol=tol, max_belief_difference_vs_exact=diff if name == "converge" else 0.0,
                          note="Mcell/s here is cells x iterations / time: frozen tiles count but cost nothing"))
    if with_plain:
        plain = infer(obs, tol=tol, max_iter=5000, dtype=np.float32, threads=threads, schedule=PLAIN)
        out.append(record("crfmap-converge-plain", size, np.float32, threads, plain.seconds / max(plain.iterations, 1),
                          iterations=plain.iterations, seconds_to_converge=plain.seconds, converged=plain.converged,
                          tol=tol, max_belief_difference_vs_exact=float(
                              np.abs(plain.beliefs.probability - exact.beliefs.probability).max())))
    return out


def peak_memory_per_cell(size, dtype="float32", block=PASS_ITERATIONS) -> dict:
    """Peak memory :func:`crfmap.crf.inference.lbp.infer` adds beyond its float64 input, per cell (child process).

    ``bytes_per_cell``: the peak resident set during the call (Linux resets its high-water mark
    through /proc/self/clear_refs) minus the resident set before it; ``array_bytes_per_cell``:
    the peak of the arrays it allocates (tracemalloc sees every NumPy allocation).
    """
    code = (
        "import tracemalloc, numpy as np\n"
        "from crfmap.crf.inference.lbp import infer\n"
        "def status(key):\n"
        "    for line in open('/proc/self/status'):\n"
        "        if line.startswith(key):\n"
        "            return int(line.split()[1]) * 1024\n"
        f"p = np.random.default_rng(0).uniform(0, 1, ({size}, {size}))\n"
        f"infer(p[:64, :64], max_iter=2, dtype=np.{dtype})\n"
        "open('/proc/self/clear_refs', 'w').write('5')\n"
        "base = status('VmRSS')\n"
        "tracemalloc.start()\n"
        f"r = infer(p, max_iter={2 * block}, tol=0.0, dtype=np.{dtype})\n"
        "arrays = tracemalloc.get_traced_memory()[1]\n"
        "print(status('VmHWM') - base, arrays)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    rss, arrays = (int(v) for v in out.stdout.strip().splitlines()[-1].split())
    cells = size * size
    return record("memory", size, dtype, None, None, peak_bytes=rss, bytes_per_cell=rss / cells,
                  array_bytes_per_cell=arrays / cells,
                  note="peak memory infer() adds beyond its float64 input (child process); "
                  "the result keeps float64 beliefs and the messages")


def compile_seconds(cold=True) -> dict:
    """First-call time of the fast kernels (float32, float64, two threads) in a child process.

    ``cold``: with an empty numba cache (JIT compilation); else with the package's own cache
    (what every later process pays).
    """
    code = (
        "import time, numpy as np\n"
        "from crfmap.crf.inference.lbp import infer\n"
        "p = np.random.default_rng(0).uniform(0, 1, (600, 600))\n"
        "t = time.perf_counter()\n"
        "infer(p[:64, :64], max_iter=3, dtype=np.float32)\n"
        "infer(p[:64, :64], max_iter=3, dtype=np.float64)\n"
        "infer(p, max_iter=40, dtype=np.float32, threads=2)\n"
        "print(time.perf_counter() - t)\n"
    )
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as cache:
        if cold:
            env["NUMBA_CACHE_DIR"] = cache
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    seconds = float(out.stdout.strip().splitlines()[-1])
    return record("jit-compile", None, None, None, None, seconds=seconds, cache="empty" if cold else "warm",
                  note="first calls of infer() in a new process: float32, float64, and the parallel pass")


GROUPS = {  # crfmap bench --only: row groups -> the tasks that make them
    "machine": ("machine",), "compile": ("compile",), "throughput": ("throughput",), "converge": ("converge",),
    "memory": ("memory",), "online": ("online",), "node": ("node",), "external": ("external",),
    "closed-loop": ("closed-loop",),
    "goals": ("start", "explorer", "reproduce", "converge-start", "preset-converge"),
}


def _all_tasks(tasks, quick, sizes, converge_start_size):
    """``tasks`` with every optional group added (``--only`` asks for groups whatever the --no-* flags say)."""
    extra = [("memory", 1024 if quick else max(sizes)), ("online", None), ("node", None), ("external", None),
             ("closed-loop", None),
             ("start", None), ("explorer", None), ("reproduce", None), ("converge-start", converge_start_size),
             ("preset-converge", None)]
    return tasks + [t for t in extra if t[0] not in {k for k, _ in tasks}]


def run(sizes=None, quick=False, repeats=None, threads=(1, 2), progress=True, online=True, memory=True,
        external=True, goals=True, work=None, cold=None, external_max_size=EXTERNAL_MAX_SIZE, explorer_changes=None,
        converge_runs=2, online_tol=None, bandwidth_mbytes=None, only=None, peers=True, node=True,
        preset_maps=None, converge_start_size=None):
    """Yield benchmark records (see the module docstring); ``quick`` is small and fast (tests, CI).

    The reproduction's lighter settings (notebook 09 says which it used): ``work`` cell updates
    per timed repeat (default :data:`WORK`), ``cold=False`` skips the two child processes that
    compile every kernel into an empty numba cache (about a minute each; default: not quick),
    ``external_max_size`` caps the PGMax / PyMaxflow grids, ``explorer_changes`` the widget
    changes timed (default 36, quick 6) and ``converge_runs`` the timed runs per convergence
    measurement (the best is kept; a smaller warm-up run loads the kernels first); ``online_tol``
    the tolerance of the online run's final map against the offline one (default 1e-7);
    ``bandwidth_mbytes`` the size of each array of the bandwidth triad (default 256, quick 64);
    ``peers=False`` leaves out the published peers' rows (``peers-*``, with the online rows) and
    ``node=False`` the ROS node's (``node-*``), which no table of notebook 09 shows.
    ``preset_maps``: the maps of the default preset's convergence rows (default: the Intel and ACES logs
    and a 4096² office; quick: a 256² office; see :data:`crfstudy.bench.goals.PRESET_MAPS`).
    ``converge_start_size``: the grid side of the thesis-table convergence rows (information; default 4096, quick 256).
    ``only``: run just these groups of rows (:data:`GROUPS`, e.g. ``("node",)``), else every one the flags allow.
    """
    from tqdm.auto import tqdm

    sizes = tuple(sizes or (QUICK_SIZES if quick else SIZES))
    repeats = repeats or (2 if quick else 5)
    work = work or (QUICK_WORK if quick else WORK)
    cold = (not quick) if cold is None else cold
    explorer_changes = explorer_changes or (6 if quick else 36)
    converge_sizes = [s for s in (QUICK_CONVERGE_SIZES if quick else CONVERGE_SIZES) if s <= max(sizes)] or [min(sizes)]
    tasks = [("machine", None), ("compile", None)]
    tasks += [("throughput", s) for s in sizes]
    tasks += [("converge", s) for s in converge_sizes]
    if memory:
        tasks.append(("memory", 1024 if quick else max(sizes)))
    if online:
        tasks += [("online", None)] + ([("node", None)] if node else []) + [("closed-loop", None)]
    if external:
        tasks.append(("external", None))

    converge_start_size = converge_start_size or (G.QUICK_CONVERGE_GOAL_SIZE if quick else G.CONVERGE_GOAL_SIZE)
    if goals:
        tasks += [("start", None), ("explorer", None), ("reproduce", None), ("converge-start", converge_start_size),
                  ("preset-converge", None)]
    if only is not None:
        unknown = [g for g in only if g not in GROUPS]
        if unknown or not only:
            raise InputError("--only", f"unknown row group(s) {', '.join(unknown) or '(none given)'}; known: "
                             f"{', '.join(GROUPS)}")
        wanted = {kind for g in only for kind in GROUPS[g]}
        tasks = [(kind, size) for kind, size in _all_tasks(tasks, quick, sizes, converge_start_size) if kind in wanted]
    bar = tqdm(tasks, desc="bench", disable=not progress)
    bounds, ceilings = {}, {}  # threads -> float32 one-pass bound, division ceiling [Mcell/s] of this run
    for kind, size in bar:
        bar.set_postfix_str(f"{kind} {size or ''}".strip())
        if kind == "machine":
            yield agreement()
            rows, bounds, ceilings = machine_rows(threads, bandwidth_mbytes or (64 if quick else 256))
            yield from rows
        elif kind == "compile":
            if cold:
                yield compile_seconds(cold=True)
            yield compile_seconds(cold=False)
        elif kind == "throughput":
            yield bench_baseline(size, repeats)
            fast = {}  # threads -> float32 kernel record: infer() is compared with the same run's kernel
            for th in threads:
                fast[th] = bench_fast(size, np.float32, th, repeats, work=work)
                yield fast[th]
            top = max(threads)
            yield bench_fast(size, np.float64, top, repeats, work=work)
            yield bench_fast(size, np.float32, top, repeats, hidden=GENERAL_TABLE, method="crfmap-fast-general",
                             work=work)
            yield bench_fast(size, np.float32, top, repeats, bounded=True, method="crfmap-fast-bounded", work=work)
            end_to_end = bench_infer(size, np.float32, top, repeats, work=work)
            yield end_to_end
            if goals:
                yield G.infer_vs_kernel(fast[top], end_to_end)
                for th in threads:
                    yield G.kernel_vs_bound(fast[th], bounds.get(th), ceilings.get(th))
            if size <= 512:
                yield bench_plain(size, 1, top)
        elif kind == "converge":
            yield from bench_converge(size, max(threads), with_plain=size <= (256 if quick else 512),
                                      runs=converge_runs)
        elif kind == "memory":
            yield peak_memory_per_cell(size)
        elif kind == "online":
            from crfstudy.bench.online import bench_online
            from crfstudy.bench.peers import bench_peers

            yield from bench_online(quick=quick, final_tol=online_tol)
            if peers:
                yield from bench_peers(quick=quick)
        elif kind == "node":
            from crfstudy.bench.node import bench_node_map, bench_node_memory, bench_node_refine

            yield from bench_node_refine(quick=quick)
            yield from bench_node_map(quick=quick)
            yield from bench_node_memory(1024 if quick else 4096)  # the node's bytes a cell beside crfmap infer's
        elif kind == "closed-loop":
            from crfstudy.bench.closed_loop import bench_closed_loop

            yield from bench_closed_loop(quick=quick)
        elif kind == "external":
            from crfstudy.bench.external import run_external

            yield from run_external([s for s in sizes if s <= external_max_size] or [min(sizes)], repeats, quick)
        elif kind == "start":
            yield from G.start_times(quick, cold=cold)
        elif kind == "explorer":
            yield from G.explorer_redraw(explorer_changes)
        elif kind == "reproduce":
            yield G.reproduce_record()
        elif kind == "converge-start":
            yield from G.converge_start(size, max(threads), runs=converge_runs)
        elif kind == "preset-converge":
            yield from G.preset_converge(quick, maps=preset_maps, threads=max(threads))


def format_record(rec) -> str:
    """One human-readable line."""
    parts = [f"{rec['method']:<22}"]
    for key in ("size", "dtype", "threads"):
        if rec.get(key) is not None:
            parts.append(f"{key}={rec[key]}")
    if rec.get("mcells_per_second") is not None:
        parts.append(f"{rec['mcells_per_second']:8.1f} Mcell/s")
    if rec.get("seconds_per_iteration") is not None:
        parts.append(f"{1e3 * rec['seconds_per_iteration']:.3f} ms/it")
    for key, value in rec.items():
        if key in ("method", "size", "dtype", "threads", "mcells_per_second", "seconds_per_iteration"):
            continue
        if isinstance(value, float):
            value = f"{value:.4g}"
        parts.append(f"{key}={value}")
    return "  ".join(parts)


def to_json(rec) -> str:
    def clean(v):
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [clean(x) for x in v]
        if isinstance(v, (np.floating, float)):
            return None if not math.isfinite(float(v)) else float(v)
        if isinstance(v, np.integer):
            return int(v)
        if isinstance(v, np.bool_):
            return bool(v)
        return v

    return json.dumps(clean(rec))


def _cpu_name() -> str:  # pragma: no cover - informational
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return os.uname().machine
