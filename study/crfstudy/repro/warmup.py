"""Warm numba's on-disk cache once, so no entry point (and no notebook) pays for compiling kernels again.

``make test`` and ``make reproduce`` run ``python -m crfstudy.repro.warmup`` first. It calls the public
functions that reach every numba kernel the command line and the notebooks use (:func:`all_tasks`):
``crfmap infer`` on a tiny grid with every schedule, in float64 and float32 and with ``--margin``;
:func:`crfmap.crf.inference.lbp.infer` on a grid large enough for the parallel pass; the grid builder and the
online mapper on a few synthetic scans; the simulator with every drive and with noise; the benchmarks'
bandwidth kernel; the background chapter's Gibbs sampler. That compiles
(or loads) them into the cache every entry point of the environment shares (``NUMBA_CACHE_DIR``, set
for the shell by make, for the command line by the venv's ``crfmap_numba_cache.pth`` and for Jupyter by
the kernel spec; see the Makefile). Compiling is single-threaded, so the tasks are shared out over
``--jobs`` processes (default: the cores, at most 4), longest first; each writes its own kernels'
cache files. With a warm cache it takes a second or two.

In a Jupyter kernel, :func:`announce_if_cold` (called when a notebook imports
:mod:`crfstudy.repro.report`, i.e. in its first code cell) prints "compiling kernels (first run only)"
and warms the cache there, so the pause happens where the message is, not on a silent later cell.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# Only the standard library at the top, everything else inside the functions: `make venv` runs this file as a script
# (``--requirements``) before anything is installed, and the warm-up while pip installs the rest (NEEDS).

# the distributions the tasks import (tests/repro/test_warmup.py checks it): `make venv` installs these first, then
# warms the cache while pip installs the rest (run as a script, ``--requirements`` names them with pyproject's versions)
NEEDS = ("numpy", "numba", "pyyaml", "pillow", "tqdm", "scipy", "lazy-loader")
CHECKOUT = Path(__file__).resolve().parents[3]
LIBRARY = CHECKOUT / "lib" / "crfmap"  # the library's sources (this runs as a script before anything is installed)
STUDY = CHECKOUT / "study" / "crfstudy"
# every folder or module holding numba kernels the tasks below compile: a change to one re-warms
NUMBA_SOURCES = ("crf", "crf/model", "crf/inference", "crf/engine", "mapping", "sim", "world/reachability.py",
                 "raycast.py", "assess/scansplit.py", "assess/block_bootstrap.py")
STUDY_NUMBA_SOURCES = ("bench/machine.py", "experiments/background.py", "closed_loop")


def requirements(pyproject=CHECKOUT / "pyproject.toml") -> list[str]:
    """The requirement strings of :data:`NEEDS` as ``pyproject`` states them (one place for the versions).

    >>> [r.split(">")[0].lower().replace("_", "-") for r in requirements()]
    ['numpy', 'numba', 'pyyaml', 'pillow', 'tqdm', 'scipy', 'lazy-loader']
    """
    import re
    import tomllib

    declared = tomllib.loads(Path(pyproject).read_text())["project"]["dependencies"]
    by_name = {re.match(r"[A-Za-z0-9._-]+", r).group(0).lower().replace("_", "-"): r for r in declared}
    missing = [n for n in NEEDS if n not in by_name]
    if missing:
        raise ValueError(f"{pyproject}: no dependency named {', '.join(missing)} (warmup.NEEDS)")
    return [by_name[n] for n in NEEDS]


def cache_dir() -> Path | None:
    """Numba's cache folder (``NUMBA_CACHE_DIR``); None means numba's default beside the sources."""
    value = os.environ.get("NUMBA_CACHE_DIR")
    return Path(value) if value else None


def _stamp() -> Path:
    return (cache_dir() or LIBRARY / "crf" / "__pycache__") / "crfmap-warmed.stamp"


def _sources() -> list[Path]:
    """The modules whose change means the warm-up must run again (their kernels, their callers, this file)."""
    out = [LIBRARY / "cli.py", LIBRARY / "commands" / "infer.py", Path(__file__).resolve()]
    for root, sources in ((LIBRARY, NUMBA_SOURCES), (STUDY, STUDY_NUMBA_SOURCES)):
        for relative in sources:
            path = root / relative
            out += sorted(path.glob("*.py")) if path.is_dir() else [path]
    return [p for p in out if p.is_file()]


def is_warm() -> bool:
    """Whether :func:`warm` ran since the last change to the code it compiles (then it has nothing to do).

    Told by the stamp the warm-up writes itself, in the cache folder: numba's cache files are its own business.
    """
    stamp = _stamp()
    return stamp.is_file() and stamp.stat().st_mtime > max(p.stat().st_mtime for p in _sources())


# --- the tasks: each reaches a group of kernels through public functions ---------------------------
def _tiny_grids():
    """Two tiny grids of P(occupied): one without and one with certain cells (P exactly 0 or 1: clamped)."""
    import numpy as np

    soft = np.random.default_rng(0).uniform(0.0, 1.0, (12, 10))
    hard = soft.copy()
    hard[2, 2:6], hard[7, 3:8] = 1.0, 0.0
    return soft, hard


def _cli_infer(*variants) -> None:
    """``crfmap infer`` on the tiny grids, once per variant (extra command-line arguments)."""
    import numpy as np

    from crfmap.cli import main

    with tempfile.TemporaryDirectory(prefix="crfmap-warmup-") as tmp:
        for k, values in enumerate(_tiny_grids()):
            grid = Path(tmp) / f"grid{k}.npy"
            np.save(grid, values)
            for variant in variants:
                argv = ["infer", str(grid), str(Path(tmp) / "out.npy"), *variant]
                with contextlib.redirect_stdout(io.StringIO()):  # one line per call would drown the message
                    status = main(argv)
                if status != 0:
                    raise RuntimeError(f"warm-up call `crfmap {' '.join(argv)}` failed")


def _schedule(name):
    return lambda: _cli_infer(["--schedule", name], ["--schedule", name, "--float32"])


def _checkerboard(dtype):
    """The default schedule in one dtype: the fast kernels (whole grid and ``--margin``) and the reference one."""

    def task():
        from crfmap.crf.inference.lbp import infer
        from crfmap.crf.inference.schedules import Checkerboard

        if dtype == "float32":
            _cli_infer(["--schedule", "checkerboard", "--float32"])
        else:
            _cli_infer(["--schedule", "checkerboard"], ["--schedule", "checkerboard", "--margin", "2"])
        from crfmap.errors import InputError

        for grid in _tiny_grids():  # clamped certain cells in the fast kernel; the reference kernel
            infer(grid, max_iter=3, dtype=dtype)  # (kernel="plain": also what damping or odd tables run)
            infer(grid, max_iter=3, schedule=Checkerboard(kernel="plain"), dtype=dtype)
            with contextlib.suppress(InputError):  # a zero entry spreads certainty (may contradict: compiled anyway)
                infer(grid, [[10.0, 1.0], [0.0, 10.0]], max_iter=3, dtype=dtype)

    return task


def _large_grid(dtype):
    """infer() where it takes the parallel pass (a grid above the serial size, 2 threads), whole and bounded."""

    def task():
        import numpy as np

        from crfmap.crf.inference.lbp import infer

        # above packed.SPARSE_CELLS (2^18) senders: the per-tile measure that freezes settled tiles runs too
        p = np.random.default_rng(0).uniform(0.0, 1.0, (540, 540))
        p[:, :20] = 0.5  # unknown cells, so a region differs from the whole grid
        first = infer(p, max_iter=3, dtype=dtype, threads=2)
        infer(p, max_iter=3, dtype=dtype, threads=2, messages=first.messages)
        infer(p, max_iter=3, dtype=dtype, threads=2, region=p != 0.5)

    return task


def _synthetic_scans(n=6, beams=90):
    """A few seeded 360 deg scans along a short path, every 17th beam a no-return (the mapping and peers tasks)."""
    import numpy as np

    from crfmap.recording import ScanSet

    rng = np.random.default_rng(0)
    ranges = rng.uniform(0.5, 3.0, (n, beams)).astype(np.float32)
    ranges[:, ::17] = np.inf  # no returns
    poses = np.column_stack([np.linspace(0, 1, n), np.zeros(n), np.linspace(0, 1, n)])
    return ScanSet(ranges, -np.pi, 2 * np.pi / beams, 0.05, 4.0, poses, np.arange(n, dtype=float))


def _mapping():
    """The grid builder (both models) and the online mapper (with and without a margin) on synthetic scans."""
    from dataclasses import replace


    from crfmap.mapping.builder import build_grid
    from crfmap.mapping.online import OnlineMapper

    scans = _synthetic_scans()
    every_other = replace(scans, ranges=scans.ranges[::2], laser_poses=scans.laser_poses[::2], stamps=scans.stamps[::2])
    for model in ("arctan", "logodds"):
        build_grid(scans, 0.1, model=model)
        build_grid(every_other, 0.1, model=model)  # strided views: another compiled signature
    for margin in (None, 2):
        mapper = OnlineMapper.for_scans(scans, 0.1, margin=margin)
        for i in range(len(scans)):
            mapper.integrate(scans.ranges[i], scans.laser_poses[i])
        mapper.finish(tol=1e-3, max_iter=5)


def _simulator():
    """The simulator with every drive, with and without noise, on the small thesis scenes."""
    from crfmap.sim.laser import Laser
    from crfmap.sim.simulator import simulate
    from crfmap.world.scenes import enclosed_boxes, occluded_walls

    import numpy as np

    from crfmap.raycast import bresenham_step, first_hit_kernel

    occupied = np.zeros((8, 8), bool)
    occupied[5, :] = True
    # the kernels as notebook 03's line_cells and first_hit (crfstudy.experiments.simulation) call them: that module
    # needs matplotlib, which this script may run without
    bresenham_step(0, 0, 7, 3, np.empty((8, 2), np.int64))
    first_hit_kernel(occupied, 1, 1, 2, 7)
    laser = Laser.with_fov(360, 90, range_max=3.0)
    scene = occluded_walls("train", size=20)
    for drive in ("look", "explore", "waypoints"):
        simulate(scene, laser, drive, progress=False)
    simulate(enclosed_boxes("train", size=20), laser, "explore", range_noise=0.05, odometry_noise=(0.002, 0.002),
             progress=False)


def _bandwidth():
    """The machine rows' kernels of the benchmarks (the speed notebook's and ``crfmap bench``'s bound and ceiling)."""
    from crfstudy.bench.machine import machine_rows

    machine_rows((1,), mbytes=1)


def _scoring():
    """Scan-split scores with bootstrap intervals (the compiled AUC over resamples, notebook 10 and ``crfmap evaluate``)."""
    import numpy as np

    from crfmap.assess.scansplit import ScanSplit, score

    hits = np.array([[0, 3, 0, 1]])
    split = ScanSplit(first_hits=hits, first_passes=np.array([[2, 0, 1, 0]]),
                      second_hits=np.array([[0, 2, 1, 0]]), second_passes=np.array([[3, 0, 0, 2]]))
    score(split, {"raw": split.raw_probability()}, n_boot=2, block=1)


def _closed_loop():
    """The closed loop's planner and costmap (notebook 11): a short exploration of a small thesis scene."""
    from crfstudy.closed_loop.exploration import ExploreSettings, explore
    from crfmap.world.scenes import enclosed_boxes

    explore(enclosed_boxes("train", size=20), "raw", ExploreSettings(max_scans=3, robot_radius=None))


def _peers():
    """The published peers ``crfmap evaluate`` scores: OctoMap's clamped update and Bayesian Hilbert maps.

    Without this task the first ``crfmap evaluate`` after ``make venv`` compiled six kernels
    (``octomap._octomap_update``, ``_ray_cells``; ``hilbert._features``, ``_fit_batch``, ``_lam``,
    ``_predict``) that no other task reaches.
    """

    from crfmap.assess.peers import PEERS, peer_rows
    from crfmap.assess.scansplit import scan_split

    scans = _synthetic_scans()
    peer_rows(scan_split(scans, 0.1), list(PEERS))  # the halves are strided views, as on a real log


def _gibbs():
    """The background chapter's Gibbs sampler (notebook 01): chains and lattices share one kernel."""
    from crfstudy.experiments.background import gibbs_ising

    gibbs_ising((3, 4), coupling=0.5, sweeps=1, chains=2)


# name -> (callable, seconds it took on an empty cache on 2 busy cores, beside pip in make venv (2026-12-03);
# the estimates that share the tasks out, longest first).
# The parallel pass (the large grids) is the costliest kernel: float64 and float32 go to different processes.
# seconds each plain schedule's task took on an empty cache (the estimates that share the tasks out); a schedule
# added to the library's registry (crfmap.crf.inference.schedules.SETTINGS) is warmed with a guessed 5 s
PLAIN_SCHEDULE_SECONDS = {"flooding": 0.1, "sweep": 3.0, "thesis": 4.5}


def all_tasks() -> dict:
    """{name: (task, estimated seconds)}: the fixed tasks, and one per plain schedule of the library's registry."""
    from crfmap.crf.inference.schedules import SETTINGS

    tasks = {  # name: (task, its seconds with an empty cache: the estimate that shares them out, measured)
        "checkerboard float64": (_checkerboard("float64"), 18.5),
        "checkerboard float32": (_checkerboard("float32"), 19.5),
        "large grids float64": (_large_grid("float64"), 51.5),
        "large grids float32": (_large_grid("float32"), 50.0),
        "mapping": (_mapping, 10.0),
        "simulator": (_simulator, 9.5),
        "bandwidth": (_bandwidth, 0.5),
        "scoring": (_scoring, 1.5),
        "peers": (_peers, 2.0),
        "gibbs": (_gibbs, 0.5),
        "closed loop": (_closed_loop, 3.0),
    }
    for name in SETTINGS:
        if name != "checkerboard":  # the checkerboard tasks above run it, fast and plain kernels
            tasks[name] = (_schedule(name), PLAIN_SCHEDULE_SECONDS.get(name, 5.0))
    return tasks


def share(tasks, jobs: int) -> list[list[str]]:
    """Tasks in ``jobs`` groups of about equal estimated seconds (longest first, each to the lightest group).

    >>> share(["flooding", "sweep", "thesis"], 2)
    [['thesis'], ['sweep', 'flooding']]
    """
    tasks_ = all_tasks()
    groups = [[] for _ in range(max(1, int(jobs)))]
    load = [0.0] * len(groups)
    for name in sorted(tasks, key=lambda t: -tasks_[t][1] if t in tasks_ else 0.0):
        k = load.index(min(load))
        groups[k].append(name)
        load[k] += tasks_[name][1] if name in tasks_ else 0.0
    return [g for g in groups if g] or [[]]


def run_tasks(names) -> dict:
    """Run these tasks in this process; returns {name: seconds}."""
    tasks = all_tasks()
    unknown = [n for n in names if n not in tasks]
    if unknown:
        raise ValueError(f"unknown warm-up task(s) {unknown}; known: {', '.join(tasks)}")
    seconds = {}
    for name in names:
        t0 = time.perf_counter()
        tasks[name][0]()
        seconds[name] = time.perf_counter() - t0
    return seconds


def default_jobs() -> int:
    return max(1, min(4, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1))


def warm(verbose: bool = True, jobs: int | None = None) -> float:
    """Compile (or load) every kernel of :func:`all_tasks` in ``jobs`` processes; returns the seconds it took."""
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    start = time.perf_counter()
    groups = share(list(all_tasks()), jobs)
    if len(groups) == 1:
        seconds = run_tasks(groups[0])
    else:
        command = [sys.executable, "-m", "crfstudy.repro.warmup", "--worker"]
        workers = [subprocess.Popen(command + group, stdout=subprocess.PIPE, text=True) for group in groups]
        seconds = {}
        for group, worker in zip(groups, workers):
            out, _ = worker.communicate()
            if worker.returncode != 0:
                raise RuntimeError(f"warm-up of {', '.join(group)} failed (exit {worker.returncode})")
            seconds.update(json.loads(out.strip().splitlines()[-1]))
    total = time.perf_counter() - start
    _stamp().parent.mkdir(parents=True, exist_ok=True)
    _stamp().touch()
    if verbose:
        parts = ", ".join(f"{name} {s:.1f}" for name, s in sorted(seconds.items(), key=lambda kv: -kv[1]))
        print(f"numba kernels ready in {total:.1f} s on {len(groups)} process(es) (s per task: {parts}; "
              f"cache: {cache_dir() or 'beside the sources'})")
    return total


def announce_if_cold() -> None:
    """In a Jupyter kernel with a cold cache: say so and compile now (the notebook's first cell)."""
    if "ipykernel" not in sys.modules or is_warm():
        return
    print("compiling kernels (first run only; numba caches them on disk) ...", flush=True)
    warm(verbose=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crfstudy.repro.warmup", description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=None, help="processes compiling at once (default: the cores, <= 4)")
    parser.add_argument("--force", action="store_true", help="run even if the cache is warm")
    parser.add_argument("--worker", nargs="*", metavar="TASK", help=argparse.SUPPRESS)  # one process's share
    parser.add_argument("--requirements", action="store_true",
                        help="print the requirements the warm-up imports (works before they are installed)")
    args = parser.parse_args(argv)
    if args.requirements:
        print(" ".join(requirements()))
        return 0
    if args.worker is not None:
        print(json.dumps(run_tasks(args.worker)))
        return 0
    from crfstudy.repro import variables
    from crfmap.errors import CrfmapError

    try:  # `make reproduce` and `make test` start here: a bad NUMBA_NUM_THREADS is named before numba fails on it
        variables.prepare()
    except CrfmapError as exc:
        print(f"warmup: error: {exc}", file=sys.stderr)
        return 2
    if is_warm() and not args.force:
        print(f"numba cache already warm ({cache_dir() or 'beside the sources'})")
        return 0
    if not is_warm():
        print("compiling kernels (first run only) ...", flush=True)
    warm(verbose=True, jobs=args.jobs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
