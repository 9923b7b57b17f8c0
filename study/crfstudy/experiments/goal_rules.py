"""Issue 38's goals as rules: each sub-goal of a recording or of the closed loop met or missed, with its numbers.

:func:`recording_goals` reads goals 1-6 and 8 off one recording's *summary* (the dictionary of numbers
:func:`crfstudy.experiments.nav_goals.score_recording` makes; :func:`example_summary` is a hand-made one),
:func:`closed_loop_goals` goal 7 off the closed loop's records (:mod:`crfstudy.experiments.closed_loop`);
:func:`goal_matrix` and :func:`goal_details` lay the verdicts out as tables. How a goal is decided (every sub-goal
is one :class:`Verdict`, its numbers beside it):

- "no worse than X" is met when the paired 95 % interval of the difference reaches 0 or the good side (the
  data do not show it worse; the issue's goal 1 says so). Met with the point estimate on the worse side is
  marked ``met*``: not shown worse, not shown as good.
- "better than X" / "fewer" / "above" is met when the whole interval lies on the good side.
- Without an interval (``n_boot = 0``, or a map measure: wall thickness, components, ECE) the point estimates
  decide; goal 8's "best of" compares point estimates, and its recall part accepts the paired interval of the
  best peer minus the default reaching 0.

>>> v = recording_goals(example_summary())
>>> [(x.goal, x.status) for x in v][:3]
[('1a', 'met*'), ('1b', 'met'), ('1c', 'missed')]
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from crfmap.crf.presets import DEFAULT_PRESET
from crfmap.errors import InputError

OLD_DEFAULT = "certainty"  # the default before issue 38: goal 1's reference for Brier and ECE
LOOP_KIND = "online-crf"  # goal 7 is the online CRF's; refined-on-arrival (the gated preset every 10 scans) informs
LOOP_VERSUS = ("raw", "octomap")
LOOP_METRICS = {"scans": "scans to 95 % coverage", "collisions": "collisions", "plans_into_walls": "plans into walls"}
MET, MET_INTERVAL, MISSED, NOT_SCORED = "met", "met*", "missed", "n/a"
LEGEND = (f"{MET}: every sub-goal met; {MET_INTERVAL}: met, one or more only by its interval (the point estimate on the "
          f"worse side, the 95 % interval reaching no difference); {MISSED}: the sub-goals named missed; "
          f"{NOT_SCORED}: not scored there.")


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
    if metric == "miss_rate" and "far_miss_rate" in d:  # the holes the costmap's inflation leaves open (information)
        evidence += (f"; of them beyond 0.5 m of every lethal cell {d['far_miss_rate']:.{digits}f} vs raw "
                     f"{r['far_miss_rate']:.{digits}f}, diff {_diff_text(d.get('far_miss_rate_diff'), d.get('far_miss_rate_diff_ci'), digits)}")
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
    paired = summary.get("ece_vs_certainty")  # the paired block-bootstrap interval of the difference, where scored
    if paired is None:  # a point comparison only
        met, only, text = (bool(e_new <= e_old) if _finite(e_new, e_old) else None), False, ""
    else:
        (met, only), text = no_worse(paired["diff"], paired["ci"]), f"; diff {_diff_text(paired['diff'], paired['ci'])}"
    out.append(Verdict("1b", f"ECE no worse than {OLD_DEFAULT}", met, f"ECE {e_new:.4f} vs {e_old:.4f}{text}", only))
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
    out.extend(navigation_verdicts(summary["nav"]))
    out.append(_localisation_verdict(summary["localisation"]))
    out.extend(_peer_verdicts(summary))
    return out


def navigation_verdicts(nav: dict) -> list:
    """Goals 2-5 (dangerous misses, ghosts, lethal precision and recall, wall shape and face) off nav2's reading of
    the default and the raw grid on one split: ``{"raw": entry, DEFAULT_PRESET: entry}`` as
    :func:`crfstudy.experiments.nav_goals.score_recording` keeps them (``summary["nav"]``)."""
    out = []
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
    if "face_offset" in nav[DEFAULT_PRESET]["all"]:  # scored since the face measure exists
        out.append(_nav_verdict("5c", "the wall face the robot saw stays where it was observed (held-out face cells' "
                                "distance to the nearest lethal cell no more than raw's)", nav, "all", "face_offset",
                                "no worse", True, digits=3))
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
    difference over scenes (:func:`crfstudy.paired.paired_difference`) decides with the "no worse" rule;
    with one scene, the point estimate.
    """
    from crfstudy.paired import paired_difference

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
    rows = [[f"{number} {what}"] + [_cell({"": _of_goal(verdicts, number)}) for verdicts in columns.values()]
            for number, what in GOALS.items()]
    return header, rows


def _of_goal(verdicts, number):
    return [v for v in verdicts if v.goal.rstrip("abcd") == number]


def _cell(groups: dict) -> str:
    """One matrix cell from ``{label: [Verdict]}``: ``n/a`` when nothing was scored, ``missed: <label> 1c, ...`` when a
    sub-goal was missed or not scored (the label names a split; "" for none), else ``met`` or ``met*``."""
    statuses = [v.status for verdicts in groups.values() for v in verdicts]
    if not statuses or all(s == NOT_SCORED for s in statuses):
        return NOT_SCORED
    missed = [f"{label} {', '.join(bad)}".strip() for label, verdicts in groups.items()
              if (bad := [v.goal for v in verdicts if v.status in (MISSED, NOT_SCORED)])]
    if missed:
        return "missed: " + "; ".join(missed)
    return MET_INTERVAL if MET_INTERVAL in statuses else MET


def harder_verdicts(summary: dict) -> dict:
    """{harder split: [Verdict]} of goals 2-5 on each harder split a summary scored nav2's reading on ({} if none)."""
    return {kind: navigation_verdicts(h["nav"]) for kind, h in (summary.get("harder") or {}).items() if "nav" in h}


def harder_matrix(summaries: dict) -> tuple:
    """(header, rows): goals 2-5 per recording on the harder splits (``{recording: summary}``).

    A cell says ``met`` / ``met*`` on every split, or ``missed: <split> <sub-goals>; ...``.
    """
    by_recording = {name: harder_verdicts(s) for name, s in summaries.items()}
    header = ["goal (harder splits)"] + list(by_recording)
    rows = [[f"{number} {GOALS[number]}"] + [_cell({kind: _of_goal(verdicts, number) for kind, verdicts in splits.items()})
                                            for splits in by_recording.values()]
            for number in ("2", "3", "4", "5")]
    return header, rows


def goal_details(columns: dict) -> tuple:
    """(header, rows): every sub-goal of every column with its verdict and the numbers that decide it."""
    rows = [[name, v.goal, v.what, v.status, v.evidence] for name, verdicts in columns.items() for v in verdicts]
    return ["where", "goal", "what", "verdict", "numbers (diff: default minus reference, 95 % CI)"], rows


def example_summary() -> dict:
    """A hand-made summary of one recording (the doctest's and the tests' starting point)."""
    def nav(miss_seen, miss_unseen, ghost, precision, recall, thickness, components, face=0.4):
        group = {"miss_rate": miss_seen, "ghost_rate": ghost, "lethal_precision": precision, "lethal_recall": recall,
                 "face_offset": face}
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
            "ece_vs_certainty": {"diff": -0.002, "ci": [-0.004, 0.0005]},
            "harder": {"temporal halves": {"opponent": "isotonic on x", "diff": 0.002, "ci": [0.001, 0.003],
                                           "nav": copy.deepcopy(rows)},
                       "scan blocks": {"opponent": "isotonic on x", "diff": -0.001, "ci": [-0.002, -0.0005],
                                       "nav": copy.deepcopy(rows)}},
            "nav": rows, "localisation": loc,
            "nav_vs_default": {"octomap": {"lethal_recall_diff": 0.04, "lethal_recall_diff_ci": [-0.01, 0.09]},
                               "raw": {"lethal_recall_diff": -0.06, "lethal_recall_diff_ci": [-0.07, -0.05]}}}


__all__ = ["OLD_DEFAULT", "MET", "MET_INTERVAL", "MISSED", "NOT_SCORED", "LEGEND", "GOALS", "Verdict", "no_worse",
           "better", "recording_goals", "navigation_verdicts", "harder_verdicts", "harder_matrix", "closed_loop_goals", "goal_matrix", "goal_details", "example_summary"]
