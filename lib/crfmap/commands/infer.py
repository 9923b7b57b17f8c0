"""``crfmap infer IN OUT``: refine a grid with loopy belief propagation."""
from __future__ import annotations

import argparse
import warnings
import sys
from dataclasses import replace

import numpy as np

from crfmap.commands.build import add_map_output_options, save_map_output
from crfmap.crf.inference.schedules import SETTINGS
from crfmap.crf.presets import DEFAULT_PRESET, PRESETS, custom_preset, get_preset
from crfmap.errors import InputError
from crfmap.checks import check_int, check_number
from crfmap.crf.model.potentials import check_table
from crfmap.io.map_server import FREE_THRESH_DEFAULT
from crfmap.crf.engine import progress
from crfmap.crf.inference.compiling import compile_timer


def add_parser(sub):
    p = sub.add_parser(
        "infer",
        help="run LBP on a grid (map_server YAML or .npy) and write the beliefs",
        description="Run loopy belief propagation on an occupancy grid's CRF and write P(occupied). "
        "Tables are 'oo,oe,eo,ee' (rows: cell occupied/empty; columns: neighbour occupied/empty).",
    )
    p.add_argument("input", help="map_server YAML or .npy grid of P(occupied)")
    p.add_argument("output", help="map_server YAML (trinary by default, see --mode) or .npy (exact P)")
    p.add_argument("--preset", default=None, choices=list(PRESETS), metavar="{" + ",".join(PRESETS) + "}",
                   help=f"the CRF's configuration, model and solver (crfmap.crf.presets; default {DEFAULT_PRESET}). "
                   + "; ".join(f"{p.name}: {p.purpose}" for p in PRESETS.values()))
    p.add_argument("--hidden", default=None, help="hidden pairwise table oo,oe,eo,ee: giving --hidden or --link "
                   "makes a custom preset of these tables instead of --preset (default 10,1,1,10, the thesis's)")
    p.add_argument("--link", default=None, help="link table oo,oe,eo,ee of a custom preset (default 1,0,0,1)")
    p.add_argument("--schedule", default=None, choices=list(SETTINGS),
                   help="message schedule (crfmap.crf.inference.schedules; default: the preset's)")
    p.add_argument("--max-iter", type=int, default=None,
                   help="iteration limit (default: the preset's; the thesis used 2)")
    p.add_argument("--tol", type=float, default=None,
                   help="stop when the largest message change is below this (default: the preset's); --tol 0 "
                   "runs all --max-iter iterations (Ctrl-C stops the run and writes nothing)")
    p.add_argument("--progress", action="store_true", default=None,
                   help="show LBP's iterations and its largest message change (default: when stderr is a terminal)")
    p.add_argument("--damping", type=float, default=0.0, help="weight of the old message, in [0, 1)")
    p.add_argument("--pairing", default=None, choices=["receiver", "oriented"],
                   help="custom --hidden tables only: how a non-symmetric hidden table applies to an edge "
                   "(default receiver; see crfmap.crf.model.potentials)")
    p.add_argument("--float32", action="store_true", help="compute in float32 (faster, less memory)")
    p.add_argument("--margin", type=int, default=None, metavar="CELLS",
                   help="infer only cells within CELLS of an observed cell; the rest stay unknown (default: the "
                   "preset's: " + ", ".join(f"{p.name} {'the whole grid' if p.margin is None else p.margin}"
                                            for p in PRESETS.values()) + "; custom tables the whole grid)")
    p.add_argument("--free-thresh", type=float, default=None,
                   help="override a YAML input's free_thresh when loading. Default: the file's, except where it "
                   "would read unknown cells as free (Humble's 0.25): then 0.196, with a warning")
    p.add_argument("--occupied-thresh", type=float, default=None, help="override a YAML input's occupied_thresh")
    add_map_output_options(p)  # --mode, --save-occupied-thresh, --save-free-thresh, --loader
    p.add_argument("--force", action="store_true", help="allow OUT to replace IN (an in-place update)")
    return p


def _check_options(args, hidden, link):
    """Options that cannot work, refused before any work is done."""

    from crfmap.commands.outputs import check_grid_output, check_output

    check_grid_output(args.output)
    if not str(args.output).lower().endswith((".yaml", ".yml")) and args.mode is not None:
        raise InputError("--mode", f"applies to map_server YAML outputs only, not to {args.output}")
    if args.tol is not None:
        check_number("--tol", args.tol, low=0.0)
    check_number("--damping", args.damping, low=0.0, high=1.0)
    if args.damping == 1.0:
        raise InputError("--damping", "must be below 1 (1 would never update a message)")
    if args.margin is not None:
        check_int("--margin", args.margin, low=0)
    for flag, value in (("--free-thresh", args.free_thresh), ("--occupied-thresh", args.occupied_thresh)):
        if value is not None:
            check_number(flag, value, low=0.0, high=1.0)
    if args.float32:  # every entry must survive float32, or the kernels would see inf or 0 (infer's own rule)
        from crfmap.crf.model.potentials import check_table_fits

        for flag, table in (("--hidden", hidden), ("--link", link)):
            check_table_fits(table, np.float32, flag)
    check_output([args.input], args.output, force=args.force)


def _preset(args):
    """The preset the options ask for: --hidden/--link make a custom one, else --preset (default DEFAULT_PRESET)."""
    if args.hidden is not None or args.link is not None:
        if args.preset is not None:
            raise InputError("--preset", "--hidden/--link make a custom preset of their own: give them or --preset")
        hidden = check_table(args.hidden or "10,1,1,10", "--hidden")
        link = check_table(args.link or "1,0,0,1", "--link")
        _check_options(args, hidden, link)
        return custom_preset(hidden, link, args.pairing or "receiver", margin=args.margin)
    name = DEFAULT_PRESET if args.preset is None else args.preset
    if args.pairing is not None:
        raise InputError("--pairing", f"applies to custom --hidden/--link tables only, not to the {name} preset")
    try:
        preset = get_preset(name)
    except InputError as e:
        raise InputError("--preset", e.problem) from None
    _check_options(args, preset.hidden, preset.link)
    return preset if args.margin is None else replace(preset, margin=args.margin)


def load_input(args):
    """The input grid. A map YAML whose free_thresh reads unknown cells as free (Humble's 0.25 reads its own grey 205
    so) is read with 0.196 unless ``--free-thresh`` is given, with one warning: refined and written, every unexplored
    cell would be free for good."""
    from crfmap.io.grid_files import load_grid

    def load(free_thresh):
        return load_grid(args.input, free_thresh=free_thresh, occupied_thresh=args.occupied_thresh,
                         loader=args.loader)

    grid = load(args.free_thresh)
    file_free = grid.meta.get("free_thresh")
    if args.free_thresh is not None or file_free is None or not file_free > FREE_THRESH_DEFAULT:
        return grid
    if args.occupied_thresh is not None and args.occupied_thresh <= FREE_THRESH_DEFAULT:
        return grid  # the override cannot lie below 0.196: the file's reading it is
    kept = load(FREE_THRESH_DEFAULT)
    unknown_file, unknown_kept = int((grid.to_int8() == -1).sum()), int((kept.to_int8() == -1).sum())
    if unknown_kept == unknown_file:
        return grid  # no cell between the two thresholds: both readings agree
    warnings.warn(f"{args.input}: free_thresh {file_free:g} would read {unknown_kept - unknown_file} unknown cells "
                  f"as free (as nav2 loads this file); kept unknown (read with free_thresh {FREE_THRESH_DEFAULT:g}); "
                  f"--free-thresh {file_free:g} gives nav2's reading", UserWarning, stacklevel=2)
    return kept


def kernel_time(kernels, compiling) -> str:
    """What the numba kernels cost apart from the work: compiling (a first run) or loading them from the cache.

    >>> kernel_time(33.1, 32.9), kernel_time(0.21, 0.0), kernel_time(0.001, 0.0)
    (' (+ 33.1 s compiling kernels, first run only)', ' (+ 0.21 s loading compiled kernels)', '')
    """
    if compiling > 0:
        return f" (+ {kernels:.1f} s compiling kernels, first run only)"
    return f" (+ {kernels:.2f} s loading compiled kernels)" if kernels >= 0.005 else ""


def run(args: argparse.Namespace) -> int:
    if args.max_iter is not None and args.max_iter < 0:
        raise InputError("--max-iter", f"must be non-negative, got {args.max_iter}")
    preset = _preset(args)
    solver = preset.solver()  # the preset's solver, each option the user gave replacing its setting
    schedule = SETTINGS[args.schedule or solver["schedule"]](damping=args.damping)
    grid = load_input(args)
    max_iter = solver["max_iter"] if args.max_iter is None else args.max_iter
    bar, on_pass = progress.bar(max_iter, desc=f"LBP on {args.input}", disable=not (args.progress or sys.stderr.isatty()))
    try:  # a bar of the iterations; Ctrl-C between two passes ends the run (the command line says nothing was written)
        with compile_timer() as kernels, compile_timer(loading=False) as compiling, progress.watch(on_pass):
            result = preset.refine(grid, schedule=schedule, max_iter=max_iter,
                                   tol=solver["tol"] if args.tol is None else args.tol,
                                   dtype=np.float32 if args.float32 else np.dtype(solver["dtype"]).type)
    finally:
        bar.close()
    # a map for nav2 gets the gate's decision; a .npy the probabilities (the beliefs)
    out = result.nav2_map if str(args.output).lower().endswith((".yaml", ".yml")) else result.beliefs
    nav2_view = save_map_output(out, args.output, args)
    print(f"{args.input}: {grid.width}x{grid.height} cells, {result.summary()}, LBP {result.seconds:.3f} s"
          f"{kernel_time(kernels.seconds, compiling.seconds)} -> {args.output}: {nav2_view}")
    return 0
