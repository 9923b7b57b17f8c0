"""``crfmap evaluate RECORDING``: scan-split table of a recording (does refining make the map better?)."""
from __future__ import annotations

import argparse
import json
import sys

from crfmap.assess.baselines import BASELINES
from crfmap.assess.peers import PEERS
from crfmap.crf.presets import DEFAULT_PRESET, PRESETS, get_preset
from crfmap.errors import InputError
from crfmap.io.recordings import load_recording


def add_parser(sub):
    p = sub.add_parser(
        "evaluate",
        help="score the raw grid, baselines, a preset and published peers against scans the map never saw",
        description="Scan-split validation (crfmap.assess.scansplit): build the grid from the even scans of a "
        "CARMEN log or ROS bag, refine it, and score P(occupied) against what the odd scans observe: Brier score, "
        "log-loss, AUC and wall recall with spatial-block bootstrap intervals, and the calibration error, for the "
        "baselines, the preset and the published peers (crfmap.assess.peers). Then the navigation tables "
        "(crfmap.assess.navigation): every map as nav2 reads the trinary file crfmap infer writes, with paired "
        "intervals of the difference to the raw grid, and localisation on each map (crfmap.assess.localisation).",
    )
    p.add_argument("input", help="CARMEN log (.log / .log.gz), ROS1 .bag or ROS2 bag folder")
    p.add_argument("--resolution", type=float, default=0.05, help="cell size in metres (default 0.05)")
    p.add_argument("--max-range", type=float, default=None, metavar="M",
                   help="CARMEN logs: the laser's maximum range; readings at or beyond it are no-returns "
                        "(default: the log's PARAM robot_front_laser_max, else crfmap.io.no_return.no_return_rule)")
    p.add_argument("--preset", default=None, choices=list(PRESETS), metavar="{" + ",".join(PRESETS) + "}",
                   help=f"the preset to score, with its own solver settings (default {DEFAULT_PRESET})")
    p.add_argument("--methods", default="all", help="comma-separated rows to score (default all: "
                   + ", ".join(list(BASELINES) + ["the preset"] + list(PEERS)) + "); raw is always scored")
    p.add_argument("--parity", type=int, default=0, choices=[0, 1], help="build from even (0) or odd (1) scans")
    p.add_argument("--boot", type=int, default=200, help="bootstrap resamples (0: no intervals)")
    p.add_argument("--block", type=int, default=16, help="bootstrap block side in cells")
    p.add_argument("--seed", type=int, default=0, help="seed of the bootstrap")
    p.add_argument("--group", default="all", choices=["all", "seen", "unseen"], help="cells to tabulate")
    p.add_argument("--no-nav", dest="nav", action="store_false", help="skip the navigation metrics and tables")
    p.add_argument("--no-localisation", dest="localisation", action="store_false",
                   help="skip localisation on each map (nav2_amcl's likelihood field scored on the held-out scans)")
    p.add_argument("--json", action="store_true", help="print the full scores as one JSON object")
    return p


def run(args: argparse.Namespace) -> int:
    from crfmap.assess.calibration import split_calibration
    from crfmap.assess.comparison import compare, parse_methods, table_rows
    from crfmap.assess.scansplit import scan_split
    from tabulate import tabulate

    if args.boot < 0:
        raise InputError("--boot", f"must be non-negative, got {args.boot}")
    if args.block < 1:
        raise InputError("--block", f"must be a positive number of cells, got {args.block}")
    if not args.resolution > 0:
        raise InputError("--resolution", f"must be positive, got {args.resolution}")

    args.preset = DEFAULT_PRESET if args.preset is None else args.preset
    try:
        get_preset(args.preset)
    except InputError as e:
        raise InputError("--preset", e.problem) from None
    methods = parse_methods(args.methods, args.preset)

    progress = sys.stderr.isatty()  # a minute or more on a real log: bars where someone watches
    rec = load_recording(args.input, max_range=args.max_range)
    split = scan_split(rec.scans, args.resolution, parity=args.parity, progress=progress)
    scores = compare(split, args.preset, n_boot=args.boot, block=args.block, seed=args.seed, methods=methods,
                     keep_beliefs=True, nav=args.nav, progress=progress)
    beliefs, maps = scores.pop("_beliefs"), scores.pop("_maps")  # probabilities; the maps nav2 reads
    calibration = split_calibration(split, beliefs, group=args.group)
    scores["_ece"] = {name: c["ece"] for name, c in calibration.items()}
    if args.localisation:
        from crfmap.assess.localisation import compare_localisation

        scores["_localisation"] = compare_localisation(maps, split.resolution, split.origin, split.second_scans,
                                                       n_boot=args.boot, seed=args.seed)
    if args.json:
        print(json.dumps(_finite(scores)))
        return 0
    header = ["method", "Brier", "95% CI", "log-loss", "95% CI", "AUC", "95% CI", "wall recall", "95% CI", "ECE"]
    lbp = scores.get("_lbp")
    state = "" if lbp is None else f"; {args.preset}: {'converged' if lbp['converged'] else 'NOT converged'}"
    print(f"{args.input}: {split.shape[1]}x{split.shape[0]} cells, {args.group} cells the second half observed "
          f"({scores['raw'][args.group]['cells']}){state}")
    rows = [row + [scores["_ece"][row[0]]] for row in table_rows(scores, args.group)]
    print(tabulate(rows, header, tablefmt="github", floatfmt=".4f"))
    if "_seconds" in scores:
        print("peer wall time: " + ", ".join(f"{n} {s:.1f} s" for n, s in scores["_seconds"].items()))
    if "_nav" in scores:
        print(nav_tables(scores["_nav"], args.group), end="")
    if "_localisation" in scores:
        print(localisation_table(scores["_localisation"]), end="")
    return 0


LOCALISATION_COLUMNS = (("beats_offsets", "beats offsets %", 100, 1), ("log_margin", "log margin", 1, 3),
                        ("translation_error", "error [cm]", 100, 1), ("rotation_error", "error [deg]", 1, 2),
                        ("found", "found %", 100, 1))


def localisation_table(loc: dict) -> str:
    """AMCL's likelihood field on each map, scored on the held-out scans, with the paired interval to raw."""
    from tabulate import tabulate

    rows = []
    for name, entry in loc.items():
        row = [name]
        for metric, _, scale, digits in LOCALISATION_COLUMNS:
            value = entry[metric] * scale
            lo, hi = (v * scale for v in entry.get(metric + "_diff_ci", (float("nan"), float("nan"))))
            row.append(f"{value:.{digits}f}" + ("" if name == "raw" or lo != lo else f" {lo:+.{digits}f}..{hi:+.{digits}f}"))
        rows.append(row)
    first = next(iter(loc.values()))
    head = (f"localisation on each map (nav2_amcl's likelihood field): {first['scans']} held-out scans at their "
            "corrected poses against\n5-30 cm / 2-10 deg offsets (beats offsets, log margin); a pose search from "
            "30 cm / 10 deg off (median error, found:\nwithin 10 cm and 3 deg), each with the paired 95% interval of "
            "its difference to raw\n")
    return head + tabulate(rows, ["method"] + [t for _, t, _, _ in LOCALISATION_COLUMNS], tablefmt="github",
                           disable_numparse=True) + "\n"


NAV_COLUMNS = (("lethal_recall", "lethal recall"), ("lethal_precision", "lethal precision"),
               ("miss_rate", "dangerous misses"), ("far_miss_rate", "misses > 0.5 m"), ("ghost_rate", "ghosts"))


def _percent(entry, metric, interval=True):
    """``"70.56 +7.4..+9.3"``: the metric in percent and its paired interval to raw in percentage points."""
    value = entry[metric]
    if value != value:  # no cells to divide by (e.g. the raw grid's lethal precision in never-seen cells)
        return "-"
    lo, hi = entry.get(metric + "_diff_ci", (float("nan"), float("nan")))
    if not interval or lo != lo:  # the reference row, no intervals (--boot 0), or no resample had the cells
        return f"{100 * value:.2f}"
    return f"{100 * value:.2f} {100 * lo:+.1f}..{100 * hi:+.1f}"


def _fixed(value, digits):
    return "-" if value != value else f"{value:.{digits}f}"  # NaN: no lethal cell at all


def nav_tables(nav: dict, group: str) -> str:
    """The two navigation tables of ``compare(...)["_nav"]``, nav2's reading of ``group`` cells and the whole map's
    walls, both fitting a 120-column terminal with the project's row names."""
    from tabulate import tabulate

    header = ["method"] + [title + " %" for _, title in NAV_COLUMNS]
    rows = [[name] + [_percent(entry[group], m, interval=name != "raw") for m, _ in NAV_COLUMNS]
            for name, entry in nav.items()]  # raw: the reference of every interval
    first = (f"nav2's reading of the written trinary map, {group} cells. Recall, misses: % of the held-out occupied "
             "cells;\nprecision: % of the held-out cells called lethal; ghosts: % of the cells passed twice, never hit; "
             "each with\nthe paired 95% interval of its difference to raw [percentage points]\n")
    shape_header = ["method", "thickness [cells]", "pieces / 10 m", "lethal cells", "never-seen called free",
                    "of them occupied"]
    shape_rows = [[name, _fixed(m["thickness"], 2), _fixed(m["components_per_10m"], 1), m["lethal_cells"],
                   m["unknown_free"], m["unknown_free_occupied"]] for name, m in ((n, e["map"]) for n, e in nav.items())]
    second = ("walls of the whole map: lethal cells per cell of skeleton length, 8-connected lethal pieces; cells the "
              "first\nhalf never observed that the map calls free, and of them those the second half shows occupied\n")
    def table(head, body):
        return tabulate(body, head, tablefmt="github", disable_numparse=True) + "\n"

    return first + table(header, rows) + second + table(shape_header, shape_rows)


def _finite(value):
    """JSON-safe copy: NaN becomes null."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if isinstance(value, float) and value != value:
        return None
    return value
