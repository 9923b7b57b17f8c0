"""The explorer's widget panel (notebook 08): controls, a status line and one image updated in place.

A change of any control runs :func:`crfstudy.experiments.explorer.run` and redraws the one
persistent figure (:class:`crfstudy.experiments.explorer_view.ExplorerView`) into an
``ipywidgets.Image``: no new figure, no cleared output. :meth:`ExplorerPanel.warm_up` compiles
every schedule's kernels once, saying so in the status line ("compiling LBP kernels (first run
only)"), so switching the schedule later does not stall; the status line reports LBP time and
drawing time apart, and flags a run that had to compile.

Widgets work without a browser (setting ``.value`` calls the handler at once), so the panel runs
headless: the benchmark (:mod:`crfstudy.bench.explorer`) times real widget changes.

>>> panel = ExplorerPanel()
>>> _ = panel.redraw()
>>> panel.controls["h_oo"].value = 8.0
>>> panel.timings[-1]["change"], bytes(panel.image.value[:4])
('h_oo', b'\\x89PNG')
"""
from __future__ import annotations

import time

import numpy as np

from crfmap.crf.inference.schedules import SCHEDULES
from crfmap.crf.presets import DEFAULT_PRESET, PRESETS, get_preset
from crfstudy.experiments import explorer
from crfstudy.experiments.explorer_view import ExplorerView

ITERATION_CHOICES = (1, 2, 3, 5, 10, 20, 50, 100)
CONVERGE = "to convergence"  # the iterations control's None (a Dropdown's None means "nothing selected")
ENTRIES = ("oo", "oe", "eo", "ee")  # rows C1 C0 (receiver), columns N1 N0 (neighbour / observation)
CUSTOM = "custom tables"  # the preset control's value once a table slider moved: exactly the sliders' tables


class ExplorerPanel:
    """The explorer's controls wired to one in-place figure (display ``widget``, then call
    :meth:`warm_up` and :meth:`redraw` once).

    Parameters are the initial setting (as :func:`crfstudy.experiments.explorer.run`), with the
    X's image noise and the simulated scenes' range noise apart (each scene uses its own). The panel starts
    from ``preset`` (:data:`~crfmap.crf.presets.DEFAULT_PRESET`); moving a table slider runs exactly
    the sliders' tables (the preset control then reads "custom tables"), choosing a preset sets the sliders
    to its tables.
    ``widget`` is the panel to display; ``controls`` maps names to widgets; ``timings`` holds one
    dict per redraw (``change``, ``seconds`` from the change to the new PNG, ``lbp_seconds``,
    ``compiled``: the run's kernels were not warm).
    """

    def __init__(self, scene="x", image_noise=explorer.DEFAULT_NOISE, range_noise=0.0, schedule="checkerboard",
                 iterations=None, radius=None, seed=0, preset=DEFAULT_PRESET):
        import ipywidgets as w

        start = get_preset(preset)

        slider = {"continuous_update": False, "style": {"description_width": "initial"}}
        c = {"scene": w.Dropdown(options=list(explorer.EXPLORER_SCENES), value=scene, description="scene"),
             "image_noise": w.FloatSlider(value=image_noise, min=0.0, max=1.0, step=0.01,
                                          description="X: image sigma", **slider),
             "range_noise": w.FloatSlider(value=range_noise, min=0.0, max=0.5, step=0.01,
                                          description="others: range C [m]", **slider),
             "preset": w.Dropdown(options=list(PRESETS) + [CUSTOM], value=start.name, description="preset")}
        for n, v in zip(ENTRIES, start.hidden.ravel()):
            c[f"h_{n}"] = w.FloatSlider(value=float(v), min=0.0, max=20.0, step=0.1, description=f"hidden {n}",
                                        **slider)
        for n, v in zip(ENTRIES, start.link.ravel()):
            c[f"l_{n}"] = w.FloatSlider(value=float(v), min=0.0, max=1.0, step=0.01, description=f"link {n}",
                                        **slider)
        c["schedule"] = w.Dropdown(options=list(SCHEDULES), value=schedule, description="schedule")
        options = [CONVERGE] + [str(k) for k in sorted(set(ITERATION_CHOICES) | ({iterations} - {None}))]
        c["iterations"] = w.Dropdown(options=options, value=CONVERGE if iterations is None else str(iterations),
                                     description="iterations")
        c["radius"] = w.FloatSlider(value=radius or 0.0, min=0.0, max=8.0, step=0.1,
                                    description="radius [m] (0 = all)", **slider)
        c["seed"] = w.BoundedIntText(value=seed, min=0, max=10_000, description="seed")
        self.controls = c
        self.status = w.HTML()
        self.image = w.Image(format="png")
        reset = w.Button(description=f"{DEFAULT_PRESET} preset")
        reset.on_click(lambda _: self.reset_tables())
        self.widget = w.VBox([
            w.HBox([c["scene"], c["image_noise"], c["range_noise"], c["seed"]]),
            w.HBox([w.VBox([c[f"h_{n}"] for n in ENTRIES]), w.VBox([c[f"l_{n}"] for n in ENTRIES]),
                    w.VBox([c["preset"], c["schedule"], c["iterations"], c["radius"], reset])]),
            self.status,
            self.image,
        ])
        self.view = ExplorerView()
        self.timings = []
        self._seen = set()  # observations simulated in this process
        self._batch = False
        for name, control in c.items():
            control.observe(lambda change, name=name: self._changed(name), names="value")

    # --- settings ---------------------------------------------------------------------------------
    def settings(self) -> dict:
        """The controls' values as :func:`crfstudy.experiments.explorer.run`'s arguments."""
        v = {name: control.value for name, control in self.controls.items()}
        custom = v["preset"] == CUSTOM
        return dict(scene=v["scene"], noise=v["image_noise"] if v["scene"] == "x" else v["range_noise"],
                    hidden=[[v["h_oo"], v["h_oe"]], [v["h_eo"], v["h_ee"]]] if custom else None,
                    link=[[v["l_oo"], v["l_oe"]], [v["l_eo"], v["l_ee"]]] if custom else None,
                    schedule=v["schedule"], iterations=None if v["iterations"] == CONVERGE else int(v["iterations"]),
                    radius=v["radius"] if v["radius"] > 0 else None, seed=int(v["seed"]),
                    preset=DEFAULT_PRESET if custom else v["preset"])

    def reset_tables(self, preset=DEFAULT_PRESET):
        """Back to ``preset`` (its tables on the sliders), redrawn once (not once per slider)."""
        self._batch = True
        try:
            self.controls["preset"].value = preset
            self._show_tables(get_preset(preset))
        finally:
            self._batch = False
        self._changed(f"{preset} preset")

    def _show_tables(self, crf):
        for name, value in zip([f"h_{n}" for n in ENTRIES] + [f"l_{n}" for n in ENTRIES],
                               np.r_[crf.hidden.ravel(), crf.link.ravel()]):
            self.controls[name].value = float(value)

    # --- compiling and redrawing ------------------------------------------------------------------
    def warm_up(self) -> dict:
        """Compile (first run) or load every schedule's kernels, showing it in the status line."""
        def say(schedule, k, total):
            self.status.value = (f"<b>compiling LBP kernels (first run only)</b>: {schedule} ({k + 1}/{total}); "
                                 "later runs load them from numba's cache")

        seconds = explorer.warm_up(on_schedule=say)
        self.status.value = (f"LBP kernels ready ({sum(seconds.values()):.1f} s: "
                             + ", ".join(f"{s} {t:.1f} s" for s, t in seconds.items()) + ")")
        return seconds

    def _changed(self, name):
        if self._batch:
            return
        self._batch = True  # the preset control and the sliders follow each other without redrawing
        try:
            if name == "preset" and self.controls["preset"].value != CUSTOM:
                self._show_tables(get_preset(self.controls["preset"].value))
            elif name[:2] in ("h_", "l_"):
                self.controls["preset"].value = CUSTOM
        finally:
            self._batch = False
        self.redraw(name)

    def redraw(self, change="initial"):
        """Run the current setting and update the figure in place; returns the Exploration (or None)."""
        s = self.settings()
        t0 = time.perf_counter()
        observed = (s["scene"], s["noise"], s["seed"])
        if s["scene"] != "x" and observed not in self._seen:
            self.status.value = f"simulating the robot in {s['scene']} (first use of this scene, noise and seed) ..."
        warm = explorer.warmed()
        if not any(k[:2] == (s["schedule"], s["radius"] is not None) for k in warm):
            self.status.value = f"<b>compiling LBP kernels for {s['schedule']} (first run only)</b> ..."
        try:
            ex = explorer.run(**s)
        except ValueError as err:  # InputError: e.g. a table row set to all zeros
            self.status.value = f"<span style='color:#b00'>{err}</span>"
            return None
        self._seen.add(observed)
        cold = (s["schedule"], ex.region is not None, ex.result.kernel) not in warm
        t1 = time.perf_counter()
        self.image.value = self.view.update(ex).png()
        t2 = time.perf_counter()
        kernels = ex.result.timings.get("compile", 0.0)  # kept out of ex.result.seconds by infer
        lbp = f"LBP {ex.result.seconds * 1e3:.0f} ms" + (
            f" (+ {kernels:.1f} s compiling or loading its kernels: first run)" if cold and kernels else "")
        self.status.value = (f"{ex.result.summary()}; MSE {ex.before.mse:.4f} -> {ex.after.mse:.4f}, "
                             f"accuracy {ex.before.accuracy:.3f} -> {ex.after.accuracy:.3f}; {lbp}, "
                             f"drawing {(t2 - t1) * 1e3:.0f} ms")
        self.timings.append({"change": change, "seconds": t2 - t0, "run_seconds": t1 - t0,
                             "draw_seconds": t2 - t1, "lbp_seconds": ex.result.seconds, "compiled": cold})
        return ex
