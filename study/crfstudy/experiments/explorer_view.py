"""The explorer's figure, built once and then updated in place (notebook 08's live panel).

A widget change used to build a new figure, lay it out and encode it: ~1.5 s, of which LBP
was ~20 ms. Here the figure, its axes, ticks and labels are drawn once per scene extent
(the *background*); a change only swaps the data of the artists that depend on it (two
images, the bound's circle, the ROC lines, titles and legend) and redraws those onto a copy
of the background (Agg blitting), then encodes the pixels with Pillow's fastest PNG level.

- :class:`ExplorerView`: ``update(exploration)`` then ``png()``; ``live=False`` gives an
  ordinary figure (what :func:`crfstudy.experiments.explorer.draw` returns and notebooks save).

>>> from crfstudy.experiments.explorer import run
>>> view = ExplorerView()
>>> view.update(run("x", iterations=2)).png()[:4]
b'\\x89PNG'
>>> len(view.figure.axes)
4
"""
from __future__ import annotations

import io

import numpy as np

from crfstudy.plotting import OCCUPANCY_CMAP
from crfmap.assess.metrics import roc_curve

FIGSIZE = (17, 4.4)  # [inch] four panels side by side
DPI = 90  # what the explorer has always shown; 1530 x 396 pixels
PNG_LEVEL = 1  # zlib level: ~3x faster than matplotlib's default, files ~10 % larger


def _fmt(table):
    return "[" + ", ".join(f"{v:g}" for v in np.asarray(table).ravel()) + "]"


def _bounds(grid):
    """(left, right, bottom, top) [m] of a grid, for imshow(origin="lower")."""
    ox, oy, _ = grid.origin
    return (ox, ox + grid.width * grid.resolution, oy, oy + grid.height * grid.resolution)


def titles(ex) -> dict:
    """Every text of the figure that depends on the setting, by artist name."""
    s = ex.settings
    ob = ex.observation
    bound = "unbounded" if s["radius"] is None else f"radius {s['radius']:g} m"
    its = "to convergence" if s["iterations"] is None else f"{s['iterations']} iterations"
    return {
        "truth": f"truth: {s['scene']}",
        "before": f"before LBP ({ob.noise_kind} {ob.noise:g})\nMSE {ex.before.mse:.4f}",
        "after": f"after LBP: {ex.result.iterations} it., "
        f"{'converged' if ex.result.converged else 'not converged'}\nMSE {ex.after.mse:.4f}",
        "suptitle": ("" if s.get("preset", "custom") == "custom" else f"{s['preset']} preset: ")
        + f"hidden {_fmt(s['hidden'])}, link {_fmt(s['link'])}, {s['schedule']}, {its}, {bound}, "
        f"seed {s['seed']}",
    }


class ExplorerView:
    """Truth, observed grid, beliefs after LBP (bound outlined) and both ROC curves, updated in place.

    Parameters
    ----------
    live : bool
        True: the changing artists are drawn apart from the background (fast :meth:`png`);
        False: an ordinary figure (``savefig`` shows everything).
    dpi : int
        Pixels per inch of :meth:`png`.
    """

    def __init__(self, live: bool = True, dpi: int = DPI):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.live = live
        self.figure = Figure(figsize=FIGSIZE, dpi=dpi)
        self.canvas = FigureCanvasAgg(self.figure)
        self._layout_for = None  # (shape, bounds) the background was drawn for
        self._truth_shown = None  # the truth grid the background holds (a scene of the same extent may differ)
        self._background = None
        self._artists = {}
        self._build()

    # --- building (once) --------------------------------------------------------------------------
    def _build(self):
        from matplotlib.patches import Circle

        fig = self.figure
        axes = fig.subplots(1, 4, gridspec_kw={"width_ratios": [1, 1, 1, 1.05]})
        a = self._artists
        blank = np.full((2, 2), 0.5)
        for ax, name in zip(axes[:3], ("truth", "before", "after")):
            a[name] = ax.imshow(blank, cmap=OCCUPANCY_CMAP, vmin=0.0, vmax=1.0, origin="lower", interpolation="nearest")
            a[name + "_title"] = ax.set_title(" \n ")
            ax.set_xlabel("x [m]")
            ax.set_ylabel("y [m]")
        # bounded LBP covers the cells whose centres lie in this disc (crfmap.crf.inference.regions.disc_region)
        a["bound"] = axes[2].add_patch(Circle((0, 0), 1.0, fill=False, edgecolor="tab:red", linewidth=1.0,
                                              visible=False))
        (a["start"],) = axes[2].plot([0], [0], marker="o", color="tab:red", markersize=4, visible=False)
        roc = axes[3]
        (a["roc_before"],) = roc.plot([0, 1], [0, 1], label="before")
        (a["roc_after"],) = roc.plot([0, 1], [0, 1], label="after")
        roc.plot([0, 1], [0, 1], color="0.7", linestyle=":", linewidth=1)
        roc.set(xlabel="false positive rate", ylabel="true positive rate", xlim=(0, 1), ylim=(0, 1.01),
                title="ROC (occupied = positive)")
        a["legend"] = roc.legend(loc="lower right", fontsize="small")
        a["suptitle"] = fig.suptitle(" ", fontsize="medium")
        self.axes = axes
        if self.live:
            for name in self._dynamic():
                a[name].set_animated(True)

    @staticmethod
    def _dynamic():
        return ("before", "after", "bound", "start", "roc_before", "roc_after", "legend", "before_title",
                "after_title", "suptitle")

    def _layout(self, truth):
        """Lay out and draw the background for this scene's shape and extent (a scene change)."""
        from matplotlib.layout_engine import ConstrainedLayoutEngine

        bounds = _bounds(truth)
        for name in ("truth", "before", "after"):
            self._artists[name].set_extent(bounds)
        for ax in self.axes[:3]:
            ax.set_xlim(bounds[:2])
            ax.set_ylim(bounds[2:])
        ConstrainedLayoutEngine().execute(self.figure)  # once per scene, not on every redraw
        self._layout_for = (truth.shape, bounds)
        self._show_truth(truth)

    def _show_truth(self, truth):
        """Put ``truth`` in its panel and redraw the background that holds it (a scene change)."""
        self._artists["truth"].set_data(truth.probability)
        self._truth_shown = truth.probability.copy()
        if self.live:
            self.canvas.draw()  # the changing artists are animated: not in the background
            self._background = self.canvas.copy_from_bbox(self.figure.bbox)

    # --- updating (every change) ------------------------------------------------------------------
    def update(self, ex):
        """Show the exploration ``ex`` (a :class:`crfstudy.experiments.explorer.Exploration`); returns self."""
        truth = ex.truth
        a = self._artists
        a["before"].set_data(ex.observation.observed.probability)
        a["after"].set_data(ex.result.beliefs.probability)
        bounded = ex.settings["radius"] is not None  # the bound around the robot (not a preset's margin)
        a["bound"].set_visible(bounded)
        a["start"].set_visible(bounded)
        if bounded:
            sx, sy = ex.observation.scene.start[:2]
            a["bound"].set_center((sx, sy))
            a["bound"].set_radius(ex.settings["radius"])
            a["start"].set_data([sx], [sy])
        for (label, grid), line, text in zip((("before", ex.observation.observed), ("after", ex.result.beliefs)),
                                             (a["roc_before"], a["roc_after"]), a["legend"].get_texts()):
            fpr, tpr, _ = roc_curve(grid, truth)
            line.set_data(fpr, tpr)
            text.set_text(f"{label} (AUC {getattr(ex, label).auc:.3f})")
        for name, text in titles(ex).items():
            a[name if name == "suptitle" else name + "_title"].set_text(text)
        if self._layout_for != (truth.shape, _bounds(truth)):
            self._layout(truth)
        elif not np.array_equal(self._truth_shown, truth.probability):  # another scene of the same extent
            self._show_truth(truth)
        if self.live:
            self._blit()
        return self

    def _blit(self):
        self.canvas.restore_region(self._background)
        names = self._dynamic()
        split = names.index("legend")  # in z-order: images and lines, the axes frames, then texts
        frames = [spine for ax in self.axes[1:] for spine in ax.spines.values()]
        for artist in [self._artists[n] for n in names[:split]] + frames + [self._artists[n] for n in names[split:]]:
            if artist.get_visible():
                self.figure.draw_artist(artist)

    def png(self) -> bytes:
        """The figure as PNG bytes (live: the pixels drawn by the last :meth:`update`)."""
        from PIL import Image

        if not self.live:
            self.canvas.draw()
        size = self.canvas.get_width_height()
        # no copy of the RGBA buffer; Pillow drops alpha in C (half the time of a NumPy slice + copy)
        image = Image.frombuffer("RGBA", size, self.canvas.buffer_rgba(), "raw", "RGBA", 0, 1).convert("RGB")
        buffer = io.BytesIO()
        image.save(buffer, format="PNG", compress_level=PNG_LEVEL)
        return buffer.getvalue()
