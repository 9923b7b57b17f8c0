"""Denoising the X (thesis sec. 4.1.1, Fig. 20-26, Tables 10-14): notebook 04's helper.

The notebook runs the experiment's calls itself (``noisy_image``, ``infer``, the three learners,
``evaluate``); this module holds the study machinery around them:

- :func:`seed_mses`, :func:`mean_sd`: a setting scored on further noise seeds of the same image;
- :func:`paired_learning`, :func:`paired_rows`: learned against default tables, scan by scan;
- :func:`toolbox_comparison`, :func:`toolbox_columns`, :func:`toolbox_rows`, :func:`toolbox_summary`: the UGM
  toolbox's hand-picked noisy-X model rebuilt, run by crfmap and by the independent ``reference_lbp``;
- :func:`implied_positive_share`: which class the thesis's precision/recall/accuracy counted as positive;
- :func:`baseline_makers`: the 3x3 neighbour mean and the graph-cut MAP labelling;
- :func:`learner_tail`: how much the thesis's learner still moved in its last tenth of LBP runs;
- the figures (each returns a Figure; the notebook saves it).

>>> round(implied_positive_share(0.9, 0.9, 0.9), 6)  # precision = recall = accuracy: every share fits
0.5
"""
from __future__ import annotations

import numpy as np

from crfmap.assess import mse
from crfmap.crf import DEFAULT_HIDDEN, DEFAULT_LINK, infer
from crfmap.errors import InputError
from crfmap.world import noisy_image
from crfstudy.plotting import plot_roc, show_grid

# the toolbox's hand-picked noisy-X demo (UGM getNoisyX): edge potential on every 4-neighbour edge
UGM_EDGE = np.array([[1.35, 1.0], [1.0, 1.35]])
LEARNER_WORDS = {"learn_thesis": "thesis's learner", "learn_gradient": "gradient learner",
                 "learn_pseudolikelihood": "pseudo-likelihood learner"}
TOOLBOX_KEYS = ("noisy", "crfmap", "reference", "thesis_style", "thesis_tables_on_toolbox_input")


def seed_mses(truth, noise: float, seeds, hidden=None, link=None, options=None) -> list:
    """MSE against ``truth`` of each further noisy scan (one per seed): after LBP, or as is if ``hidden`` is None."""
    if hidden is None:  # no LBP: the noisy scans themselves
        return [mse(noisy_image(truth, noise, seed=s), truth) for s in seeds]
    return [mse(infer(noisy_image(truth, noise, seed=s), hidden, link, **options).beliefs, truth) for s in seeds]


def mean_sd(values) -> tuple:
    """(mean, population sd) of ``values`` as floats, the +- the tables print."""
    return float(np.mean(values)), float(np.std(values))


def learner_name(name: str) -> str:
    """A learning run's plain name: ``"learn_gradient (converged)"`` -> ``"gradient learner (converged)"``."""
    learner, _, setting = name.partition(" ")
    if learner not in LEARNER_WORDS:
        raise InputError("name", f"expected one of {', '.join(LEARNER_WORDS)} and a setting, got {name!r}")
    return f"{LEARNER_WORDS[learner]} {setting}"


def paired_learning(truth, noise: float, seeds, learned: dict, defaults: dict, seed: int = 0) -> tuple:
    """Each learned table set against the default tables under its LBP setting, on the same further scans.

    ``learned``: name -> (learning result, LBP options); ``defaults``: setting name -> LBP options,
    matched to a run by identity of its options. Returns (name -> ``paired_difference`` result plus
    ``against``, setting name -> per-seed MSE of the default tables).
    """
    from crfstudy.paired import paired_difference

    default_mses = {name: seed_mses(truth, noise, seeds, DEFAULT_HIDDEN, DEFAULT_LINK, options)
                    for name, options in defaults.items()}
    paired = {}
    for name, (run, options) in learned.items():
        reference = next(n for n, o in defaults.items() if o is options)
        ours = seed_mses(truth, noise, seeds, run.hidden, run.link, options)
        paired[name] = dict(paired_difference(ours, default_mses[reference], n_boot=10000, seed=seed),
                            against=f"default tables, {reference}")
    return paired, default_mses


def paired_rows(paired: dict) -> list:
    """Table rows of :func:`paired_learning`: means +- sd, the difference with its interval, the sign test."""
    return [[name, d["against"], f"{d['mean_a']:.4f} +- {d['sd_a']:.4f}", f"{d['mean_b']:.4f} +- {d['sd_b']:.4f}",
             f"{d['mean_difference']:+.4f} [{d['difference_ci'][0]:+.4f}, {d['difference_ci'][1]:+.4f}]",
             f"{d['wins']} / {d['losses']} / {d['ties']}", d["sign_test_p"]] for name, d in paired.items()]


def implied_positive_share(precision: float, recall: float, accuracy: float) -> float:
    """The positive class's share s of the cells that makes the three numbers consistent.

    The error rate is s (r (1 - p) / p + 1 - r), so s = (1 - a) / (r (1 - p) / p + 1 - r).
    """
    return (1 - accuracy) / (recall * (1 - precision) / precision + 1 - recall)


def pixel_error(probability, occupied) -> float:
    """Fraction of cells whose max-marginal state (P > 0.5) differs from ``occupied``."""
    return float(np.mean((np.asarray(probability) > 0.5) != occupied))


def toolbox_comparison(truth, noise: float, seeds, converged: dict) -> tuple:
    """The UGM toolbox's noisy-X model, per noise seed, run by crfmap and by ``reference_lbp``.

    Toolbox noise ``X + randn/2`` on its image (1 = white background); the stroke's node potential
    ``1/(1+exp(X_noisy - 0.5))`` is crfmap's observed P(occupied), with the identity link and
    :data:`UGM_EDGE`. Both LBPs run to tolerance 1e-12. Beside them, per seed: the thesis-style
    pipeline (``noisy_image`` at ``noise``, default tables, ``converged``) and the default tables on
    the toolbox's input. Returns (one dict of pixel errors and iterations per seed, the first seed's
    (toolbox noisy image, observed, crfmap result, reference marginals, thesis-style result)).
    """
    from crfstudy.references import reference_lbp

    image = 1.0 - truth.probability  # the toolbox's X: 1 = white background, 0 = the stroke
    occupied = truth.probability > 0.5
    identity = np.eye(2)
    rows, example = [], None
    for s in seeds:
        x_noisy = image + np.random.default_rng(s).standard_normal(image.shape) / 2
        observed = 1.0 / (1.0 + np.exp(x_noisy - 0.5))  # the toolbox's node potential of the stroke
        ours = infer(observed, UGM_EDGE, identity, schedule="checkerboard", max_iter=10000, tol=1e-12)
        ref, ref_iterations = reference_lbp(observed, UGM_EDGE, identity, 5000, tol=1e-12)
        thesis_style = infer(noisy_image(truth, noise, seed=s), DEFAULT_HIDDEN, DEFAULT_LINK, **converged)
        thesis_tables = infer(observed, DEFAULT_HIDDEN, DEFAULT_LINK, **converged)
        rows.append({
            "seed": s,
            "max_abs_difference": float(np.abs(ours.beliefs.probability - ref).max()),
            "crfmap_iterations": ours.iterations, "reference_iterations": ref_iterations,
            "noisy": pixel_error(observed, occupied), "crfmap": pixel_error(ours.beliefs.probability, occupied),
            "reference": pixel_error(ref, occupied),
            "thesis_style": pixel_error(thesis_style.beliefs.probability, occupied),
            "thesis_tables_on_toolbox_input": pixel_error(thesis_tables.beliefs.probability, occupied),
        })
        if example is None:
            example = (x_noisy, observed, ours, ref, thesis_style)
    return rows, example


def toolbox_columns(rows: list) -> dict:
    """:func:`toolbox_comparison`'s rows as one array per key, over the seeds."""
    return {key: np.array([r[key] for r in rows]) for key in rows[0]}


def _mean_sd_text(values) -> str:
    return f"{values.mean():.4f} +- {values.std():.4f}"


def toolbox_rows(toolbox: dict, noise: float) -> list:
    """The toolbox comparison's table rows: setup, model, pixel error mean +- sd, largest marginal difference."""
    return [
        ["toolbox model, noisy image (max of node potentials)", "toolbox noise: X + randn/2",
         _mean_sd_text(toolbox["noisy"]), ""],
        ["toolbox model, crfmap LBP (converged)", "hidden [[1.35, 1], [1, 1.35]], identity link",
         _mean_sd_text(toolbox["crfmap"]), f"{toolbox['max_abs_difference'].max():.1e}"],
        ["toolbox model, reference_lbp (converged)", "same model, independent code", _mean_sd_text(toolbox["reference"]),
         "0 (itself)"],
        ["thesis-style pipeline (Fig. 22 -> 23)", f"noisy_image sigma {noise}, default tables, converged",
         _mean_sd_text(toolbox["thesis_style"]), ""],
        ["thesis's default tables on the toolbox's noisy image", "[[10, 1], [1, 10]], identity link, converged",
         _mean_sd_text(toolbox["thesis_tables_on_toolbox_input"]), ""],
    ]


def toolbox_summary(toolbox: dict, first_seed: int) -> dict:
    """The toolbox comparison's numbers: seeds, largest marginal difference, each pixel error's mean and sd."""
    summary = {"seeds": len(toolbox["seed"]), "first_seed": first_seed,
               "max_abs_difference": float(toolbox["max_abs_difference"].max())}
    summary.update({f"pixel_error_{key}_mean": float(toolbox[key].mean()) for key in TOOLBOX_KEYS})
    summary.update({f"pixel_error_{key}_sd": float(toolbox[key].std()) for key in TOOLBOX_KEYS})
    return summary


def baseline_makers() -> dict:
    """name -> grid -> grid: the 3x3 neighbour mean and, with PyMaxflow installed, the graph-cut MAP (default tables)."""
    from crfstudy.experiments import rooms

    makers = {"3x3 neighbour mean": rooms.neighbour_mean3}
    if rooms.graph_cut_available():
        from crfmap.assess.mincut import graph_cut_map

        def graph_cut(grid):
            return grid.with_probability(graph_cut_map(grid.probability, DEFAULT_HIDDEN, DEFAULT_LINK)[0].astype(float))

        makers["graph-cut MAP (default tables)"] = graph_cut
    return makers


def learner_tail(trace: list, share: float = 0.1) -> dict:
    """What the thesis's learner still did in the last ``share`` of its LBP runs.

    Returns the LBP runs after the start, how many steps of the tail were kept, and how far the best
    MSE fell in the tail (the best kept MSE before it minus the best overall).
    """
    tail_start = int((1 - share) * len(trace))
    tail = trace[tail_start:]
    best_before_tail = min(r["mse"] for r in trace[:max(tail_start, 1)] if r["accepted"])
    return {"lbp_runs": len(trace) - 1, "accepted_in_tail": int(sum(r["accepted"] for r in tail)),
            "mse_fall_in_tail": float(best_before_tail - min(r["mse"] for r in trace))}


# ---- figures ----------------------------------------------------------------------------------------------------------

def truth_figure(truth):
    """Fig. 20: the X's ground truth."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4, 4), layout="constrained")
    show_grid(ax, truth, "Fig. 20: ground truth (stroke occupied)", cells=True)
    return fig


def noisy_figure(test, train, truth, seed: int, train_seed: int):
    """Fig. 22: the test scan and the training scan, each with its MSE."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(8, 4), layout="constrained")
    show_grid(axes[0], test, f"Fig. 22: noisy scan (test, seed {seed})\nMSE {mse(test, truth):.4f}", cells=True)
    show_grid(axes[1], train, f"training scan (seed {train_seed})\nMSE {mse(train, truth):.4f}", cells=True)
    return fig


def lbp_figure(converged, two_iterations, truth):
    """Fig. 23: LBP with the default tables, converged and after 2 iterations of the thesis schedule."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(8, 4), layout="constrained")
    show_grid(axes[0], converged.beliefs, f"Fig. 23: converged ({converged.iterations} it.)\n"
                                          f"MSE {mse(converged.beliefs, truth):.4f}", cells=True)
    show_grid(axes[1], two_iterations.beliefs, f"thesis schedule, 2 iterations\n"
                                               f"MSE {mse(two_iterations.beliefs, truth):.4f}", cells=True)
    return fig


def learned_figure(applied: dict, truth):
    """Fig. 24: the test scan after LBP with each learner's tables (``applied``: run name -> LBP result)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(10, 9.4), layout="constrained")  # 2x2: a row of four left tiny panels
    for ax, (name, result) in zip(axes.ravel(), applied.items()):
        show_grid(ax, result.beliefs, f"{learner_name(name)}\ntest MSE {mse(result.beliefs, truth):.4f}", cells=True)
    fig.suptitle("Fig. 24: after LBP with learned tables (learned on the training scan, applied to the test scan)")
    return fig


def roc_figure(curves: dict):
    """Fig. 26: the ROC curves (label -> (fpr, tpr, auc)), whole and zoomed on the upper left."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5), layout="constrained")
    plot_roc(axes[0], curves, title="Fig. 26: ROC, occupied = positive")
    plot_roc(axes[1], curves, title="zoom on the upper left")
    axes[1].set_xlim(0, 0.2)
    axes[1].set_ylim(0.7, 1.005)
    return fig


def toolbox_figure(truth, example: tuple, toolbox_seed: int):
    """Fig. 21, 25: the toolbox's noisy X, its node potential, crfmap's and the reference's LBP, their difference."""
    import matplotlib.pyplot as plt

    x_noisy, observed, ours, ref, _ = example
    occupied = truth.probability > 0.5
    fig, axes = plt.subplots(2, 3, figsize=(13, 8.5), layout="constrained")
    show_grid(axes[0, 0], truth, "clean X (stroke occupied)", cells=True)
    im = axes[0, 1].imshow(x_noisy, cmap="gray", origin="lower", interpolation="nearest")
    axes[0, 1].set_title(f"Fig. 21 analogue: the toolbox's noisy X\n(X + randn/2, seed {toolbox_seed}; "
                         "white = background)")
    fig.colorbar(im, ax=axes[0, 1], fraction=0.046, pad=0.04)
    show_grid(axes[0, 2], observed, f"toolbox node potential of the stroke\n"
                                    f"pixel error {pixel_error(observed, occupied):.4f}", cells=True)
    show_grid(axes[1, 0], ours.beliefs, f"Fig. 25 analogue: crfmap LBP, toolbox model\n"
                                        f"pixel error {pixel_error(ours.beliefs.probability, occupied):.4f}", cells=True)
    show_grid(axes[1, 1], ref, f"reference_lbp, same model\npixel error {pixel_error(ref, occupied):.4f}", cells=True)
    diff = np.abs(ours.beliefs.probability - ref)
    im = axes[1, 2].imshow(np.log10(np.maximum(diff, 1e-17)), origin="lower", interpolation="nearest", cmap="viridis")
    axes[1, 2].set_title(f"log10 |crfmap - reference|\nmax {diff.max():.1e}")
    fig.colorbar(im, ax=axes[1, 2], fraction=0.046, pad=0.04)
    for ax in (axes[0, 1], axes[1, 2]):
        ax.set_xlabel("x [cells]")
        ax.set_ylabel("y [cells]")
    fig.suptitle("Fig. 21, 25: the UGM toolbox's hand-picked denoising model, run by crfmap and by an independent LBP")
    return fig
