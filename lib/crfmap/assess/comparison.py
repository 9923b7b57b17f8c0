"""Every evaluated method on one scan split: the rows ``crfmap evaluate`` prints and the notebooks tabulate.

The rows come from the registries: the baselines (:data:`crfmap.assess.baselines.BASELINES`), any preset
(:data:`crfmap.crf.presets.PRESETS`) and the published peers (:data:`crfmap.assess.peers.PEERS`).
"""
from __future__ import annotations

from tqdm.auto import tqdm

from crfmap.assess.baselines import BASELINES, all_baselines
from crfmap.assess.navigation import nav_scores
from crfmap.assess.peers import PEERS, peer_rows
from crfmap.assess.scansplit import DEFAULT_BLOCK, ScanSplit, score
from crfmap.crf.presets import DEFAULT_PRESET, PRESETS, get_preset
from crfmap.errors import InputError


def method_names(preset: str = DEFAULT_PRESET) -> list:
    """Every row that can be scored, in table order: the baselines, ``preset``, the peers.

    >>> method_names()[:2], method_names()[-3:]
    (['raw', 'logodds'], ['octomap', 'octomap-defaults', 'hilbert'])
    """
    if preset not in PRESETS:
        raise InputError("preset", f"must be one of {', '.join(PRESETS)}, got {preset!r}")
    return list(BASELINES) + [preset] + list(PEERS)


def parse_methods(text: str, preset: str = DEFAULT_PRESET) -> list:
    """The rows a ``--methods`` text asks for (``"all"`` or comma-separated names); ``raw`` is always first.

    >>> parse_methods("octomap")
    ['raw', 'octomap']
    """
    known = method_names(preset)
    if text.strip() == "all":
        return known
    names = [n.strip() for n in text.split(",") if n.strip()]
    unknown = [n for n in names if n not in known]
    if unknown or not names:
        raise InputError("--methods", f"unknown row(s) {', '.join(unknown) or '(none given)'}; known: {', '.join(known)}")
    return ["raw"] + [n for n in names if n != "raw"]


def compare(split: ScanSplit, preset: str = DEFAULT_PRESET, n_boot: int = 200, block: int = DEFAULT_BLOCK,
            seed: int = 0, extra: dict | None = None, keep_beliefs: bool = False, methods=None, nav: bool = True,
            progress: bool = False) -> dict:
    """Score the rows ``methods`` (names of :func:`method_names`; None: every baseline and ``preset``) on a split.

    ``"raw"`` is always scored, as the paired reference. Returns the :func:`crfmap.assess.scansplit.score` dictionary
    of each row's beliefs, plus ``"_lbp"`` (the preset's LBP summary), ``"_seconds"`` (each peer's wall time [s]) and
    ``"_vs_preset"`` (``{name: {group: {"brier_diff": ..., "brier_diff_ci": ...}}}``, every other row against the
    preset). ``extra``: more ``{name: P}`` rows. ``nav``: also every row's map for nav2 (a gated preset's
    :attr:`~crfmap.crf.inference.result.LBPResult.nav2_map`) scored by :func:`crfmap.assess.navigation.nav_scores`
    on the same resamples, under ``"_nav"``. ``keep_beliefs``: the scored ``{name: P}`` under ``"_beliefs"`` and the
    maps for nav2 under ``"_maps"``. ``progress``: a tqdm bar of the steps.
    """
    wanted = list(BASELINES) + [preset] if methods is None else list(methods)
    unknown = [m for m in wanted if m not in method_names(preset)]
    if unknown:
        raise InputError("methods", f"unknown row(s) {', '.join(unknown)}; known: {', '.join(method_names(preset))}")
    peer_names = [m for m in wanted if m in PEERS]
    bar = tqdm(total=2 + (preset in wanted) + len(peer_names) + bool(nav), desc="evaluate", unit="step",
               disable=not progress)
    predictions = all_baselines(split, names=[m for m in wanted if m in BASELINES])
    bar.update(1)
    out_lbp = None
    maps = {}  # a preset's map for nav2 where it differs from its beliefs (an evidence gate's decision)
    if preset in wanted:
        result = get_preset(preset).refine(hits=split.first_hits, passes=split.first_passes)  # as users run it
        predictions[preset] = result.beliefs.probability
        maps[preset] = result.nav2_map.probability
        out_lbp = {"converged": result.converged, "iterations": result.iterations, "last_change": result.last_change}
        bar.update(1)
    seconds = {}
    for name in peer_names:  # one at a time, so that the bar moves
        peer, took = peer_rows(split, [name])
        predictions.update(peer)
        seconds.update(took)
        bar.update(1)
    predictions.update(extra or {})
    maps = {**predictions, **maps}
    out = score(split, predictions, n_boot=n_boot, block=block, seed=seed, reference="raw")
    bar.update(1)
    if nav:  # nav2 reads the written map: a gated preset's decision, every other row's P
        same = all(maps[name] is p for name, p in predictions.items())  # else its auc / nll are the maps' own
        out["_nav"] = nav_scores(split, maps, n_boot=n_boot, block=block, seed=seed, reference="raw",
                                 scores=out if same else None)
        bar.update(1)
    if out_lbp is not None:
        out["_lbp"] = out_lbp
    if seconds:
        out["_seconds"] = seconds
    if preset in predictions and len(predictions) > 1:  # every row against the preset, on the same resamples
        versus = score(split, predictions, n_boot=n_boot, block=block, seed=seed, reference=preset,
                       metrics=("brier", "logloss"))
        out["_vs_preset"] = {name: {g: {k: v for k, v in entry.items() if "_diff" in k} for g, entry in groups.items()}
                             for name, groups in versus.items() if name != preset}
    bar.close()
    if keep_beliefs:
        out["_beliefs"] = predictions
        out["_maps"] = maps
    return out


def table_rows(scores: dict, group: str = "all", metrics=("brier", "logloss", "auc", "wall_recall")) -> list:
    """Rows ``[name, metric, "lo-hi", ...]`` of a :func:`crfmap.assess.scansplit.score` result for one group."""
    rows = []
    for name, groups in scores.items():
        if name.startswith("_"):
            continue
        entry = groups[group]
        row = [name]
        for m in metrics:
            row.append(entry[m])
            lo, hi = entry.get(m + "_ci", (float("nan"), float("nan")))
            row.append(f"{lo:.4f}-{hi:.4f}")
        rows.append(row)
    return rows
