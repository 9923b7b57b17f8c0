"""Notebook 09's tables from ``crfmap bench`` records: throughput, independent libraries, what users wait for.

Each function takes the records of :func:`crfstudy.bench.suite.run` (dicts with a ``"method"``) and returns
table rows; :func:`pick` selects records.

>>> records = [{"method": "crfmap-fast", "size": 256, "threads": 1, "mcells_per_second": 10.0},
...            {"method": "crfmap-fast", "size": 256, "threads": 2, "mcells_per_second": 18.0}]
>>> [r["threads"] for r in pick(records, "crfmap-fast", threads=2)]
[2]
"""
from __future__ import annotations

THROUGHPUT_SIZES = (512, 2048)  # grids the throughput table reports, besides the smallest and the largest


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


def goals_rows(records, start_goal) -> list:
    """Rows (measurement, grid, value, goal) of what users wait for (:mod:`crfstudy.bench.goals`' records)."""
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
