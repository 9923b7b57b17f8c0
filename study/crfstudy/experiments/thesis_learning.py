"""The thesis's learning experiments as tables (notebooks 05 and 06): learners, metric rows, tables, summaries.

Both notebooks learn tables on a TRAIN room with three learners under two LBP settings
(:func:`crfstudy.experiments.pipeline.train_and_test`) and tabulate the outcome the same way:

- :func:`make_learners`: the thesis's coordinate search, the gradient learner and our search + gradient;
- :func:`metrics_table`: MSE, precision, recall, accuracy per (setting, tables), beside the thesis's row;
- :func:`potentials_rows`: the default, the thesis's and our learned tables (Tables 16-19, 21-24);
- :func:`results_summary`, :func:`learned_summary`: the same numbers as plain dicts for ``save_numbers``;
- :func:`same_cells_predictions`, :func:`same_cells_table`: every grid scored on the same cells.
"""
from __future__ import annotations

from crfmap.assess.learning import learn_gradient, learn_thesis
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK
from crfstudy.experiments.pipeline import THESIS_TWO_ITERATIONS, TO_CONVERGENCE, learn_search_gradient, metric_row
from crfmap.crf.inference.lbp import infer
from crfstudy.experiments import rooms

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


def results_summary(run, env: str) -> dict:
    """Room ``env``'s scores as dicts: "before", then "tables | setting" for every LBP run on it."""
    out = {"before": run.before[env].as_dict()}
    for (setting, e, name), r in run.results.items():
        if e == env:
            out[f"{name} | {setting}"] = r.as_dict()
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


def same_cells_table(scores: dict, caption: str) -> dict:
    """``save_table`` keywords (header, rows, caption) of :func:`crfstudy.experiments.rooms.score_methods`' scores."""
    rows = [[name, s["mse"], s["precision_seen"], s["recall_seen"], s["accuracy_seen"], s["accuracy_unseen"],
             s["coverage_unseen"]] for name, s in scores.items()]
    return dict(header=SAME_CELLS_HEADER, rows=rows, caption=caption)
