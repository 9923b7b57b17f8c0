"""Statistics over generated rooms: every method scored on the same cells, with baselines and intervals.

The thesis's simulated experiments use one room each, perfect sensors and one scan. This module
repeats an experiment over many generated rooms (``seed`` jitters the occluded walls or draws
random boxes), with the thesis's range noise ``d +- C`` and odometry noise, and builds the grid
from the *odometry* poses (so motion noise blurs the map, as it would on a robot).

Every method is scored against the truth on three fixed sets of cells, the same for every method,
so "before" and "after" LBP are comparable (:func:`score_methods`):

- ``all``: MSE over every cell (the thesis's MSE);
- ``seen``: precision / recall / accuracy over the cells the scan saw (the grid before LBP is
  decided on exactly these);
- ``unseen``: accuracy on the cells the scan never saw, and ``coverage``: the fraction of them a
  method gives a state (not exactly 0.5).

Baselines beside LBP: the raw arctan grid (eq. 16), the log-odds grid of the same scans, the 3x3
neighbour mean, and the exact MAP labelling by a graph cut (only when PyMaxflow is installed).
:func:`summarise` gives mean, sd and a bootstrap 95 % interval of the mean over rooms.

>>> r = run_rooms("occluded", seeds=[0], range_noise=0.0, odometry_noise=0.0)
>>> sorted(r["methods"]) == sorted(r["per_room"][0])
True
"""
from __future__ import annotations

import importlib.util
from dataclasses import replace

import numpy as np

from crfmap.assess.metrics import evaluate
from crfmap.assess.mincut import graph_cut_map
from crfmap.crf.inference.lbp import infer
from crfmap.crf.model.potentials import DEFAULT_HIDDEN, DEFAULT_LINK
from crfmap.errors import InputError
from crfmap.frames import compose
from crfmap.grid import UNKNOWN, OccupancyGrid
from crfmap.mapping.builder import build_grid
from crfmap.world.scenes import enclosed_boxes, occluded_walls
from crfstudy.experiments.pipeline import truth_bounds
from crfmap.sim.simulator import simulate
from crfmap.assess.learning import learn_gradient

KINDS = ("occluded", "enclosed", "hollow")
# The thesis's noise model (sec. 3.1): ranges d +- C, C ~ U[0, bound]; odometry steps +- C as well.
RANGE_NOISE = 0.05  # [m], half a 0.1 m cell
ODOMETRY_NOISE = (0.002, 0.002)  # [m, rad] per 0.1 s motion step
TO_CONVERGENCE = {"threads": 1, "max_iter": 1000, "tol": 1e-5}
THESIS_TWO = {"schedule": "thesis", "max_iter": 2}
PAD_CELLS = 20  # odometry drift can take the robot's estimate outside the room


def room(kind: str, seed: int):
    """A generated room: ``occluded`` (walls jittered), ``enclosed`` or ``hollow`` (random boxes).

    >>> room("hollow", 3).name
    'hollow-train'
    """
    if kind == "occluded":
        return occluded_walls("train", seed=seed)
    if kind in ("enclosed", "hollow"):
        return enclosed_boxes("train", hollow=(kind == "hollow"), seed=seed)
    raise InputError("kind", f"must be one of {', '.join(KINDS)}, got {kind!r}")


def odometry_scans(recording):
    """The recording's scans with the laser poses the *odometry* gives (map <- odom <- base <- laser)."""
    odo = recording.odometry
    at = np.clip(np.searchsorted(odo.stamps, recording.scans.stamps - 1e-9), 0, len(odo.stamps) - 1)
    base = compose(np.asarray(recording.meta["map_to_odom"], float), odo.poses[at])
    return replace(recording.scans, laser_poses=compose(base, np.asarray(recording.laser_mount, float)))


def padded_grid(scans, truth: OccupancyGrid, model="arctan", pad=PAD_CELLS) -> OccupancyGrid:
    """The grid of ``scans`` over the truth's cells; built ``pad`` cells wider, so drifted poses still fit."""
    x0, y0, x1, y1 = truth_bounds(truth)
    margin = pad * truth.resolution
    wide = build_grid(scans, truth.resolution, model=model, bounds=(x0 - margin, y0 - margin, x1 + margin, y1 + margin))
    h, w = truth.shape
    return truth.with_probability(wide.probability[pad:pad + h, pad:pad + w])


def neighbour_mean3(grid: OccupancyGrid) -> OccupancyGrid:
    """Each cell: the mean P of the known cells in its 3x3 window, itself included (0.5 if none).

    >>> neighbour_mean3(OccupancyGrid(np.array([[1.0, 0.5, 0.0]]))).probability.tolist()
    [[1.0, 0.5, 0.0]]
    """
    p = grid.probability
    known = (p != UNKNOWN).astype(float)
    pad_p, pad_k = np.pad(p * known, 1), np.pad(known, 1)
    h, w = p.shape
    total = sum(pad_p[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3))
    count = sum(pad_k[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3))
    return grid.with_probability(np.where(count > 0, total / np.maximum(count, 1), UNKNOWN))


def graph_cut_available() -> bool:
    """Whether PyMaxflow is installed (the graph-cut MAP baseline is skipped otherwise)."""
    return importlib.util.find_spec("maxflow") is not None


def baselines(scans, truth, observed) -> dict:
    """name -> grid of the methods that are not LBP: raw arctan grid, log-odds grid, 3x3 neighbour mean,
    and the graph-cut MAP labelling with the default tables (only when PyMaxflow is installed)."""
    out = {"raw arctan grid (no LBP)": observed,
           "log-odds grid (no LBP)": padded_grid(scans, truth, model="logodds"),
           "3x3 neighbour mean": neighbour_mean3(observed)}
    if graph_cut_available():
        occupied, _ = graph_cut_map(observed.probability, DEFAULT_HIDDEN, DEFAULT_LINK)
        out["graph-cut MAP (default tables)"] = observed.with_probability(occupied.astype(float))
    return out


def methods(scans, truth, observed, hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK, learned=None) -> dict:
    """name -> predicted grid (P(occupied)) for one room: :func:`baselines`, LBP converged and 2 iterations.

    ``learned``: (hidden, link) learned elsewhere; adds converged LBP with them, once with the
    thesis's pairing (rows = receiving cell) and once with the proper pairwise ("oriented") one.
    """
    out = baselines(scans, truth, observed)
    out["LBP, converged"] = infer(observed, hidden, link, **TO_CONVERGENCE).beliefs
    out["LBP, thesis schedule, 2 iterations"] = infer(observed, hidden, link, **THESIS_TWO).beliefs
    if learned is not None:
        for pairing in ("receiver", "oriented"):
            out[f"LBP, learned on another room ({pairing} pairing)"] = infer(
                observed, learned[0], learned[1], pairing=pairing, **TO_CONVERGENCE).beliefs
    return out


def score_methods(predictions: dict, truth: OccupancyGrid, observed: OccupancyGrid) -> dict:
    """name -> scores on the same cells for every method (see the module docstring)."""
    seen = observed.probability != UNKNOWN
    out = {}
    for name, grid in predictions.items():
        p = grid.probability
        on_seen = evaluate(grid, truth, seen)
        on_unseen = evaluate(grid, truth, ~seen) if (~seen).any() else None
        decided_unseen = (p != UNKNOWN) & ~seen
        out[name] = {
            "mse": float(np.mean((p - truth.probability) ** 2)),
            "precision_seen": on_seen.precision, "recall_seen": on_seen.recall, "accuracy_seen": on_seen.accuracy,
            "accuracy_unseen": on_unseen.accuracy if on_unseen else float("nan"),
            "coverage_unseen": float(decided_unseen.sum() / max(int((~seen).sum()), 1)),
            "coverage_all": float(np.mean(p != UNKNOWN)),
        }
    return out


def scan_room(kind: str, seed: int, drive=None, laser=None, range_noise=RANGE_NOISE,
              odometry_noise=ODOMETRY_NOISE) -> tuple:
    """(scene, scans with odometry poses, arctan grid over the truth's cells) of one generated room."""
    scene = room(kind, seed)
    rec = simulate(scene, laser, drive, seed=seed, range_noise=range_noise, odometry_noise=odometry_noise,
                   progress=False)
    scans = odometry_scans(rec)
    return scene, scans, padded_grid(scans, scene.truth)


def learn_on_room(kind: str, seed: int, steps=20, drive=None, laser=None, range_noise=RANGE_NOISE,
                  odometry_noise=ODOMETRY_NOISE):
    """The gradient learner (converged LBP, from the default tables) on one noisy training room."""
    scene, _, observed = scan_room(kind, seed, drive, laser, range_noise, odometry_noise)
    return learn_gradient(observed, scene.truth, steps=steps, lbp_options=TO_CONVERGENCE, progress=False)


def run_rooms(kind: str, seeds, drive=None, laser=None, range_noise=RANGE_NOISE, odometry_noise=ODOMETRY_NOISE,
              hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK, learned=None) -> dict:
    """Scan every generated room of ``kind`` (one per seed), build its grid from odometry, score all methods.

    ``learned``: optional (hidden, link) learned on another room (see :func:`methods`).
    Returns {"per_room": [name -> scores], "methods": [...], "unseen_fraction": [...], "settings": {...}}.
    """
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise InputError("seeds", "need at least one room")
    per_room, unseen = [], []
    for s in seeds:
        scene, scans, observed = scan_room(kind, s, drive, laser, range_noise, odometry_noise)
        predictions = methods(scans, scene.truth, observed, hidden, link, learned)
        per_room.append(score_methods(predictions, scene.truth, observed))
        unseen.append(float(np.mean(observed.probability == UNKNOWN)))
    return {"per_room": per_room, "methods": list(per_room[0]), "unseen_fraction": unseen,
            "settings": {"kind": kind, "seeds": seeds, "drive": drive if drive is None or isinstance(drive, str) else repr(drive), "range_noise_m": range_noise,
                         "odometry_noise": list(np.atleast_1d(odometry_noise)),
                         "graph_cut": graph_cut_available()}}


def bootstrap_interval(values, level=0.95, resamples=2000, seed=0) -> tuple:
    """Percentile bootstrap interval of the mean (NaNs dropped); (nan, nan) for no values.

    >>> lo, hi = bootstrap_interval([1.0, 2.0, 3.0, 4.0])
    >>> 1.0 <= lo <= 2.5 <= hi <= 4.0
    True
    """
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return float("nan"), float("nan")
    means = np.random.default_rng(seed).choice(v, size=(resamples, v.size)).mean(axis=1)
    tail = 100 * (1 - level) / 2
    return float(np.percentile(means, tail)), float(np.percentile(means, 100 - tail))


def summarise(run: dict) -> dict:
    """method -> metric -> {"mean", "sd", "low", "high", "n"} over the rooms (95 % bootstrap interval)."""
    out = {}
    for name in run["methods"]:
        out[name] = {}
        for metric in run["per_room"][0][name]:
            v = np.array([r[name][metric] for r in run["per_room"]], float)
            ok = v[np.isfinite(v)]
            low, high = bootstrap_interval(ok)
            out[name][metric] = {"mean": float(ok.mean()) if ok.size else float("nan"),
                                 "sd": float(ok.std(ddof=1)) if ok.size > 1 else 0.0,
                                 "low": low, "high": high, "n": int(ok.size)}
    return out


# Short keys for the paper's placeholders ({{number:NAME.lbp.mse.mean}}).
SLUGS = {"raw arctan grid (no LBP)": "raw", "log-odds grid (no LBP)": "logodds", "3x3 neighbour mean": "neighbour",
         "graph-cut MAP (default tables)": "graphcut", "LBP, converged": "lbp", "LBP, thesis schedule, 2 iterations": "lbp2",
         "LBP, learned on another room (receiver pairing)": "learned_receiver",
         "LBP, learned on another room (oriented pairing)": "learned_oriented"}


def flat_summary(run: dict, summary: dict) -> dict:
    """The summary under short keys (:data:`SLUGS`), with the settings and the unseen fraction, for save_numbers."""
    out = {SLUGS.get(name, name): by_metric for name, by_metric in summary.items()}
    out["rooms"] = len(run["per_room"])
    out["unseen_fraction_mean"] = float(np.mean(run["unseen_fraction"]))
    out["settings"] = run["settings"]
    return out


def summary_rows(summary: dict, metrics=("mse", "precision_seen", "recall_seen", "accuracy_seen",
                                          "accuracy_unseen", "coverage_unseen")) -> list:
    """Table rows: method, then "mean +- sd [low, high]" per metric."""
    rows = []
    for name, by_metric in summary.items():
        cells = []
        for m in metrics:
            s = by_metric[m]
            cells.append("n/a" if not np.isfinite(s["mean"]) else
                         f"{s['mean']:.3f} ± {s['sd']:.3f} [{s['low']:.3f}, {s['high']:.3f}]")
        rows.append([name, *cells])
    return rows
