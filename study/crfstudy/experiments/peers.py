"""Notebook 10's "Published peers" section: every method per recording, calibration, maps side by side.

The peers' maps (:mod:`crfmap.assess.peers`) are cached under ``crfstudy.paths.OUT / "cache" / "peers"``,
keyed by the first half's scans, the grid, the peers' constants and the settings, so a rerun does not refit them.

Settings (:class:`PeerSettings`): :data:`FULL` fits the Hilbert map on every scan of the first half with
the constants chosen on Intel (:mod:`crfmap.mapping.hilbert`); :data:`QUICK` (the notebook's quick run,
CI) fits it on every 4th scan with features twice as far apart, only to show the section runs: its
numbers are not the peer's. OctoMap's update is cheap and runs on every scan in both.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, replace
import time

import numpy as np

from crfstudy import paths
from crfmap.crf.presets import DEFAULT_PRESET, get_preset
from crfmap.assess.peers import OCTOMAP_INTEL, hilbert_row, peer_rows
from crfmap.mapping import hilbert
from crfmap.io.atomic import atomic_path
from crfmap.assess.calibration import apply_temperature, split_calibration
from crfmap.assess.scansplit import score
from crfstudy.experiments.beyond_figures import densest_window

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
        preds[f"{ANALYSED}-T"] = apply_temperature(preds[ANALYSED], temperature)
    versus = {ref: score(split, preds, n_boot=n_boot, block=block, seed=seed, reference=ref)
              for ref in PRESET_ROWS if ref in preds}
    calib = split_calibration(split, preds)  # every row: the baselines as well as the presets and the peers
    return {"scores": versus[ANALYSED], "versus": versus, "calibration": calib}


def _ci(entry, key):
    lo, hi = entry.get(key + "_ci", (np.nan, np.nan))
    return f"[{lo:.4f}, {hi:.4f}]"


def _diff(entry):
    d = entry.get("brier_diff_ci", (np.nan, np.nan))
    return f"{entry['brier_diff']:+.4f} [{d[0]:+.4f}, {d[1]:+.4f}]"


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
        rows.append([name, a["brier"], _ci(a, "brier"), *(_diff(v[name]["all"]) for v in versus.values()),
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
