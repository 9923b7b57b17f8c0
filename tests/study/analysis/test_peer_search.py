"""The peers' searches: the preset's rule on small splits, their cached Intel results, and the rows that use them."""
import itertools
import json

import numpy as np
import pytest

from crfmap.assess import peers
from crfmap.assess.scansplit import scan_split
from crfmap.data import have_data
from crfmap.errors import InputError
from crfmap.mapping import hilbert
from crfmap.recording import ScanSet
from crfstudy.analysis import peer_search as ps
from crfstudy.analysis.coordinate import SearchResult, coordinate_descent

OCTOMAP_KEYS = tuple(ps.OCTOMAP_GRID)
HILBERT_KEYS = tuple(ps.HILBERT_GRID)


def _split(seed=0, n=8):
    rng = np.random.default_rng(seed)
    poses = np.column_stack([rng.uniform(1.8, 2.2, n), rng.uniform(1.8, 2.2, n), rng.uniform(-3, 3, n)])
    scans = ScanSet(rng.uniform(0.5, 1.5, (n, 40)).astype(np.float32), -np.pi / 2, np.pi / 39, 0.1, 5.0, poses,
                    np.arange(n, dtype=float))
    return scan_split(scans, 0.1)


def test_octomap_search_is_the_preset_rule_and_its_trace_is_honest():
    sp = _split()
    grid = {"p_hit": (0.6, 0.7, 0.9), "p_miss": (0.2, 0.4), "clamp_min": (0.05, 0.1192)}
    r = ps.octomap_search(sp, grid=grid)
    for entry in r.trace:  # every traced score is that configuration's score
        assert entry["brier"] == pytest.approx(ps.octomap_brier(sp, {k: entry[k] for k in OCTOMAP_KEYS}), abs=1e-12)
    assert r.converged and r.start == ps.OCTOMAP_START
    for name, values in grid.items():  # no single-coordinate move from the best helps (brute force)
        for v in values:
            assert ps.octomap_brier(sp, dict(r.best, **{name: v})) >= r.best_brier - 1e-12
    full = min(ps.octomap_brier(sp, dict(ps.OCTOMAP_START, **dict(zip(grid, combo))))
               for combo in itertools.product(*grid.values()))
    assert full <= r.best_brier <= r.trace[0]["brier"]


def test_hilbert_search_records_each_fit():
    sp = _split(1)
    grid = {"length_scale": (0.2, 0.3), "feature_spacing": (0.2,), "free_spacing": (0.25,)}
    start = {"feature_spacing": 0.2, "length_scale": 0.3, "free_spacing": 0.25}
    r = ps.hilbert_coordinate_search(sp, grid=grid, start=start)
    assert r.configurations == 2 and all(e["seconds"] >= 0 and 0 <= e["auc_all"] <= 1 for e in r.trace)
    for entry in r.trace:
        row = ps.hilbert_search(sp, [(entry["feature_spacing"], entry["length_scale"], entry["free_spacing"])])[0]
        assert entry["brier"] == pytest.approx(row["brier_all"], abs=1e-12)
        assert entry["logloss_all"] == pytest.approx(row["logloss_all"], abs=1e-12)


def test_interior_and_refusals():
    r = SearchResult({"a": 2, "b": 0.5}, 0.0, grid={"a": (1, 2, 3), "b": (0.5, 0.7)})
    assert r.interior() == {"a": True, "b": False}
    with pytest.raises(InputError, match="grid"):
        ps.octomap_search(_split(), grid={"nope": (1, 2)})
    with pytest.raises(InputError, match="start"):
        coordinate_descent(lambda c: 0.0, {"a": (1, 2)}, {"a": 3})
    with pytest.raises(InputError, match="first half's scans"):
        from crfmap.assess.scansplit import ScanSplit
        ps.octomap_brier(ScanSplit(*(np.ones((2, 2), int) for _ in range(4))), ps.OCTOMAP_START)


@pytest.mark.parametrize("peer,grid,start,keys", [("octomap", ps.OCTOMAP_GRID, ps.OCTOMAP_START, OCTOMAP_KEYS),
                                                  ("hilbert", ps.HILBERT_GRID, ps.HILBERT_START, HILBERT_KEYS)])
def test_cache_is_this_search_on_intel_and_its_choice_is_interior(peer, grid, start, keys):
    cached = ps.load_cached(peer)
    assert cached["grid"] == {k: list(v) for k, v in grid.items()} and cached["start"] == start
    assert cached["recording"] == ps.TRAINING and cached["resolution_m"] == ps.TRAINING_RESOLUTION
    assert cached["configurations"] == len(cached["trace"]) and cached["converged"]
    assert cached["best_brier"] == min(e["brier"] for e in cached["trace"])
    scored = {tuple(e[k] for k in keys): e["brier"] for e in cached["trace"]}
    for name, values in grid.items():  # every one-coordinate move from the best was scored, none better
        for v in values:
            assert scored[tuple(dict(cached["best"], **{name: v})[k] for k in keys)] >= cached["best_brier"]
        position = list(values).index(cached["best"][name])
        assert 0 < position < len(values) - 1, f"{peer}: {name} = {cached['best'][name]} sits on its grid's edge"
    assert cached["interior"] == {k: True for k in grid}
    assert cached["earlier"] == json.loads(json.dumps(ps.EARLIER[peer]))  # the dropped grids, recorded


def test_peer_rows_use_the_cached_choices_and_record_the_searches():
    octo, hil = ps.load_cached("octomap"), ps.load_cached("hilbert")
    assert peers.OCTOMAP_INTEL == octo["best"]
    assert {"feature_spacing": hilbert.FEATURE_SPACING, "length_scale": hilbert.LENGTH_SCALE,
            "free_spacing": hilbert.FREE_SPACING} == hil["best"]
    # the tables beside the constants are the caches' scores (rounded as printed)
    octo_scores = {tuple(e[k] for k in OCTOMAP_KEYS): e["brier"] for e in octo["trace"]}
    assert len(ps.OCTOMAP_SEARCH_INTEL) == len(set(ps.OCTOMAP_SEARCH_INTEL))
    for *constants, brier in ps.OCTOMAP_SEARCH_INTEL:
        assert brier == pytest.approx(octo_scores[tuple(constants)], abs=5e-8)
    assert ps.OCTOMAP_SEARCH_INTEL[0][:4] == tuple(octo["best"][k] for k in OCTOMAP_KEYS)
    columns = ps.HILBERT_SEARCH_COLUMNS
    assert len(ps.HILBERT_SEARCH_INTEL) == len(hil["trace"])
    for row, entry in zip(ps.HILBERT_SEARCH_INTEL, hil["trace"]):
        got = dict(zip(columns, row))
        assert tuple(got[k] for k in HILBERT_KEYS) == tuple(entry[k] for k in HILBERT_KEYS)
        assert got["brier_all"] == pytest.approx(entry["brier"], abs=5e-5)
        for k in ("logloss_all", "auc_all", "wall_recall"):
            assert got[k] == pytest.approx(entry[k], abs=5e-4)


@pytest.mark.skipif(not have_data(ps.TRAINING), reason="Intel log not downloaded")
def test_cached_octomap_scores_are_reproduced_on_intel():
    cached = ps.load_cached("octomap")
    sp = ps.training_split()
    picks = [cached["trace"][0], min(cached["trace"], key=lambda e: e["brier"]), cached["trace"][len(cached["trace"]) // 2]]
    for entry in picks:  # the library defaults (the start), the chosen values, one in between
        assert ps.octomap_brier(sp, {k: entry[k] for k in OCTOMAP_KEYS}) == pytest.approx(entry["brier"], abs=1e-9)
    # the peer row is the chosen constants' map
    from crfmap.assess.scansplit import score
    row = score(sp, {"octomap": peers.octomap_row(sp)}, n_boot=0, groups=("all",), metrics=("brier",))
    assert row["octomap"]["all"]["brier"] == pytest.approx(cached["best_brier"], abs=1e-9)


def test_command_refuses_bad_arguments_and_missing_data(tmp_path, monkeypatch, capsys):
    assert ps.main([]) == 2 and ps.main(["nope"]) == 2 and ps.main(["octomap", "--nope"]) == 2
    monkeypatch.setenv("CRFMAP_DATA", str(tmp_path))
    assert ps.main(["octomap"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("crfmap peer search:") and "intel" in err[-1].lower()
