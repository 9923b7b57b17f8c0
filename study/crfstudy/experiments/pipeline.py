"""The simulated experiments of thesis sec. 4.1.2: scan a scene, build its grid, run LBP, score it.

One pipeline serves the occlusion (sec. 4.1.2) and enclosed-environment (sec. 4.1.2.1)
experiments:

1. :func:`scan_scene`: simulate the robot in a scene (perfect odometry and ranges by default,
   as in the thesis) and build the arctan grid (eq. 16) over exactly the truth's cells.
2. :func:`evaluate_pipeline`: LBP with given tables on that grid, scored against the truth
   (MSE, precision, recall, accuracy, AUC; :mod:`crfmap.assess.metrics`).
3. :func:`train_and_test`: learn tables on a TRAIN environment with each learner and each
   LBP setting, and apply them to a TEST environment beside the default tables.

:func:`search_tables` and :func:`learn_search_gradient` are our extra learner: a coarse grid
search over the strength of a symmetric hidden table and the bias of the link table, then the
gradient learner from the best point. It exists because, from the default tables, converged LBP
sits on a plateau of the MSE (the beliefs are saturated), where the thesis's steps of 0.01 and
a local gradient both stall.

>>> from crfmap.world.scenes import enclosed_boxes
>>> observed, recording = scan_scene(enclosed_boxes("train", size=20), drive="look", progress=False)
>>> observed.shape, recording.scans.ranges.shape
((20, 20), (1, 360))
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from crfmap.mapping.builder import build_grid
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.result import LBPResult
from crfmap.assess.learning import LearningResult, check_pair, learn_gradient, lbp_mse, rescale
from crfmap.assess.metrics import Report, evaluate, roc_curve
from crfmap.crf.model.potentials import check_table, DEFAULT_HIDDEN, DEFAULT_LINK
from crfmap.recording import Recording
from crfmap.world.scene import Scene
from crfmap.sim.simulator import simulate

# LBP on these 40 x 40 grids: one numba thread is faster than several (the work per
# iteration is tiny) and keeps timings steady on a shared machine.
TO_CONVERGENCE = {"threads": 1}
THESIS_TWO_ITERATIONS = {"schedule": "thesis", "max_iter": 2}  # the thesis's setting (sec. 4.1)
SEARCH_STRENGTHS = (1.5, 2.0, 3.0, 5.0, 10.0)  # hidden [[a, 1], [1, a]]; 10 = the default
SEARCH_BIASES = (0.5, 0.8, 1.0, 1.25, 2.0)  # link [[1, 0], [0, b]]; b > 1 leans unseen cells to empty


def truth_bounds(truth: OccupancyGrid) -> tuple:
    """(xmin, ymin, xmax, ymax) [m] of an unrotated grid, to build another grid over the same cells.

    >>> truth_bounds(OccupancyGrid(np.zeros((2, 3)), 0.5, origin=(1.0, 2.0, 0.0)))
    (1.0, 2.0, 2.5, 3.0)
    """
    if not isinstance(truth, OccupancyGrid):
        raise InputError("truth", f"expected an OccupancyGrid, got {type(truth).__name__}")
    if truth.origin[2] != 0.0:
        raise InputError("truth", f"the grid is rotated (origin yaw {truth.origin[2]:g} rad); need yaw 0")
    return truth.bounds()


def scan_scene(scene: Scene, laser=None, drive=None, *, model="arctan", seed=0, progress=False,
               **simulate_options) -> tuple:
    """Simulate the robot scanning ``scene`` and build the grid over the truth's cells.

    Parameters
    ----------
    scene : crfmap.world.scene.Scene
    laser : crfmap.sim.simulator.Laser or None (the simulator's default: 360 beams, 5 m)
    drive : a drive of :mod:`crfmap.sim.drives` (``Look(turns=2)``), a mode name "look", "explore",
        "waypoints" (that drive with its defaults) or None (``scene.default_mode``)
    model : "arctan" (thesis eq. 16) or "logodds"
    seed : int, passed to the simulator (only matters with noise)
    simulate_options : more keyword arguments of :func:`crfmap.sim.simulator.simulate`, e.g.
        ``range_noise``, ``odometry_noise``; none means perfect sensors (the thesis)

    Returns
    -------
    (OccupancyGrid, Recording)
        The grid has the truth's shape, resolution and origin; cells never seen are 0.5.
        The laser poses are the true ones (perfect odometry, as in the thesis).
    """
    if not isinstance(scene, Scene):
        raise InputError("scene", f"expected a crfmap.world.scene.Scene, got {type(scene).__name__}")
    recording: Recording = simulate(scene, laser, drive, seed=seed, progress=progress, **simulate_options)
    truth = scene.truth
    observed = build_grid(recording.scans, truth.resolution, model=model, bounds=truth_bounds(truth),
                          progress=progress)
    if observed.shape != truth.shape:  # the bounds are exact, so this would be a builder bug
        raise InputError("scene", f"built grid {observed.shape} does not match the truth {truth.shape}")
    observed.meta.update(scene=scene.name, mode=recording.meta["mode"])
    return observed, recording


@dataclass
class PipelineResult:
    """The beliefs LBP gave, their scores against the truth, and LBP's diagnostics.

    ``lbp`` is None for the grid before LBP (see :func:`score`).
    """

    beliefs: OccupancyGrid
    metrics: Report
    lbp: LBPResult | None = None
    hidden: np.ndarray | None = None
    link: np.ndarray | None = None

    def as_dict(self) -> dict:
        """Metrics plus the LBP iteration count and whether it converged (NaN / None before LBP)."""
        out = self.metrics.as_dict()
        out["iterations"] = self.lbp.iterations if self.lbp is not None else 0
        out["converged"] = self.lbp.converged if self.lbp is not None else None
        return out

    def roc(self, truth):
        """(fpr, tpr, auc) of the beliefs against ``truth``, for :func:`crfstudy.plotting.plot_roc`."""
        fpr, tpr, _ = roc_curve(self.beliefs, truth)
        return fpr, tpr, self.metrics.auc


def score(grid: OccupancyGrid, truth: OccupancyGrid) -> PipelineResult:
    """Score a grid as it is (the "before LBP" row)."""
    check_pair(grid, truth, grids_only=True)
    return PipelineResult(grid, evaluate(grid, truth))


def evaluate_pipeline(observed: OccupancyGrid, truth: OccupancyGrid, hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK,
                      lbp_options=None) -> PipelineResult:
    """Run LBP on ``observed`` with these tables and score the beliefs against ``truth``.

    ``lbp_options`` are keyword arguments of :func:`crfmap.crf.inference.lbp.infer` (default
    :data:`TO_CONVERGENCE`: run to convergence; :data:`THESIS_TWO_ITERATIONS` is the thesis's).

    >>> g = OccupancyGrid(np.array([[0.9, 0.5, 0.9]]))
    >>> r = evaluate_pipeline(g, OccupancyGrid(np.array([[1.0, 1.0, 1.0]])))
    >>> r.metrics.recall, r.lbp.converged
    (1.0, True)
    """
    check_pair(observed, truth, grids_only=True)
    hidden = check_table(hidden, "hidden")
    link = check_table(link, "link")
    options = dict(TO_CONVERGENCE if lbp_options is None else lbp_options)
    result = infer(observed, hidden, link, **options)
    return PipelineResult(result.beliefs, evaluate(result.beliefs, truth), result, hidden, link)


# --- our extra learner: coarse search, then gradient -------------------------------------
def search_tables(observed, truth, strengths=SEARCH_STRENGTHS, biases=SEARCH_BIASES, lbp_options=None) -> tuple:
    """LBP's MSE for hidden ``[[a, 1], [1, a]]`` and link ``[[1, 0], [0, b]]`` over a grid of (a, b).

    Returns (best hidden, best link, mse[i, j] for strengths[i], biases[j]).

    >>> obs = OccupancyGrid(np.array([[0.75, 0.5, 0.25, 0.25]]))
    >>> H, L, table = search_tables(obs, OccupancyGrid(np.array([[1.0, 0.0, 0.0, 0.0]])), (1.5, 10.0), (1.0, 2.0))
    >>> table.shape
    (2, 2)
    """
    check_pair(observed, truth, grids_only=True)
    strengths = [float(a) for a in strengths]
    biases = [float(b) for b in biases]
    if not strengths or not biases or min(strengths) <= 0 or min(biases) <= 0:
        raise InputError("strengths/biases", "need at least one positive value of each")
    options = dict(TO_CONVERGENCE if lbp_options is None else lbp_options)
    table = np.array([[lbp_mse(observed, truth, [[a, 1.0], [1.0, a]], [[1.0, 0.0], [0.0, b]], options)
                       for b in biases] for a in strengths])
    i, j = np.unravel_index(int(np.argmin(table)), table.shape)
    hidden = np.array([[strengths[i], 1.0], [1.0, strengths[i]]])
    link = np.array([[1.0, 0.0], [0.0, biases[j]]])
    return hidden, link, table


def learn_search_gradient(observed, truth, *, strengths=SEARCH_STRENGTHS, biases=SEARCH_BIASES, lbp_options=None,
                          progress=True, **gradient_options) -> LearningResult:
    """Coarse search (:func:`search_tables`), then :func:`crfmap.assess.learning.learn_gradient` from its best point.

    ``mse_before`` is the MSE of the default tables, ``mse_after`` the learned one; ``trace``
    starts with one row per searched (a, b), then the gradient learner's rows.
    """
    options = dict(TO_CONVERGENCE if lbp_options is None else lbp_options)
    before = lbp_mse(observed, truth, DEFAULT_HIDDEN, DEFAULT_LINK, options)
    hidden0, link0, table = search_tables(observed, truth, strengths, biases, options)
    fine = learn_gradient(observed, truth, hidden0, link0, lbp_options=options, progress=progress, **gradient_options)
    hidden, link, after = fine.hidden, fine.link, fine.mse_after
    if table.min() < after:  # the gradient learner floors zero entries first; never report worse than its start
        hidden, link = rescale(hidden0, link0)
        after = float(table.min())
    trace = [{"step": "search", "strength": a, "bias": b, "mse": float(table[i, j])}
             for i, a in enumerate(strengths) for j, b in enumerate(biases)] + fine.trace
    return LearningResult(hidden, link, before, float(after), trace, "search+gradient")


# --- train on one environment, test on another ---------------------------------------------
@dataclass
class TrainTest:
    """Everything :func:`train_and_test` computed.

    ``learned[(setting, learner)]`` = LearningResult on the train grid;
    ``results[(setting, environment, tables)]`` = PipelineResult, ``tables`` being ``"default"``
    or a learner's name; ``before[environment]`` = the grid before LBP, scored.
    """

    observed: dict
    truth: dict
    before: dict = field(default_factory=dict)
    learned: dict = field(default_factory=dict)
    results: dict = field(default_factory=dict)
    lbp_settings: dict = field(default_factory=dict)

    def tables(self, setting: str, name: str) -> tuple:
        """(hidden, link) used for ``name`` ("default" or a learner) under ``setting``."""
        if name == "default":
            return DEFAULT_HIDDEN.copy(), DEFAULT_LINK.copy()
        r = self.learned[(setting, name)]
        return r.hidden, r.link


def train_and_test(train: tuple, test: tuple, learners: dict, lbp_settings=None, progress=True) -> TrainTest:
    """Learn tables on ``train`` with every learner under every LBP setting; apply them to both grids.

    Parameters
    ----------
    train, test : (observed OccupancyGrid, truth OccupancyGrid)
    learners : name -> callable(observed, truth, lbp_options) returning a LearningResult,
        e.g. ``{"thesis": lambda o, t, opts: learn_thesis(o, t, lbp_options=opts)}``
    lbp_settings : name -> keyword arguments of :func:`crfmap.crf.inference.lbp.infer`; default
        ``{"converged": TO_CONVERGENCE, "thesis 2 iterations": THESIS_TWO_ITERATIONS}``

    Returns
    -------
    TrainTest
    """
    settings = dict(lbp_settings or {"converged": TO_CONVERGENCE, "thesis 2 iterations": THESIS_TWO_ITERATIONS})
    grids = {"train": train, "test": test}
    for env, pair in grids.items():
        if not (isinstance(pair, tuple) and len(pair) == 2):
            raise InputError(env, "expected a pair (observed grid, truth grid)")
        check_pair(*pair, grids_only=True)
    if not learners:
        raise InputError("learners", "give at least one learner")
    out = TrainTest(observed={k: v[0] for k, v in grids.items()}, truth={k: v[1] for k, v in grids.items()},
                    lbp_settings=settings)
    from tqdm.auto import tqdm

    for env, (obs, tru) in grids.items():
        out.before[env] = score(obs, tru)
    jobs = [(s, name) for s in settings for name in learners]
    for setting, name in tqdm(jobs, desc="learning", disable=not progress, leave=False):
        out.learned[(setting, name)] = learners[name](train[0], train[1], dict(settings[setting]))
    for setting, options in settings.items():
        for env, (obs, tru) in grids.items():
            for name in ("default", *learners):
                hidden, link = out.tables(setting, name)
                out.results[(setting, env, name)] = evaluate_pipeline(obs, tru, hidden, link, options)
    return out


def metric_row(result: PipelineResult, keys=("mse", "precision", "recall", "accuracy")) -> list:
    """The values of ``keys`` from a result's metrics (NaN where undefined)."""
    d = result.as_dict()
    return [d[k] if d[k] is not None else math.nan for k in keys]
