"""Notebook 09's figure of what users wait for: infer() against its kernel, first run against warm start,
time to converge against size (from ``crfmap bench`` records, :mod:`crfstudy.experiments.speed_tables`)."""
from __future__ import annotations

import numpy as np

from crfstudy.bench import goals
from crfstudy.experiments.speed_tables import pick


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
    import matplotlib.pyplot as plt

    fig, (ax_e2e, ax_start, ax_conv) = plt.subplots(1, 3, figsize=(15, 4.5), layout="constrained")
    _end_to_end(ax_e2e, records)
    _start(ax_start, records, numba_threads)
    _converge(ax_conv, records, top)
    return fig
