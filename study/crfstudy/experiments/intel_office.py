"""Notebook 07's study machinery for the real office (the Intel Research Lab log): its figures, the bookkeeping of
the LBP runs of Fig. 43, the cross-validation of Table 26 (predictors, folds, the loop over them, the table), the
leave-one-out check, the same-cell scores, the online section's runs and table, and the numbers the paper quotes.

The notebook shows the calls that make the maps and beliefs (``build_grid``, ``infer``, ``OnlineMapper``);
what is here turns them into figures, rows and numbers. ``neighbour_mean``
(:func:`crfstudy.analysis.crossval.neighbour_mean`) is here for the notebook too.
"""
from __future__ import annotations

import time

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Circle

from crfmap.assess import evaluate
from crfmap.grid import UNKNOWN
from crfstudy.analysis.crossval import (block_folds, cross_validate, leave_one_out, lbp_predictor,
                                        neighbour_mean,  # noqa: F401 - notebook 07's gap baseline, used from here
                                        neighbour_predictor, random_folds)
from crfstudy.analysis.samecells import block_scores, fold_scores
from crfstudy.experiments.office_online import (default_table_drift, map_online, near_versus_offline, online_numbers,
                                                versus_offline)
from crfstudy.plotting import imshow_extent, plot_roc, show_grid

LBP = "LBP, to convergence"  # the predictors' names, as Table 26's rows and the paper's numbers read them
LBP_THESIS = "LBP, thesis schedule, 2 iterations"
NEIGHBOURS = "neighbour mean 3x3 (baseline)"
ALL_FREE = "all free (majority class)"
TABLE26_HEADER = ["map", "held out", "prediction", "precision", "recall", "accuracy", "AUC", "scored / held out"]
THESIS_TABLE26 = ["thesis: School of IT, partial", "'leave one out' (not defined)", "LBP, bounded, 2 iterations",
                  0.8436, 0.6229, 0.977, "n/a", "n/a"]  # the thesis's Table 26, quoted beside ours


def _mark_robot(ax, robot, radius):
    ax.plot(*robot[:2], "*", color="C1", ms=14, mec="k")
    ax.add_patch(Circle(robot[:2], radius, fill=False, ls="--", ec="C1", lw=1.2))


def map_figure(grid, title: str, path, robot=None, radius=None):
    """``grid`` with the robot's ``path`` (poses, x y first) in red; with ``robot`` (a pose), a star there and
    the circle of ``radius`` [m] round it."""
    fig, ax = plt.subplots(figsize=(8, 8), layout="constrained")
    show_grid(ax, grid, title)
    ax.plot(*np.asarray(path)[:, :2].T, color="C3", lw=0.6)
    if robot is not None:
        _mark_robot(ax, robot, radius)
    return fig


def lbp_run_numbers(before, runs: dict, results: dict) -> dict:
    """Per LBP run of Fig. 43 (``runs``: name -> the options given to ``infer``, ``results``: name -> its result):
    iterations, convergence, the cells it updated, the unknown cells it filled (of which occupied), the known
    cells of ``before`` it flipped and the occupied ones it turned free."""
    was_unknown = ~before.known()
    before_occupied = before.probability > 0.5
    numbers = {}
    for name, r in results.items():
        p = r.beliefs.probability
        numbers[name] = {"iterations": r.iterations, "converged": r.converged, "seconds": r.seconds,
                         "last_max_change": float(r.max_change[-1]),
                         "cells_updated": int(runs[name]["region"].sum()) if "region" in runs[name] else int(p.size),
                         "unknown_cells_filled": int(np.count_nonzero(was_unknown & (p != UNKNOWN))),
                         "of_which_occupied": int(np.count_nonzero(was_unknown & (p > 0.5))),
                         "known_cells_flipped": int(np.count_nonzero(~was_unknown & ((p > 0.5) != before_occupied))),
                         "occupied_cells_turned_free": int(np.count_nonzero(before_occupied & (p < 0.5)))}
    return numbers


def lbp_figure(before, results: dict, robot, radius, zoom=None):
    """``before`` and every run's beliefs (2 x 3 panels), the robot and its bound marked; ``zoom`` [m]: only that
    far round the robot."""
    fig, axes = plt.subplots(2, 3, figsize=(15, 10.5), layout="constrained")
    show_grid(axes[0, 0], before, "before LBP (Fig. 42)")
    for ax, (name, r) in zip(axes.flat[1:], results.items()):
        state = "converged" if r.converged else "NOT converged"
        title = name.replace("near known", "near observations")  # the report's words
        show_grid(ax, r.beliefs, f"{title}\n{r.iterations} iterations, {state}", )
        ax.title.set_fontsize(10)
    for ax in axes.flat:
        _mark_robot(ax, robot, radius)
        if zoom:
            ax.set_xlim(robot[0] - zoom, robot[0] + zoom)
            ax.set_ylim(robot[1] - zoom, robot[1] + zoom)
    return fig


def lbp_run_table(numbers: dict) -> tuple:
    """(header, rows) of :func:`lbp_run_numbers`' runs."""
    header = ["run", "iterations", "converged", "seconds", "unknown cells filled", "of which occupied",
              "known cells flipped", "occupied cells turned free"]
    return header, [[k, v["iterations"], v["converged"], v["seconds"], v["unknown_cells_filled"],
                     v["of_which_occupied"], v["known_cells_flipped"], v["occupied_cells_turned_free"]]
                    for k, v in numbers.items()]


def _all_free(masked, held_out):
    return np.zeros(masked.shape)


def predictors(hidden, link, margin: int, lbp_options: dict, thesis_options: dict) -> dict:
    """Table 26's predictors by name: LBP to convergence (``lbp_options``), LBP with ``thesis_options``, both on
    the cells within ``margin`` of a known one; the 3 x 3 neighbour mean; every cell free."""
    return {LBP: lbp_predictor(hidden, link, margin=margin, **lbp_options),
            LBP_THESIS: lbp_predictor(hidden, link, margin=margin, **thesis_options),
            NEIGHBOURS: neighbour_predictor(1), ALL_FREE: _all_free}


def fold_sets(known, k_folds: int, seed: int, block=None) -> dict:
    """The ``known`` cells dealt into ``k_folds`` folds: ``"random"`` cells, and with ``block`` [cells] also
    ``"blocks"``, squares of that side held out whole."""
    folds = {"random": random_folds(known, k_folds, seed=seed)}
    if block is not None:
        folds["blocks"] = block_folds(known, k_folds, block=block, seed=seed)
    return folds


def cross_validate_all(experiments: dict, run) -> dict:
    """``experiments``: key -> (grid, folds, predictor); each cross-validated on the folds of ``run``, its time
    printed."""
    cv = {}
    for key, (grid, folds, predictor) in experiments.items():
        t0 = time.perf_counter()
        cv[key] = cross_validate(grid, folds, predictor, run=run)
        print(f"{' / '.join(key)}: {time.perf_counter() - t0:.1f} s")
    return cv


def table26(cv: dict, map_names: dict, fold_names: dict) -> tuple:
    """(header, rows, numbers) of Table 26: the thesis's row, then one per cross-validation of ``cv`` (keys
    (map, folds, prediction)); ``numbers``: each one's report, coverage and folds under "map / folds / prediction"."""
    rows = [list(THESIS_TABLE26)]
    numbers = {}
    for key, result in cv.items():
        r = result.report()
        held = int(result.held_out.sum())
        scored = held - r.unknown
        rows.append([map_names[key[0]], fold_names[key[1]], key[2], r.precision, r.recall, r.accuracy, r.auc,
                     f"{scored} / {held}"])
        numbers[" / ".join(key)] = {**r.as_dict(), "coverage": result.coverage, "held_out": held,
                                    "folds_run": len(result.per_fold), "seconds": result.seconds,
                                    "lbp_converged_all": all(f.get("converged", True) for f in result.per_fold)}
    return TABLE26_HEADER, rows, numbers


def leave_one_out_check(grid, folds_run, predictor, n_cells: int, window: int, seed: int) -> dict:
    """Literal leave-one-out on ``n_cells`` held-out cells of ``folds_run`` (half occupied, half free, seeded),
    each predicted alone by ``predictor`` on a ``window`` of cells round it, against the folds' predictions."""
    rng = np.random.default_rng(seed)
    pool = {label: np.argwhere(folds_run.held_out & ((grid.probability > 0.5) == label)) for label in (True, False)}
    sample = np.vstack([cells[rng.choice(len(cells), n_cells // 2, replace=False)] for cells in pool.values()])
    t0 = time.perf_counter()
    loo = leave_one_out(grid, sample[:, ::-1], predictor, window=window)
    seconds = time.perf_counter() - t0
    in_folds = folds_run.predicted.probability[sample[:, 0], sample[:, 1]]
    labels = grid.probability[sample[:, 0], sample[:, 1]] > 0.5
    return {"cells": len(sample), "window_cells": window, "seconds": seconds,
            "same_label_as_folds": float(np.mean((loo > 0.5) == (in_folds > 0.5))),
            "mean_abs_difference": float(np.mean(np.abs(loo - in_folds))),
            "accuracy_loo": float(np.mean((loo > 0.5) == labels)),
            "accuracy_folds": float(np.mean((in_folds > 0.5) == labels))}


def versus_finished(predictions: dict, finished, cell_sets: dict) -> tuple:
    """(header, rows, numbers): each of ``predictions`` (name -> grid) scored (:func:`crfmap.assess.evaluate`) against ``finished``
    on each of ``cell_sets`` (name -> mask); on the set of seen cells only the map itself and LBP."""
    header = ["cells", "prediction", "precision", "recall", "accuracy", "scored / cells"]
    rows, numbers = [], {}
    for cell_set, mask in cell_sets.items():
        for name, grid in predictions.items():
            if cell_set.startswith("seen") and (name.startswith("neighbour") or name.startswith("all free")):
                continue
            r = evaluate(grid, finished, mask)
            n = int(mask.sum())
            rows.append([cell_set, name, r.precision, r.recall, r.accuracy, f"{n - r.unknown} / {n}"])
            numbers[f"{cell_set} / {name}"] = {**r.as_dict(), "cells": n}
    return header, rows, numbers


def same_cells(cv: dict, labels, gap_predictions: dict, gaps, gap_reference: str, seed: int) -> dict:
    """Every method scored on the cells all of them decide (:mod:`crfstudy.analysis.samecells`): per fold set of
    the finished map's cross-validations (fold bootstrap), and on the partial map's ``gaps`` (spatial blocks)."""
    cross_validation = {}
    for folds_kind in ("random", "blocks"):
        runs = {key[2]: result for key, result in cv.items() if key[:2] == ("full", folds_kind)}
        first = next(iter(runs.values()))
        cross_validation[folds_kind] = fold_scores({name: r.predicted for name, r in runs.items()}, labels,
                                                   first.held_out, first.folds, reference=LBP, n_boot=10000,
                                                   seed=seed)
    gap_scores = block_scores(gap_predictions, labels, gaps, reference=gap_reference, block=16, n_boot=2000,
                              seed=seed)
    return {"cross_validation": cross_validation, "gaps": gap_scores}


def same_cells_rows(cross_validation: dict, fold_names: dict) -> list:
    """Rows of the same-cell table: fold mean [95 % CI] of each metric, accuracy minus LBP's [95 % CI]."""
    rows = []
    for folds_kind, out in cross_validation.items():
        for name, e in out["methods"].items():
            vs = e["vs_reference"].get("accuracy")
            rows.append([fold_names[folds_kind], name, f"{out['common_cells']} / {out['held_out_cells']}",
                         *(f"{e[m]['fold_mean']:.4f} [{e[m]['fold_ci'][0]:.4f}, {e[m]['fold_ci'][1]:.4f}]"
                           for m in ("precision", "recall", "accuracy")),
                         f"{vs['mean_difference']:+.4f} [{vs['difference_ci'][0]:+.4f}, {vs['difference_ci'][1]:+.4f}]"
                         if vs else ""])
    return rows


def roc_figure(cv: dict, fold_names: dict):
    """Fig. 44: ROC of the finished map's held-out cells, one panel per fold set (every prediction but all free)."""
    fig, axes = plt.subplots(1, 2, figsize=(13, 6), layout="constrained")
    for ax, folds_kind in zip(axes, ("random", "blocks")):
        curves = {}
        for key, result in cv.items():
            if key[0] == "full" and key[1] == folds_kind and not key[2].startswith("all free"):
                fpr, tpr, _ = result.roc()
                curves[key[2]] = (fpr, tpr, result.report().auc)
        plot_roc(ax, curves, f"Fig. 44: held-out cells, {fold_names[folds_kind]}")
    return fig


def map_online_timed(mapper, stream, snapshot_at, log_seconds) -> tuple:
    """(run, numbers): ``stream`` mapped scan by scan by ``mapper``, snapshots at ``snapshot_at``
    (:func:`crfstudy.experiments.office_online.map_online`), and its timing and map numbers."""
    run = map_online(mapper, stream, snapshot_at)
    return run, online_numbers(mapper, run, log_seconds)


def online_against_offline(stream, resolution, hidden, mapper_near, tol) -> tuple:
    """({versus_offline, near_versus_offline, default_table_offline}, the offline grid): the online result with
    table ``hidden`` against build_grid + infer, on the whole grid and on ``mapper_near``'s region, and how
    offline LBP with the default table drifts on the same grid (:mod:`crfstudy.experiments.office_online`)."""
    versus, offline_grid = versus_offline(stream, resolution, hidden, tol)
    near = near_versus_offline(stream, resolution, offline_grid, hidden, mapper_near, tol)
    return {"versus_offline": versus, "near_versus_offline": near,
            "default_table_offline": default_table_drift(offline_grid, tol)}, offline_grid


def online_figure(stream, snapshot_at, snapshots: dict, snapshots_near: dict, radius, max_iter, margin):
    """One row per moment of ``snapshot_at``: observations, online beliefs, online beliefs near observations,
    with the path so far, the robot and the LBP disc of ``radius``."""
    # one row per moment, one column per kind of map: three wide columns fit a page better than four narrow ones
    fig, axes = plt.subplots(len(snapshot_at), 3, figsize=(15, 4.6 * len(snapshot_at)), layout="constrained")
    for moment, n in enumerate(snapshot_at):
        pose = stream.laser_poses[n - 1]
        when = f"after {n} scans ({stream.stamps[n - 1] - stream.stamps[0]:.0f} s of log)"
        panels = zip(snapshots[n] + snapshots_near[n][1:],
                     ("observations (arctan grid)", "online LBP beliefs", f"online LBP, margin {margin} cells"))
        for kind, (grid, what) in enumerate(panels):
            ax = axes[moment, kind]
            show_grid(ax, grid, f"{what},\n{when}")
            ax.title.set_fontsize(10)
            ax.plot(*stream.laser_poses[:n, :2].T, color="C3", lw=0.6)
            _mark_robot(ax, pose, radius)
            left, right, bottom, top = imshow_extent(grid)
            ax.set_xlim(left, right)  # the disc may reach past the grid; keep the grid's frame
            ax.set_ylim(bottom, top)
    fig.suptitle(f"Online mapping of the Intel log: beliefs while mapping (default tables, LBP within "
                 f"{radius:g} m of the laser, <= {max_iter} iterations per scan)")
    return fig


def online_table(online: dict, max_iter: int, margin: int, hidden, log_seconds) -> tuple:
    """(header, rows) of the online table: the thesis, the two online runs, online + finish() against offline with
    the converging table ``hidden``, and near observations with both tables (``online``: the notebook's numbers)."""
    vs, nv, near = online["versus_offline"], online["near_versus_offline"], online["near_observations"]
    scans, hidden = online["scans"], np.asarray(hidden).tolist()
    header = ["run", "scans", "ms per scan (median / p90)", "seconds", "x real time", "LBP iterations",
              "converged", "largest belief difference, online vs offline"]
    finish_seconds = vs["online_mapping_seconds"] + vs["finish_seconds"]
    rows = [
        ["thesis", "n/a", "n/a (not run online)", "n/a", "n/a", "2 per snapshot", "n/a", "n/a"],
        ["online, default tables, 4 m disc", scans,
         f"{online['ms_per_scan_median']:.2f} / {online['ms_per_scan_p90']:.2f}", online["seconds_total"],
         round(online["real_time_factor"]), f"<= {max_iter} per scan", "n/a", "n/a"],
        [f"online, default tables, 4 m disc, near observations ({margin} cells)", scans,
         f"{near['ms_per_scan_median']:.2f} / {near['ms_per_scan_p90']:.2f}", near["seconds_total"],
         round(near["real_time_factor"]), f"<= {max_iter} per scan", "n/a", "n/a"],
        [f"online + finish(), hidden {hidden}", scans, "", finish_seconds, round(log_seconds / finish_seconds),
         f"finish: {vs['finish_iterations']}", vs["finish_converged"], vs["max_abs_belief_difference"]],
        [f"offline build_grid + infer, hidden {hidden}", scans, "", vs["offline_seconds"], "",
         vs["offline_iterations"], vs["offline_converged"], 0.0],
        [f"near observations: online + finish() vs infer(region), hidden {hidden}", scans, "", "", "",
         f"{nv['weak_finish_iterations']} / {nv['weak_offline_iterations']}", nv["weak_converged"],
         nv["weak_max_abs_belief_difference"]],
        ["near observations: online + finish() vs infer(region), default tables", scans, "", "", "",
         f"{nv['default_finish_iterations']} / {nv['default_offline_iterations']}",
         f"{nv['default_finish_converged']} / {nv['default_offline_converged']}",
         f"same state on {100 * nv['default_same_state_fraction']:.1f} % of the region's cells"],
    ]
    return header, rows


def paper_numbers(office: dict, online: dict) -> dict:
    """The numbers the paper's prose quotes, under plain keys, from the notebook's ``office`` and ``online``."""
    def cv(key):
        return office["table26"][key]

    bounded = office["fig43"]["1: bounded disc (thesis sec. 3.4.4)"]
    unbounded = office["fig43"]["2: unbounded (whole grid)"]
    seen = office["partial_vs_finished"]
    return {
        "occupied_fraction_of_known": office["full_map"]["occupied_fraction_of_known"],
        "lbp_random": cv(f"full / random / {LBP}"), "lbp2_random": cv(f"full / random / {LBP_THESIS}"),
        "neighbour_random": cv(f"full / random / {NEIGHBOURS}"), "all_free_random": cv(f"full / random / {ALL_FREE}"),
        "lbp_blocks": cv(f"full / blocks / {LBP}"), "neighbour_blocks": cv(f"full / blocks / {NEIGHBOURS}"),
        "partial_seen_recall_before": seen["seen in the partial map / partial map as built"]["recall"],
        "partial_seen_recall_after": seen["seen in the partial map / partial map after LBP (near known)"]["recall"],
        "bounded_unknown_filled": bounded["unknown_cells_filled"],
        "bounded_unknown_made_occupied": bounded["of_which_occupied"],
        "bounded_iterations": bounded["iterations"], "bounded_converged": bounded["converged"],
        "unbounded_iterations": unbounded["iterations"], "unbounded_converged": unbounded["converged"],
        "online_walls_kept": online["observed_occupied_fraction_still_occupied"],
        "online_never_seen_given_state": online["never_observed_cells_given_a_state"],
        "online_real_time_factor": online["real_time_factor"], "online_ms_per_scan": online["ms_per_scan_median"],
        "online_scans": online["scans"],
        "default_offline_converged": online["default_table_offline"]["converged"],
        "default_offline_iterations": online["default_table_offline"]["iterations"],
    }
