"""Speed as users feel it (issue 13): one record per goal, measured in the same run as the suite.

- ``infer-vs-kernel``: :func:`crfmap.crf.inference.lbp.infer` end to end (packing, iterations, beliefs,
  unpacking) against its kernel's per-iteration throughput, same size, dtype and threads
  (goal: ratio >= 0.8 at 2048², 4096², 8192²). Built from the suite's own ``crfmap-fast`` and
  ``crfmap-infer`` records of that size, so both come from one run.
- ``start-cold`` / ``start-warm`` / ``start-env``: wall time of ``crfmap infer`` on a 512² map in
  a new process, with an empty numba cache, with that cache once warmed by the first run, and
  with the environment's own cache as it is (what the next user call pays); goals: the empty
  cache's first call <= 20 s (what a user who installed with pip waits once), and the
  environment's - warm <= 2 s after the make targets have warmed the cache. Quick runs skip the
  empty cache.
- ``explorer-redraw``: median seconds from a widget change to the new PNG in the explorer panel,
  headless (real ``ipywidgets`` value changes, kernels warmed first; goal <= 0.3 s), with the
  scene change apart (it re-lays the figure out).
- ``reproduce``: the last ``make reproduce`` run's timing record
  (``paper/generated/reproduce_timings.json``), or a record saying there is none (goal: <= 5
  min from a fresh clone).
- ``preset-converge``: the default preset (``crfmap infer``'s own call: float64, tol 1e-5) to
  convergence on the largest real-size maps crfmap builds -- the Intel and ACES logs at 0.05 m --
  and a 4096² synthetic office (quick: a 256² office only), against the NumPy baseline's time for
  :data:`PRESET_GOAL_ITERATIONS` iterations on a grid of the same shape, measured in the same run
  (goal: preset seconds <= that).
- ``converge-start``: 4096² (quick: 256²) noisy office floor, table [[10, 1], [1, 10]], until the
  largest message change is below 1e-4, from the plain (uniform) start and, when
  :func:`crfmap.crf.inference.lbp.infer` has one, from a coarse-to-fine start, with the largest belief
  difference between the two (goal: <= 1 s).

The coarse start is picked up by keyword: the first of :data:`COARSE_START_OPTIONS` whose
keyword ``infer`` accepts and whose value it does not reject; ``crfmap bench`` then reports it as
``start: <keyword>=<value>``: ``init="coarse"`` (:mod:`crfmap.crf.inference.multiscale`; ``start`` names the
thesis schedule's corner and rejects ``"coarse"``).
"""
from __future__ import annotations

import inspect
import json
import os
import subprocess
import sys
import tempfile
import time
from functools import partial
from pathlib import Path

import numpy as np

from crfstudy.bench.common import CONVERGE_TOL, bench_grid, median_time, record
from crfstudy.experiments.explorer_panel import ExplorerPanel
from crfstudy.experiments import explorer
from crfstudy.experiments.explorer_view import ExplorerView
from crfstudy import paths
from crfstudy.repro.buildinfo import wall_record
from crfmap.errors import DataMissingError, InputError
from crfmap.data import data_file
from crfmap.io.carmen import read_carmen
from crfmap.mapping.builder import build_grid
from crfstudy.bench.baseline import NumpyCheckerboard
from crfmap.crf.presets import DEFAULT_PRESET, get_preset
from crfmap.crf.inference.lbp import infer

INFER_GOAL = 0.8  # end-to-end / kernel per-iteration throughput
START_GOAL = 2.0  # [s] first `crfmap infer` minus a warm one, caches warmed by make
COLD_START_GOAL = 20.0  # [s] first `crfmap infer` on a 512² map with an empty numba cache (a pip user's first call)
PRESET_GOAL_ITERATIONS = 5  # the default preset converged within this many NumPy-baseline iterations' time
PRESET_REPEATS = 5  # best of: a refine of Intel takes ~25 ms, where best of 2 varied by 50% between runs
PRESET_MAPS = ("intel", "aces", "office")  # the largest real-size maps crfmap builds, and a synthetic office
PRESET_OFFICE_SIZE = 4096
QUICK_PRESET_OFFICE_SIZE = 256
REDRAW_GOAL = 0.3  # [s] explorer, widget change to new image
REPRODUCE_GOAL = 300.0  # [s] make reproduce from a fresh clone
BOUND_GOAL = 2.0  # kernel per-iteration throughput / one-pass bandwidth bound (2048², all threads)
BOUND_GOAL_SIZE = 2048
ONE_THREAD_GOAL = 1000.0  # [Mcell/s] kernel, float32, one thread, on a cache-resident grid
ONE_THREAD_GOAL_SIZE = 512
CONVERGE_GOAL_SIZE = 4096
QUICK_CONVERGE_GOAL_SIZE = 256
START_MAP_SIZE = 512  # [cells] per side of the map `crfmap infer` reads in the start rows
# infer(..., **option) for a coarse-to-fine start, tried in this order (see the module docstring)
COARSE_START_OPTIONS = ({"init": "coarse"}, {"start": "coarse"}, {"coarse_to_fine": True}, {"multiscale": True})
# explorer widget changes timed, in this order (cycled): tables, link, schedule, iterations, bound, noise, seed
REDRAW_CHANGES = (("h_oo", 8.0), ("h_ee", 8.0), ("l_oo", 0.8), ("schedule", "thesis"), ("iterations", "2"),
                  ("schedule", "flooding"), ("radius", 1.5), ("schedule", "sweep"), ("iterations", "to convergence"),
                  ("image_noise", 0.5), ("seed", 1), ("schedule", "checkerboard"), ("radius", 0.0),
                  ("h_oo", 10.0), ("h_ee", 10.0), ("l_oo", 1.0), ("image_noise", 0.42), ("seed", 0))


# --- end to end against the kernel --------------------------------------------------------------------


def infer_vs_kernel(kernel: dict, end_to_end: dict) -> dict:
    """Ratio of a ``crfmap-infer`` record's throughput to its ``crfmap-fast`` record's (same run)."""
    ratio = end_to_end["mcells_per_second"] / kernel["mcells_per_second"]
    return record("infer-vs-kernel", kernel["size"], kernel["dtype"], kernel["threads"], None,
                  kernel_mcells_per_second=kernel["mcells_per_second"],
                  infer_mcells_per_second=end_to_end["mcells_per_second"], ratio=ratio, goal=INFER_GOAL,
                  iterations_per_call=end_to_end.get("iterations_timed"),
                  note=f"infer() end to end over its kernel per iteration, {end_to_end.get('iterations_timed')} "
                  "iterations per call (packing and unpacking spread over them)")


def kernel_vs_bound(kernel: dict, bound_mcells_per_second, ceiling_mcells_per_second=None) -> dict:
    """A float32 ``crfmap-fast`` record against the one-pass bandwidth bound measured in the same run, and against
    the division ceiling of the same run (:mod:`crfstudy.bench.machine`; None: not measured).

    Goals (issue 13): >= :data:`BOUND_GOAL` x the bound at :data:`BOUND_GOAL_SIZE`² with every
    thread; >= :data:`ONE_THREAD_GOAL` Mcell/s on one thread at :data:`ONE_THREAD_GOAL_SIZE`².

    >>> r = kernel_vs_bound({"size": 2048, "dtype": "float32", "threads": 2, "mcells_per_second": 1900.0}, 1000.0,
    ...                     3800.0)
    >>> r["ratio_to_bound"], r["goal_ratio"], r["ratio_to_division_ceiling"]
    (1.9, 2.0, 0.5)
    """
    mcells = kernel["mcells_per_second"]
    ratio = None if not bound_mcells_per_second else mcells / bound_mcells_per_second
    return record("kernel-vs-bound", kernel["size"], kernel["dtype"], kernel["threads"], None,
                  kernel_mcells_per_second=mcells, bound_mcells_per_second=bound_mcells_per_second,
                  ratio_to_bound=ratio, goal_ratio=(BOUND_GOAL if kernel["size"] == BOUND_GOAL_SIZE and kernel["threads"] > 1
                              else None),
                  goal_mcells_per_second=(ONE_THREAD_GOAL if kernel["size"] == ONE_THREAD_GOAL_SIZE
                                          and kernel["threads"] == 1 else None),
                  division_ceiling_mcells_per_second=ceiling_mcells_per_second,
                  ratio_to_division_ceiling=(None if not ceiling_mcells_per_second
                                             else mcells / ceiling_mcells_per_second),
                  note="kernel per iteration over the one-pass bound of the memory-bandwidth row and over the "
                  "division ceiling, both with the same threads (same run)")


# --- cold and warm start ------------------------------------------------------------------------------


def _crfmap_command():
    script = Path(sys.executable).with_name("crfmap")
    return [str(script)] if script.exists() else [sys.executable, "-m", "crfmap.cli"]


def _time_infer(folder, cache):
    env = dict(os.environ)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache)
    out = Path(folder) / "beliefs.npy"
    t = time.perf_counter()
    done = subprocess.run(_crfmap_command() + ["infer", str(Path(folder) / "map.npy"), str(out)],
                          capture_output=True, text=True, env=env)
    seconds = time.perf_counter() - t
    if done.returncode != 0:
        raise RuntimeError(f"crfmap infer failed: {done.stderr.strip().splitlines()[-1:]}")
    return seconds


def start_times(quick=False, cold=None) -> list:
    """``crfmap infer`` in a new process: empty cache (``cold``; default: not quick), warmed cache, environment's."""
    cold_run = (not quick) if cold is None else cold
    out = []
    with tempfile.TemporaryDirectory() as folder:
        np.save(Path(folder) / "map.npy", bench_grid(START_MAP_SIZE, kind="office"))
        common = dict(map_size=START_MAP_SIZE, command="crfmap infer map.npy beliefs.npy")
        env_seconds = _time_infer(folder, None)
        if not cold_run:  # compiling every kernel takes a minute: the environment's cache, now warm, stands in
            cold, warm = None, _time_infer(folder, None)
        else:
            cache = Path(folder) / "numba-cache"
            cache.mkdir()
            cold = _time_infer(folder, cache)
            warm = _time_infer(folder, cache)
    if cold is not None:
        out.append(record("start-cold", START_MAP_SIZE, None, None, None, seconds=cold, cache="empty",
                          minus_warm_seconds=cold - warm, goal_seconds=COLD_START_GOAL, **common))
    else:
        out.append(record("start-cold", START_MAP_SIZE, None, None, None, seconds=None, cache="empty",
                          note="skipped (quick run or cold=False): compiling every kernel takes about a minute; "
                          "`crfmap bench` measures it", **common))
    warmed = "the empty one, after the first run" if cold_run else "the environment's, after the first run"
    out.append(record("start-warm", START_MAP_SIZE, None, None, None, seconds=warm, cache=warmed, **common))
    out.append(record("start-env", START_MAP_SIZE, None, None, None, seconds=env_seconds,
                      cache=os.environ.get("NUMBA_CACHE_DIR", "numba's default (__pycache__ beside the modules)"),
                      minus_warm_seconds=env_seconds - warm, goal_minus_warm_seconds=START_GOAL, **common,
                      note="the environment's cache as this run found it: what the next call of crfmap infer pays"))
    return out


# --- explorer -----------------------------------------------------------------------------------------


def explorer_redraw(changes=12) -> list:
    """Median time from a widget change to the new PNG, headless, over ``changes`` changes."""
    panel = ExplorerPanel()
    t = time.perf_counter()
    panel.warm_up()
    warm_up = time.perf_counter() - t
    panel.redraw()
    c = panel.controls
    first = len(panel.timings)
    for k in range(changes):
        name, value = REDRAW_CHANGES[k % len(REDRAW_CHANGES)]
        c[name].value = value
    timed = panel.timings[first:]
    for scene in ("office", "x"):
        c["scene"].value = scene
    scene_changes = panel.timings[-2:]

    def med(key, rows):
        return float(np.median([r[key] for r in rows]))

    # the way it was drawn before (a new figure per change, laid out and fully drawn): same run, for the ratio
    ex = explorer.run()
    full = []
    for _ in range(3):
        t = time.perf_counter()
        ExplorerView(live=False).update(ex).png()
        full.append(time.perf_counter() - t)

    rec = record("explorer-redraw", None, None, explorer.THREADS, None, seconds=med("seconds", timed),
                 changes=len(timed),
                 max_seconds=float(max(r["seconds"] for r in timed)), lbp_seconds=med("lbp_seconds", timed),
                 run_seconds=med("run_seconds", timed), draw_seconds=med("draw_seconds", timed),
                 compiled_during_changes=sum(r["compiled"] for r in timed), warm_up_seconds=warm_up,
                 full_redraw_seconds=float(np.median(full)),
                 goal_seconds=REDRAW_GOAL,
                 note="median over widget changes (tables, link, schedule, iterations, bound, noise, seed) on the X; "
                 "run = observation + LBP + metrics, draw = in-place figure update + PNG; full_redraw = a new "
                 "figure laid out, drawn and encoded (how every change was drawn before)")
    scene = record("explorer-scene-change", None, None, None, None, seconds=med("seconds", scene_changes),
                   draw_seconds=med("draw_seconds", scene_changes),
                   note="X -> office -> X (observations cached): the figure is laid out again")
    return [rec, scene]


# --- make reproduce -----------------------------------------------------------------------------------


def reproduce_record(path=None, wall_path=None) -> dict:
    """The last ``make reproduce`` run's timings (``paper/generated/reproduce_timings.json``), if any.

    ``seconds`` is the run's wall clock from ``out/logs/reproduce_wall.json`` when that record is
    as new as the timings (from the start of ``make reproduce`` if make passed it, else the
    workflow's own), otherwise the notebooks' summed run times.
    """
    path = Path(path or paths.GENERATED / "reproduce_timings.json")
    if not path.exists():
        return record("reproduce", None, None, None, None, seconds=None, goal_seconds=REPRODUCE_GOAL,
                      note=f"no timing record ({path.name} not found): run `make reproduce` first")
    data = json.loads(path.read_text())
    notebooks = data.get("seconds") or {}
    slowest = max(notebooks, key=notebooks.get) if notebooks else None
    extra = {k: v for k, v in data.items() if k not in ("seconds", "total_seconds")}
    # the wall-clock record of the same run (repro.reproduce writes it after a full run), if it is that run's
    wall_path = paths.OUT / "logs" / "reproduce_wall.json" if wall_path is None else Path(wall_path)
    wall = wall_record(wall_path) if wall_path.exists() else {}
    if wall and wall_path.stat().st_mtime < path.stat().st_mtime:
        wall = {}  # older than the timings: another run's
    seconds = wall.get("make_seconds") or wall.get("workflow_seconds")
    what = ("wall clock of `make reproduce` (venv, warm-up, workflow)" if wall.get("make_seconds") else
            "wall clock of the workflow" if wall else "no wall-clock record: the notebooks' summed run times")
    fresh = [r for r in wall.get("runs", []) if isinstance(r, dict) and r.get("new_venv") and r.get("make_seconds")]
    return record("reproduce", None, None, None, None, seconds=seconds if wall else data.get("total_seconds"),
                  goal_seconds=REPRODUCE_GOAL, workflow_seconds=wall.get("workflow_seconds"),
                  new_venv=wall.get("new_venv"), runs_recorded=len(wall.get("runs", [])),
                  last_fresh_clone_seconds=fresh[-1]["make_seconds"] if fresh else None,
                  last_fresh_clone_finished=fresh[-1].get("finished") if fresh else None,
                  notebook_seconds_total=data.get("total_seconds"), notebook_seconds=notebooks, slowest=slowest,
                  recorded=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(path.stat().st_mtime)),
                  **{f"record_{k}": v for k, v in extra.items()},
                  note=f"read from the last make reproduce run, not measured here; seconds = {what}")


# --- the default preset on real-size maps --------------------------------------------------------------


def _preset_map(name, quick):
    """(observed P grid, what it is) for :data:`PRESET_MAPS`, or (None, why not) when its data is missing."""
    if name == "office":
        size = QUICK_PRESET_OFFICE_SIZE if quick else PRESET_OFFICE_SIZE
        return bench_grid(size, kind="office"), f"synthetic office floor {size}², flip noise 0.2"

    try:
        path = data_file(f"carmen/{name}-corrected.log.gz")
    except DataMissingError as exc:
        return None, str(exc)
    scans = read_carmen(path, warn=False).scans  # as crfmap build reads it (corrected poses; odometry unused)
    return build_grid(scans, 0.05).probability, f"{path.name}, every scan, 0.05 m cells"


def preset_converge(quick=False, maps=None, threads=None) -> list:
    """The default preset to convergence vs :data:`PRESET_GOAL_ITERATIONS` NumPy-baseline iterations (see above)."""
    preset = get_preset(DEFAULT_PRESET)
    out = []
    for name in maps or (("office",) if quick else PRESET_MAPS):
        grid, what = _preset_map(name, quick)
        if grid is None:
            out.append(record("preset-converge", None, None, None, None, map=name, seconds=None,
                              note=f"skipped: {what}"))
            continue
        options = dict(tol=1e-5, max_iter=1000, dtype=np.float64)  # crfmap infer's defaults
        if threads:
            options["threads"] = threads
        preset.refine(grid[:256, :256].copy(), **options)  # loads the kernels: not convergence time
        best = None
        for _ in range(PRESET_REPEATS):
            t = time.perf_counter()
            r = preset.refine(grid, **options)
            seconds = time.perf_counter() - t
            if best is None or seconds < best[0]:
                best = (seconds, r.iterations, r.converged)
            del r
        baseline = NumpyCheckerboard(grid, dtype=np.float32)
        baseline.iterate(1)
        per_iteration = min(median_time(partial(baseline.iterate, 2), 1) for _ in range(PRESET_REPEATS)) / 2
        del baseline
        budget = PRESET_GOAL_ITERATIONS * per_iteration
        seconds, iterations, converged = best
        out.append(record("preset-converge", max(grid.shape), np.float64, threads, None, map=name,
                          shape=list(grid.shape), preset=DEFAULT_PRESET, seconds=seconds, iterations=iterations,
                          converged=converged, baseline_seconds_per_iteration=per_iteration,
                          goal_seconds=budget, ratio_to_goal=seconds / budget,
                          note=f"{what}; crfmap infer's call (float64, tol 1e-5), best of {PRESET_REPEATS}, vs "
                          f"{PRESET_GOAL_ITERATIONS} iterations of the NumPy baseline (float32) on the same shape"))
    return out


# --- convergence --------------------------------------------------------------------------------------


def coarse_start_option():
    """The keyword arguments of :func:`crfmap.crf.inference.lbp.infer`'s coarse-to-fine start, or None.

    An option counts when ``infer`` takes the keyword, accepts the value and its first iteration
    then differs from the uniform start's (``start`` exists for the thesis schedule's corner and
    the checkerboard ignores it).
    """
    accepted = inspect.signature(infer).parameters
    probe = bench_grid(256, kind="office")  # large enough to have a coarser level
    uniform = infer(probe, max_iter=1, tol=0.0).beliefs.probability
    for option in COARSE_START_OPTIONS:
        if not set(option) <= set(accepted):
            continue
        try:
            beliefs = infer(probe, max_iter=1, tol=0.0, **option).beliefs.probability
        except (InputError, ValueError, TypeError):
            continue
        if not np.array_equal(beliefs, uniform):
            return option
    return None


def converge_start(size, threads, tol=CONVERGE_TOL, max_iter=5000, runs=2) -> list:
    """Time and iterations to convergence from the plain start and (when infer has one) a coarse one.

    Each start first runs once on a 512² corner (loading or compiling its kernels), then the best
    of ``runs`` timed runs on the full grid is kept; ``first_run_seconds`` is the first of them,
    which also pays for touching the grid-sized buffers for the first time in the process.
    """
    obs = bench_grid(size, kind="office")
    starts = {"uniform": {}}
    option = coarse_start_option()
    if option is not None:
        starts[", ".join(f"{k}={v}" for k, v in option.items())] = option
    results = {}
    for name, kwargs in starts.items():
        options = dict(tol=tol, max_iter=max_iter, dtype=np.float32, threads=threads, **kwargs)
        infer(obs[:512, :512].copy(), **options)  # warm-up: kernel loading is not convergence time
        best, first = None, None
        for _ in range(max(runs, 1)):
            # a result held across calls keeps infer's reusable buffers, so the next call would pay
            # fresh pages: keep what is reported (and a copy of the beliefs), drop the result
            r = infer(obs, **options)
            first = r.seconds if first is None else first
            if best is None or r.seconds < best[0]:
                best = (r.seconds, r.iterations, r.converged, r.beliefs.probability.copy())
            del r
        results[name] = best + (first,)
    plain_beliefs = results["uniform"][3]
    out = []
    for name, (seconds, iterations, converged, beliefs, first) in results.items():
        out.append(record("converge-start", size, np.float32, threads, seconds / max(iterations, 1),
                          start=name, iterations=iterations, seconds_to_converge=seconds, converged=converged,
                          runs=max(runs, 1), first_run_seconds=first,
                          tol=tol,
                          max_belief_difference_vs_uniform=float(np.abs(beliefs - plain_beliefs).max()),
                          note="noisy office floor, [[10, 1], [1, 10]] (the thesis's table, its ordered phase): "
                          "information, no goal (issue 22: the default preset's row is the convergence goal)"))
    if option is None:
        out.append(record("converge-start", size, np.float32, threads, None, start="coarse", iterations=None,
                          seconds_to_converge=None, note="infer() has no coarse-to-fine start yet (looked for "
                          + ", ".join(f"{k}={v!r}" for o in COARSE_START_OPTIONS for k, v in o.items()) + ")"))
    return out
