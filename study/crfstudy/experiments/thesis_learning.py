"""The thesis's learning experiments in simulated rooms (notebooks 05 and 06, sec. 4.1.2 and 4.1.2.1).

Both notebooks scan a TRAIN and a TEST room (:func:`scan_scene`), learn tables on TRAIN with three
learners under two LBP settings and apply them to both rooms (:func:`train_and_test`, both from
:mod:`crfstudy.experiments.pipeline`), and lay the outcome out the same way:

- learners and tables: :func:`make_learners`, :func:`metrics_table` (beside the thesis's row),
  :func:`potentials_rows` (Tables 16-19, 21-24), :func:`results_summary`, :func:`learned_summary`,
  :func:`same_cells_scores` (every grid scored on the same cells) and :func:`same_cells_table`;
- figures: :func:`panels_figure` (grids side by side, the robot's start marked), :func:`landscape_figure`,
  :func:`roc_figure`, :func:`iterations_figure`;
- the occlusion room (05): :func:`reading_rows`, :func:`thesis_pass_from`, :func:`beside_printed`,
  :func:`headline`, :func:`lower_mse_without_lower_recall` and why its result does not reproduce
  (:func:`why_study`, :func:`schedule_rows`, :func:`sensing_rows`, :func:`corner_spread`);
- the boxes (06): :func:`scan_boxes`, :func:`run_summary`, :func:`hollow_rows`, :func:`cross_rows`,
  :func:`mse_tradeoff_rows`;
- many noisy generated rooms (both): :func:`noisy_rooms`, paired room by room by :func:`paired_over_rooms`
  and :func:`paired_rows`.
"""
from __future__ import annotations

import numpy as np

from crfmap.assess.learning import learn_gradient, learn_thesis
from crfmap.assess.metrics import evaluate
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.schedules import Thesis
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK
from crfmap.errors import InputError
from crfmap.grid import UNKNOWN
from crfmap.world.scenes import enclosed_boxes
from crfstudy.experiments import rooms
from crfstudy.experiments.pipeline import (THESIS_TWO_ITERATIONS, TO_CONVERGENCE, evaluate_pipeline,
                                           learn_search_gradient, metric_row, scan_scene, score,
                                           train_and_test)  # noqa: F401  (the notebooks take train_and_test from here, their one helper)
from crfstudy.paired import paired_difference, value_range
from crfstudy.plotting import plot_roc, show_grid


SETTINGS = {"converged": TO_CONVERGENCE, "thesis 2 iterations": THESIS_TWO_ITERATIONS}
LEARNER_LABEL = {"default": "without learning", "thesis": "with learning (thesis's learner)",
                 "gradient": "with learning (gradient learner)",
                 "search+gradient": "with learning (search + gradient, extra)"}
METRICS_HEADER = ["grid", "LBP", "MSE", "precision", "recall", "accuracy", "LBP iterations",
                  "thesis MSE", "thesis precision", "thesis recall", "thesis accuracy"]
POTENTIALS_HEADER = ["table", "source", "C1 N1", "C1 N0", "C0 N1", "C0 N0"]
SAME_CELLS_HEADER = ["method", "MSE (all cells)", "precision (seen cells)", "recall (seen cells)",
                     "accuracy (seen cells)", "accuracy (unseen cells)", "coverage of unseen cells"]
THESIS_ALPHA = 0.01  # the thesis's step of the coordinate search


def make_learners(thesis_rounds: int, gradient_steps: int) -> dict:
    """name -> learner(observed, truth, lbp_options), as :func:`~crfstudy.experiments.pipeline.train_and_test` takes.

    >>> list(make_learners(2, 3))
    ['thesis', 'gradient', 'search+gradient']
    """
    return {
        "thesis": lambda o, t, opts: learn_thesis(o, t, alpha=THESIS_ALPHA, max_rounds=thesis_rounds,
                                                  lbp_options=opts, progress=False),
        "gradient": lambda o, t, opts: learn_gradient(o, t, steps=gradient_steps, lbp_options=opts, progress=False),
        "search+gradient": lambda o, t, opts: learn_search_gradient(o, t, steps=gradient_steps, lbp_options=opts,
                                                                    progress=False),
    }


def learner_names(run) -> list:
    """The learners of a :class:`~crfstudy.experiments.pipeline.TrainTest`, in the order they ran."""
    return list(dict.fromkeys(name for _, name in run.learned))


def metrics_table(run, env: str, thesis: dict, extra=None) -> list:
    """Rows of :data:`METRICS_HEADER` for room ``env``: before LBP, then every setting x (default, learners).

    ``thesis``: {"before", "default", "learned"} -> the thesis's [MSE, precision, recall, accuracy]
    (None entries where it gave none); the search + gradient learner is ours, so no thesis row.
    ``extra``: (label, LBP label, PipelineResult) rows added last, beside the thesis's default row.
    """
    rows = [["before LBP", "", *metric_row(run.before[env]), "", *thesis["before"]]]
    for setting in run.lbp_settings:
        for name in ("default", *learner_names(run)):
            r = run.results[(setting, env, name)]
            key = "default" if name == "default" else ("learned" if name != "search+gradient" else None)
            rows.append([f"after LBP, {LEARNER_LABEL[name]}", setting, *metric_row(r), r.lbp.iterations,
                         *(thesis[key] if key else [None] * 4)])
    for label, lbp, r in extra or ():
        rows.append([label, lbp, *metric_row(r), r.lbp.iterations, *thesis["default"]])
    return rows


def potentials_rows(run, thesis_hidden, thesis_link, tables=(16, 17, 18, 19), tag="") -> list:
    """Rows of :data:`POTENTIALS_HEADER`: default, thesis's learned and our learned hidden tables, then the links.

    ``tables``: the thesis's numbers of (default hidden, learned hidden, default link, learned link);
    ``tag`` is appended to each of our rows' source.
    """
    default_hidden, learned_hidden, default_link, learned_link = (f"(Table {t})" for t in tables)
    rows = [[f"hidden {default_hidden}", "default", *DEFAULT_HIDDEN.ravel()],
            [f"hidden {learned_hidden}", "thesis, learned", *thesis_hidden]]
    rows += [[f"hidden {learned_hidden}", f"ours, {name} learner, {setting}{tag}", *res.hidden.ravel()]
             for (setting, name), res in run.learned.items()]
    rows += [[f"link {default_link}", "default", *DEFAULT_LINK.ravel()],
             [f"link {learned_link}", "thesis, learned", *thesis_link]]
    rows += [[f"link {learned_link}", f"ours, {name} learner, {setting}{tag}", *res.link.ravel()]
             for (setting, name), res in run.learned.items()]
    return rows


def learned_summary(run) -> dict:
    """"learner | setting" -> the learned tables, the train MSE before and after, the trace's length."""
    return {f"{name} | {setting}": {"hidden": res.hidden, "link": res.link, "train_mse_before": res.mse_before,
                                    "train_mse_after": res.mse_after, "trace_length": len(res.trace)}
            for (setting, name), res in run.learned.items()}


def results_summary(run, env: str, extra=None) -> dict:
    """Room ``env``'s scores as dicts: "before", then "tables | setting" for every LBP run on it, then ``extra``
    (label -> PipelineResult of a run outside ``run``)."""
    out = {"before": run.before[env].as_dict()}
    for (setting, e, name), r in run.results.items():
        if e == env:
            out[f"{name} | {setting}"] = r.as_dict()
    out.update({label: r.as_dict() for label, r in (extra or {}).items()})
    return out


def same_cells_predictions(run, env: str, scans, truth, grid) -> dict:
    """name -> grid: the baselines of :func:`crfstudy.experiments.rooms.baselines`, every LBP run of ``run`` on
    room ``env``, and converged LBP with each learner's tables under the proper pairwise ("oriented") pairing."""
    predictions = rooms.baselines(scans, truth, grid)
    names = learner_names(run)
    for setting in run.lbp_settings:
        for name in ("default", *names):
            predictions[f"LBP {setting}, {LEARNER_LABEL[name]}"] = run.results[(setting, env, name)].beliefs
    for name in names:
        hidden, link = run.tables("converged", name)
        predictions[f"LBP converged, {LEARNER_LABEL[name]}, oriented pairing"] = infer(
            grid, hidden, link, pairing="oriented", threads=1).beliefs
    return predictions


def same_cells_scores(run, env: str, scans, truth, grid) -> dict:
    """name -> scores on the same cells (:func:`crfstudy.experiments.rooms.score_methods`) of every grid of
    :func:`same_cells_predictions`."""
    return rooms.score_methods(same_cells_predictions(run, env, scans, truth, grid), truth, grid)


def same_cells_table(scores: dict, caption: str) -> dict:
    """``save_table`` keywords (header, rows, caption) of :func:`crfstudy.experiments.rooms.score_methods`' scores."""
    rows = [[name, s["mse"], s["precision_seen"], s["recall_seen"], s["accuracy_seen"], s["accuracy_unseen"],
             s["coverage_unseen"]] for name, s in scores.items()]
    return dict(header=SAME_CELLS_HEADER, rows=rows, caption=caption)


# --- panels of the simulated scenes ---------------------------------------------------------------
def draw(ax, grid, title, scene=None) -> None:
    """``grid`` on ``ax`` under ``title``; with ``scene``, its robot's start as a red dot."""
    show_grid(ax, grid, title)
    if scene is not None:  # the robot's start
        ax.plot(scene.start[0], scene.start[1], marker="o", color="C3", markersize=7, markeredgecolor="white")


def panels_figure(panels, shape=(1, 1), figsize=(4.6, 4.6)):
    """A figure of grids side by side, row by row: each panel is (grid, title) or (grid, title, scene)."""
    import matplotlib.pyplot as plt

    if len(panels) != shape[0] * shape[1]:
        raise InputError("panels", f"{len(panels)} panels for a {shape[0]} x {shape[1]} figure")
    fig, axes = plt.subplots(*shape, figsize=figsize, layout="constrained")
    for ax, panel in zip(np.atleast_1d(axes).ravel(), panels):
        draw(ax, *panel)
    return fig


def landscape_figure(landscape, strengths, biases, title):
    """The MSE over hidden strengths a (rows) and link biases b (columns), each cell labelled with its value."""
    import matplotlib.pyplot as plt

    landscape = np.asarray(landscape, dtype=float)
    if landscape.shape != (len(strengths), len(biases)):
        raise InputError("landscape", f"shape {landscape.shape}, expected (strengths, biases) = "
                                      f"({len(strengths)}, {len(biases)})")
    fig, ax = plt.subplots(figsize=(6, 4.4), layout="constrained")
    im = ax.imshow(landscape, origin="lower", cmap="viridis", aspect="auto")
    for i in range(len(strengths)):
        for j in range(len(biases)):  # dark text on viridis's bright end: white on yellow was unreadable
            ax.text(j, i, f"{landscape[i, j]:.3f}", ha="center", va="center", fontsize=8,
                    color="black" if im.norm(landscape[i, j]) > 0.6 else "white")
    ax.set_xticks(range(len(biases)), [str(b) for b in biases])
    ax.set_yticks(range(len(strengths)), [str(a) for a in strengths])
    ax.set_xlabel("link bias b: link [[1, 0], [0, b]]")
    ax.set_ylabel("hidden strength a: hidden [[a, 1], [1, a]]")
    ax.set_title(title)
    fig.colorbar(im, ax=ax, label="MSE")
    return fig


# --- why the occlusion result does not reproduce: four causes varied one at a time (notebook 05) -----
# On the TRAIN room, with everything else fixed: (1) the schedule and the corner the thesis's breadth-first
# pass starts from, (2) the number of iterations, (3) the sensing, (4) the coupling a of [[a, 1], [1, a]].
# Each grid is scored by why_row: MSE over all cells, precision and recall over the cells the scan saw (the
# same cells in every row) and "walls kept", the fraction of the seen wall cells that stay above 0.5.
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


def corner_spread(why) -> tuple:
    """The thesis's 2-iteration pass from each corner ({corner: row}) and, per metric, its range over the corners."""
    corner_rows = {k.removeprefix("thesis_"): v for k, v in why["schedules"].items() if k.startswith("thesis_")}
    return corner_rows, {m: value_range(corner_rows, m) for m in ("mse", "recall_seen", "walls_kept")}


# --- the occlusion room (notebook 05) ------------------------------------------------------------------------
def reading_rows(readings: dict, truth, thesis_mse_before: float) -> tuple:
    """One row per way of scanning the room (name -> (grid, recording)): scans, unknown share, MSE before and
    after converged LBP with the default tables, beside the thesis's MSE before LBP; and the same as numbers
    under the name's first word."""
    rows, numbers = [], {}
    for name, (grid, recording) in readings.items():
        before = score(grid, truth).metrics
        after = evaluate_pipeline(grid, truth).metrics
        unknown = float(np.mean(grid.probability == 0.5))
        scans = len(recording.scans.ranges)
        rows.append([name, scans, unknown, before.mse, after.mse, thesis_mse_before])
        numbers[name.split()[0]] = {"scans": scans, "unknown_fraction": unknown, "mse_before": before.mse,
                                    "mse_after_default_lbp": after.mse}
    return rows, numbers


def thesis_pass_from(observed, truth, corner: str):
    """The thesis's 2 iterations with the default tables, its breadth-first pass started at ``corner``."""
    return evaluate_pipeline(observed, truth, lbp_options=dict(THESIS_TWO_ITERATIONS, schedule=Thesis(corner)))


def roc_figure(run, env: str, title: str):
    """ROC curves on room ``env``: before LBP, each LBP setting with the default tables, converged LBP with each
    learner's tables."""
    import matplotlib.pyplot as plt

    truth = run.truth[env]
    curves = {"before LBP": run.before[env].roc(truth)}
    for setting in run.lbp_settings:
        curves[f"{setting}, default tables"] = run.results[(setting, env, "default")].roc(truth)
    for name in learner_names(run):
        curves[f"converged, {name} learner"] = run.results[("converged", env, name)].roc(truth)
    fig, ax = plt.subplots(figsize=(6, 5.5), layout="constrained")
    plot_roc(ax, curves, title)
    return fig


def median_beliefs(result, truth) -> tuple:
    """The median belief of ``result`` on the truth's walls and on its free cells."""
    beliefs = result.beliefs.probability
    return float(np.median(beliefs[truth.probability > 0.5])), float(np.median(beliefs[truth.probability < 0.5]))


def beside_printed(rows: list, printed: dict) -> list:
    """:func:`metrics_table` rows with the thesis's four columns replaced by what it printed, one text per row:
    ``printed["before"]`` beside "before LBP", ``"default"`` beside rows without learning, ``"learned"`` beside
    learned rows and "n/a" beside the extra rows."""
    def text(label):
        if label == "before LBP":
            return printed["before"]
        if "without" in label:
            return printed["default"]
        return printed["learned"] if "extra" not in label else "n/a"

    return [row[:7] + [text(row[0])] for row in rows]


def headline(run, env: str) -> str:
    """One line: room ``env``'s MSE before LBP, after converged LBP with the default tables and with the best
    learner's tables (recall beside both)."""
    before = run.before[env].metrics.mse
    default = run.results[("converged", env, "default")].metrics
    best = min(learner_names(run), key=lambda name: run.results[("converged", env, name)].metrics.mse)
    learned = run.results[("converged", env, best)].metrics
    return (f"{env}: MSE before {before:.4f} -> default LBP {default.mse:.4f} (recall {default.recall:.3f}) -> "
            f"learned ({best}) {learned.mse:.4f} (recall {learned.recall:.3f})")


def lower_mse_without_lower_recall(run) -> list:
    """(setting, room, tables) of the LBP runs with a lower MSE than before LBP but not both a lower recall and a
    lower accuracy (thesis sec. 4.2: learning on MSE trades them away)."""
    out = []
    for (setting, env, name), r in run.results.items():
        before = run.before[env].metrics
        if r.metrics.mse < before.mse and not (r.metrics.recall < before.recall
                                               and r.metrics.accuracy < before.accuracy):
            out.append((setting, env, name))
    return out


# --- the boxes (notebook 06) ---------------------------------------------------------------------------------
def scan_boxes(hollow: bool, laser, seed: int) -> dict:
    """"train" and "test" -> (scene, observed grid, recording) of :func:`crfmap.world.enclosed_boxes`, every
    reachable cell visited."""
    out = {}
    for variant in ("train", "test"):
        scene = enclosed_boxes(variant, hollow=hollow)
        observed, recording = scan_scene(scene, laser, drive="explore", seed=seed)
        out[variant] = (scene, observed, recording)
    return out


def run_summary(run) -> dict:
    """Both rooms' scores and the learned tables as plain dicts."""
    return {"train": results_summary(run, "train"), "test": results_summary(run, "test"),
            "learned": learned_summary(run)}


def hollow_rows(run) -> tuple:
    """Rows (room, grid, LBP, MSE, accuracy, precision, recall, MSE worse, accuracy worse than no LBP) and
    (room, setting, tables) -> (MSE worse, accuracy worse) than the grid before LBP."""
    rows, worse = [], {}
    for env in ("train", "test"):
        before = run.before[env].metrics
        rows.append([env, "before LBP", "", before.mse, before.accuracy, before.precision, before.recall, "", ""])
        for setting in run.lbp_settings:
            for name in ("default", *learner_names(run)):
                m = run.results[(setting, env, name)].metrics
                worse[(env, setting, name)] = (m.mse > before.mse, m.accuracy < before.accuracy)
                rows.append([env, f"after LBP, {LEARNER_LABEL[name]}", setting, m.mse, m.accuracy, m.precision,
                             m.recall, "yes" if m.mse > before.mse else "no",
                             "yes" if m.accuracy < before.accuracy else "no"])
    return rows, worse


def cross_rows(runs: dict, boxes: dict) -> tuple:
    """Each learner's converged tables from one kind of boxes' TRAIN room applied to the other kind's TEST room.

    ``runs``, ``boxes``: "filled" and "hollow" -> the :func:`train_and_test` run and the :func:`scan_boxes` scans.
    Returns rows (learned on, applied to, learner, MSE before LBP, MSE with the same kind's tables, MSE and
    accuracy with the other kind's) and "learner | learned on -> applied to" -> the scores.
    """
    rows, cross = [], {}
    for source, target in (("filled", "hollow"), ("hollow", "filled")):
        scene, observed, _ = boxes[target]["test"]
        learned_on, tested_on = f"{source} TRAIN", f"{target} TEST"
        for name in learner_names(runs[source]):
            r = evaluate_pipeline(observed, scene.truth, *runs[source].tables("converged", name))
            same = runs[target].results[("converged", "test", name)]
            rows.append([learned_on, tested_on, name, runs[target].before["test"].metrics.mse, same.metrics.mse,
                         r.metrics.mse, r.metrics.accuracy])
            cross[f"{name} | {learned_on} -> {tested_on}"] = r.as_dict()
    return rows, cross


def mse_tradeoff_rows(runs: dict) -> list:
    """Learned runs (label -> :func:`train_and_test` run) with a lower MSE than the default tables' in the same
    setting and room while precision, recall or accuracy fall: label, room, setting, learner, both MSEs, what fell."""
    trade = []
    for label, run in runs.items():
        for (setting, env, name), r in run.results.items():
            if name == "default":
                continue
            d = run.results[(setting, env, "default")].metrics
            m = r.metrics
            worse_on = [k for k in ("precision", "recall", "accuracy") if getattr(m, k) < getattr(d, k) - 1e-12]
            if m.mse < d.mse and worse_on:
                trade.append([label, env, setting, name, d.mse, m.mse, ", ".join(worse_on)])
    return trade


# --- many noisy generated rooms (both notebooks) ---------------------------------------------------------------
NOISE_TEXT = (f"range noise +-C with C ~ U[0, {rooms.RANGE_NOISE} m], odometry noise {rooms.ODOMETRY_NOISE[0]} m / "
              f"{rooms.ODOMETRY_NOISE[1]} rad per step")


def noisy_rooms(kind: str, n_rooms: int, learning_steps: int, laser, drive=None) -> dict:
    """Rooms 0 .. n_rooms - 1 of ``kind`` (:func:`crfstudy.experiments.rooms.run_rooms`, noisy, grid from the
    odometry), every method scored on the same cells, with tables the gradient learner learned on room 1000.

    Returns "learned" (the LearningResult), "run", "summary" (over rooms), "rows" (of
    :data:`SAME_CELLS_HEADER`) and "flat" (the summary under short keys, for ``save_numbers``).
    """
    learned = rooms.learn_on_room(kind, 1000, steps=learning_steps, drive=drive, laser=laser)
    run = rooms.run_rooms(kind, range(n_rooms), drive=drive, laser=laser, learned=(learned.hidden, learned.link))
    summary = rooms.summarise(run)
    return {"learned": learned, "run": run, "summary": summary, "rows": rooms.summary_rows(summary),
            "flat": rooms.flat_summary(run, summary)}


def paired_over_rooms(run: dict, seed: int) -> dict:
    """Each learned method against converged LBP with the default tables, paired room by room:
    method -> {"mse", "recall_seen"} -> :func:`crfstudy.paired.paired_difference` (10000 resamples)."""
    per_room = run["per_room"]
    return {method: {metric: paired_difference([r[method][metric] for r in per_room],
                                               [r["LBP, converged"][metric] for r in per_room], n_boot=10000,
                                               seed=seed, lower_is_better=(metric == "mse"))
                     for metric in ("mse", "recall_seen")}
            for method in run["methods"] if method.startswith("LBP, learned")}


def paired_rows(pairs: dict) -> list:
    """Rows: method, metric, both means, the mean difference with its interval, better / worse / tied, sign test p."""
    return [[method, metric, d["mean_a"], d["mean_b"], f"{d['mean_difference']:+.4f} [{d['difference_ci'][0]:+.4f}, "
             f"{d['difference_ci'][1]:+.4f}]", f"{d['wins']} / {d['losses']} / {d['ties']}", d["sign_test_p"]]
            for method, by_metric in pairs.items() for metric, d in by_metric.items()]
