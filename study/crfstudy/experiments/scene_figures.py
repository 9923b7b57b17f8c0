"""Panels of the simulated scenes (notebooks 05 and 06): a grid with the robot's start, the MSE landscape.

>>> import matplotlib.pyplot as plt
>>> from crfmap.world.scenes import enclosed_boxes
>>> scene = enclosed_boxes("train", size=20)
>>> fig, ax = plt.subplots()
>>> draw(ax, scene.truth, "truth", scene)
>>> len(ax.lines)  # the start marker
1
>>> plt.close(fig)
"""
from __future__ import annotations

import numpy as np

from crfmap.errors import InputError
from crfstudy.plotting import show_grid


def draw(ax, grid, title, scene=None) -> None:
    """``grid`` on ``ax`` under ``title``; with ``scene``, its robot's start as a red dot."""
    show_grid(ax, grid, title)
    if scene is not None:  # the robot's start
        ax.plot(scene.start[0], scene.start[1], marker="o", color="C3", markersize=7, markeredgecolor="white")


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
