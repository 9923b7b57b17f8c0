"""The default's trade-off curves (issue 38): what one setting of the gated preset buys on one goal and costs on another.

Issue 38 asks, where a goal cannot be met without losing another, for the measured trade-off as one setting moves.
Four settings move here (:data:`SETTINGS`), one at a time, every other constant the default's:

- the coupling J (:data:`COUPLINGS`, the gate search's grid): a stronger coupling calibrates the beliefs better
  (ECE, goal 1b) but lets LBP call more lone returns lethal (ghosts, goal 3);
- the never-observed prior pi (:data:`PRIORS`): the probability of a cell no beam reached (off wall lines). It moves
  no decision (the gate reads such cells unknown), only calibration (goals 1a-1c);
- the gate's ``free_evidence`` (:data:`FREE_EVIDENCE`): the net passes a cell needs before nav2 may read it free.
  Fewer passes free more cells (faster exploration, goal 7a) and open more held-out walls (dangerous misses, goal 2);
- the gate's ``lethal_evidence`` (:data:`LETHAL_EVIDENCE`): the net hits that keep a cell lethal whatever its
  neighbours say. Fewer keep more lone returns (ghosts, goal 3) and more of the face the robot saw (goal 5c).

Each setting is scored on every recording's even / odd scan split (:data:`crfstudy.experiments.nav_goals.RECORDINGS`)
with the goal table's rules (:mod:`crfstudy.experiments.goal_rules`): the paired 95 % spatial-block intervals of
the Brier and ECE differences to ``certainty`` (goal 1) and of the nav2 measures' differences to the raw grid
(goals 2-4). ``python -m crfstudy.analysis.tradeoff [RECORDING ...]`` prints the two tables; notebook 12 saves them.
Nothing here chooses anything: the curves say what the chosen default gave up.
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace

import numpy as np

from crfmap.assess.navigation import nav_scores
from crfmap.assess.scansplit import score
from crfmap.crf.presets import DEFAULT_PRESET, coupling_table, get_preset
from crfstudy.calibration import paired_calibration
from crfstudy.experiments.goal_rules import OLD_DEFAULT, better, no_worse

COUPLINGS = (0.25, 0.30, 0.33, 0.35)  # J: the gate search's grid (0.35: the certainty preset's, on the Bethe point)
PRIORS = (0.1, 0.15, 0.2, 0.25, 0.3, 0.35)  # P of a never-observed cell off every wall line (the gate search's grid, 0.5 left out)
LETHAL_EVIDENCE = (1, 2, 3)  # net hits that keep a cell lethal (2: the default; 1: every net hit, no ghost removal)
FREE_EVIDENCE = (1, 2, 3, 4)  # net passes before a cell may read free (2: the default; 1: what the raw grid needs at 0.196)
# (goal, measure, group, lower is better, rule): the sub-goals a setting moves, as the goal table decides them
SUBGOALS = (("1a", "brier", "all", True, "no worse"), ("1b", "ece", "all", True, "no worse"),
            ("2a", "miss_rate", "seen", True, "no worse"), ("3", "ghost_rate", "all", True, "better"),
            ("4a", "lethal_precision", "all", False, "no worse"), ("4b", "lethal_recall", "all", False, "better"),
            ("5c", "face_offset", "all", True, "no worse"))


def variants(setting: str) -> dict:
    """{label: Preset} of the default preset with one setting moved over its grid (``"J"`` or ``"free_evidence"``).

    >>> list(variants("free_evidence"))
    ['free_evidence 1', 'free_evidence 2', 'free_evidence 3', 'free_evidence 4']
    """
    base = get_preset(DEFAULT_PRESET)
    if setting == "J":
        return {f"J {j:.2f}": replace(base, hidden=coupling_table(j)) for j in COUPLINGS}
    if setting == "unobserved_prior":
        return {f"unobserved_prior {p:g}": replace(base, gate=replace(base.gate, unobserved_prior=p)) for p in PRIORS}
    if setting in ("free_evidence", "lethal_evidence"):
        grid = FREE_EVIDENCE if setting == "free_evidence" else LETHAL_EVIDENCE
        return {f"{setting} {n}": replace(base, gate=replace(base.gate, **{setting: n})) for n in grid}
    raise ValueError(f"setting must be one of {', '.join(SETTINGS)}, got {setting!r}")


def score_variants(split, presets: dict, n_boot: int = 200, block: int = 16, seed: int = 0) -> dict:
    """{label: {goal: {"diff", "ci", "value", "met", "interval_only"}}} of each preset on one scan split.

    Goals 1a / 1b against ``certainty`` (beliefs), goals 2a-4b against the raw grid (the nav2 map), on the same
    resamples as the goal table (same ``n_boot``, ``block`` and ``seed``).
    """
    counts = dict(hits=split.first_hits, passes=split.first_passes)
    old = get_preset(OLD_DEFAULT).refine(**counts).beliefs.probability
    raw = split.raw_probability()
    lbp = {}  # LBP once per coupling: variants of the gate share it and differ only in how the refinement ends
    out = {}
    for label, preset in presets.items():
        key = preset.hidden.tobytes()
        if key not in lbp:
            lbp[key] = replace(preset, gate=None, temperature=1.0).refine(**counts)
        result = lbp[key]
        beliefs, nav_map = preset.finish(result.beliefs.probability, **counts)
        nav_map = beliefs if nav_map is None else nav_map
        brier = score(split, {OLD_DEFAULT: old, label: beliefs}, n_boot=n_boot, block=block, seed=seed,
                      reference=OLD_DEFAULT, metrics=("brier",))[label]["all"]
        ece = paired_calibration(split, {OLD_DEFAULT: old, label: beliefs}, OLD_DEFAULT, n_boot=n_boot, block=block,
                                 seed=seed)[label]
        both = nav_scores(split, {"raw": raw, label: nav_map}, n_boot=n_boot, block=block, seed=seed)
        nav = both[label]
        entries = {"1a": (brier["brier"], brier["brier_diff"], brier.get("brier_diff_ci")),
                   "1b": (ece["ece"], ece["ece_diff"], ece["ece_diff_ci"])}
        for goal, metric, group, _, _ in SUBGOALS[2:]:
            g = nav[group]
            entries[goal] = (g[metric], g[metric + "_diff"], g.get(metric + "_diff_ci"))
        out[label] = {}
        for goal, _, _, lower, rule in SUBGOALS:
            value, diff, ci = entries[goal]
            ci = None if ci is None else [float(ci[0]), float(ci[1])]
            met, only = no_worse(diff, ci, lower) if rule == "no worse" else (better(diff, ci, lower), False)
            out[label][goal] = {"value": float(value), "diff": float(diff), "ci": ci, "met": met,
                                "interval_only": bool(only)}
        out[label]["iterations"] = int(result.iterations)
        # the planner's room: seen cells the map calls free, against the raw grid's (the price of fewer misses)
        out[label]["free_vs_raw"] = float(nav["seen"]["free"] / max(both["raw"]["seen"]["free"], 1))
    return out


def tradeoff_table(scores: dict) -> tuple:
    """(header, rows): per setting, each sub-goal's count of recordings met and its mean difference.

    ``scores``: {recording: :func:`score_variants` result}. A cell reads ``met on k of n (mean diff)``.
    """
    recordings = list(scores)
    labels = list(next(iter(scores.values())))
    header = ["setting", *(f"{goal} {metric} ({'vs ' + OLD_DEFAULT if goal.startswith('1') else 'vs raw'})"
                           for goal, metric, *_ in SUBGOALS), "free cells vs raw (seen, mean)", "LBP iterations (max)"]
    rows = []
    for label in labels:
        row = [label]
        for goal, *_ in SUBGOALS:
            entries = [scores[r][label][goal] for r in recordings]
            met = sum(bool(e["met"]) for e in entries)
            row.append(f"{met} of {len(entries)} ({np.mean([e['diff'] for e in entries]):+.4f})")
        row.append(f"{np.mean([scores[r][label]['free_vs_raw'] for r in recordings]):.3f}")
        row.append(max(scores[r][label]["iterations"] for r in recordings))
        rows.append(row)
    return header, rows


SETTINGS = ("J", "unobserved_prior", "free_evidence", "lethal_evidence")  # what variants() moves, one at a time
CLOSED_LOOP_KINDS = ("online-crf", "refined-on-arrival")  # the onboard maps that run the default preset


def closed_loop_records(settings, setting: str = "free_evidence", progress=None) -> list:
    """The closed loop (notebook 11's scenes, :func:`crfstudy.experiments.nav_goals.run_closed_loop_records`'
    settings) with each variant of ``setting`` as the onboard preset; the raw grid once, as the reference.

    Records as :func:`crfstudy.experiments.closed_loop.run_closed_loop`'s, the kind named ``"<kind>, <label>"``.
    """
    from crfstudy.closed_loop.exploration import ExploreSettings
    from crfstudy.experiments.closed_loop import closed_loop_scenes, run_closed_loop

    scenes = closed_loop_scenes(settings.n_floors, settings.floor_size, settings.loop_resolution,
                                thesis_scenes=settings.thesis_scenes)
    records, _ = run_closed_loop(scenes, kinds=["raw"], settings=ExploreSettings(max_scans=settings.max_scans),
                                 seed=settings.seed, progress=progress)
    for label, preset in variants(setting).items():
        explore = ExploreSettings(max_scans=settings.max_scans, onboard_options={"preset": preset})
        got, _ = run_closed_loop(scenes, kinds=CLOSED_LOOP_KINDS, settings=explore, seed=settings.seed,
                                 progress=progress)
        records += [dict(r, kind=f"{r['kind']}, {label}") for r in got]
    return records


LOOP_METRICS = ("scans", "plans_into_walls", "dangerous_miss_rate", "ghosts")  # columns of closed_loop_table


def closed_loop_table(records, reference="raw", n_boot=2000, seed=0) -> tuple:
    """(header, rows): per onboard kind (a row) the mean over scenes of :data:`LOOP_METRICS` and its paired
    difference to ``reference`` with a 95 % bootstrap interval over scenes: notebook 11's paired table, turned so
    that the many kinds are rows."""
    from crfstudy.experiments.closed_loop import METRICS, paired_table

    header, rows = paired_table(records, reference=reference, n_boot=n_boot, seed=seed, metrics=LOOP_METRICS)
    kinds = [k for k in dict.fromkeys(r["kind"] for r in records) if k != reference]
    turned = ["onboard map", *(f"{METRICS[m][0]} (vs {reference})" for m in LOOP_METRICS)]
    # paired_table's columns: the metric, the reference, then every other kind in the records' order
    return turned, [[kind, *(row[1 + i] for row in rows)] for i, kind in enumerate([reference, *kinds])]


def run(files: dict, settings=SETTINGS, resolution: float = 0.05, n_boot: int = 200, block: int = 16, seed: int = 0,
        progress: bool = True) -> dict:
    """{setting: {recording: :func:`score_variants`}} of each setting's grid on every recording of ``files`` (each
    recording read and split once for all settings)."""
    from tqdm.auto import tqdm

    from crfmap.assess.scansplit import scan_split
    from crfmap.io.recordings import load_recording

    out = {setting: {} for setting in settings}
    for name, path in tqdm(files.items(), desc="trade-offs", unit="recording", disable=not progress):
        split = scan_split(load_recording(path).scans, resolution)
        for setting in settings:
            out[setting][name] = score_variants(split, variants(setting), n_boot=n_boot, block=block, seed=seed)
    return out


def main(argv=None) -> int:
    from tabulate import tabulate

    from crfmap.data import data_file
    from crfstudy.experiments.nav_goals import RECORDINGS

    parser = argparse.ArgumentParser(prog="python -m crfstudy.analysis.tradeoff", description=__doc__.splitlines()[0])
    parser.add_argument("recordings", nargs="*", metavar="RECORDING", help=f"any of {', '.join(RECORDINGS)} "
                        "(default: all)")
    parser.add_argument("--boot", type=int, default=200, help="bootstrap resamples (default 200)")
    parser.add_argument("--closed-loop", action="store_true", help="also explore notebook 11's scenes with each "
                        "free_evidence (about a minute)")
    args = parser.parse_args(argv)
    unknown = [r for r in args.recordings if r not in RECORDINGS]
    if unknown:
        parser.error(f"unknown recording(s) {', '.join(unknown)}; known: {', '.join(RECORDINGS)}")
    files = {name: data_file(RECORDINGS[name]) for name in (args.recordings or RECORDINGS)}
    for setting, scores in run(files, n_boot=args.boot).items():
        header, rows = tradeoff_table(scores)
        print(f"\n{setting}: sub-goals met on {len(files)} recordings (mean difference)\n")
        print(tabulate(rows, header, tablefmt="github"))
    if args.closed_loop:
        from crfstudy.experiments.nav_goals import GoalSettings

        settings = GoalSettings()
        header, rows = closed_loop_table(closed_loop_records(settings), n_boot=settings.loop_boot, seed=settings.seed)
        print("\nfree_evidence in the closed loop (means over scenes; paired differences to raw)\n")
        print(tabulate(rows, header, tablefmt="github"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
