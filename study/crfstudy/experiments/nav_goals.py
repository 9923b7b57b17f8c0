"""Issue 38's goal table: does the default preset beat the raw grid where a robot feels it, on every recording?

For each recording (:data:`RECORDINGS`: Intel and ACES chose the default, the other four only confirm it)
:func:`score_recording` scores the raw grid, the old default ``certainty``, the default
(:data:`crfmap.crf.presets.DEFAULT_PRESET`) and the published peers on the even / odd scan split
(:func:`crfmap.assess.comparison.compare`: Brier, and the map as nav2 reads it, with paired spatial-block
intervals against the raw grid), their calibration (ECE), AMCL's localisation on each map
(:func:`crfmap.assess.localisation.compare_localisation`, the held-out scans) and, on the harder splits of
:mod:`crfstudy.splits`, the default against the calibrated independent-cell models
(:mod:`crfstudy.analysis.ablations`, fitted on Intel's even / odd split as in notebook 10). The result is a
compact dictionary of numbers (a *summary*); :func:`recording_goals` reads goals 1-6 and 8 off it.
Goal 7 comes from the closed loop (:mod:`crfstudy.experiments.closed_loop`): :func:`closed_loop_goals`.

How each goal is decided: :mod:`crfstudy.experiments.goal_rules`.

``python -m crfstudy.experiments.nav_goals [--quick] [RECORDING ...]`` prints the table (notebook 12 saves it).

Notebook 12 takes its study parts from this module: :func:`run`, the tables of :mod:`~crfstudy.experiments.goal_rules`
(:func:`goal_matrix`, :func:`goal_details`, :func:`harder_matrix`, taken from here), :func:`verdict_numbers`,
:func:`goals_figure`, and the trade-offs of :mod:`crfstudy.analysis.tradeoff` with the goal table's settings
(:func:`tradeoff_curves`, :func:`tradeoff_tables`, :func:`tradeoff_loop_records`, :func:`tradeoff_loop_table`).

>>> GoalSettings().resolution, "hilbert" in QUICK.peers
(0.05, False)
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass

import numpy as np

from crfmap.assess.peers import PEERS
from crfmap.crf.presets import DEFAULT_PRESET
from crfmap.data import data_file, have_data
from crfmap.errors import InputError
from crfstudy.analysis import tradeoff
from crfstudy.experiments.goal_rules import (LEGEND, MISSED, OLD_DEFAULT, closed_loop_goals, goal_details, goal_matrix,
                                             harder_matrix, recording_goals)

RECORDINGS = {  # name: file under crfmap.data.data_root(); the names notebook 10 uses
    "intel": "carmen/intel-corrected.log.gz", "aces": "carmen/aces-corrected.log.gz",
    "ros2": "rosbags/olin_comprobo24_turtlebot4/macfirst_floor_take_2",
    "ros1": "rosbags/zaki0929_bagfiles/2019_jan17_expt04_bagfile.bag",
    "csail": "carmen/csail-corrected.log.gz", "fr101": "carmen/freiburg-101-corrected.log.gz"}
ROLES = {"intel": "choosing", "aces": "choosing"}  # issue 38: chosen on these two; every other one confirms
QUICK_RECORDINGS = ("ros2", "ros1")  # CI: the two small bags
TRAINING = "intel"  # the calibrated independent-cell models are fitted on its even / odd split
CALIBRATED = ("isotonic on x", "raw, Platt-calibrated")  # the independent-cell models of crfstudy.analysis.ablations



@dataclass(frozen=True)
class GoalSettings:
    """Everything that sets the goal table's numbers (the notebook's parameters; :data:`QUICK` for CI)."""

    resolution: float = 0.05  # [m] cell size of every recording's grids
    n_boot: int = 200  # spatial-block (maps) and scan (AMCL) bootstrap resamples
    block: int = 16  # [cells] bootstrap block side
    seed: int = 0
    peers: tuple = PEERS  # crfmap.assess.peers rows: every published peer (constants chosen on Intel; OctoMap's defaults)
    split_block: int = 50  # [scans] scan blocks of the harder splits
    split_tile: float = 4.0  # [m] spatial tiles of the harder splits
    loc_scans: int = 150  # held-out scans AMCL is scored on, evenly spread over the log
    n_floors: int = 4  # closed loop: procedural office floors (notebook 11's setting) ...
    floor_size: tuple = (12.0, 10.0)  # [m]
    thesis_scenes: tuple = ("enclosed-train", "enclosed-test", "occluded-train")  # ... and the thesis's scenes
    loop_resolution: float = 0.1  # [m]
    max_scans: int = 600  # closed loop: scan budget per run
    loop_boot: int = 2000  # bootstrap resamples over the closed loop's scenes


QUICK = GoalSettings(resolution=0.1, n_boot=20, peers=tuple(p for p in PEERS if p != "hilbert"), loc_scans=30,
                     n_floors=1, floor_size=(8.0, 6.0), thesis_scenes=("enclosed-train",), max_scans=150, loop_boot=200)


def peer_rows(hilbert: bool = True) -> tuple:
    """The published peers scored beside the presets (:data:`crfmap.assess.peers.PEERS`), without the Bayesian
    Hilbert map unless ``hilbert`` (the slowest fit by far)."""
    return tuple(p for p in PEERS if hilbert or p != "hilbert")


# --- scoring --------------------------------------------------------------------------------------------------


def fit_calibrators(split) -> dict:
    """{name: fitted model} of :data:`CALIBRATED` on ``split`` (the training recording's even / odd split)."""
    from crfstudy.analysis.ablations import IsotonicEvidence, PlattRaw

    return {CALIBRATED[0]: IsotonicEvidence.fit_split(split), CALIBRATED[1]: PlattRaw.fit_split(split)}


def _calibrated(model, split):
    return model.predict_split(split) if hasattr(model, "predict_split") else model.predict(split.raw_probability())


def _pair(ci):
    return None if ci is None else [float(ci[0]), float(ci[1])]


def harder_scores(scans, settings: GoalSettings, calibrators: dict) -> dict:
    """{split name: {"brier": {row: Brier, all cells}, "opponent", "diff", "ci", "groups", "cells"}} on the harder splits.

    Rows: raw, the old default, the default and the calibrated models; ``opponent`` is the calibrated model with the
    lower Brier on all cells there, ``diff`` / ``ci`` the default minus it (paired interval), ``groups`` the same
    for the cells the map had seen and those it had not: {group: {"diff", "ci"}}.
    """
    from crfmap.assess.navigation import nav_scores
    from crfmap.assess.scansplit import GROUPS, score
    from crfstudy.splits import harder_splits
    from crfmap.crf.presets import get_preset

    out = {}
    for kind, sp in harder_splits(scans, settings.resolution, block=settings.split_block,
                                  tile=settings.split_tile).items():
        preds = {"raw": sp.raw_probability()}
        results = {name: get_preset(name).refine(hits=sp.first_hits, passes=sp.first_passes)
                   for name in (OLD_DEFAULT, DEFAULT_PRESET)}
        preds.update({name: r.beliefs.probability for name, r in results.items()})
        preds.update({name: _calibrated(model, sp) for name, model in calibrators.items()})
        s = score(sp, preds, n_boot=settings.n_boot, block=settings.block, seed=settings.seed,
                  reference=DEFAULT_PRESET, metrics=("brier",))
        brier = {name: s[name]["all"]["brier"] for name in preds}
        opponent = min(calibrators, key=brier.get)  # the stronger independent-cell model on this split
        groups = {}
        for group in GROUPS:
            entry = s[opponent][group]  # opponent minus default: flipped to default minus opponent
            ci = entry.get("brier_diff_ci")
            groups[group] = {"diff": -entry["brier_diff"], "ci": None if ci is None else [-ci[1], -ci[0]],
                             "cells": entry["cells"]}
        # goals 2-5 on this split too: nav2's reading of the default's map against the raw grid's, same resamples
        nav = nav_scores(sp, {"raw": preds["raw"], DEFAULT_PRESET: results[DEFAULT_PRESET].nav2_map.probability},
                         n_boot=settings.n_boot, block=settings.block, seed=settings.seed)
        out[kind] = {"brier": brier, "opponent": opponent, **groups["all"], "groups": groups,
                     "nav": {name: _nav_entry(entry) for name, entry in nav.items()}}
    return out


def _nav_entry(nav: dict) -> dict:
    keep = ("lethal_recall", "lethal_precision", "miss_rate", "far_miss_rate", "ghost_rate", "face_offset")
    out = {}
    for group in ("all", "seen", "unseen"):
        g = nav[group]
        out[group] = {m: g[m] for m in keep}
        out[group].update({f"{m}_diff": g[m + "_diff"] for m in keep if m + "_diff" in g})
        out[group].update({f"{m}{s}": _pair(g[m + s]) for m in keep for s in ("_ci", "_diff_ci") if m + s in g})
    out["map"] = {m: nav["map"][m] for m in ("thickness", "components_per_10m", "lethal_cells", "unknown_free")}
    return out


def score_recording(scans, settings: GoalSettings, calibrators: dict, progress=None) -> dict:
    """The summary of one recording (a dict of numbers, see the module doc) that :func:`recording_goals` reads.

    ``scans``: the recording's ScanSet; ``calibrators``: :func:`fit_calibrators` of the training recording;
    ``progress``: a callable given a short label before each stage (a tqdm bar's ``set_postfix_str``).
    """
    from crfmap.assess.calibration import split_calibration
    from crfmap.assess.comparison import compare
    from crfmap.assess.localisation import compare_localisation
    from crfmap.assess.navigation import nav_scores
    from crfmap.assess.scansplit import scan_split
    from crfmap.crf.presets import get_preset
    from crfstudy.calibration import paired_calibration

    say = progress or (lambda _: None)
    started = time.perf_counter()
    s = settings
    say("scan split")
    split = scan_split(scans, s.resolution)
    say("certainty")
    old = get_preset(OLD_DEFAULT).refine(hits=split.first_hits, passes=split.first_passes).beliefs.probability
    say("compare" + (" (fitting " + ", ".join(s.peers) + ")" if s.peers else ""))
    res = compare(split, DEFAULT_PRESET, n_boot=s.n_boot, block=s.block, seed=s.seed, extra={OLD_DEFAULT: old},
                  keep_beliefs=True, methods=["raw", DEFAULT_PRESET, *s.peers])
    beliefs, maps = res["_beliefs"], res["_maps"]  # probabilities (Brier, ECE) and the maps nav2 reads (the rest)
    # goal 8's "within its interval of the best" on lethal recall: the best of raw and the peers against the default,
    # on the same resamples (same split, block and seed); only that pair is scored again
    recall = {m: res["_nav"][m]["all"]["lethal_recall"] for m in maps if m not in (DEFAULT_PRESET, OLD_DEFAULT)}
    best = max(recall, key=recall.get)
    versus = nav_scores(split, {DEFAULT_PRESET: maps[DEFAULT_PRESET], best: maps[best]}, n_boot=s.n_boot,
                        block=s.block, seed=s.seed, reference=DEFAULT_PRESET, scores=res)
    old_vs = res["_vs_preset"][OLD_DEFAULT]["all"]  # certainty minus default: flip to default minus certainty
    ci = old_vs.get("brier_diff_ci")
    ece_pair = paired_calibration(split, {m: beliefs[m] for m in (OLD_DEFAULT, DEFAULT_PRESET)}, OLD_DEFAULT,
                                  n_boot=s.n_boot, block=s.block, seed=s.seed)[DEFAULT_PRESET]
    say("localisation")
    # goal 6 is the default against raw; the old default beside them (the peers' AMCL is not a goal: time saved)
    on = {m: maps[m] for m in ("raw", OLD_DEFAULT, DEFAULT_PRESET)}
    loc = compare_localisation(on, split.resolution, split.origin, split.second_scans, n_boot=s.n_boot, seed=s.seed,
                               max_scans=s.loc_scans)
    say("harder splits")
    harder = harder_scores(scans, s, calibrators)
    return {
        "scans": len(scans), "grid": list(split.shape), "cells_scored": int(split.group("all").sum()),
        "brier": {m: {g: res[m][g]["brier"] for g in ("all", "seen", "unseen")} for m in maps},
        "brier_vs_certainty": {"diff": -old_vs["brier_diff"], "ci": None if ci is None else [-ci[1], -ci[0]]},
        "ece": {m: c["ece"] for m, c in split_calibration(split, beliefs).items()},
        "ece_vs_certainty": {"diff": ece_pair["ece_diff"], "ci": _pair(ece_pair["ece_diff_ci"])},
        "nav": {m: _nav_entry(res["_nav"][m]) for m in maps},
        "nav_vs_default": {best: {k: (_pair(v) if k.endswith("_ci") else v) for k, v in versus[best]["all"].items()
                                  if k.startswith("lethal_recall_diff")}},
        "localisation": {m: {k: (_pair(v) if k.endswith("_ci") else v) for k, v in e.items()} for m, e in loc.items()},
        "harder": harder, "lbp": res.get("_lbp"), "peer_seconds": res.get("_seconds", {}),
        "seconds": time.perf_counter() - started,
    }


# --- the goals --------------------------------------------------------------------------------------------------


def run_closed_loop_records(settings: GoalSettings, kinds=None, progress=None) -> list:
    """The closed loop's records (every onboard kind, None: all of :data:`crfstudy.closed_loop.onboard.ONBOARD_MAPS`,
    on every scene; the range noise's seed ``settings.seed``)."""
    from crfstudy.closed_loop.exploration import ExploreSettings
    from crfstudy.experiments.closed_loop import closed_loop_scenes, run_closed_loop

    scenes = closed_loop_scenes(settings.n_floors, settings.floor_size, settings.loop_resolution,
                                thesis_scenes=settings.thesis_scenes)
    explore = ExploreSettings(max_scans=settings.max_scans)  # notebook 11's other settings are the defaults
    records, _ = run_closed_loop(scenes, kinds=kinds, settings=explore, seed=settings.seed, progress=progress)
    return records


# --- the table ----------------------------------------------------------------------------------------------------

def goals_figure(summaries: dict):
    """Per recording, the default against raw (and certainty): misses, ghosts, wall thickness, AMCL found."""
    import matplotlib.pyplot as plt

    panels = (("miss_rate", "seen", "dangerous misses, seen cells"), ("ghost_rate", "all", "ghost obstacles"),
              ("thickness", "map", "wall thickness [cells]"), ("found", "loc", "AMCL found (10 cm, 3 deg)"))
    rows = ("raw", OLD_DEFAULT, DEFAULT_PRESET)
    names = list(summaries)
    fig, axes = plt.subplots(1, len(panels), figsize=(3.4 * len(panels), 3.2), constrained_layout=True)
    x = np.arange(len(names))
    width = 0.8 / len(rows)
    for ax, (metric, group, title) in zip(axes, panels):
        for k, row in enumerate(rows):
            vals, lo, hi = [], [], []
            for name in names:
                s = summaries[name]
                e = s["localisation"][row] if group == "loc" else s["nav"][row][group]
                v = e[metric]
                ci = e.get(metric + "_ci") or [v, v]
                vals.append(v), lo.append(v - ci[0]), hi.append(ci[1] - v)
            ax.bar(x + (k - 1) * width, vals, width, yerr=[lo, hi], label=row, capsize=2)
        ax.set_xticks(x, names, fontsize=8), ax.set_title(title, fontsize=9)
    axes[0].legend(fontsize=7)
    return fig


def verdict_numbers(columns: dict) -> tuple:
    """(verdicts, missed) of :func:`run`'s ``columns`` as plain numbers: ``verdicts[where][goal]`` = {what, verdict,
    numbers}, ``missed[where]`` = the goals :data:`~crfstudy.experiments.goal_rules.MISSED` there."""
    verdicts = {where: {v.goal: {"what": v.what, "verdict": v.status, "numbers": v.evidence} for v in vs}
                for where, vs in columns.items()}
    missed = {where: [g for g, v in vs.items() if v["verdict"] == MISSED] for where, vs in verdicts.items()}
    return verdicts, missed


# --- the trade-offs (crfstudy.analysis.tradeoff) at the goal table's settings ------------------------------------

TRADEOFF_MOVED = {  # what each trade-off table moves, as its caption names it
    "J": "the coupling J",
    "unobserved_prior": "the never-observed prior pi (it moves no decision: the gate reads those cells unknown)",
    "free_evidence": "the gate's free_evidence (net passes before a cell reads free)",
    "lethal_evidence": "the gate's lethal_evidence (net hits that keep a cell lethal)"}


def tradeoff_curves(files: dict, settings: GoalSettings) -> dict:
    """{setting: {recording: scores}} of :func:`crfstudy.analysis.tradeoff.run` on ``files`` ({name: path}) at the
    goal table's resolution, resamples, block and seed."""
    return tradeoff.run(files, resolution=settings.resolution, n_boot=settings.n_boot, block=settings.block,
                        seed=settings.seed, progress=False)


def tradeoff_tables(curves: dict, settings: GoalSettings) -> dict:
    """{setting: {header, rows, caption}} (``save_table``'s arguments): :func:`crfstudy.analysis.tradeoff.tradeoff_table` of each of
    :func:`tradeoff_curves`' settings, captioned with what it moves (:data:`TRADEOFF_MOVED`)."""
    tables = {}
    for setting, scores in curves.items():
        caption = (f"The default preset {DEFAULT_PRESET} with {TRADEOFF_MOVED[setting]} moved, every other constant "
                   f"kept: per sub-goal, the recordings ({', '.join(scores)}) where it is met by the goal table's "
                   f"rules, and the mean difference ({settings.n_boot} resamples); free cells: seen cells nav2 reads "
                   "free, as a share of the raw grid's.")
        header, rows = tradeoff.tradeoff_table(scores)
        tables[setting] = {"header": header, "rows": rows, "caption": caption}
    return tables


def tradeoff_loop_records(settings: GoalSettings) -> list:
    """The closed loop with each of the gate's ``free_evidence`` (:func:`crfstudy.analysis.tradeoff.closed_loop_records`)
    on the goal table's scenes, budget and seed."""
    return tradeoff.closed_loop_records(settings)


def tradeoff_loop_table(records: list, settings: GoalSettings) -> tuple:
    """(header, rows): :func:`crfstudy.analysis.tradeoff.closed_loop_table` of ``records`` with the goal table's
    resamples over scenes and seed."""
    return tradeoff.closed_loop_table(records, n_boot=settings.loop_boot, seed=settings.seed)


# --- the command --------------------------------------------------------------------------------------------------


def run(files: dict, settings: GoalSettings, training=None, progress: bool = True) -> tuple:
    """(summaries, records, columns) for the recordings ``files`` ({name: path}) and the closed loop.

    The calibrated independent-cell models are fitted on the even / odd split of the recording at ``training``
    (a path; None: the first of ``files``). ``columns``: {recording or closed loop: [Verdict]} for the tables.
    """
    from tqdm.auto import tqdm

    from crfmap.assess.scansplit import scan_split
    from crfmap.io.recordings import load_recording

    if not files:
        raise InputError("recordings", "nothing to score")
    trainer = next(iter(files.values())) if training is None else training
    calibrators = fit_calibrators(scan_split(load_recording(trainer).scans, settings.resolution))
    summaries, bar = {}, tqdm(list(files), desc="recordings", disable=not progress, file=sys.stderr)
    for name in bar:
        bar.set_description(name)
        summaries[name] = score_recording(load_recording(files[name]).scans, settings, calibrators,
                                          progress=bar.set_postfix_str)
        summaries[name]["calibrated_on"] = str(trainer)
    if progress:
        print("closed loop ...", file=sys.stderr)
    records = run_closed_loop_records(settings)
    columns = {name: recording_goals(s) for name, s in summaries.items()}
    columns["closed loop"] = closed_loop_goals(records, n_boot=settings.loop_boot, seed=settings.seed)
    columns["closed loop (refined on arrival)"] = closed_loop_goals(records, kind="refined-on-arrival",
                                                                    n_boot=settings.loop_boot, seed=settings.seed)
    return summaries, records, columns


def main(argv=None) -> int:
    """``python -m crfstudy.experiments.nav_goals [--quick] [RECORDING ...]``: print issue 38's goal table."""
    import argparse

    from crfmap.environment import prepare
    from crfstudy.repro.report import markdown_table

    parser = argparse.ArgumentParser(prog="python -m crfstudy.experiments.nav_goals", description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="CI's settings: coarse grids, few resamples, no hilbert")
    parser.add_argument("recordings", nargs="*", metavar="RECORDING",
                        help=f"any of {', '.join(RECORDINGS)} (default: all; with --quick {', '.join(QUICK_RECORDINGS)})")
    args = parser.parse_args(argv)
    names = args.recordings or list(QUICK_RECORDINGS if args.quick else RECORDINGS)
    settings = QUICK if args.quick else GoalSettings()
    started = time.perf_counter()
    try:
        prepare()
        unknown = [n for n in names if n not in RECORDINGS]
        if unknown:
            raise InputError("RECORDING", f"unknown {', '.join(unknown)}; known: {', '.join(RECORDINGS)}")
        files = {name: data_file(RECORDINGS[name]) for name in names}
        training = data_file(RECORDINGS[TRAINING]) if have_data(RECORDINGS[TRAINING]) else None
        summaries, _, columns = run(files, settings, training=training)
    except InputError as e:  # an unknown recording, the data missing
        print(f"nav goals: {e}", file=sys.stderr)
        return 2
    print(markdown_table(*goal_matrix(columns)))
    print(LEGEND + "\n")
    print(markdown_table(*harder_matrix(summaries)) + "\n")
    print(markdown_table(*goal_details(columns)))
    print(f"{'quick' if args.quick else 'full'} settings, {time.perf_counter() - started:.0f} s")
    return 0


__all__ = ["RECORDINGS", "ROLES", "QUICK_RECORDINGS", "TRAINING", "CALIBRATED", "GoalSettings", "QUICK", "peer_rows",
           "fit_calibrators", "harder_scores", "score_recording", "run_closed_loop_records", "goals_figure", "run",
           "verdict_numbers", "goal_matrix", "goal_details", "harder_matrix", "LEGEND", "TRADEOFF_MOVED",
           "tradeoff_curves", "tradeoff_tables", "tradeoff_loop_records", "tradeoff_loop_table", "main"]

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
