"""The trade-off curves: each variant scored by the goal table's rules, tables that count what the numbers say."""
import numpy as np
import pytest

from crfmap.assess.navigation import nav_scores
from crfmap.assess.scansplit import ScanSplit
from crfmap.crf.presets import DEFAULT_PRESET, get_preset
from crfstudy.analysis import tradeoff
from crfstudy.experiments.goal_rules import no_worse


def _split(seed=0, shape=(30, 36)):
    rng = np.random.default_rng(seed)
    h1, e1, h2, e2 = (rng.integers(0, 4, shape) for _ in range(4))
    h1[:, :4] = e1[:, :4] = 0  # never seen by the first half
    return ScanSplit(h1, e1, h2, e2, resolution=0.05)


def test_variants_move_one_setting_and_keep_the_default_in_the_grid():
    default = get_preset(DEFAULT_PRESET)
    couplings = tradeoff.variants("J")
    assert [round(p.coupling, 2) for p in couplings.values()] == list(tradeoff.COUPLINGS)
    assert all(p.gate == default.gate for p in couplings.values())
    gates = tradeoff.variants("free_evidence")
    assert [p.gate.free_evidence for p in gates.values()] == list(tradeoff.FREE_EVIDENCE)
    assert all(np.array_equal(p.hidden, default.hidden) for p in gates.values())
    assert default.gate.free_evidence in tradeoff.FREE_EVIDENCE and round(default.coupling, 2) in tradeoff.COUPLINGS
    with pytest.raises(ValueError, match="setting"):
        tradeoff.variants("margin")


def test_score_variants_applies_the_goal_rules_to_the_nav2_map():
    sp = _split()
    presets = tradeoff.variants("free_evidence")
    got = tradeoff.score_variants(sp, presets, n_boot=20, block=6, seed=1)
    for label, preset in presets.items():
        nav_map = preset.refine(hits=sp.first_hits, passes=sp.first_passes).nav2_map.probability
        want = nav_scores(sp, {"raw": sp.raw_probability(), label: nav_map}, n_boot=20, block=6, seed=1)[label]["seen"]
        entry = got[label]["2a"]
        assert entry["value"] == want["miss_rate"] and entry["diff"] == want["miss_rate_diff"]
        assert (entry["met"], entry["interval_only"]) == no_worse(want["miss_rate_diff"],
                                                                   list(want["miss_rate_diff_ci"]))
    # more passes before a cell may read free: never more dangerous misses, never more free cells
    rates = [got[label]["2a"]["value"] for label in presets]
    free = [got[label]["free_vs_raw"] for label in presets]
    assert rates == sorted(rates, reverse=True) and free == sorted(free, reverse=True)
    assert len({got[label]["1a"]["value"] for label in presets}) == 1  # the gate never touches the beliefs


def test_tables_count_the_recordings_that_meet_each_subgoal():
    entry = {"value": 0.1, "diff": -0.01, "ci": [-0.02, 0.0], "interval_only": False}
    one = {g: dict(entry, met=True) for g, *_ in tradeoff.SUBGOALS}
    two = {g: dict(entry, met=g != "3", diff=0.03) for g, *_ in tradeoff.SUBGOALS}
    scores = {"a": {"v": dict(one, iterations=10, free_vs_raw=0.9)}, "b": {"v": dict(two, iterations=30, free_vs_raw=1.0)}}
    header, rows = tradeoff.tradeoff_table(scores)
    assert len(header) == len(rows[0]) and rows[0][0] == "v" and rows[0][-1] == 30 and rows[0][-2] == "0.950"
    goal3 = [g for g, *_ in tradeoff.SUBGOALS].index("3") + 1
    assert rows[0][1] == "2 of 2 (+0.0100)" and rows[0][goal3] == "1 of 2 (+0.0100)"


def test_closed_loop_table_pairs_every_kind_with_the_reference_scene_by_scene():
    records = [{"scene": s, "kind": k, "scans": scans, "plans_into_walls": 1, "dangerous_miss_rate": 0.01, "ghosts": 2}
               for s, base in (("s1", 50), ("s2", 70), ("s3", 90))
               for k, scans in (("raw", base), ("crf", base + 5))]
    header, rows = tradeoff.closed_loop_table(records, n_boot=200)
    assert [r[0] for r in rows] == ["raw", "crf"] and rows[0][1] == "70"
    assert rows[1][1] == "75 (+5 [+5, +5])"  # every scene 5 scans more: the interval is the point


def test_lethal_evidence_variants_move_only_that_field():
    default = get_preset(DEFAULT_PRESET)
    got = tradeoff.variants("lethal_evidence")
    assert [p.gate.lethal_evidence for p in got.values()] == list(tradeoff.LETHAL_EVIDENCE)
    assert all(p.gate.free_evidence == default.gate.free_evidence for p in got.values())
    assert set(tradeoff.SETTINGS) == {"J", "unobserved_prior", "free_evidence", "lethal_evidence"}
    priors = tradeoff.variants("unobserved_prior")
    assert [p.gate.unobserved_prior for p in priors.values()] == list(tradeoff.PRIORS)
    assert default.gate.unobserved_prior in tradeoff.PRIORS
