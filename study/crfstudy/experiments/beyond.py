"""Notebook 10 (beyond the thesis): the study loops, tables and figures around the library calls it shows.

Sections, in the notebook's order: the (J, K) phase diagram (:func:`phase_diagrams`, :func:`phase_diagram_figure`),
scan-split tables of every row (:func:`scansplit_tables`) and the goals each recording is checked on
(:func:`recording_goals`), transfer of learned potentials (:func:`transfer_tables`), the before/after maps
(:func:`before_after_figure`), the preset search's check (:func:`preset_search_report`), ablations
(:func:`ablation_study`, :func:`ablation_table`), harder splits (:func:`harder_split_scores`, :func:`split_tables`,
:func:`split_counts`) and the published peers (:func:`peer_recordings`, :func:`score_all`, :func:`peer_table`).

The peers' maps (:mod:`crfmap.assess.peers`) are cached under ``crfstudy.paths.OUT / "cache" / "peers"``,
keyed by the first half's scans, the grid, the peers' constants and the settings, so a rerun does not refit them.
Settings (:class:`PeerSettings`): :data:`FULL` fits the Hilbert map on every scan of the first half with
the constants chosen on Intel (:mod:`crfmap.mapping.hilbert`); :data:`QUICK` (the notebook's quick run,
CI) fits it on every 4th scan with features twice as far apart, only to show the section runs: its
numbers are not the peer's. OctoMap's update is cheap and runs on every scan in both.

>>> import matplotlib; matplotlib.use("Agg")
>>> d = {"intel": {"brier": np.ones((3, 2)), "wall_recall": np.ones((3, 2))}}
>>> fig = phase_diagram_figure(d, [0.1, 0.2, 0.6], [0.5, 2.0], critical=0.44)
>>> [round(float(t), 2) for t in fig.axes[0].get_xlim()]
[0.05, 0.8]
"""
from __future__ import annotations

import hashlib
import inspect
import json
from dataclasses import asdict, dataclass, replace
import time

import numpy as np

from crfstudy import paths
from crfstudy import splits as scan_splits
from crfstudy.analysis import ablations, modelspace, preset_search
from crfstudy.analysis.coordinate import split_brier
from crfstudy.analysis.peer_search import HILBERT_SEARCH_COLUMNS, HILBERT_SEARCH_INTEL
from crfstudy.plotting import OCCUPANCY_CMAP, shared_colorbar, show_grid
from crfmap import DataMissingError
from crfmap.assess import compare, scan_split, score
from crfmap.assess.calibration import split_calibration
from crfmap.assess.peers import OCTOMAP_INTEL, hilbert_row, peer_rows
from crfmap.crf import DEFAULT_PRESET, get_preset, infer, table_coupling
from crfmap.crf.presets import temper
from crfmap.data import data_file
from crfmap.io import atomic_path, load_recording
from crfmap.mapping import build_grid, hilbert

# The two buildings beyond the four recordings of the other sections: CARMEN logs from Radish, nothing tuned on them.
MORE_RECORDINGS = {"csail": "carmen/csail-corrected.log.gz", "fr101": "carmen/freiburg-101-corrected.log.gz"}
# The model the study analyses (its constants were searched on Intel): the default preset is it at a weaker coupling
# plus an evidence gate, chosen for navigation, so both are scored and the peers' paired differences are to each.
ANALYSED = "certainty"
PRESET_ROWS = tuple(dict.fromkeys((ANALYSED, DEFAULT_PRESET)))  # one row if the default is the analysed model
TABLE_ROWS = ("raw", "logodds", "thesis", "graphcut", *PRESET_ROWS, "octomap", "hilbert")
CACHE_VERSION = 2  # bump when a peer's algorithm changes (2: the settings are in the key)


@dataclass(frozen=True)
class PeerSettings:
    """How heavy the peers' fits are: the Hilbert map's scans and feature grid (None: its chosen constant)."""

    hilbert_scan_step: int = 1  # fit on every this-many-th scan of the first half
    feature_spacing: float | None = None  # [m] between RBF centres
    length_scale: float | None = None  # [m] RBF width
    free_spacing: float | None = None  # [m] between free points along a beam

    def hilbert_options(self) -> dict:
        return {k: v for k, v in asdict(self).items() if k != "hilbert_scan_step" and v is not None}


FULL = PeerSettings()
QUICK = PeerSettings(hilbert_scan_step=4, feature_spacing=0.15, length_scale=0.06, free_spacing=0.15)


def _key(split, name, settings=FULL) -> str:
    h = hashlib.sha256()
    scans = split.first_scans
    for a in (scans.ranges, scans.laser_poses):
        h.update(np.ascontiguousarray(a).tobytes())
    constants = [CACHE_VERSION, name, split.resolution, split.bounds, float(scans.angle_min),
                 float(scans.angle_increment), float(scans.range_min), float(scans.range_max),
                 sorted(OCTOMAP_INTEL.items()), hilbert.FEATURE_SPACING,
                 hilbert.LENGTH_SCALE, hilbert.FREE_SPACING, hilbert.EM_ITERATIONS, hilbert.PRIOR_VARIANCE,
                 hilbert.CUTOFF, asdict(settings)]
    h.update(json.dumps(constants).encode())
    return h.hexdigest()[:20]


def _fit(split, name, settings, progress):
    """({name: P}, {name: seconds}) of one peer on ``split`` with ``settings``."""
    if name != "hilbert" or settings == FULL:
        return peer_rows(split, [name], progress=progress)
    start = time.perf_counter()
    lighter = replace(split, first_scans=split.first_scans.every(settings.hilbert_scan_step)) \
        if split.first_scans is not None else split
    p = hilbert_row(lighter, progress=progress, **settings.hilbert_options())
    return {name: p}, {name: time.perf_counter() - start}


def cached_peer_rows(label, split, methods=("octomap", "hilbert"), progress=False, quick=False):
    """({name: P}, {name: seconds}) of the peers on ``split``; seconds are those of the fit that made the cache.

    ``quick``: the :data:`QUICK` settings (a light Hilbert fit, for CI), else :data:`FULL`.
    """
    settings = QUICK if quick else FULL
    folder = paths.OUT / "cache" / "peers"
    rows, seconds = {}, {}
    for name in methods:
        path = folder / f"{label}-{name}-{_key(split, name, settings)}.npz"
        if path.exists():
            with np.load(path) as data:
                rows[name], seconds[name] = data["p"], float(data["seconds"])
            continue
        got, secs = _fit(split, name, settings, progress)
        rows[name], seconds[name] = got[name], secs[name]
        folder.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            np.savez_compressed(f, p=rows[name], seconds=seconds[name])
    return rows, seconds


def preset_rows(split) -> dict:
    """{name: P} of every preset row of the table (:data:`PRESET_ROWS`) on a split's first half, as users run them."""
    return {name: get_preset(name).refine(hits=split.first_hits, passes=split.first_passes).beliefs.probability
            for name in PRESET_ROWS}


def score_all(split, predictions, n_boot, block, seed, temperature=None):
    """Scores with paired differences to the analysed model (``scores``) and to each preset row (``versus``, by
    preset), calibration of every scored row, and (given T) the tempered analysed model ``<ANALYSED>-T``."""
    preds = {n: p for n, p in predictions.items() if n in TABLE_ROWS}
    if temperature is not None:
        preds[f"{ANALYSED}-T"] = temper(preds[ANALYSED], temperature)
    versus = {ref: score(split, preds, n_boot=n_boot, block=block, seed=seed, reference=ref)
              for ref in PRESET_ROWS if ref in preds}
    calib = split_calibration(split, preds)  # every row: the baselines as well as the presets and the peers
    return {"scores": versus[ANALYSED], "versus": versus, "calibration": calib}


def _interval(entry, key, signed=False):
    lo, hi = entry.get(key + "_ci", (np.nan, np.nan))
    return f"[{lo:+.4f}, {hi:+.4f}]" if signed else f"[{lo:.4f}, {hi:.4f}]"


def _diff_interval(entry):
    """``brier_diff`` with its paired interval: "+0.0012 [-0.0003, +0.0025]"."""
    return f"{entry['brier_diff']:+.4f} {_interval(entry, 'brier_diff', signed=True)}"


def peer_table(label, result, seconds):
    """``save_table`` arguments: every method's Brier (all/seen/unseen), paired difference to each preset row, AUC,
    recall, ECE."""
    versus = result.get("versus", {ANALYSED: result["scores"]})
    header = ["method", "Brier all", "95% CI", *(f"minus {ref}, 95% CI" for ref in versus), "Brier seen",
              "Brier unseen", "log-loss", "AUC", "wall recall", "ECE", "fit [s]"]
    rows = []
    for name, g in result["scores"].items():
        a = g["all"]
        ece = result["calibration"].get(name, {}).get("ece", np.nan)
        rows.append([name, a["brier"], _interval(a, "brier"), *(_diff_interval(v[name]["all"]) for v in versus.values()),
                     g["seen"]["brier"], g["unseen"]["brier"], a["logloss"], a["auc"], a["wall_recall"], ece,
                     seconds.get(name, "")])
    return dict(header=header, rows=rows, caption=f"Published peers on {label}: scan-split scores, paired differences "
                f"to the {' and the '.join(versus)} presets (negative: lower Brier than that preset), expected "
                "calibration error.")


def peer_sentence(label, result, peer, preset=ANALYSED):
    """One plain sentence on how ``peer`` compares with ``preset`` on a recording, from the numbers."""
    s = result.get("versus", {ANALYSED: result["scores"]})[preset]
    parts = []
    for group, words in (("all", "all observed cells"), ("seen", "cells the map had seen"),
                         ("unseen", "never-seen cells")):
        e = s[peer][group]
        lo, hi = e.get("brier_diff_ci", (np.nan, np.nan))
        verdict = ("the preset is better" if lo > 0 else "the peer is better" if hi < 0 else "no clear difference")
        parts.append(f"{words}: {e['brier']:.4f} vs {s[preset][group]['brier']:.4f} ({verdict})")
    ece = result["calibration"][peer]["ece"], result["calibration"][preset]["ece"]
    return (f"{label}, {peer} vs {preset} (Brier): " + "; ".join(parts)
            + f"; calibration error {ece[0]:.3f} vs {ece[1]:.3f}.")


def reliability_figure(calibrations):
    """One panel per recording: mean P per bin against the odd scans' occupied share, one line per method.

    Three panels a row and one legend below them, each method in the same colour in every panel: six panels in one
    row, each with its own legend, were unreadable at the page's width. The calibration errors are in the peer
    table.
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    ncols = min(3, len(calibrations))
    nrows = -(-len(calibrations) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.4 * ncols, 3.0 * nrows + 0.7), squeeze=False,
                             sharex=True, sharey=True, layout="constrained")
    methods = list(dict.fromkeys(name for calib in calibrations.values() for name in calib))
    colours = {name: f"C{i % 10}" for i, name in enumerate(methods)}
    for ax, (label, calib) in zip(axes.flat, calibrations.items()):
        ax.plot([0, 1], [0, 1], color="0.7", lw=1)
        for name, c in calib.items():
            used = c["count"] > 0
            ax.plot(c["mean_p"][used], c["share"][used], marker="o", ms=3, lw=1, color=colours[name])
        ax.set_title(label)
    for ax in axes[-1]:
        ax.set_xlabel("predicted P(occupied)")
    for ax in axes[:, 0]:
        ax.set_ylabel("observed occupied share")
    for ax in axes.flat[len(calibrations):]:
        ax.set_axis_off()
    handles = [Line2D([], [], color=colours[name], marker="o", ms=3, lw=1) for name in methods]
    fig.legend(handles, methods, loc="outside lower center", ncols=min(len(methods), 5), fontsize=8)
    return fig


def maps_figure(predictions, window, label):
    """Each method's map of the same window (y0, y1, x0, x1 in cells), side by side."""
    import matplotlib.pyplot as plt

    y0, y1, x0, x1 = window
    fig, axes = plt.subplots(1, len(predictions), figsize=(3.2 * len(predictions), 3.4))
    for ax, (name, p) in zip(np.atleast_1d(axes), predictions.items()):
        ax.imshow(1 - p[y0:y1, x0:x1], origin="lower", cmap="gray", vmin=0, vmax=1)
        ax.set_title(f"{label}: {name}", fontsize=9); ax.set_axis_off()
    fig.tight_layout()
    return fig


def busiest_window(split, side=200):
    """The ``side`` x ``side`` cell window with the most cells the first half observed (coarse search)."""
    return densest_window(split.first_hits + split.first_passes > 0, side)


def _edges(values) -> np.ndarray:
    """Cell edges around sampled values on a metric axis: midpoints inside, half a step beyond the ends.

    >>> np.round(_edges([0.1, 0.2, 0.6]), 6).tolist()
    [0.05, 0.15, 0.4, 0.8]
    """
    v = np.asarray(values, dtype=float)
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = (v[1:] + v[:-1]) / 2
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def spaced_labels(values, span: float, min_gap: float = 0.06) -> list:
    """Tick labels for sampled ``values`` on an axis ``span`` long: a value closer than ``min_gap`` of the span to
    the last labelled one gets a tick without a label (the labels of 0.3, 0.35 and 0.44 ran into each other).

    >>> spaced_labels([0, 0.1, 0.2, 0.3, 0.35, 0.44, 0.6, 1.15], span=1.55)
    ['0', '0.1', '0.2', '0.3', '', '0.44', '0.6', '1.15']
    """
    labels, last = [], None
    for v in values:
        keep = last is None or v - last >= min_gap * span
        labels.append(f"{v:g}" if keep else "")
        last = v if keep else last
    return labels


def phase_diagram_figure(diagrams, couplings, link_strengths, critical):
    """Brier score and wall recall over the sampled (coupling J, link strength K), one column per recording.

    Both axes are metric (each sample a cell around its value, so unevenly spaced samples are drawn
    where they lie) and the critical coupling is a dashed line at its value.
    """
    import matplotlib.pyplot as plt

    # a smaller canvas for the same page width: its text prints larger (at four by seven inches a column it came
    # out at four points)
    fig, axes = plt.subplots(2, len(diagrams), figsize=(3.2 * len(diagrams), 6), squeeze=False, layout="constrained")
    jx, ky = _edges(couplings), _edges(link_strengths)
    for col, (name, d) in enumerate(diagrams.items()):
        for row, key in enumerate(("brier", "wall_recall")):
            ax = axes[row, col]
            mesh = ax.pcolormesh(jx, ky, np.asarray(d[key]).T, cmap="viridis_r" if key == "brier" else "viridis")
            ax.axvline(critical, color="w", ls="--", lw=1)
            ax.set_xticks(couplings, spaced_labels(couplings, jx[-1] - jx[0]), rotation=90, fontsize=9)
            ax.set_yticks(link_strengths, spaced_labels(link_strengths, ky[-1] - ky[0]), fontsize=9)
            ax.set_title(f"{name}: {'Brier' if key == 'brier' else 'wall recall'}")
            ax.set_xlabel("coupling J")
            ax.set_ylabel("link strength K")
            fig.colorbar(mesh, ax=ax, shrink=0.9)
    return fig


def densest_window(mask, side):
    """The (y0, y1, x0, x1) square of ``side`` cells (clipped to the grid) holding the most True cells of ``mask``.

    A coarse search (steps of side / 8) over a summed-area table.

    >>> m = np.zeros((40, 40), bool); m[30:34, 5:9] = True
    >>> densest_window(m, 8)
    (26, 34, 1, 9)
    """
    mask = np.asarray(mask, bool)
    h, w = mask.shape
    side_y, side_x = min(side, h), min(side, w)
    c = np.pad(mask.astype(np.int64).cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    best, where = -1, (0, side_y, 0, side_x)
    for y in range(0, h - side_y + 1, max(1, side_y // 8)):
        for x in range(0, w - side_x + 1, max(1, side_x // 8)):
            n = c[y + side_y, x + side_x] - c[y, x + side_x] - c[y + side_y, x] + c[y, x]
            if n > best:
                best, where = n, (y, y + side_y, x, x + side_x)
    return where


def before_after_figure(maps, name, window):
    """The same map raw and refined, side by side, one shared P(occupied) colour bar; below each, the ``window``
    (y0, y1, x0, x1 cells, outlined in the map above) enlarged, every cell drawn.
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    y0, y1, x0, x1 = window
    fig, axes = plt.subplots(2, len(maps), figsize=(5 * len(maps), 10), squeeze=False, layout="constrained",
                             height_ratios=(1, 1))
    im = None
    for col, (title, p) in enumerate(maps.items()):
        p = np.asarray(p)
        im = show_grid(axes[0, col], p, title=f"{name}: {title}", colorbar=False)
        axes[0, col].add_patch(Rectangle((x0 - 0.5, y0 - 0.5), x1 - x0, y1 - y0, fill=False, edgecolor="tab:blue",
                                         linewidth=1.5))
        zoom = axes[1, col]
        zoom.imshow(p[y0:y1, x0:x1], cmap=OCCUPANCY_CMAP, vmin=0.0, vmax=1.0, origin="lower", interpolation="nearest",
                    extent=(x0 - 0.5, x1 - 0.5, y0 - 0.5, y1 - 0.5))
        zoom.set_title("the outlined square, every cell", fontsize="small")
        zoom.set_xlabel("x [cells]")
        zoom.set_ylabel("y [cells]")
    shared_colorbar(fig, im, axes, orientation="horizontal")
    return fig


# ---- the phase diagram and the scan-split tables -------------------------------------------------------------------
def phase_diagrams(splits, training, couplings, link_strengths, **lbp) -> dict:
    """{recording: symmetric-table diagram} in the order of ``splits`` (:func:`modelspace.symmetric_tables`).

    The training recording runs first: every other recording also keeps the refined grid of the training's best
    table, the "table from training" row, without a second LBP run.
    """
    diagrams = {training: modelspace.symmetric_tables(splits[training], couplings, link_strengths, **lbp)}
    keep = [diagrams[training]["best"]]
    diagrams.update({name: modelspace.symmetric_tables(sp, couplings, link_strengths, keep=keep, **lbp)
                     for name, sp in splits.items() if name != training})
    return {name: diagrams[name] for name in splits}


SCANSPLIT_HEADER = ["method", "Brier all", "95% CI", "Brier seen", "diff to raw, 95% CI", "Brier unseen", "95% CI",
                    "wall recall", "AUC", "log-loss"]


def scansplit_tables(results, names, roles, resolution, n_boot, block, seed) -> dict:
    """``save_table`` arguments per recording of ``names``: every row of :func:`crfmap.assess.compare`'s result
    (rows named with "_" are its kept grids, not rows); a one-row note for a recording not run (quick mode runs the
    two small bags)."""
    tables = {}
    for name in names:
        if name not in results:
            tables[name] = dict(header=SCANSPLIT_HEADER, rows=[["(not run in quick mode)"] + [""] * (len(SCANSPLIT_HEADER) - 1)],
                                caption=f"Scan-split validation, {name}: not run in quick mode.")
            continue
        rows = [[method, g["all"]["brier"], _interval(g["all"], "brier"), g["seen"]["brier"],
                 _diff_interval(g["seen"]), g["unseen"]["brier"], _interval(g["unseen"], "brier"),
                 g["all"]["wall_recall"], g["all"]["auc"], g["all"]["logloss"]]
                for method, g in results[name].items() if not method.startswith("_")]
        tables[name] = dict(header=SCANSPLIT_HEADER, rows=rows,
                            caption=f"Scan-split validation, {name} ({roles[name]} recording), {resolution:g} m cells, "
                                    f"{n_boot} block-bootstrap resamples (blocks of {block} cells), seed {seed}.")
    return tables


def table_summary(table) -> str:
    """A scan-split table's rows as a few printed lines (method, Brier with interval, seen, unseen, recall)."""
    return "\n".join(f"  {r[0]:14s} {r[1]:.4f} {r[2]}  seen {r[3]:.4f} {r[4]}  unseen {r[5]:.4f}  recall {r[7]:.3f}"
                     for r in table["rows"])


def recording_goals(result, role, n_boot, analysed=ANALYSED, default=DEFAULT_PRESET) -> dict:
    """The goals one recording is checked on, from its :func:`crfmap.assess.compare` result: the analysed preset
    against the raw grid (an interval below zero where resampled) and against every other row, walls kept; and the
    default preset's scores beside it (``default``)."""
    c, raw = result[analysed], result["raw"]
    others = [m for m in result if not m.startswith("_") and m not in (analysed, f"{analysed}-MAP")]
    lost = {g: [m for m in others if result[m][g]["brier"] <= c[g]["brier"]] for g in ("all", "seen", "unseen")}
    d = result[default]  # the default preset, against the raw grid on the same resamples
    return {
        "role": role,
        "lower_brier_all": bool(c["all"]["brier_diff_ci"][1] < 0) if n_boot else bool(c["all"]["brier_diff"] < 0),
        "lower_brier_unseen": bool(c["unseen"]["brier"] < raw["unseen"]["brier"]),
        "not_worse_seen": bool(c["seen"].get("brier_diff_ci", (0, c["seen"]["brier_diff"]))[0] <= 0),
        "beats_every_baseline_all": not lost["all"],
        "baselines_better_all": lost["all"], "baselines_better_seen": lost["seen"],
        "baselines_better_unseen": lost["unseen"],
        "wall_recall": c["all"]["wall_recall"], "raw_wall_recall": raw["all"]["wall_recall"],
        "walls_kept": bool(c["all"]["wall_recall"] >= raw["all"]["wall_recall"]),
        "brier_all": c["all"]["brier"], "raw_brier_all": raw["all"]["brier"],
        "brier_unseen": c["unseen"]["brier"], "brier_seen_diff": c["seen"]["brier_diff"],
        "brier_seen_diff_ci": c["seen"].get("brier_diff_ci"),
        "default": {"preset": default, "brier_all": d["all"]["brier"],
                    "brier_all_diff": d["all"]["brier_diff"], "brier_all_diff_ci": d["all"].get("brier_diff_ci"),
                    "brier_seen": d["seen"]["brier"], "brier_unseen": d["unseen"]["brier"],
                    "wall_recall": d["all"]["wall_recall"], "logloss": d["all"]["logloss"],
                    "certainty_logloss": c["all"]["logloss"], "raw_logloss": raw["all"]["logloss"]},
    }


# ---- transfer --------------------------------------------------------------------------------------------------------
def transfer_tables(splits, results, preset, couplings, scales, steps, analysed=ANALYSED) -> tuple:
    """(scaled rows, pseudo-likelihood rows, {recording: (J, scale) chosen}): potentials learned on each recording
    (a row), scored on every recording (a column) by the scan-split Brier score on all cells.

    (a) the scaled preset's coupling J and evidence scale chosen by the scan-split loss on the training recording:
    every (J, scale) is scored on every recording once, the transfer rows read the chosen pair's score; (b) hidden
    and link tables learned by pseudo-likelihood (``steps`` steps), run by converged LBP within ``preset``'s
    region. The last two scaled rows are the analysed preset and the raw grid (from ``results``).
    """
    scaled_scores = {name: modelspace.scaled_scores(sp, couplings, scales) for name, sp in splits.items()}
    learned_scaled = {name: modelspace.fit_scaled(sp, couplings, scales, scores=scaled_scores[name])
                      for name, sp in splits.items()}
    learned_pl = {name: modelspace.fit_pseudolikelihood(sp, steps=steps) for name, sp in splits.items()}
    rows_scaled, rows_pl = [], []
    for train in splits:
        J, s = learned_scaled[train]
        H, L = learned_pl[train]
        row_s, row_p = [f"{train} (J={J:g}, scale={s:g})"], [f"{train} (J={table_coupling(H):.2f})"]
        for test, sp in splits.items():
            row_s.append(scaled_scores[test][(J, s)])
            region = preset.region(sp.first_hits + sp.first_passes > 0)
            raw = sp.raw_probability()
            q = infer(raw, H, L, region=region, max_iter=1000, dtype=np.float32).beliefs.probability
            row_p.append(split_brier(sp, np.where(region, q, raw)))
        rows_scaled.append(row_s)
        rows_pl.append(row_p)
    rows_scaled.append(["recommended preset"] + [results[t][analysed]["all"]["brier"] for t in splits])
    rows_scaled.append(["raw grid"] + [results[t]["raw"]["all"]["brier"] for t in splits])
    return rows_scaled, rows_pl, learned_scaled


# ---- the preset search -----------------------------------------------------------------------------------------------
def preset_search_report(preset, splits, results, resolution, analysed=ANALYSED) -> dict:
    """The cached coordinate search that chose the preset's constants on Intel, checked against today's code.

    Where Intel is in ``splits`` at the search's resolution, the search's best configuration is scored again and
    must give the cached Brier score (else the cache is stale: AssertionError). Returns the search, its trace as
    ``save_table`` arguments (``table``), the numbers to save (``numbers``), and a one-line ``summary``.
    """
    search = preset_search.load_cached()
    constants = preset_search.preset_constants(preset)
    check = {}
    if "intel" in splits and resolution == search["resolution_m"]:  # the cache still matches the code and the data
        check = {"search_best_brier_now": preset_search.search_brier(splits["intel"], search["best"]),
                 "preset_brier": results["intel"][analysed]["all"]["brier"]}
        assert abs(check["search_best_brier_now"] - search["best_brier"]) < 1e-7, "stale preset search cache"
        check["preset_minus_search_best"] = check["preset_brier"] - search["best_brier"]
    differs = {k: {"preset": constants[k], "search": v} for k, v in search["best"].items() if constants[k] != v}
    rows = [[e["round"], e["coordinate"], *(e[k] for k in search["order"]), e["brier"]] for e in search["trace"]]
    table = dict(header=["round", "constant moved", *search["order"], "Brier (Intel, all cells)"], rows=rows,
                 digits=6, caption=f"The coordinate search of the certainty preset's constants on Intel (even / "
                 f"odd scans, {search['resolution_m']:g} m cells, LBP in float32): every configuration scored, in the "
                 f"order scored; {search['configurations']} configurations, {search['rounds']} rounds.")
    numbers = {**{k: search[k] for k in ("best", "best_brier", "rounds", "converged", "configurations", "grid",
                                         "start", "order", "recording", "resolution_m")},
               "grid_sizes": {k: len(v) for k, v in search["grid"].items()},
               "preset": constants, "differs": differs, "check": check}
    summary = (f"search best {search['best']} (Brier {search['best_brier']:.6f}, {search['configurations']} "
               f"configurations); the preset differs in {differs or 'nothing'} {check}")
    return {"search": search, "table": table, "numbers": numbers, "summary": summary}


# ---- ablations and harder splits -------------------------------------------------------------------------------------
def ablation_study(splits, results, training, n_boot, block, seed) -> dict:
    """The analysed preset's ablations and two calibrated independent-cell models fitted on ``training``, scored on
    every recording against the raw grid and against the preset (paired resamples).

    Returns ``calibrators``, ``predictions`` and ``scores`` (per recording, per reference), the ablations' LBP state
    (``lbp``), the log-odds baseline's parameters (``logodds_parameters``, :func:`crfmap.mapping.build_grid`'s
    defaults) and the fitted calibrations (``calibration``).
    """
    calibrators = {"isotonic on x": ablations.IsotonicEvidence.fit_split(splits[training]),
                   "raw, Platt-calibrated": ablations.PlattRaw.fit_split(splits[training])}
    predictions, lbp, scores = {}, {}, {}
    for name, sp in splits.items():
        kept = results[name]["_beliefs"]
        preds, lbp[name] = ablations.ablation_predictions(sp, calibrators)
        predictions[name] = {"raw": kept["raw"], "logodds": kept["logodds"], ANALYSED: kept[ANALYSED], **preds}
        scores[name] = {ref: score(sp, predictions[name], n_boot=n_boot, block=block, seed=seed, reference=ref,
                                   metrics=("brier", "wall_recall")) for ref in ("raw", ANALYSED)}
    logodds_parameters = {k: v.default for k, v in inspect.signature(build_grid).parameters.items()
                          if k in ("p_hit", "p_miss", "logodds_limit")}
    isotonic, platt = calibrators["isotonic on x"], calibrators["raw, Platt-calibrated"]
    calibration = {"isotonic_x": isotonic.x, "isotonic_p": isotonic.p, "platt_alpha": platt.alpha,
                   "platt_beta": platt.beta, "fitted_on": training}
    return {"calibrators": calibrators, "predictions": predictions, "lbp": lbp, "scores": scores,
            "logodds_parameters": logodds_parameters, "calibration": calibration}


def ablation_table(study, training, resolution, n_boot, block) -> tuple:
    """(``save_table`` arguments, numbers per recording and method) of an :func:`ablation_study`."""
    rows, numbers = [], {}
    for name, s in study["scores"].items():
        numbers[name] = {}
        for method in study["predictions"][name]:
            r, c = s["raw"][method], s[ANALYSED][method]
            rows.append([name, method, r["all"]["brier"], _diff_interval(r["all"]), _diff_interval(c["all"]),
                         _diff_interval(c["seen"]), r["unseen"]["brier"], r["all"]["wall_recall"]])
            numbers[name][method] = {
                g: {"brier": r[g]["brier"], "minus_raw": r[g]["brier_diff"], "minus_raw_ci": r[g].get("brier_diff_ci"),
                    "minus_certainty": c[g]["brier_diff"], "minus_certainty_ci": c[g].get("brier_diff_ci"),
                    "cells": r[g]["cells"]} for g in ("all", "seen", "unseen")}
            numbers[name][method]["wall_recall"] = r["all"]["wall_recall"]
    parameters = ", ".join(f"{k} = {v:g}" for k, v in study["logodds_parameters"].items())
    table = dict(header=["recording", "method", "Brier all", "minus raw, 95% CI", "minus certainty, 95% CI",
                         "seen: minus certainty, 95% CI", "Brier unseen", "wall recall"], rows=rows,
                 caption=f"Ablations of the certainty preset and independent-cell models fitted on {training} (scan "
                         f"split, {resolution:g} m cells; paired {n_boot}-resample spatial-block intervals, blocks of "
                         f"{block} cells). Negative differences: lower Brier than the raw grid / than the preset. "
                         f"Log-odds baseline: {parameters}.")
    return table, numbers


def _headlines(scored, methods) -> dict:
    return {m: {"vs_raw": scan_splits.headline(scored["raw"], m), "vs_certainty": scan_splits.headline(scored[ANALYSED], m)}
            for m in methods}


def harder_split_scores(recordings, study, preset, resolution, n_boot, block, seed, split_block, split_tile) -> dict:
    """{recording: {split: {method: headline against the raw grid and against the preset}}}: the even/odd split
    from ``study`` (:func:`ablation_study`), then :func:`crfstudy.splits.harder_splits` (temporal halves, blocks of
    ``split_block`` scans, spatial tiles of ``split_tile`` m), each with the preset, J = 0 and both calibrators (also
    with unseen cells at 0.5)."""
    calibrators = study["calibrators"]
    methods = (ANALYSED, "J = 0", *calibrators, *(c + ", unseen at 0.5" for c in calibrators))
    harder = {name: {"even/odd": _headlines(s, methods)} for name, s in study["scores"].items()}
    for name, rec in recordings.items():
        for kind, sp in scan_splits.harder_splits(rec.scans, resolution, block=split_block, tile=split_tile).items():
            preds = {"raw": sp.raw_probability(),
                     ANALYSED: preset.refine(hits=sp.first_hits, passes=sp.first_passes, max_iter=5000).beliefs.probability,
                     "J = 0": preset.observation(hits=sp.first_hits, passes=sp.first_passes)}
            observed = sp.first_hits + sp.first_passes > 0
            for cal_name, model in calibrators.items():
                p = model.predict_split(sp) if cal_name.startswith("isotonic") else model.predict(preds["raw"])
                preds[cal_name], preds[cal_name + ", unseen at 0.5"] = p, np.where(observed, p, 0.5)
            scored = {ref: score(sp, preds, n_boot=n_boot, block=block, seed=seed, reference=ref, metrics=("brier",))
                      for ref in ("raw", ANALYSED)}
            harder[name][kind] = _headlines(scored, [m for m in preds if m != "raw"])
    return harder


def block_sensitivity(splits, study, block_sizes, n_boot, seed) -> dict:
    """{recording: {block side: intervals}} of the preset minus the raw grid for other bootstrap block sides."""
    return {name: scan_splits.block_sensitivity(sp, {k: study["predictions"][name][k] for k in ("raw", ANALYSED)},
                                                block_sizes, n_boot=n_boot, seed=seed)
            for name, sp in splits.items()}


def _headline_text(h) -> str:
    lo, hi = h["ci"] if h["ci"] is not None else (np.nan, np.nan)
    return f"{h['diff']:+.4f} [{lo:+.4f}, {hi:+.4f}]"


def _pair(interval) -> str:
    """An interval as "[-0.0012, +0.0003]"; "n/a" where there was none (a group too small to resample)."""
    return "n/a" if interval is None else f"[{interval[0]:+.4f}, {interval[1]:+.4f}]"


def split_tables(harder, block_check, n_boot, block, seed, split_block, split_tile) -> tuple:
    """``save_table`` arguments of the harder splits and of the block-size check."""
    rows = []
    for name, kinds in harder.items():
        for kind, methods in kinds.items():
            for g in ("all", "seen", "unseen"):
                rows.append([name, kind, g, methods[ANALYSED]["vs_raw"][g]["cells"],
                             _headline_text(methods[ANALYSED]["vs_raw"][g]),
                             _headline_text(methods["J = 0"]["vs_certainty"][g]),
                             _headline_text(methods["isotonic on x"]["vs_certainty"][g]),
                             _headline_text(methods["isotonic on x, unseen at 0.5"]["vs_certainty"][g])])
    splits_table = dict(
        header=["recording", "split", "group", "cells scored", "certainty minus raw", "J = 0 minus certainty",
                "isotonic minus certainty", "isotonic (unseen 0.5) minus certainty"], rows=rows,
        caption=f"Brier differences with paired 95 % spatial-block intervals ({n_boot} resamples, blocks of {block} "
                f"cells) on four scan splits: even/odd, temporal halves, blocks of {split_block} scans, spatial "
                f"tiles of {split_tile:g} m. Negative: the first method has the lower Brier score.")
    block_rows = [[name, b, *(_pair(v[ANALYSED][g]) for g in ("all", "seen", "unseen"))]
                  for name, per_block in block_check.items() for b, v in per_block.items()]
    blocks_table = dict(header=["recording", "block [cells]", "all", "seen", "unseen"], rows=block_rows,
                        caption="The preset minus the raw grid (Brier, even/odd scans): paired 95 % intervals for other "
                                f"bootstrap block sides ({n_boot} resamples, seed {seed}).")
    return splits_table, blocks_table


def split_counts(harder) -> dict:
    """On the harder splits (not even/odd), counted: where the preset beats the raw grid (seen cells, all cells) and
    where the isotonic independent-cell model beats the preset (all cells); ``lower`` by the point estimate,
    ``significant`` with the interval below zero."""
    cases = [kinds[k] for kinds in harder.values() for k in kinds if k != "even/odd"]

    def count(first, against, group):
        heads = [m[first][against][group] for m in cases]
        return {"lower": sum(h["diff"] < 0 for h in heads),
                "significant": sum(h["ci"] is not None and h["ci"][1] < 0 for h in heads)}

    return {"cases": len(cases), "certainty_vs_raw_seen": count(ANALYSED, "vs_raw", "seen"),
            "certainty_vs_raw_all": count(ANALYSED, "vs_raw", "all"),
            "isotonic_vs_certainty_all": count("isotonic on x", "vs_certainty", "all")}


# ---- the published peers --------------------------------------------------------------------------------------------
def peer_recordings(splits, roles, results, resolution, quick, analysed=ANALYSED) -> tuple:
    """(splits, roles, {recording: {row: P}}, {recording: {peer: fit seconds}}) for the peers section.

    The recordings of the sections above (their kept grids), then :data:`MORE_RECORDINGS` (not in quick mode; a
    missing one is skipped with what to download) with every table row computed; the peers' maps come from
    :func:`cached_peer_rows`.
    """
    peer_splits, peer_roles = dict(splits), dict(roles)
    beliefs = {n: r["_beliefs"] for n, r in results.items()}
    for label, relative in ({} if quick else MORE_RECORDINGS).items():
        try:
            sp = scan_split(load_recording(data_file(relative)).scans, resolution)
        except DataMissingError as exc:  # named with what to download; the section runs without it
            print(f"skipping {label}: {exc}")
            continue
        peer_splits[label], peer_roles[label] = sp, "confirmation"
        rows = [m for m in TABLE_ROWS if m not in ("octomap", "hilbert", *PRESET_ROWS)]
        beliefs[label] = compare(sp, analysed, n_boot=0, methods=rows, keep_beliefs=True, nav=False)["_beliefs"]
        beliefs[label].update(preset_rows(sp))
    seconds = {}
    for label, sp in peer_splits.items():
        rows, seconds[label] = cached_peer_rows(label, sp, progress=True, quick=quick)
        beliefs[label].update(rows)
        print(label, peer_roles[label], {k: f"{v:.1f} s" for k, v in seconds[label].items()})
    return peer_splits, peer_roles, beliefs, seconds


def peers_table(tables, training) -> dict:
    """``save_table`` arguments: every recording's :func:`peer_table` in one table, a recording column first."""
    return dict(header=["recording"] + tables[training]["header"],
                rows=[[label] + row for label, table in tables.items() for row in table["rows"]],
                caption="Published peers on every recording: scan-split scores, paired differences to the "
                        f"{' and the '.join(PRESET_ROWS)} presets (negative: lower Brier than that preset), expected "
                        "calibration error.")


def peer_numbers(peer_results, default=DEFAULT_PRESET) -> dict:
    """The peers section's numbers per recording: scores, differences to the default preset, calibration error and
    reliability curves, and the Hilbert map's constant search on Intel."""
    return {
        "versus_default": {label: {name: {g: {k: v for k, v in e.items() if "diff" in k} for g, e in groups.items()}
                                   for name, groups in res["versus"][default].items()}
                           for label, res in peer_results.items()},
        "hilbert_search_intel": [dict(zip(HILBERT_SEARCH_COLUMNS, row)) for row in HILBERT_SEARCH_INTEL],
        "scores": {label: {name: {g: dict(e) for g, e in groups.items()} for name, groups in res["scores"].items()}
                   for label, res in peer_results.items()},
        "ece": {label: {name: c["ece"] for name, c in res["calibration"].items()} for label, res in peer_results.items()},
        "reliability": {label: {name: {k: c[k] for k in ("count", "mean_p", "share")}
                                for name, c in res["calibration"].items()} for label, res in peer_results.items()},
    }
