"""``crfmap infer IN OUT``: refine a grid with loopy belief propagation."""
from __future__ import annotations

import argparse

from crfmap.errors import InputError
from crfmap.commands.build import add_map_output_options, save_map_output


def add_parser(sub):
    p = sub.add_parser(
        "infer",
        help="run LBP on a grid (map_server YAML or .npy) and write the beliefs",
        description="Run loopy belief propagation on an occupancy grid's CRF and write P(occupied). "
        "Tables are 'oo,oe,eo,ee' (rows: cell occupied/empty; columns: neighbour occupied/empty).",
    )
    p.add_argument("input", help="map_server YAML or .npy grid of P(occupied)")
    p.add_argument("output", help="map_server YAML (trinary by default, see --mode) or .npy (exact P)")
    p.add_argument("--preset", default="certainty", choices=["certainty", "thesis"],
                   help="certainty (default): recommended for real maps; each cell's link strength follows its "
                   "evidence (a map file's P read back as net hits), coupling below critical, LBP only within 5 "
                   "cells of an observation (better scan-split scores on every real recording; see crfmap "
                   "evaluate). thesis: the thesis's tables [[10,1],[1,10]] and identity link over the whole "
                   "grid, for the reproduction (ordered phase: erases thin walls, fills unseen space)")
    p.add_argument("--hidden", default=None, help="hidden pairwise table oo,oe,eo,ee (default: the thesis's "
                   "10,1,1,10; giving --hidden or --link runs these tables instead of the certainty preset)")
    p.add_argument("--link", default=None, help="link table oo,oe,eo,ee (default 1,0,0,1)")
    p.add_argument("--schedule", default="checkerboard", choices=["checkerboard", "flooding", "sweep", "thesis"])
    p.add_argument("--max-iter", type=int, default=1000, help="iteration limit (the thesis used 2)")
    p.add_argument("--tol", type=float, default=1e-5, help="stop when the largest message change is below this")
    p.add_argument("--damping", type=float, default=0.0, help="weight of the old message, in [0, 1)")
    p.add_argument("--pairing", default="receiver", choices=["receiver", "oriented"],
                   help="how a non-symmetric hidden table applies to an edge (see crfmap.crf.potentials)")
    p.add_argument("--float32", action="store_true", help="compute in float32 (faster, less memory)")
    p.add_argument("--margin", type=int, default=None, metavar="CELLS",
                   help="infer only cells within CELLS of an observed cell; the rest stay unknown "
                   "(default: the whole grid, as the thesis; see crfmap.crf.lbp.near_known)")
    p.add_argument("--free-thresh", type=float, default=None,
                   help="override a YAML input's free_thresh when loading (Humble's map_saver writes 0.25, "
                   "which turns unknown grey 205 into free; 0.196 keeps it unknown)")
    p.add_argument("--occupied-thresh", type=float, default=None, help="override a YAML input's occupied_thresh")
    add_map_output_options(p)  # --mode, --save-occupied-thresh, --save-free-thresh, --loader
    p.add_argument("--force", action="store_true", help="allow OUT to replace IN (an in-place update)")
    return p


def _check_options(args, hidden, link):
    """Options that cannot work, refused before any work is done."""
    import math

    import numpy as np

    from crfmap.checks import check_int, check_number
    from crfmap.commands.outputs import check_output

    if not str(args.output).lower().endswith((".yaml", ".yml")) and args.mode is not None:
        raise InputError("--mode", f"applies to map_server YAML outputs only, not to {args.output}")
    check_number("--tol", args.tol, low=0.0)
    check_number("--damping", args.damping, low=0.0, high=1.0)
    if args.damping == 1.0:
        raise InputError("--damping", "must be below 1 (1 would never update a message)")
    if args.margin is not None:
        check_int("--margin", args.margin, low=0)
    for flag, value in (("--free-thresh", args.free_thresh), ("--occupied-thresh", args.occupied_thresh)):
        if value is not None:
            check_number(flag, value, low=0.0, high=1.0)
    if args.float32:  # every entry must survive float32, or the kernels would see inf or 0
        info = np.finfo(np.float32)
        for flag, table in (("--hidden", hidden), ("--link", link)):
            values = np.asarray(table, np.float64)
            positive = values[values > 0]
            if positive.size and (positive.max() > info.max / 16 or positive.min() < info.tiny):
                raise InputError(flag, f"entries {values.ravel().tolist()} do not fit float32 "
                                       f"({info.tiny:.1e} .. {info.max / 16:.1e}); rescale the table or drop --float32")
            if not math.isfinite(float(values.max())):
                raise InputError(flag, "entries must be finite")
    check_output([args.input], args.output, force=args.force)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from crfmap.crf.lbp import infer
    from crfmap.io.grid_files import load_grid
    from crfmap.crf.potentials import check_table

    if args.max_iter < 0:
        raise InputError("--max-iter", f"must be non-negative, got {args.max_iter}")
    hidden = check_table(args.hidden or "10,1,1,10", "--hidden")
    link = check_table(args.link or "1,0,0,1", "--link")
    _check_options(args, hidden, link)
    scaled = args.preset == "certainty" and args.hidden is None and args.link is None
    grid = load_grid(args.input, free_thresh=args.free_thresh, occupied_thresh=args.occupied_thresh,
                     loader=args.loader)
    region = None
    if scaled:  # the certainty preset: per-cell link strengths from P, near observations only
        from dataclasses import replace

        from crfmap.crf.presets import get_preset

        preset = get_preset("certainty")
        if args.margin is not None:
            preset = replace(preset, margin=args.margin)
        result = preset.refine(grid, schedule=args.schedule, max_iter=args.max_iter, tol=args.tol,
                               damping=args.damping, dtype=np.float32 if args.float32 else np.float64)
    elif args.margin is not None:
        from crfmap.crf.lbp import near_known

        region = near_known(grid, args.margin)
    if not scaled:
        result = infer(grid, hidden, link, schedule=args.schedule, max_iter=args.max_iter, tol=args.tol,
                       damping=args.damping, pairing=args.pairing, region=region,
                       dtype=np.float32 if args.float32 else np.float64)
    if region is not None:  # outside the region nothing was inferred: keep the input there
        beliefs = np.where(region, result.beliefs.probability, grid.probability)
        result.beliefs = result.beliefs.with_probability(beliefs)
    nav2_view = save_map_output(result.beliefs, args.output, args)
    print(f"{args.input}: {grid.width}x{grid.height} cells, {result.summary()}, "
          f"{result.seconds:.3f} s -> {args.output}: {nav2_view}")
    return 0
