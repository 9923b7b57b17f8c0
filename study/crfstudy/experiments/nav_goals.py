"""Issue 38's goal table: does the default preset beat the raw grid where a robot feels it, on every recording?

For each recording (:data:`RECORDINGS`: Intel and ACES chose the default, the other four only confirm it)
:func:`score_recording` scores the raw grid, the old default ``certainty``, the default
(:data:`crfmap.crf.presets.DEFAULT_PRESET`) and the published peers on the even / odd scan split
(:func:`crfmap.assess.comparison.compare`: Brier, and the map as nav2 reads it, with paired spatial-block
intervals against the raw grid), their calibration (ECE), AMCL's localisation on each map
(:func:`crfmap.assess.localisation.compare_localisation`, the held-out scans) and, on the harder splits of
:mod:`crfmap.assess.splits`, the default against the calibrated independent-cell models
(:mod:`crfstudy.analysis.ablations`, fitted on Intel's even / odd split as in notebook 10). The result is a
compact dictionary of numbers (a *summary*); :func:`recording_goals` reads goals 1-6 and 8 off it.
Goal 7 comes from the closed loop (:mod:`crfstudy.experiments.closed_loop`): :func:`closed_loop_goals`.

How a goal is decided (every sub-goal is one :class:`Verdict`, its numbers beside it):

- "no worse than X" is met when the paired 95 % interval of the difference reaches 0 or the good side (the
  data do not show it worse; the issue's goal 1 says so). Met with the point estimate on the worse side is
  marked ``met*``: not shown worse, not shown as good.
- "better than X" / "fewer" / "above" is met when the whole interval lies on the good side.
- Without an interval (``n_boot = 0``, or a map measure: wall thickness, components, ECE) the point estimates
  decide; goal 8's "best of" compares point estimates, and its recall part accepts the paired interval of the
  best peer minus the default reaching 0.

``python -m crfstudy.experiments.nav_goals [--quick] [RECORDING ...]`` prints the table (notebook 12 saves it).

>>> v = recording_goals(example_summary())
>>> [(x.goal, x.status) for x in v][:3]
[('1a', 'met*'), ('1b', 'met'), ('1c', 'missed')]
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass

import numpy as np

from crfmap.crf.presets import DEFAULT_PRESET
from crfmap.errors import InputError

RECORDINGS = {  # name: file under crfmap.data.data_root(); the names notebook 10 uses
    "intel": "carmen/intel-corrected.log.gz", "aces": "carmen/aces-corrected.log.gz",
    "ros2": "rosbags/olin_comprobo24_turtlebot4/macfirst_floor_take_2",
    "ros1": "rosbags/zaki0929_bagfiles/2019_jan17_expt04_bagfile.bag",
    "csail": "carmen/csail-corrected.log.gz", "fr101": "carmen/freiburg-101-corrected.log.gz"}
ROLES = {"intel": "choosing", "aces": "choosing"}  # issue 38: chosen on these two; every other one confirms
QUICK_RECORDINGS = ("ros2", "ros1")  # CI: the two small bags
TRAINING = "intel"  # the calibrated independent-cell models are fitted on its even / odd split
OLD_DEFAULT = "certainty"  # the default before issue 38: goal 1's reference for Brier and ECE
CALIBRATED = ("isotonic on x", "raw, Platt-calibrated")  # the independent-cell models of crfstudy.analysis.ablations
ONBOARD = ("raw", "online-crf", "octomap", "refined-on-arrival")  # closed-loop kinds (crfmap.sim.onboard)
LOOP_KIND = "online-crf"  # goal 7 is the online CRF's; refined-on-arrival (the gated preset every 10 scans) informs
LOOP_VERSUS = ("raw", "octomap")
LOOP_METRICS = {"scans": "scans to 95 % coverage", "collisions": "collisions", "plans_into_walls": "plans into walls"}
MET, MET_INTERVAL, MISSED, NOT_SCORED = "met", "met*", "missed", "n/a"
LEGEND = (f"{MET}: every sub-goal met; {MET_INTERVAL}: met, one or more only by its interval (the point estimate on the "
          f"worse side, the 95 % interval reaching no difference); {MISSED}: the sub-goals named missed; "
          f"{NOT_SCORED}: not scored there.")


@dataclass(frozen=True)
class GoalSettings:
    """Everything that sets the goal table's numbers (the notebook's parameters; :data:`QUICK` for CI)."""

    resolution: float = 0.05  # [m] cell size of every recording's grids
    n_boot: int = 200  # spatial-block (maps) and scan (AMCL) bootstrap resamples
    block: int = 16  # [cells] bootstrap block side
    seed: int = 0
    peers: tuple = ("octomap", "hilbert")  # crfmap.assess.peers rows; hilbert at its constants chosen on Intel
    split_block: int = 50  # [scans] scan blocks of the harder splits
    split_tile: float = 4.0  # [m] spatial tiles of the harder splits
    loc_scans: int = 150  # held-out scans AMCL is scored on, evenly spread over the log
    n_floors: int = 4  # closed loop: procedural office floors (notebook 11's setting) ...
    floor_size: tuple = (12.0, 10.0)  # [m]
    thesis_scenes: tuple = ("enclosed-train", "enclosed-test", "occluded-train")  # ... and the thesis's scenes
    loop_resolution: float = 0.1  # [m]
    max_scans: int = 600  # closed loop: scan budget per run
    loop_boot: int = 2000  # bootstrap resamples over the closed loop's scenes


QUICK = GoalSettings(resolution=0.1, n_boot=20, peers=("octomap",), loc_scans=30, n_floors=1, floor_size=(8.0, 6.0),
                     thesis_scenes=("enclosed-train",), max_scans=150, loop_boot=200)


@dataclass(frozen=True)
class Verdict:
    """One sub-goal on one recording (or the closed loop): met or not, and the numbers that decide it."""

    goal: str  # "1a", "2b", ...
    what: str
    met: bool | None  # None: not scored (a row or a number missing)
    evidence: str
    interval_only: bool = False  # met under a "no worse" rule with the point estimate on the worse side

    @property
    def status(self) -> str:
        if self.met is None:
            return NOT_SCORED
        return (MET_INTERVAL if self.interval_only else MET) if self.met else MISSED


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
    from crfmap.assess.scansplit import GROUPS, score
    from crfmap.assess.splits import harder_splits
    from crfmap.crf.presets import get_preset

    out = {}
    for kind, sp in harder_splits(scans, settings.resolution, block=settings.split_block,
                                  tile=settings.split_tile).items():
        preds = {"raw": sp.raw_probability()}
        preds.update({name: get_preset(name).refine(hits=sp.first_hits, passes=sp.first_passes).beliefs.probability
                      for name in (OLD_DEFAULT, DEFAULT_PRESET)})
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
        out[kind] = {"brier": brier, "opponent": opponent, **groups["all"], "groups": groups}
    return out


def _nav_entry(nav: dict) -> dict:
    keep = ("lethal_recall", "lethal_precision", "miss_rate", "far_miss_rate", "ghost_rate")
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
    maps = res["_beliefs"]
    # goal 8's "within its interval of the best" on lethal recall: the best of raw and the peers against the default,
    # on the same resamples (same split, block and seed); only that pair is scored again
    recall = {m: res["_nav"][m]["all"]["lethal_recall"] for m in maps if m not in (DEFAULT_PRESET, OLD_DEFAULT)}
    best = max(recall, key=recall.get)
    versus = nav_scores(split, {DEFAULT_PRESET: maps[DEFAULT_PRESET], best: maps[best]}, n_boot=s.n_boot,
                        block=s.block, seed=s.seed, reference=DEFAULT_PRESET, scores=res)
    old_vs = res["_vs_preset"][OLD_DEFAULT]["all"]  # certainty minus default: flip to default minus certainty
    ci = old_vs.get("brier_diff_ci")
    say("localisation")
    loc = compare_localisation(maps, split.resolution, split.origin, split.second_scans, n_boot=s.n_boot,
                               seed=s.seed, max_scans=s.loc_scans)
    say("harder splits")
    harder = harder_scores(scans, s, calibrators)
    return {
        "scans": len(scans), "grid": list(split.shape), "cells_scored": int(split.group("all").sum()),
        "brier": {m: {g: res[m][g]["brier"] for g in ("all", "seen", "unseen")} for m in maps},
        "brier_vs_certainty": {"diff": -old_vs["brier_diff"], "ci": None if ci is None else [-ci[1], -ci[0]]},
        "ece": {m: c["ece"] for m, c in split_calibration(split, maps).items()},
        "nav": {m: _nav_entry(res["_nav"][m]) for m in maps},
        "nav_vs_default": {best: {k: (_pair(v) if k.endswith("_ci") else v) for k, v in versus[best]["all"].items()
                                  if k.startswith("lethal_recall_diff")}},
        "localisation": {m: {k: (_pair(v) if k.endswith("_ci") else v) for k, v in e.items()} for m, e in loc.items()},
        "harder": harder, "lbp": res.get("_lbp"), "peer_seconds": res.get("_seconds", {}),
        "seconds": time.perf_counter() - started,
    }


# --- the goals --------------------------------------------------------------------------------------------------


def _fmt(value, digits=4):
    return "nan" if value is None or not math.isfinite(value) else f"{value:+.{digits}f}"


def _diff_text(diff, ci, digits=4):
    if ci is None:
        return _fmt(diff, digits)
    return f"{_fmt(diff, digits)} [{_fmt(ci[0], digits)}, {_fmt(ci[1], digits)}]"


def _finite(*values):
    return all(v is not None and math.isfinite(v) for v in values)


def no_worse(diff, ci, lower_is_better=True) -> tuple:
    """(met, interval_only) of "no worse": the interval of the difference reaches 0 or the good side.

    >>> no_worse(0.01, [-0.01, 0.03]), no_worse(0.01, [0.002, 0.03]), no_worse(-0.01, None)
    ((True, True), (False, False), (True, False))
    """
    sign = 1 if lower_is_better else -1
    if not _finite(diff):
        return None, False
    if ci is None or not _finite(*ci):
        return bool(sign * diff <= 0), False
    met = bool(min(sign * ci[0], sign * ci[1]) <= 0)
    return met, bool(met and sign * diff > 0)


def better(diff, ci, lower_is_better=True):
    """Met when the whole interval of the difference lies on the good side (the point estimate without one).

    >>> better(-0.01, [-0.02, -0.001]), better(-0.01, [-0.02, 0.0]), better(0.02, [0.01, 0.03], lower_is_better=False)
    (True, False, True)
    """
    sign = 1 if lower_is_better else -1
    if not _finite(diff):
        return None
    if ci is None or not _finite(*ci):
        return bool(sign * diff < 0)
    return bool(max(sign * ci[0], sign * ci[1]) < 0)


def _nav_verdict(goal, what, nav, group, metric, rule, lower_is_better, digits=4):
    d, r = nav[DEFAULT_PRESET][group], nav["raw"][group]
    diff, ci = d.get(metric + "_diff"), d.get(metric + "_diff_ci")
    met, only = no_worse(diff, ci, lower_is_better) if rule == "no worse" else (better(diff, ci, lower_is_better),
                                                                                 False)
    evidence = (f"{metric} {d[metric]:.{digits}f} vs raw {r[metric]:.{digits}f}; diff {_diff_text(diff, ci, digits)}"
                if _finite(d[metric], r[metric]) else f"{metric}: nothing to score ({d[metric]} vs {r[metric]})")
    return Verdict(goal, what, met, evidence, only)


def recording_goals(summary: dict) -> list:
    """Goals 1-6 and 8 of issue 38 for the default preset on one recording's summary (:func:`score_recording`)."""
    out = []
    b = summary["brier_vs_certainty"]
    met, only = no_worse(b["diff"], b["ci"])
    out.append(Verdict("1a", f"Brier (all observed cells) no worse than {OLD_DEFAULT}", met,
                       f"{DEFAULT_PRESET} minus {OLD_DEFAULT} {_diff_text(b['diff'], b['ci'])}", only))
    ece = summary["ece"]
    e_new, e_old = ece[DEFAULT_PRESET], ece[OLD_DEFAULT]
    out.append(Verdict("1b", f"ECE no worse than {OLD_DEFAULT}", bool(e_new <= e_old) if _finite(e_new, e_old) else None,
                       f"ECE {e_new:.4f} vs {e_old:.4f}"))
    harder = summary.get("harder") or {}
    parts, wins = [], []
    for kind, h in harder.items():
        wins.append(better(h["diff"], h["ci"]))
        by_group = h.get("groups", {})
        seen = "; ".join(f"{g} {_fmt(by_group[g]['diff'])}" for g in ("seen", "unseen") if g in by_group)
        parts.append(f"{kind}: minus {h['opponent']} {_diff_text(h['diff'], h['ci'])}" + (f" ({seen})" if seen else "")
                     + (f", {OLD_DEFAULT} {_fmt(h['brier'][OLD_DEFAULT] - h['brier'][h['opponent']])}"
                        if OLD_DEFAULT in h.get("brier", {}) else ""))
    met = None if not wins or None in wins else all(wins)
    out.append(Verdict("1c", "Brier better than the calibrated independent-cell model on the harder splits", met,
                       f"won {sum(bool(w) for w in wins)} of {len(wins)}; " + "; ".join(parts)))
    nav = summary["nav"]
    out.append(_nav_verdict("2a", "dangerous misses (seen cells) no more than raw", nav, "seen", "miss_rate",
                            "no worse", True))
    out.append(_nav_verdict("2b", "dangerous misses (never-seen cells) no more than raw", nav, "unseen", "miss_rate",
                            "no worse", True))
    out.append(_nav_verdict("3", "ghost obstacles fewer than raw", nav, "all", "ghost_rate", "better", True))
    out.append(_nav_verdict("4a", "lethal precision at least raw's", nav, "all", "lethal_precision", "no worse", False))
    out.append(_nav_verdict("4b", "lethal recall above raw's", nav, "all", "lethal_recall", "better", False))
    d, r = nav[DEFAULT_PRESET]["map"], nav["raw"]["map"]
    out.append(Verdict("5a", "walls at most one cell thicker than raw's", bool(d["thickness"] <= r["thickness"] + 1)
                       if _finite(d["thickness"], r["thickness"]) else None,
                       f"thickness {d['thickness']:.2f} vs raw {r['thickness']:.2f} cells"))
    out.append(Verdict("5b", "fewer lethal components per 10 m than raw", bool(d["components_per_10m"]
                       < r["components_per_10m"]) if _finite(d["components_per_10m"], r["components_per_10m"]) else None,
                       f"components per 10 m {d['components_per_10m']:.2f} vs raw {r['components_per_10m']:.2f}"))
    out.append(_localisation_verdict(summary["localisation"]))
    out.extend(_peer_verdicts(summary))
    return out


def _localisation_verdict(loc):
    d, r = loc[DEFAULT_PRESET], loc["raw"]
    checks, parts = [], []
    for metric, higher, unit, scale in (("found", True, "%", 100), ("translation_error", False, " cm", 100),
                                        ("rotation_error", False, " deg", 1)):
        diff, ci = d[metric + "_diff"], d.get(metric + "_diff_ci")
        checks.append(no_worse(diff, ci, lower_is_better=not higher))
        ci_s = None if ci is None else [scale * ci[0], scale * ci[1]]
        parts.append(f"{metric} {scale * d[metric]:.2f}{unit} vs raw {scale * r[metric]:.2f}{unit}, diff "
                     f"{_diff_text(scale * diff, ci_s, 2)}")
    mets = [m for m, _ in checks]
    met = None if None in mets else all(mets)
    return Verdict("6", "AMCL localisation at least as good as on raw", met, "; ".join(parts),
                   bool(met and any(only for _, only in checks)))


def _peer_verdicts(summary):
    nav, group = summary["nav"], "all"
    rivals = [m for m in nav if m not in (DEFAULT_PRESET, OLD_DEFAULT)]  # raw and the peers scored
    out = []
    for goal, metric, lower, what in (("8a", "miss_rate", True, "dangerous misses"),
                                      ("8b", "ghost_rate", True, "ghost obstacles"),
                                      ("8c", "lethal_precision", False, "lethal precision")):
        mine = nav[DEFAULT_PRESET][group][metric]
        values = {m: nav[m][group][metric] for m in rivals}
        finite = {m: v for m, v in values.items() if _finite(v)}
        best = (min if lower else max)(finite, key=finite.get) if finite else None
        met = None if best is None or not _finite(mine) else bool(mine <= finite[best] if lower
                                                                  else mine >= finite[best])
        out.append(Verdict(goal, f"best of {'/'.join(rivals)} on {what}", met,
                           f"{metric} {mine:.4f}; " + ", ".join(f"{m} {v:.4f}" for m, v in values.items())))
    mine = nav[DEFAULT_PRESET][group]["lethal_recall"]
    values = {m: nav[m][group]["lethal_recall"] for m in rivals}
    best = max(values, key=values.get)
    vs = summary["nav_vs_default"].get(best, {})  # best minus default
    diff, ci = vs.get("lethal_recall_diff"), vs.get("lethal_recall_diff_ci")
    met, only = (True, False) if mine >= values[best] else no_worse(diff, ci)
    out.append(Verdict("8d", f"lethal recall within its interval of the best of {'/'.join(rivals)}", met,
                       f"lethal_recall {mine:.4f}; " + ", ".join(f"{m} {v:.4f}" for m, v in values.items())
                       + f"; {best} minus {DEFAULT_PRESET} {_diff_text(diff, ci)}", only))
    return out


def closed_loop_goals(records, kind: str = LOOP_KIND, versus=LOOP_VERSUS, n_boot: int = 2000, seed: int = 0) -> list:
    """Goal 7 for onboard map ``kind``: no more scans to 95 %, collisions and plans into walls than each of ``versus``.

    ``records``: :func:`crfstudy.experiments.closed_loop.run_closed_loop`'s, one per (scene, kind). The paired
    difference over scenes (:func:`crfmap.assess.paired.paired_difference`) decides with the "no worse" rule;
    with one scene, the point estimate.
    """
    from crfmap.assess.paired import paired_difference

    by = {(r["scene"], r["kind"]): r for r in records}
    scenes = list(dict.fromkeys(r["scene"] for r in records))
    missing = [k for k in (kind, *versus) if not any((s, k) in by for s in scenes)]
    if missing:
        raise InputError("records", f"no closed-loop run of {', '.join(missing)}")
    out = []
    for i, (metric, label) in enumerate(LOOP_METRICS.items()):
        mine = np.array([by[s, kind][metric] for s in scenes], float)
        mets, onlys, parts = [], [], []
        for other in versus:
            theirs = np.array([by[s, other][metric] for s in scenes], float)
            if len(scenes) >= 2:
                d = paired_difference(mine, theirs, n_boot=n_boot, seed=seed)
                diff, ci = d["mean_difference"], list(d["difference_ci"])
            else:
                diff, ci = float(mine[0] - theirs[0]), None
            met, only = no_worse(diff, ci)
            mets.append(met), onlys.append(only)
            parts.append(f"vs {other} {theirs.mean():.3g}: {_diff_text(diff, ci, 2)}")
        out.append(Verdict(f"7{'abc'[i]}", f"{label} no more than {' and '.join(versus)}", all(mets),
                           f"{kind} mean {mine.mean():.3g} over {len(scenes)} scenes; " + "; ".join(parts),
                           bool(all(mets) and any(onlys))))
    return out


def run_closed_loop_records(settings: GoalSettings, kinds=ONBOARD, progress=None) -> list:
    """The closed loop's records (every kind on every scene, the range noise's seed ``settings.seed``)."""
    from crfmap.sim.exploration import ExploreSettings
    from crfstudy.experiments.closed_loop import closed_loop_scenes, run_closed_loop

    scenes = closed_loop_scenes(settings.n_floors, settings.floor_size, settings.loop_resolution,
                                thesis_scenes=settings.thesis_scenes)
    explore = ExploreSettings(max_scans=settings.max_scans)  # notebook 11's other settings are the defaults
    records, _ = run_closed_loop(scenes, kinds=kinds, settings=explore, seed=settings.seed, progress=progress)
    return records


# --- the table ----------------------------------------------------------------------------------------------------

GOALS = {"1": "Brier and ECE kept; beats independent cells on harder splits", "2": "no more dangerous misses than raw",
         "3": "fewer ghosts than raw", "4": "lethal precision and recall vs raw", "5": "thin, continuous walls",
         "6": "AMCL localisation vs raw", "7": "closed loop: scans, collisions, plans into walls",
         "8": "best of raw and the peers"}


def goal_matrix(columns: dict) -> tuple:
    """(header, rows): one row per goal 1-8, one column per recording / closed loop (``{name: [Verdict]}``).

    A cell says ``met`` (every sub-goal met; ``met*``: one only by its interval), ``missed: 1c, ...`` (the sub-goals
    missed) or ``n/a`` (not scored there).
    """
    header = ["goal"] + list(columns)
    rows = []
    for number, what in GOALS.items():
        row = [f"{number} {what}"]
        for verdicts in columns.values():
            mine = [v for v in verdicts if v.goal.rstrip("abcd") == number]
            statuses = [v.status for v in mine]
            if not mine or all(s == NOT_SCORED for s in statuses):
                row.append(NOT_SCORED)
            elif MISSED in statuses or NOT_SCORED in statuses:
                row.append("missed: " + ", ".join(v.goal for v in mine if v.status in (MISSED, NOT_SCORED)))
            else:
                row.append(MET_INTERVAL if MET_INTERVAL in statuses else MET)
        rows.append(row)
    return header, rows


def goal_details(columns: dict) -> tuple:
    """(header, rows): every sub-goal of every column with its verdict and the numbers that decide it."""
    rows = [[name, v.goal, v.what, v.status, v.evidence] for name, verdicts in columns.items() for v in verdicts]
    return ["where", "goal", "what", "verdict", "numbers (diff: default minus reference, 95 % CI)"], rows


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


# --- the command --------------------------------------------------------------------------------------------------


def run(files: dict, settings: GoalSettings, training=None, progress: bool = True) -> tuple:
    """(summaries, records, columns) for the recordings ``files`` ({name: path}) and the closed loop.

    The calibrated independent-cell models are fitted on the even / odd split of the recording at ``training``
    (a path; None: the first of ``files``). ``columns``: {recording or closed loop: [Verdict]} for the tables.
    """
    from tqdm.auto import tqdm

    from crfmap.assess.scansplit import scan_split
    from crfmap.commands.build import load_recording

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

    from crfmap.data import data_file, have_data
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
        _, _, columns = run(files, settings, training=training)
    except InputError as e:  # an unknown recording, the data missing
        print(f"nav goals: {e}", file=sys.stderr)
        return 2
    print(markdown_table(*goal_matrix(columns)))
    print(LEGEND + "\n")
    print(markdown_table(*goal_details(columns)))
    print(f"{'quick' if args.quick else 'full'} settings, {time.perf_counter() - started:.0f} s")
    return 0


def example_summary() -> dict:
    """A hand-made summary of one recording (the doctest's and the tests' starting point)."""
    def nav(miss_seen, miss_unseen, ghost, precision, recall, thickness, components):
        group = {"miss_rate": miss_seen, "ghost_rate": ghost, "lethal_precision": precision, "lethal_recall": recall}
        return {"all": dict(group), "seen": dict(group), "unseen": dict(group, miss_rate=miss_unseen),
                "map": {"thickness": thickness, "components_per_10m": components}}

    rows = {"raw": nav(0.10, 0.0, 0.02, 0.80, 0.60, 1.2, 9.0), OLD_DEFAULT: nav(0.14, 0.05, 0.01, 0.78, 0.62, 3.5, 4.0),
            DEFAULT_PRESET: nav(0.08, 0.0, 0.005, 0.85, 0.66, 1.8, 6.0), "octomap": nav(0.03, 0.0, 0.03, 0.7, 0.7, 1.1, 12)}
    raw = rows["raw"]
    for group in ("all", "seen", "unseen"):  # the default's differences to raw, with intervals around them
        for metric, value in list(rows[DEFAULT_PRESET][group].items()):
            d = value - raw[group][metric]
            rows[DEFAULT_PRESET][group][metric + "_diff"] = d
            rows[DEFAULT_PRESET][group][metric + "_diff_ci"] = [d - 0.01, d + 0.01] if d else [0.0, 0.0]
    loc = {"raw": {"found": 0.9, "translation_error": 0.03, "rotation_error": 0.8},
           DEFAULT_PRESET: {"found": 0.88, "found_diff": -0.02, "found_diff_ci": [-0.06, 0.02],
                            "translation_error": 0.03, "translation_error_diff": 0.0,
                            "translation_error_diff_ci": [-0.004, 0.004], "rotation_error": 0.8,
                            "rotation_error_diff": 0.0, "rotation_error_diff_ci": [-0.1, 0.1]}}
    return {"brier_vs_certainty": {"diff": 0.0002, "ci": [-0.0001, 0.0005]},
            "ece": {DEFAULT_PRESET: 0.010, OLD_DEFAULT: 0.012, "raw": 0.08},
            "harder": {"temporal halves": {"opponent": CALIBRATED[0], "diff": 0.002, "ci": [0.001, 0.003]},
                       "scan blocks": {"opponent": CALIBRATED[0], "diff": -0.001, "ci": [-0.002, -0.0005]}},
            "nav": rows, "localisation": loc,
            "nav_vs_default": {"octomap": {"lethal_recall_diff": 0.04, "lethal_recall_diff_ci": [-0.01, 0.09]},
                               "raw": {"lethal_recall_diff": -0.06, "lethal_recall_diff_ci": [-0.07, -0.05]}}}


__all__ = ["RECORDINGS", "ROLES", "GoalSettings", "QUICK", "Verdict", "fit_calibrators", "harder_scores",
           "score_recording", "no_worse", "better", "recording_goals", "closed_loop_goals", "run_closed_loop_records",
           "goal_matrix", "goal_details", "goals_figure", "run", "main", "example_summary"]

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
