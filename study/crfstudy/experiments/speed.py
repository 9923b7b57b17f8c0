"""Notebook 09's benchmark run, figures and tables, from the records of :func:`crfstudy.bench.suite.run`.

- :func:`measure`: the benchmark run (the grid sizes, the reproduction's lighter settings or the quick ones), and
  :func:`settings_text`, what the captions say about those settings against ``make bench``'s full sweep.
- :func:`throughput_figure`, :func:`converge_figure`, :func:`goals_figure`: the figures (each returns a Figure).
- :func:`throughput_rows`, :func:`external_rows`, :func:`goals_rows`: the tables' rows; :func:`speed_caption`
  the speed table's caption, :func:`converge_lines` the convergence runs as text, :func:`slowest_cells` where the
  previous reproduction's time went.

Each function takes the records (dicts with a ``"method"``); :func:`pick` selects records.

>>> records = [{"method": "crfmap-fast", "size": 256, "threads": 1, "mcells_per_second": 10.0},
...            {"method": "crfmap-fast", "size": 256, "threads": 2, "mcells_per_second": 18.0}]
>>> [r["threads"] for r in pick(records, "crfmap-fast", threads=2)]
[2]
"""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from crfstudy import paths
from crfstudy.bench import goals
from crfstudy.bench import suite as bench
from crfstudy.repro.timings import slowest_cells_table

THROUGHPUT_SIZES = (512, 2048)  # grids the throughput table reports, besides the smallest and the largest
CONVERGE_SERIES = (("crfmap-converge", "fast, frozen tiles (default)", "C1-s"),  # (method, label, style)
                   ("crfmap-converge-exact", "fast, every cell (freeze=0)", "C0-o"),
                   ("crfmap-converge-plain", "plain reference kernel", "k-^"))


def benchmark_sizes(sizes, quick: bool) -> list:
    """The grid sides to time: the quick ones, else ``sizes`` (None: the full sweep of ``make bench``)."""
    return list(bench.QUICK_SIZES if quick else sizes or bench.SIZES)


def measure(sizes, threads, quick: bool, **settings) -> list:
    """Every record of one benchmark run (:func:`crfstudy.bench.suite.run`, online mapping and memory included,
    with a progress bar) on grids of ``sizes`` with ``threads``; ``settings``: the lighter settings of the
    reproduction (``repeats``, ``work``, ...), ignored when ``quick`` (the quick ones then)."""
    return list(bench.run(sizes=sizes, quick=quick, threads=tuple(threads), progress=True, online=True, memory=True,
                          **({} if quick else settings)))


def settings_text(quick: bool, sizes, repeats, work, converge_runs, external_max_size, explorer_changes, online_tol,
                  bandwidth_mbytes, cold, peers, preset_maps, converge_start_size) -> str:
    """What the captions say about this run's settings against ``make bench``'s full sweep."""
    if quick:
        return "quick settings (tests and CI)"
    return (f"reproduction settings, lighter than `make bench`: grids up to {max(sizes)}^2, medians of {repeats} "
            f"repeats of {work:.0e} cell updates, best of {converge_runs} convergence run(s), PGMax / PyMaxflow "
            f"up to {external_max_size}^2, {explorer_changes} explorer changes, online final maps to {online_tol:g}, "
            f"bandwidth triad on {bandwidth_mbytes} MB arrays"
            + ("" if cold else ", no empty-cache compilation (`make bench` times it)")
            + ("" if peers else ", no published-peer or ROS node rows")
            + f", the default preset's convergence on {', '.join(preset_maps)} only, the thesis table's on "
            f"{converge_start_size}^2")


def _by_size(records):
    return sorted(records, key=lambda r: r["size"])


def _log_log(ax, ylabel, title):
    # both of notebook 09's size sweeps span orders of magnitude in cells and in the measure
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("cells")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)


def throughput_figure(records, series, bound: float, top: int):
    """Mcell/s against grid cells for each of ``series`` ((method, match, label, style)), with the float32
    one-pass ``bound`` of ``top`` threads dashed."""
    fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
    for method, match, label, style in series:
        rs = _by_size(pick(records, method, **match))
        ax.plot([r["size"] ** 2 for r in rs], [r["mcells_per_second"] for r in rs], style, label=label)
    ax.axhline(bound, color="k", ls="--", lw=1, label=f"one-pass bound, {top} threads ({bound:.0f})")
    _log_log(ax, "million cell-updates per second", "One checkerboard LBP iteration")
    return fig


def converge_figure(records):
    """Seconds to converge against grid cells, for each kind of run of :data:`CONVERGE_SERIES` measured."""
    fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
    for method, label, style in CONVERGE_SERIES:
        rs = _by_size(pick(records, method))
        if rs:
            ax.plot([r["size"] ** 2 for r in rs], [r["seconds_to_converge"] for r in rs], style, label=label)
    _log_log(ax, "seconds to converge (max change < 1e-4)", "Time to converge, noisy office floors")
    return fig


def converge_lines(records) -> str:
    """One line per convergence run, by size: iterations, seconds, largest belief difference to the exact run."""
    runs = [r for method, _, _ in CONVERGE_SERIES for r in pick(records, method)]
    return "\n".join(f"{r['size']:5d}^2 {r['method']:<22} {r['iterations']:4d} iterations "
                     f"{r['seconds_to_converge']:.3f} s  max belief difference vs exact "
                     f"{r['max_belief_difference_vs_exact']:.1e}"
                     for r in sorted(runs, key=lambda r: (r["size"], r["method"])))


def speed_caption(sizes, top: int, bandwidth: dict, bound: float, settings: str) -> str:
    """The speed table's caption: the machine (CPU, ``top`` threads, its ``bandwidth`` record), the one-pass
    ``bound``, whether the sweep was reduced, and this run's ``settings`` (:func:`settings_text`)."""
    caption = (f"Speed of crfmap on this machine ({bench._cpu_name()}, {top} threads, measured bandwidth "
               f"{bandwidth['gbytes_per_second']:.1f} GB/s, one-pass bound {bound:.0f} Mcell/s in float32). "
               "The thesis did not time LBP (it ran 2 iterations).")
    if max(sizes) < max(bench.SIZES):
        caption += f" Reduced sweep (grids up to {max(sizes)}^2); the full sweep to {max(bench.SIZES)}^2 is `make bench`."
    return caption + f" This run: {settings}."


def slowest_cells(n: int = 5) -> str:
    """The ``n`` slowest code cells of each notebook of the last ``make reproduce`` run (a Markdown table)."""
    return slowest_cells_table(paths.OUT / "notebooks", n=n)


def pick(records, method, **match) -> list:
    """The records of ``method`` whose fields equal ``match``."""
    return [r for r in records if r["method"] == method and all(r.get(k) == v for k, v in match.items())]


def external_rows(records) -> list:
    """Rows of PGMax's LBP and PyMaxflow's graph cut against crfmap (float32, 1 thread), or their notes."""
    fast_1 = {r["size"]: r["mcells_per_second"] for r in pick(records, "crfmap-fast", dtype="float32", threads=1)}
    rows = []
    for r in (r for r in records if r["method"].startswith(("pgmax", "pymaxflow"))):
        if r["method"] == "pgmax-bp" and r.get("mcells_per_second"):
            rows.append([f"PGMax {r.get('version', '')} LBP (flooding)", f"{r['size']}^2",
                         round(r["mcells_per_second"], 2),
                         round(r["mcells_per_second"] / fast_1[r["size"]], 4) if r["size"] in fast_1 else None, None,
                         f"max belief difference {r['max_belief_difference']:.1e} (crfmap float32 vs float64: "
                         f"{r['crfmap_float32_vs_float64']:.1e})", ""])
        elif r["method"] == "pymaxflow-map" and r.get("seconds") is not None:
            rows.append([f"PyMaxflow {r.get('version', '')} graph-cut MAP, {r['grid']} grid", f"{r['size']}^2", None,
                         None, round(r["seconds"], 3), f"{100 * r['agreement_with_lbp']:.1f} % of cells as LBP's "
                         f"labels; energy {r['energy_map']:.4g} (MAP) vs {r['energy_lbp_labels']:.4g} (LBP labels)",
                         ""])
        elif r.get("note"):
            rows.append([r["method"], f"{r['size']}^2" if r.get("size") else "", None, None, None, None, r["note"]])
    return rows


def _start_rows(records, start_goal) -> list:
    cold = {m: pick(records, m)[0] for m in ("start-cold", "start-warm", "start-env") if pick(records, m)}
    rows = []
    if cold.get("start-cold", {}).get("seconds") is not None:
        first = cold["start-cold"]
        rows.append(["crfmap infer, first call with an empty cache [s]", "512^2", round(first["seconds"], 1),
                     f"<= {first['goal_seconds']:g}" if first.get("goal_seconds") else ""])
        rows.append(["crfmap infer: empty cache minus warm [s]", "512^2", round(first["minus_warm_seconds"], 1),
                     "(compiling)"])
    elif "start-cold" in cold:
        rows.append(["crfmap infer, first call with an empty cache [s]", "512^2", None, "not timed here: `make bench`"])
    if "start-env" in cold:
        rows.append(["crfmap infer: environment's cache minus warm [s]", "512^2",
                     round(cold["start-env"]["minus_warm_seconds"], 1), f"<= {start_goal:g}"])
    return rows


def _explorer_and_reproduce_rows(records) -> list:
    rows = []
    for r in pick(records, "explorer-redraw"):
        rows.append([f"explorer redraw, median of {r['changes']} changes, LBP on {r['threads']} thread [s]", "",
                     round(r["seconds"], 3), f"<= {r['goal_seconds']:g}"])
        rows.append(["explorer: a new figure per change (as before) / in place", "",
                     round(r["full_redraw_seconds"] / r["seconds"], 1), ""])
    for r in pick(records, "explorer-scene-change"):
        rows.append(["explorer scene change [s]", "", round(r["seconds"], 3), ""])
    for r in pick(records, "reproduce"):
        what = ("wall clock incl. venv and warm-up" if r.get("workflow_seconds") and "venv" in r["note"] else
                "workflow wall clock" if r.get("workflow_seconds") else "notebooks summed")
        rows.append([f"make reproduce, previous run, {what} [s]" + (" (quick)" if r.get("record_quick") else ""), "",
                     None if r["seconds"] is None else round(r["seconds"], 0), f"<= {r['goal_seconds']:g}"])
    return rows


def goals_rows(records, start_goal=goals.START_GOAL) -> list:
    """Rows (measurement, grid, value, goal) of what users wait for (:mod:`crfstudy.bench.goals`' records);
    ``start_goal``: the goal of the environment's first call minus a warm one [s]."""
    rows = []
    for r in sorted(pick(records, "infer-vs-kernel"), key=lambda r: r["size"]):
        rows.append([f"infer() end to end / kernel, float32, {r['threads']} threads, {r['iterations_per_call']} it. "
                     "per call", f"{r['size']}^2", round(r["ratio"], 2), f">= {r['goal']:g}"])
    for r in pick(records, "kernel-vs-bound"):
        if r["goal_ratio"] is not None and r["ratio_to_bound"] is not None:
            rows.append([f"kernel / one-pass bandwidth bound, float32, {r['threads']} threads", f"{r['size']}^2",
                         round(r["ratio_to_bound"], 2), f">= {r['goal_ratio']:g}"])
        if r["goal_mcells_per_second"] is not None:
            rows.append([f"kernel, float32, {r['threads']} thread [Mcell/s]", f"{r['size']}^2",
                         round(r["kernel_mcells_per_second"]), f">= {r['goal_mcells_per_second']:g}"])
        ceiling = r.get("division_ceiling_mcells_per_second")
        if ceiling and (r["goal_ratio"] is not None or r["goal_mcells_per_second"] is not None):
            threads = f"{r['threads']} thread" + ("s" if r["threads"] > 1 else "")
            rows.append([f"division ceiling, float32, {threads}: the kernel's rate if it only did its 4 divisions "
                         "a cell [Mcell/s]", f"{r['size']}^2", round(ceiling), "(information)"])
    rows += _start_rows(records, start_goal) + _explorer_and_reproduce_rows(records)
    for r in pick(records, "converge-start"):
        if r["seconds_to_converge"] is not None:
            rows.append([f"converge, {r['start']} start, {r['iterations']} it., {r['threads']} threads, best of "
                         f"{r['runs']} [s]", f"{r['size']}^2", round(r["seconds_to_converge"], 3),
                         "(information: the thesis's table)"])
            rows.append([f"converge, {r['start']} start: first run in the process (fresh buffers) [s]",
                         f"{r['size']}^2", round(r["first_run_seconds"], 3), ""])
        else:
            rows.append([f"converge, {r['start']} start", f"{r['size']}^2", None, r["note"]])
    for r in pick(records, "preset-converge"):
        if r.get("seconds") is None:
            rows.append([f"default preset to convergence, {r['map']}", "", None, r["note"]])
            continue
        shape = "x".join(str(n) for n in r["shape"])
        rows.append([f"default preset ({r['preset']}) to convergence, {r['map']}, {r['iterations']} it., "
                     f"{r.get('dtype', 'float64')} [s]", shape, round(r["seconds"], 3),
                     f"<= {r['goal_seconds']:.3g} (5 NumPy-baseline it.)"])
    return rows


def throughput_rows(records, series, smallest, bound) -> list:
    """Rows of the speed table: each series' Mcell/s at the smallest, 512², 2048² and the largest grid (x the
    NumPy baseline, x the one-pass ``bound``), time to converge, online mapping, peak memory.

    ``series``: (method, match, label, style) as the throughput figure draws them.
    """
    largest = max(r["size"] for r in pick(records, "crfmap-fast"))
    base = {r["size"]: r["mcells_per_second"] for r in pick(records, "numpy-baseline")}
    rows = []
    for method, match, label, _ in series:
        for r in sorted(pick(records, method, **match), key=lambda r: r["size"]):
            if r["size"] in (smallest, *THROUGHPUT_SIZES, largest):
                rows.append([label, f"{r['size']}^2", round(r["mcells_per_second"], 1),
                             round(r["mcells_per_second"] / base[r["size"]], 1),
                             round(r["mcells_per_second"] / bound, 2), "not reported"])
    for size, r in sorted({r["size"]: r for r in pick(records, "crfmap-converge")}.items()):
        rows.append([f"time to converge (<1e-4), {r['iterations']} it.", f"{size}^2",
                     round(r["seconds_to_converge"], 3), None, None, "not reported"])
    online = {r["method"]: r for r in records if r["method"].startswith(("online", "builder"))}
    if "online-intel" in online and "ms_per_scan_median" in online["online-intel"]:
        o = online["online-intel"]
        rows.append(["online: ms per scan (median), Intel 5 cm", f"{o['size']} wide", round(o["ms_per_scan_median"], 2),
                     None, None, "not reported"])
        rows.append(["online: whole log, x real time", f"{o['scans']} scans", round(o["real_time_factor"], 0),
                     None, None, "not reported"])
    if "online-intel-margin" in online and "ms_per_scan_median" in online["online-intel-margin"]:
        o = online["online-intel-margin"]
        rows.append([f"online near observations ({o['margin_cells']} cells): ms per scan (median)",
                     f"{o['size']} wide", round(o["ms_per_scan_median"], 2), None, None, "not reported"])
    mem = pick(records, "memory")
    if mem:
        rows.append(["peak memory of infer(), bytes per cell", f"{mem[0]['size']}^2", round(mem[0]["bytes_per_cell"], 1),
                     None, None, "not reported"])
    return rows


def _end_to_end(ax, records):
    # end to end vs kernel, per size: bars in Mcell/s, ratio above each pair
    ratios = sorted(pick(records, "infer-vs-kernel"), key=lambda r: r["size"])
    x = np.arange(len(ratios))
    th = "/".join(map(str, sorted({r["threads"] for r in ratios})))
    ax.bar(x - 0.2, [r["kernel_mcells_per_second"] for r in ratios], 0.4, color="C1",
           label=f"kernel per iteration, float32, {th} threads")
    ax.bar(x + 0.2, [r["infer_mcells_per_second"] for r in ratios], 0.4, color="C5",
           label=f"infer() end to end, float32, {th} threads")
    for k, r in enumerate(ratios):
        ax.annotate(f"{r['ratio']:.2f}x", (k, max(r["kernel_mcells_per_second"], r["infer_mcells_per_second"])),
                    ha="center", va="bottom", fontsize=8)
    ax.set_xticks(x, [f"{r['size']}²" for r in ratios])
    ax.set_ylabel("million cell-updates per second")
    ax.set_title(f"infer() end to end vs its kernel (goal >= {ratios[0]['goal'] if ratios else 0.8:g}x)")
    ax.margins(y=0.3)  # room for the legend above the bars
    ax.legend(fontsize=8, loc="upper left")


def _start(ax, records, numba_threads):
    # cold vs warm start of `crfmap infer` (threads: numba's default, all cores)
    starts = [(label, pick(records, method)) for method, label in (("start-cold", "empty cache"),
                                                                     ("start-warm", "warmed cache"),
                                                                     ("start-env", "environment's cache"))]
    starts = [(label, rs[0]["seconds"]) for label, rs in starts if rs and rs[0]["seconds"] is not None]
    if not any(label == "empty cache" for label, _ in starts):
        ax.text(0.98, 0.02, "empty cache: not timed in this run (`make bench`)", transform=ax.transAxes,
                ha="right", va="bottom", fontsize=8)
    ax.barh([s[0] for s in starts], [s[1] for s in starts], color=["C3", "C2", "C0"][:len(starts)])
    for k, (_, s) in enumerate(starts):
        ax.annotate(f"{s:.1f} s", (s, k), va="center", fontsize=8)
    ax.set_xlabel(f"seconds, `crfmap infer` on a {goals.START_MAP_SIZE}² map, new process, {numba_threads} threads")
    ax.set_title("First run (compiling) vs warm start")


def _converge(ax, records, top):
    # time to converge against size, with the thesis-table rows (information; 4096², 2048² in the reproduction)
    for method, label, style in (("crfmap-converge", f"fast, frozen tiles, {top} threads", "C1-s"),
                                 ("crfmap-converge-exact", f"fast, every cell, {top} threads", "C0-o")):
        rs = sorted(pick(records, method), key=lambda r: r["size"])
        ax.plot([r["size"] ** 2 for r in rs], [r["seconds_to_converge"] for r in rs], style, label=label)
    for r in pick(records, "converge-start"):
        if r["seconds_to_converge"] is not None:
            ax.plot([r["size"] ** 2], [r["seconds_to_converge"]], "k*" if r["start"] == "uniform" else "r*",
                    markersize=10, label=f"thesis's table (information): {r['start']} start, {r['iterations']} it., "
                    f"{r['threads']} threads")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("cells")
    ax.set_ylabel("seconds to converge (max change < 1e-4)")
    ax.set_title("Convergence against size")
    ax.legend(fontsize=7)


def goals_figure(records, top: int, numba_threads: int):
    """Three panels: infer() vs its kernel, first run vs warm start, convergence against size.

    ``top``: the most threads measured; ``numba_threads``: the threads a new ``crfmap infer`` process uses.
    """
    fig, (ax_e2e, ax_start, ax_conv) = plt.subplots(1, 3, figsize=(15, 4.5), layout="constrained")
    _end_to_end(ax_e2e, records)
    _start(ax_start, records, numba_threads)
    _converge(ax_conv, records, top)
    return fig
