"""Why the thesis's occlusion result does not reproduce (notebook 05): four causes varied one at a time.

On the occlusion TRAIN room, with everything else fixed, :func:`why_study` varies

1. the **schedule** and the corner the thesis's breadth-first pass starts from (2 iterations each),
2. the **number of iterations** (1 .. 1000) of three schedules,
3. the **sensing**: more beams, more turns, every reachable cell visited,
4. the **coupling** a of a symmetric hidden table [[a, 1], [1, a]] (converged LBP),

and scores each grid with :func:`why_row`: MSE over all cells, precision and recall over the cells the
scan saw (the same cells in every row), and "walls kept", the fraction of the seen wall cells that stay
above 0.5. :func:`schedule_rows`, :func:`sensing_rows` and :func:`iterations_figure` lay the result out.
"""
from __future__ import annotations

import numpy as np

from crfmap.assess.metrics import evaluate
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.schedules import Thesis
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK
from crfmap.errors import InputError
from crfmap.grid import UNKNOWN

SCHEDULES = ("thesis", "sweep", "flooding", "checkerboard")
CORNERS = ("lower-left", "lower-right", "upper-left", "upper-right")  # the thesis's pass starts at one of them
ITERATION_COUNTS = (1, 2, 3, 5, 10, 20, 50, 1000)
ITERATION_SCHEDULES = (("checkerboard", "lower-left"), ("thesis", "lower-left"), ("thesis", "upper-left"))
COUPLINGS = (1.5, 2.0, 3.0, 5.0, 10.0)  # a of the hidden [[a, 1], [1, a]]; 10 = the default
THESIS_TABLE15_DEFAULT = {"mse": 0.0623, "precision": 1, "recall": 0.5}  # its 2-iteration LBP, default tables


def _key(schedule, corner):
    return f"{schedule}_{corner}".replace("-", "_")


def _label(key):
    return key.replace("_", " ", 1).replace("_", "-")


def _run(observed, schedule, corner, max_iter, hidden=DEFAULT_HIDDEN):
    return infer(observed, hidden, DEFAULT_LINK, schedule=Thesis(corner) if schedule == "thesis" else schedule,
                 max_iter=max_iter, threads=1)


def why_row(grid, truth, seen) -> dict:
    """MSE over all cells; precision, recall over the cells the scan saw; seen walls kept (P > 0.5)."""
    on_seen = evaluate(grid, truth, seen)
    walls_seen = seen & (truth.probability > 0.5)
    return {"mse": evaluate(grid, truth).mse, "precision_seen": on_seen.precision,
            "recall_seen": on_seen.recall, "walls_kept": float((grid.probability[walls_seen] > 0.5).mean())}


def sensing_row(grid, truth) -> dict:
    """A grid scanned some other way: its unknown share, the median P on its seen walls, MSE before and after
    converged LBP with the default tables, and the seen walls that LBP keeps."""
    ws = (grid.probability != UNKNOWN) & (truth.probability > 0.5)
    after = infer(grid, DEFAULT_HIDDEN, DEFAULT_LINK, threads=1).beliefs
    return {"unknown_fraction": float(np.mean(grid.probability == UNKNOWN)),
            "median_p_on_seen_walls": float(np.median(grid.probability[ws])),
            "mse_before": evaluate(grid, truth).mse, "mse_after": evaluate(after, truth).mse,
            "walls_kept": float((after.probability[ws] > 0.5).mean())}


def why_study(observed, truth, sensed=None, iteration_counts=ITERATION_COUNTS, couplings=COUPLINGS) -> dict:
    """The four studies on ``observed`` (the scan of the room whose truth is ``truth``).

    ``sensed``: name -> grid of the same room scanned another way (the sensing study; empty if None).
    Returns a dict: "before", the seen wall cells' evidence, "schedules", "iterations", "sensing", "coupling".
    """
    if observed.shape != truth.shape:
        raise InputError("observed", f"shape {observed.shape} differs from the truth's {truth.shape}")
    seen = observed.probability != UNKNOWN
    walls_seen = seen & (truth.probability > 0.5)
    if not walls_seen.any():
        raise InputError("observed", "the scan saw no wall cell of the truth: nothing to keep or erase")
    values, counts = np.unique(observed.probability[walls_seen].round(3), return_counts=True)
    why = {"before": why_row(observed, truth, seen), "seen_wall_cells": int(walls_seen.sum()),
           "seen_walls_at_p075_fraction": float(counts[values == 0.75].sum() / counts.sum()),
           "seen_walls_below_0.5": int(counts[values < 0.5].sum())}
    why["schedules"] = {}  # (1) schedule and start corner, 2 iterations each
    for schedule in SCHEDULES:
        for corner in CORNERS if schedule == "thesis" else ("lower-left",):
            why["schedules"][_key(schedule, corner)] = why_row(_run(observed, schedule, corner, 2).beliefs, truth, seen)
    why["iterations"] = {}  # (2) number of iterations
    for schedule, corner in ITERATION_SCHEDULES:
        series = why["iterations"][_key(schedule, corner)] = []
        for k in iteration_counts:
            r = _run(observed, schedule, corner, k)
            series.append(dict(why_row(r.beliefs, truth, seen), iterations=r.iterations, converged=r.converged))
    why["sensing"] = {name: sensing_row(grid, truth) for name, grid in (sensed or {}).items()}  # (3)
    why["coupling"] = {}  # (4) coupling strength, converged
    for a in couplings:
        r = infer(observed, [[a, 1.0], [1.0, a]], DEFAULT_LINK, threads=1)
        why["coupling"][f"a_{a:g}".replace(".", "_")] = dict(why_row(r.beliefs, truth, seen), converged=r.converged,
                                                             ising_coupling=float(np.log(a) / 2))
    return why


def schedule_rows(why) -> list:
    """Rows: before LBP, 2 iterations of each schedule / corner, converged with each coupling, the thesis."""
    rows = [["before LBP", "", why["before"]["mse"], why["before"]["precision_seen"], why["before"]["recall_seen"]]]
    rows += [["2 iterations", _label(k), v["mse"], v["precision_seen"], v["recall_seen"]]
             for k, v in why["schedules"].items()]
    rows += [["converged, hidden [[a, 1], [1, a]]", f"a = {k[2:].replace('_', '.')}", v["mse"], v["precision_seen"],
              v["recall_seen"]] for k, v in why["coupling"].items()]
    t = THESIS_TABLE15_DEFAULT
    rows += [["thesis Table 15 (2 iterations, its corner)", "", t["mse"], t["precision"], t["recall"]]]
    return rows


def sensing_rows(why) -> list:
    """Rows: scan, unknown cells, median P on seen walls, MSE before and after LBP, seen walls kept."""
    return [[k.replace("_", " "), v["unknown_fraction"], v["median_p_on_seen_walls"], v["mse_before"], v["mse_after"],
             v["walls_kept"]] for k, v in why["sensing"].items()]


def iterations_figure(why):
    """MSE and seen walls kept against LBP iterations, one line per schedule, the grid before LBP dashed."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4), layout="constrained")
    for key, series in why["iterations"].items():
        its = [s["iterations"] for s in series]
        axes[0].plot(its, [s["mse"] for s in series], marker="o", label=_label(key))
        axes[1].plot(its, [s["walls_kept"] for s in series], marker="o", label=_label(key))
    for ax, what, before in ((axes[0], "MSE (all cells)", why["before"]["mse"]),
                             (axes[1], "seen walls kept (P > 0.5)", why["before"]["walls_kept"])):
        ax.axhline(before, color="0.5", ls="--", label="before LBP")
        ax.set_xscale("log")
        ax.set_xlabel("LBP iterations")
        ax.set_ylabel(what)
        ax.legend(fontsize="small")
    axes[0].set_title("MSE against iterations (default tables)")
    axes[1].set_title("walls kept against iterations")
    return fig
