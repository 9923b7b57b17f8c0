"""What the interactive explorer (notebook 08) computes and draws, as plain functions.

One call runs one setting end to end: make a scene, observe it (image noise on the X, or a
simulated robot with range noise elsewhere), run LBP with a preset (:mod:`crfmap.crf.presets`,
:data:`~crfmap.crf.presets.DEFAULT_PRESET` unless told) or with tables of one's own, a schedule, a
number of iterations and a bound, and draw truth / before / after / ROC. The notebook wires widgets to
:func:`explore`; nothing here waits for input, so it runs headless too.

- :func:`observe`: the scene's truth and its observed grid (cached: moving a table slider does
  not re-simulate the robot).
- :func:`run`: LBP on the observation, with the metrics before and after.
- :func:`draw` / :func:`explore`: the figure (a :class:`matplotlib.figure.Figure`, not a pyplot
  one, so a widget redrawing it many times leaks nothing).
- :func:`warm_up`: compile (or load from numba's cache) every schedule's kernels on a tiny grid,
  so the first switch to a schedule does not stall the panel (:mod:`crfstudy.experiments.explorer_panel`).
- :func:`panel`: that panel of widgets, wired to :func:`run` (what notebook 08 displays).

>>> ex = run("x", noise=0.42, seed=0)
>>> bool(ex.after.mse < ex.before.mse)
True
"""
from __future__ import annotations

import io
from dataclasses import dataclass, field
from functools import lru_cache
import time

import numpy as np

from crfmap.checks import check_int, check_number, check_positive
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.regions import disc_region
from crfmap.crf.inference.result import LBPResult
from crfmap.crf.inference.schedules import SCHEDULES, Checkerboard
from crfmap.assess.metrics import Report, evaluate
from crfmap.crf.presets import DEFAULT_PRESET, Preset, custom_preset, get_preset
from crfmap.world import scenes
from crfmap.world.office import office_floor
from crfmap.mapping.builder import build_grid
from crfmap.sim.simulator import simulate
from crfstudy.experiments.explorer_view import ExplorerView

EXPLORER_SCENES = ("x", "occluded-train", "occluded-test", "enclosed-train", "enclosed-test",
                   "hollow-train", "hollow-test", "office")
DEFAULT_NOISE = 0.42  # sigma of the X image's Gaussian noise: a noisy MSE near the thesis's 0.0825
OFFICE_SIZE = (8.0, 6.0)  # [m] width, height of the explorer's office: small enough to redraw live
OFFICE_RESOLUTION = 0.1  # [m/cell]
TO_CONVERGENCE = 1000  # iterations cap when "to convergence" is asked for
TOLERANCE = 1e-5  # largest message change that counts as converged
# the explorer's grids have a few thousand cells: one thread is as fast, and never waits at a
# parallel barrier for a second core that other work is using (seen as 0.2-1 s stalls)
THREADS = 1
_WARMED = set()  # (schedule, bounded, kernel) that ran in this process: their kernels are compiled


@dataclass
class Observation:
    """A scene's truth and what the robot (or the noisy scan) made of it."""

    scene: object  # crfmap.world.scene.Scene
    observed: OccupancyGrid
    noise: float
    noise_kind: str  # "image sigma" (the X) or "range C [m]" (simulated scenes)
    seed: int


@dataclass
class Exploration:
    """One run of the explorer: the observation, LBP's result and the metrics before and after."""

    observation: Observation
    result: LBPResult
    before: Report
    after: Report
    region: np.ndarray | None
    settings: dict = field(default_factory=dict)

    @property
    def truth(self) -> OccupancyGrid:
        return self.observation.scene.truth


def _check_scene(scene):
    if scene not in EXPLORER_SCENES:
        raise InputError("scene", f"must be one of {', '.join(EXPLORER_SCENES)}, got {scene!r}")
    return scene


def _check_noise(noise):
    return check_number("noise", noise, low=0.0)


def _check_seed(seed):
    return check_int("seed", seed, low=0)


@lru_cache(maxsize=32)
def _observe(scene, noise, seed):
    if scene == "x":
        made = scenes.x_image()
        return Observation(made, scenes.noisy_image(made.truth, noise, seed=seed), noise, "image sigma", seed)

    if scene == "office":
        made = office_floor(*OFFICE_SIZE, resolution=OFFICE_RESOLUTION, seed=seed)
    else:
        made = scenes.make_scene(scene)
    truth = made.truth
    recording = simulate(made, seed=seed, range_noise=noise, progress=False)
    observed = build_grid(recording.scans, truth.resolution, bounds=truth.bounds())
    return Observation(made, observed, noise, "range C [m]", seed)


def observe(scene="x", noise=DEFAULT_NOISE, seed=0) -> Observation:
    """The truth of ``scene`` and its observed grid.

    ``"x"``: the UGM X with Gaussian image noise of sigma ``noise`` (:func:`crfmap.world.scenes.noisy_image`).
    Every other scene: the robot simulated in the scene's default mode with range noise
    ``+-C``, C ~ U[0, ``noise``] [m], and the thesis's arctan grid built over the truth's bounds.
    ``"office"`` is an 8 m x 6 m floor at 0.1 m whose layout is drawn from ``seed``.
    Results are cached (treat them as read-only).

    >>> ob = observe("enclosed-train", noise=0.0)
    >>> ob.observed.shape == ob.scene.truth.shape, bool((ob.observed.probability == 0.5).any())
    (True, True)
    """
    return _observe(_check_scene(scene), _check_noise(noise), _check_seed(seed))


def _check_iterations(iterations):
    if iterations is None:
        return TO_CONVERGENCE
    return check_int("iterations", iterations, low=0)


def _check_radius(radius):
    if radius is None:
        return None
    return check_positive("radius", radius)


def explorer_preset(preset=DEFAULT_PRESET, hidden=None, link=None) -> Preset:
    """The CRF the explorer runs: ``preset`` (a name or a :class:`~crfmap.crf.presets.Preset`), or,
    when tables are given, exactly those tables on the grid's P (a custom preset; a missing one: the
    preset's).

    >>> explorer_preset().name == DEFAULT_PRESET, explorer_preset(hidden=[[10, 1], [1, 10]]).name
    (True, 'custom')
    """
    base = preset if isinstance(preset, Preset) else get_preset(preset)
    if hidden is None and link is None:
        return base
    return custom_preset(base.hidden if hidden is None else hidden, base.link if link is None else link)


def run(scene="x", noise=DEFAULT_NOISE, hidden=None, link=None, schedule="checkerboard",
        iterations=None, radius=None, seed=0, preset=DEFAULT_PRESET) -> Exploration:
    """Observe ``scene`` and run LBP on it with these settings.

    Parameters
    ----------
    scene : one of :data:`EXPLORER_SCENES`
    noise : image sigma (``"x"``) or range noise bound C [m] (other scenes)
    hidden, link : 2x2 tables (rows C1 C0, columns N1 N0): LBP with exactly these on the grid's P; None
        (both): ``preset``'s CRF (see :func:`explorer_preset`)
    schedule : one of :data:`crfmap.crf.inference.schedules.SCHEDULES`
    iterations : int, or None to run to convergence (max message change < 1e-5)
    radius : None, or bounded LBP (sec. 3.4.4): only cells within ``radius`` [m] of the robot's
        start send messages
    seed : int, noise (and office layout) seed
    preset : a name of :data:`crfmap.crf.presets.PRESETS` (default ``DEFAULT_PRESET``) or a Preset

    Returns
    -------
    Exploration
    """
    ob = observe(scene, noise, seed)
    crf = explorer_preset(preset, hidden, link)
    if schedule not in SCHEDULES:
        raise InputError("schedule", f"must be one of {', '.join(SCHEDULES)}, got {schedule!r}")
    max_iter = _check_iterations(iterations)
    radius = _check_radius(radius)
    bound = None if radius is None else disc_region(ob.observed, ob.scene.start[:2], radius)
    result = crf.refine(ob.observed, within=bound, schedule=schedule, max_iter=max_iter, tol=TOLERANCE,
                        threads=THREADS)
    region = crf.region(ob.observed.probability != 0.5)
    region = bound if region is None else region if bound is None else region & bound
    _WARMED.add((schedule, region is not None, result.kernel))
    truth = ob.scene.truth
    settings = {"scene": scene, "noise": ob.noise, "noise_kind": ob.noise_kind, "preset": crf.name,
                "hidden": crf.hidden.tolist(), "link": crf.link.tolist(), "schedule": schedule,
                "iterations": iterations, "radius": radius, "seed": seed}
    return Exploration(ob, result, evaluate(ob.observed, truth), evaluate(result.beliefs, truth), region, settings)


def warmed() -> frozenset:
    """(schedule, bounded, kernel) combinations whose LBP kernels already ran in this process."""
    return frozenset(_WARMED)


WARM_UP_SIZE = 48  # [cells] per side of the warm-up grid: big enough to take every kernel's code path


def warm_up(schedules=SCHEDULES, on_schedule=None) -> dict:
    """Compile (or load from numba's on-disk cache) every LBP kernel the explorer can call.

    The first call of a numba kernel in a process compiles it (tens of seconds with an empty
    cache) or loads it from the cache; doing that here, on a tiny grid, keeps a later switch of
    the schedule control from stalling the panel and from counting compilation as run time.
    Each schedule runs unbounded and bounded; the checkerboard also on the plain kernel (tables
    the fast kernel cannot take fall back to it).

    Parameters
    ----------
    schedules : schedules to warm up
    on_schedule : callable(schedule, index, total) or None, called before each schedule

    Returns
    -------
    dict
        schedule -> seconds its warm-up took (compilation or cache loading, plus a few iterations)

    >>> sorted(warm_up(["thesis"]))
    ['thesis']
    """
    rng = np.random.default_rng(0)
    grid = OccupancyGrid(rng.uniform(0.05, 0.95, (WARM_UP_SIZE, WARM_UP_SIZE)), resolution=0.1)
    inner = np.zeros(grid.shape, dtype=bool)
    inner[WARM_UP_SIZE // 4:-WARM_UP_SIZE // 4, WARM_UP_SIZE // 4:-WARM_UP_SIZE // 4] = True
    seconds = {}
    for k, schedule in enumerate(schedules):
        if on_schedule is not None:
            on_schedule(schedule, k, len(schedules))
        t0 = time.perf_counter()
        kernels = ("auto", "plain") if schedule == "checkerboard" else ("auto",)
        for kernel in kernels:
            for region in (None, inner):
                settings = Checkerboard(kernel=kernel) if schedule == "checkerboard" else schedule
                r = infer(grid, schedule=settings, max_iter=2, tol=TOLERANCE, region=region, threads=THREADS)
                _WARMED.add((schedule, region is not None, r.kernel))
        seconds[schedule] = time.perf_counter() - t0
    # a table with zero entries spreads certainty from exact 0/1 cells (crfmap.crf.model.evidence): compile that too
    certain = grid.probability.copy()
    certain[0, 0] = 1.0
    for region in (None, inner):
        infer(OccupancyGrid(certain, resolution=0.1), hidden=[[1.0, 0.0], [0.0, 1.0]], max_iter=2, tol=TOLERANCE,
              region=region, threads=THREADS)
    return seconds


def draw(ex: Exploration):
    """Truth, observed grid, grid after LBP (bound outlined) and both ROC curves, in one figure.

    An ordinary :class:`matplotlib.figure.Figure`; the live panel updates one figure in place
    instead (:class:`crfstudy.experiments.explorer_view.ExplorerView`).
    """
    return ExplorerView(live=False).update(ex).figure


def explore(scene="x", noise=DEFAULT_NOISE, hidden=None, link=None, schedule="checkerboard",
            iterations=None, radius=None, seed=0, preset=DEFAULT_PRESET):
    """:func:`run` then :func:`draw`: the explorer's figure for one setting.

    >>> fig = explore("x", iterations=2, schedule="thesis")
    >>> len(fig.axes)  # truth, before, after, ROC
    4
    """
    return draw(run(scene, noise, hidden, link, schedule, iterations, radius, seed, preset))


def to_png(fig, dpi: int = 90) -> bytes:
    """The figure as PNG bytes (for ``IPython.display.Image``, whatever matplotlib backend is active)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    return buffer.getvalue()


def panel(scene="x", image_noise=DEFAULT_NOISE, range_noise=0.0, schedule="checkerboard", iterations=None,
          radius=None, seed=0, preset=DEFAULT_PRESET):
    """The explorer's widget panel (:class:`crfstudy.experiments.explorer_panel.ExplorerPanel`) for this setting.

    Imported here on first use: the panel module imports this one, and ipywidgets is only needed live.
    """
    from crfstudy.experiments.explorer_panel import ExplorerPanel

    return ExplorerPanel(scene, image_noise, range_noise, schedule, iterations, radius, seed, preset)
