"""The thesis's worked example (sec. 3.4.2) and first learning steps (sec. 3.5), notebook 02's helper.

The 2x2 CRF of Fig. 18 is four cells C1..C4 on a 2x2 grid; a *layout* maps each cell name to its
(y, x) (row 0 = lowest y), and observation node 4 + i belongs to cell C_i (the thesis's delta_(4+i)->i).
:func:`observed_grid` places the observations, :func:`incoming` reads one message of an LBP result
by sender and receiver, :func:`slip_beliefs` recomputes B1 and B4 with the thesis's misprinted
0.24, and the figure functions draw the example and the learners' runs (each returns a Figure; the
notebook saves it). :func:`exact_marginals` (the brute-force reference of ``crfstudy.references``)
is re-exported here: it is the honest reference the notebook compares converged LBP with.

>>> layout = {"C1": (0, 0), "C4": (0, 1), "C2": (1, 0), "C3": (1, 1)}
>>> observed_grid(layout, {5: 0.6, 6: 0.8, 7: 0.3, 8: 0.4}).tolist()
[[0.6, 0.4], [0.8, 0.3]]
"""
from __future__ import annotations

import numpy as np

from crfmap.assess import mse
from crfmap.crf import message
from crfmap.errors import InputError
from crfmap.crf.model.potentials import TO_EAST, TO_NORTH, TO_SOUTH, TO_WEST
from crfstudy.plotting import show_grid
from crfstudy.references import exact_marginals

__all__ = ["exact_marginals", "incoming", "learning_grids_figure", "learning_trace_figure", "observed_grid",
           "slip_beliefs", "table_text", "worked_example_figure"]

# the slot a message is stored in at its receiver, by the step (dy, dx) from sender to receiver
_SLOT = {(0, 1): TO_EAST, (0, -1): TO_WEST, (1, 0): TO_NORTH, (-1, 0): TO_SOUTH}


def observed_grid(layout: dict, observation: dict) -> np.ndarray:
    """The 2x2 grid of P(occupied): cell C_i (at ``layout["C_i"]``) holds observation node 4 + i's value."""
    grid = np.empty((2, 2))
    for cell, yx in layout.items():
        grid[yx] = observation[4 + int(cell[1])]
    return grid


def incoming(messages, layout: dict, sender: str, receiver: str) -> float:
    """P(occupied) of the message ``sender`` -> ``receiver`` in an LBP result's ``messages``.

    ``infer`` stores a message at its receiver, in the slot of the direction it travels; the two cells
    must be 4-neighbours.
    """
    (sy, sx), (ry, rx) = layout[sender], layout[receiver]
    step = (ry - sy, rx - sx)
    if step not in _SLOT:
        raise InputError("sender", f"{sender} and {receiver} are not neighbours in the layout")
    return float(messages[_SLOT[step], ry, rx])


def _normalise(occupied, empty):
    return occupied / (occupied + empty)


def slip_beliefs(d21, d41, d51, d34, d84, hidden, slip=0.24) -> tuple:
    """B1, delta_1->4(O) and B4 as the thesis would get them with delta_2->1(E) printed as ``slip``.

    The thesis prints delta_2->1(E) = 0.26 (= 1 - 0.74) and then multiplies with 0.24. B1 multiplies
    the three messages into C1; C1's message to C4 is its cavity belief without C4 (from C2 and
    observation 5) sent through ``hidden``; B4 multiplies that with delta_3->4 and delta_8->4.
    """
    b1 = _normalise(d21 * d41 * d51, slip * (1 - d41) * (1 - d51))
    d14 = message(hidden, _normalise(d21 * d51, slip * (1 - d51)))
    b4 = _normalise(d14 * d34 * d84, (1 - d14) * (1 - d34) * (1 - d84))
    return b1, d14, b4


def worked_example_figure(observed: np.ndarray, layout: dict, one_pass, arrows):
    """Fig. 18, 19: the observations per cell, and the beliefs after one pass with the messages drawn.

    ``arrows``: (sender, receiver, P(occupied)) of each message to draw, offset to the right of its
    edge so the two messages of one edge do not overlap.
    """
    import matplotlib.pyplot as plt

    from crfmap import OccupancyGrid

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.6), layout="constrained")
    ax = axes[0]
    show_grid(ax, OccupancyGrid(observed), "Fig. 18: the 2x2 CRF, layout A (observations)", cells=True, colorbar=True)
    for cell, (y, x) in layout.items():
        p = observed[y, x]
        ax.text(x, y, f"{cell}\nobs {4 + int(cell[1])}: {p:.1f}", ha="center", va="center",
                color="white" if p > 0.5 else "black", fontsize=11)
    ax = axes[1]
    show_grid(ax, one_pass.beliefs, "Fig. 19: beliefs after one pass, messages into C1 and C4", cells=True,
              colorbar=True)
    for cell, (y, x) in layout.items():
        p = one_pass.beliefs.probability[y, x]
        ax.text(x, y + (0.3 if y else -0.3), f"{cell}: {p:.3f}", ha="center", va="center",
                color="white" if p > 0.5 else "black")
    for sender, receiver, value in arrows:
        (sy, sx), (ry, rx) = layout[sender], layout[receiver]
        d = np.array([rx - sx, ry - sy], dtype=float)  # direction of travel (x, y)
        n = np.array([d[1], -d[0]])  # to its right
        start = np.array([sx, sy]) + 0.3 * d + 0.08 * n
        end = np.array([rx, ry]) - 0.3 * d + 0.08 * n
        ax.annotate("", xy=end, xytext=start, arrowprops=dict(arrowstyle="-|>", color="C1", lw=2))
        ax.text(*((start + end) / 2 + 0.17 * n), f"{value:.3f}", color="C1", ha="center", va="center", fontsize=10,
                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.85))
    for ax in axes:
        ax.set_xticks([0, 1])
        ax.set_yticks([0, 1])
    return fig


def table_text(table) -> str:
    """A 2x2 table on one line, three significant digits: ``[[10, 1], [1, 10]]``."""
    return "[[" + ", ".join(f"{v:.3g}" for v in table[0]) + "], [" + ", ".join(f"{v:.3g}" for v in table[1]) + "]]"


def learning_trace_figure(thesis_run, gradient_run, pl_run):
    """Tables 7-9 as curves: each LBP run of the thesis's learner, each gradient step, the pseudo-likelihood."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4), layout="constrained")
    ax = axes[0]
    steps = np.array([r["step"] for r in thesis_run.trace])
    tried = np.array([r["mse"] for r in thesis_run.trace])
    kept = np.array([r["accepted"] for r in thesis_run.trace])
    ax.plot(steps[~kept], tried[~kept], ".", color="0.6", label="step tried, not kept")
    ax.plot(steps[kept], tried[kept], ".", color="C0", label="step kept")
    ax.plot(steps, np.minimum.accumulate(tried), color="C0", linewidth=1)
    ax.set(xlabel="LBP run", ylabel="MSE after LBP", title="thesis's learner (alpha = 0.01)")
    ax.legend(fontsize="small")
    ax = axes[1]
    g_steps = np.array([r["step"] for r in gradient_run.trace])
    g_mse = np.array([r["mse"] for r in gradient_run.trace])
    g_kept = np.array([r["accepted"] for r in gradient_run.trace])
    ax.plot(g_steps[~g_kept], g_mse[~g_kept], ".", color="0.6", label="step tried, not kept")
    ax.plot(g_steps[g_kept], g_mse[g_kept], "o-", color="C1", markersize=3, label="step kept")
    ax.set(xlabel="gradient step (16 LBP runs each)", ylabel="MSE after LBP", title="gradient learner")
    ax.legend(fontsize="small")
    ax = axes[2]
    ax.plot([r["step"] for r in pl_run.trace], [r["objective"] for r in pl_run.trace], color="C2")
    ax.set(xlabel="step", ylabel="mean log pseudo-likelihood", title="pseudo-likelihood learner (no LBP inside)")
    fig.suptitle("Tables 7-9: learning on the toy scene")
    return fig


def learning_grids_figure(truth, observed, beliefs: dict):
    """Truth, the noisy grid and LBP's beliefs under each table set (``beliefs``: label -> grid), MSE in titles.

    Two rows of three panels, a colour bar at the end of each row (a row of six left each panel tiny).
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(11, 7.4), layout="constrained")
    axes = axes.ravel()
    show_grid(axes[0], truth, "truth", cells=True, colorbar=False)
    show_grid(axes[1], observed, f"noisy, MSE {mse(observed, truth):.4f}", cells=True, colorbar=False)
    for k, (ax, (label, grid)) in enumerate(zip(axes[2:], beliefs.items()), start=2):
        show_grid(ax, grid, f"LBP, {label}: {mse(grid, truth):.4f}", cells=True, colorbar=k % 3 == 2)
    return fig
