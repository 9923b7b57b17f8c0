"""Scan-split validation on small synthetic recordings, against slow obvious references."""
import numpy as np
import pytest

from crfmap.assess.scansplit import ScanSplit, scan_split, score, split_scans
from crfmap.errors import InputError
from crfmap.mapping.builder import build_grid, count_hits
from crfmap.crf.presets import DEFAULT_PRESET as D  # the row of the default preset


def test_halves_are_the_even_and_odd_scans_on_one_grid(room):
    scans = room
    sp = scan_split(scans, 0.1, bounds=(0, 0, 2, 2))
    h1, e1 = count_hits(split_scans(scans, 0), 0.1, bounds=(0, 0, 2, 2))
    h2, e2 = count_hits(split_scans(scans, 1), 0.1, bounds=(0, 0, 2, 2))
    assert np.array_equal(sp.first_hits, h1) and np.array_equal(sp.second_passes, e2)
    assert np.array_equal(sp.first_hits + sp.second_hits, count_hits(scans, 0.1, bounds=(0, 0, 2, 2))[0])
    raw = build_grid(split_scans(scans, 0), 0.1, bounds=(0, 0, 2, 2)).probability
    assert np.allclose(sp.raw_probability(), raw)


def _naive(p, y):
    brier = np.mean((p - y) ** 2)
    pos, neg = p[y == 1], p[y == 0]
    auc = np.mean([(a > b) + 0.5 * (a == b) for a in pos for b in neg])
    return brier, auc, np.mean(pos > 0.5)


def test_scores_match_a_naive_reference_and_the_unseen_group_is_half():
    rng = np.random.default_rng(1)
    shape = (12, 15)
    h1, e1, h2, e2 = (rng.integers(0, 3, shape) for _ in range(4))
    h1[:, :3] = e1[:, :3] = 0  # never seen by the first half
    sp = ScanSplit(h1, e1, h2, e2)
    pred = np.round(rng.uniform(0, 1, shape), 1)  # ties on purpose
    out = score(sp, {"p": pred, "raw": sp.raw_probability()}, n_boot=0)
    for group in ("all", "seen", "unseen"):
        m = sp.group(group)
        y = ((h2 >= e2) & (h2 > 0))[m].astype(float)
        brier, auc, recall = _naive(pred[m], y)
        assert out["p"][group]["brier"] == pytest.approx(brier)
        assert out["p"][group]["auc"] == pytest.approx(auc)
        assert out["p"][group]["wall_recall"] == pytest.approx(recall)
    assert out["raw"]["unseen"]["brier"] == 0.25 and out["raw"]["unseen"]["auc"] == 0.5


def test_bootstrap_is_seeded_covers_the_estimate_and_pairs_differences():
    rng = np.random.default_rng(2)
    shape = (64, 64)
    h1, e1, h2, e2 = (rng.integers(0, 3, shape) for _ in range(4))
    sp = ScanSplit(h1, e1, h2, e2)
    preds = {"raw": sp.raw_probability(), "same": sp.raw_probability().copy(), "half": np.full(shape, 0.5)}
    a = score(sp, preds, n_boot=50, block=8, seed=3, reference="raw")
    b = score(sp, preds, n_boot=50, block=8, seed=3, reference="raw")
    assert a["half"]["all"]["brier_ci"] == b["half"]["all"]["brier_ci"]
    lo, hi = a["raw"]["all"]["brier_ci"]
    assert lo < a["raw"]["all"]["brier"] < hi
    assert a["same"]["all"]["brier_diff_ci"] == (0.0, 0.0)  # paired: identical predictions never differ
    assert a["half"]["all"]["brier"] == pytest.approx(0.25)


def test_resampled_metrics_equal_one_resample_at_a_time():
    """The compiled all-resamples path against the per-resample reference (_Scorer.metrics)."""
    from crfmap.assess.scansplit import _Scorer

    rng = np.random.default_rng(4)
    n, n_blocks = 500, 23
    p = np.round(rng.uniform(0, 1, n), 2)  # ties on purpose
    y = (rng.uniform(0, 1, n) < p).astype(float)
    inverse = rng.integers(0, n_blocks, n)
    draws = np.array([np.bincount(rng.integers(0, n_blocks, n_blocks), minlength=n_blocks) for _ in range(30)],
                     dtype=float)
    scorer = _Scorer(p, y, inverse, n_blocks)
    fast = scorer.resampled(draws)
    for k, w in enumerate(draws):
        one = scorer.metrics(w)
        for m in ("brier", "logloss", "auc", "wall_recall"):
            assert fast[m][k] == pytest.approx(one[m], rel=1e-12)


def test_a_subset_of_groups_and_metrics_equals_the_full_result():
    rng = np.random.default_rng(5)
    sp = ScanSplit(*(rng.integers(0, 3, (40, 40)) for _ in range(4)))
    preds = {"raw": sp.raw_probability(), "half": np.full((40, 40), 0.5)}
    full = score(sp, preds, n_boot=20, block=8, seed=1, reference="raw")
    part = score(sp, preds, n_boot=20, block=8, seed=1, reference="raw", groups=("unseen",), metrics=("brier",))
    assert list(part["half"]) == ["unseen"]
    assert part["half"]["unseen"]["brier_ci"] == full["half"]["unseen"]["brier_ci"]  # same resamples
    assert part["half"]["unseen"]["brier_diff"] == full["half"]["unseen"]["brier_diff"]
    assert "auc" not in part["half"]["unseen"]
    with pytest.raises(InputError, match="subsets"):
        score(sp, preds, groups=("walls",))


def test_compare_keeps_the_grids_it_scored_only_when_asked():
    from crfmap.assess.comparison import compare

    sp = ScanSplit(*(np.random.default_rng(6).integers(0, 3, (20, 20)) for _ in range(4)))
    kept = compare(sp, n_boot=0, keep_beliefs=True)
    assert "_beliefs" not in compare(sp, n_boot=0)  # plain results stay JSON-friendly (crfmap evaluate --json)
    np.testing.assert_array_equal(kept["_beliefs"]["raw"], sp.raw_probability())
    again = score(sp, {D: kept["_beliefs"][D]}, n_boot=0)[D]["all"]["brier"]
    assert again == kept[D]["all"]["brier"]


def test_compare_shows_its_steps_when_asked_and_scores_the_same(room, capsys):
    from crfmap.assess.comparison import compare

    sp = scan_split(room, 0.1, bounds=(0, 0, 2, 2))
    quiet = compare(sp, n_boot=0, methods=["raw", "mean3x3", D, "octomap"])
    assert capsys.readouterr().err == ""
    shown = compare(sp, n_boot=0, methods=["raw", "mean3x3", D, "octomap"], progress=True)
    err = capsys.readouterr().err
    assert "evaluate" in err and "5/5" in err  # baselines, the preset, one peer, the scores, the nav2 reading
    shown.pop("_seconds")
    quiet.pop("_seconds")
    np.testing.assert_equal(shown, quiet)  # (NaN where a group has no cell, equal to NaN here)


def test_bad_input_is_named():
    sp = ScanSplit(*(np.zeros((2, 2), int) for _ in range(4)))
    with pytest.raises(InputError, match="shape"):
        score(sp, {"p": np.zeros((3, 3))})
    with pytest.raises(InputError, match="probabilities"):
        score(sp, {"p": np.full((2, 2), 2.0)})
    with pytest.raises(InputError, match="non-negative"):
        ScanSplit(*(np.full((2, 2), -1) for _ in range(4)))


def _auc_one_resample_at_a_time(y, inverse, starts, draws):
    """The all-resamples AUC loop as it was before it went over every resample at once (its summation order)."""
    out = np.empty(len(draws))
    for k, w in enumerate(draws):
        total = neg_below = n_pos = n_neg = 0.0
        for r, start in enumerate(starts):
            end = starts[r + 1] if r + 1 < len(starts) else len(y)
            pos_g = neg_g = 0.0
            for i in range(start, end):
                pos_g += w[inverse[i]] * y[i]
                neg_g += w[inverse[i]] * (1.0 - y[i])
            total += pos_g * (neg_below + 0.5 * neg_g)
            neg_below += neg_g
            n_pos += pos_g
            n_neg += neg_g
        out[k] = total / (n_pos * n_neg) if n_pos > 0 and n_neg > 0 else np.nan
    return out


def test_the_resampled_auc_is_bit_for_bit_the_one_resample_at_a_time_sum():
    from crfmap.assess.block_bootstrap import _auc_resampled

    rng = np.random.default_rng(8)
    n, n_blocks = 400, 17
    for p in (np.round(rng.uniform(0, 1, n), 1), rng.uniform(0, 1, n)):  # many ties, then none
        order = np.argsort(p, kind="stable")
        y = (rng.uniform(0, 1, n) < p)[order].astype(float)
        inverse = rng.integers(0, n_blocks, n)[order]
        starts = np.concatenate([[0], np.flatnonzero(np.diff(p[order])) + 1]).astype(np.int64)
        draws = np.array([np.bincount(rng.integers(0, n_blocks, n_blocks), minlength=n_blocks) for _ in range(25)],
                         dtype=float)
        np.testing.assert_array_equal(_auc_resampled(y, inverse, starts, draws),
                                      _auc_one_resample_at_a_time(y, inverse, starts, draws))
    only_walls = np.ones(5)
    assert np.isnan(_auc_resampled(only_walls, np.zeros(5, np.int64), np.array([0], np.int64), np.ones((2, 1)))).all()


def test_a_split_scored_again_gives_the_same_numbers_and_notices_new_counts():
    """score() keeps the split's cells and blocks between calls: the same result as a fresh split, per block size."""
    rng = np.random.default_rng(9)
    counts = [rng.integers(0, 3, (30, 30)) for _ in range(4)]
    sp = ScanSplit(*counts)
    preds = {"raw": sp.raw_probability(), "half": np.full((30, 30), 0.5)}
    for block in (8, 8, 5, 8):
        again = score(sp, preds, n_boot=10, block=block, seed=2, reference="raw")
        assert repr(again) == repr(score(ScanSplit(*counts), preds, n_boot=10, block=block, seed=2, reference="raw"))
    sp.second_hits = counts[0] * 2  # new counts: new labels and groups (repr: NaN equals NaN)
    assert repr(score(sp, preds, n_boot=0)) == repr(score(ScanSplit(counts[0], counts[1], counts[0] * 2, counts[3]),
                                                          preds, n_boot=0))


def test_the_split_keeps_each_halfs_scans(room):
    for parity in (0, 1):
        sp = scan_split(room, 0.1, parity=parity, bounds=(0, 0, 2, 2))
        assert sp.first_scans.stamps.tolist() == split_scans(room, parity).stamps.tolist()
        assert sp.second_scans.stamps.tolist() == split_scans(room, 1 - parity).stamps.tolist()
        h2, e2 = count_hits(sp.second_scans, 0.1, bounds=(0, 0, 2, 2))
        assert np.array_equal(h2, sp.second_hits) and np.array_equal(e2, sp.second_passes)


def test_block_resamples_are_the_draws_score_uses():
    from crfmap.assess.scansplit import block_resamples, percentile_interval

    rng = np.random.default_rng(5)
    sp = ScanSplit(*(rng.integers(0, 3, (40, 40)) for _ in range(4)))
    p = sp.raw_probability()
    s = score(sp, {"raw": p}, n_boot=25, block=8, seed=4, metrics=("brier",))
    r = block_resamples(sp, n_boot=25, block=8, seed=4)
    for group in ("all", "seen", "unseen"):
        g = r[group]
        cells, errors = g.draws[:, g.inverse], (p[g.mask] - g.labels) ** 2  # [resample, cell] weights
        brier = (cells * errors).sum(axis=1) / cells.sum(axis=1)
        assert s["raw"][group]["brier_ci"] == pytest.approx(percentile_interval(brier, 0.95))
