"""``crfmap bench``: how fast LBP runs here, against a vectorised NumPy baseline (see crfstudy.bench.suite)."""
from __future__ import annotations

import argparse

import numba

from crfmap.errors import InputError


def add_parser(sub):
    p = sub.add_parser(
        "bench",
        help="measure LBP throughput, convergence time, memory and online mapping speed",
        description="Measure, in one run: the vectorised NumPy baseline, crfmap's kernels at 1 and 2 "
        "threads, the memory bandwidth and the bound it implies, time to convergence, peak memory, "
        "and online mapping on the Intel lab log (if present). Medians of repeats; the first call "
        "of each kernel (JIT compilation or cache loading) is reported apart.",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object per line")
    p.add_argument("--sizes", type=int, nargs="+", metavar="N", help="grid sides to time (default 256 .. 8192)")
    p.add_argument("--quick", action="store_true", help="small grids and few repeats (a minute or less)")
    p.add_argument("--repeats", type=int, default=None, metavar="N", help="timed repeats per measurement")
    p.add_argument("--threads", type=int, nargs="+", default=None, metavar="T",
                   help="thread counts to time (default 1 and all cores)")
    p.add_argument("--no-online", action="store_true", help="skip the Intel-log online mapping run")
    p.add_argument("--no-memory", action="store_true", help="skip the peak-memory child process")
    p.add_argument("--no-external", action="store_true", help="skip the PGMax / PyMaxflow rows (run when installed)")
    p.add_argument("--only", nargs="+", default=None, metavar="GROUP",
                   help="run only these groups of rows: machine, compile, throughput, converge, memory, online, "
                   "node, external, closed-loop, goals (e.g. --only node: the live node's rows)")
    p.add_argument("--no-goals", action="store_true",
                   help="skip issue 13's rows (start times, explorer redraw, reproduce time, 4096^2 convergence)")
    return p


def run(args: argparse.Namespace) -> int:
    from crfstudy.bench.suite import format_record, run as run_bench, to_json

    if args.sizes and any(n < 16 or n > 32768 for n in args.sizes):
        raise InputError("--sizes", f"grid sides must be between 16 and 32768 cells, got {args.sizes}")
    if args.repeats is not None and args.repeats < 1:
        raise InputError("--repeats", f"must be at least 1, got {args.repeats}")
    cores = numba.config.NUMBA_NUM_THREADS
    threads = tuple(args.threads or sorted({1, cores}))
    if any(t < 1 or t > cores for t in threads):
        raise InputError("--threads", f"thread counts must be between 1 and {cores}, got {list(threads)}")
    for rec in run_bench(sizes=args.sizes, quick=args.quick, repeats=args.repeats, threads=threads,
                         progress=True, online=not args.no_online, memory=not args.no_memory,
                         external=not args.no_external, goals=not args.no_goals, only=args.only):
        print(to_json(rec) if args.json else format_record(rec), flush=True)
    return 0
