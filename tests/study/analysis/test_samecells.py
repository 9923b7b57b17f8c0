"""Scoring on common cells, against crfmap.assess.metrics and loops."""
import numpy as np
import pytest

from crfmap.assess.metrics import evaluate
from crfstudy.analysis.samecells import block_scores, classification, common_mask, fold_scores
from crfmap.errors import InputError


def _case(seed=0, shape=(24, 30)):
    rng = np.random.default_rng(seed)
    labels = np.where(rng.random(shape) < 0.2, 0.9, 0.1)
    truth = labels > 0.5
    good = np.where(rng.random(shape) < 0.9, truth, ~truth) * 0.6 + 0.2
    shy = np.where(rng.random(shape) < 0.4, 0.5, np.where(rng.random(shape) < 0.95, truth, ~truth) * 0.8 + 0.1)
    folds = rng.integers(0, 5, shape)
    return labels, {"good": good, "shy": shy}, folds


def test_common_cells_are_those_every_method_decides_and_metrics_match_evaluate():
    labels, preds, _ = _case()
    mask = np.ones(labels.shape, bool)
    common = common_mask(preds, mask)
    assert np.array_equal(common, preds["shy"] != 0.5)
    for p in preds.values():
        ours, ref = classification(p, labels, common), evaluate(p, labels, common)
        assert ours["precision"] == pytest.approx(ref.precision) and ours["recall"] == pytest.approx(ref.recall)
        assert ours["accuracy"] == pytest.approx(ref.accuracy)


def test_fold_scores_per_fold_and_paired_differences():
    labels, preds, folds = _case(1)
    held = np.ones(labels.shape, bool)
    out = fold_scores(preds, labels, held, folds, reference="good", n_boot=500)
    common = common_mask(preds, held)
    assert out["common_cells"] == common.sum() and out["folds"] == [0, 1, 2, 3, 4]
    shy = out["methods"]["shy"]
    for f, entry in zip(out["folds"], shy["per_fold"]):
        cells = common & (folds == f)
        assert entry["accuracy"] == pytest.approx(np.mean((preds["shy"][cells] > 0.5) == (labels[cells] > 0.5)))
    acc = [e["accuracy"] for e in shy["per_fold"]]
    ref = [e["accuracy"] for e in out["methods"]["good"]["per_fold"]]
    assert shy["accuracy"]["fold_mean"] == pytest.approx(np.mean(acc))
    assert shy["vs_reference"]["accuracy"]["mean_difference"] == pytest.approx(np.mean(np.subtract(acc, ref)))
    lo, hi = shy["accuracy"]["fold_ci"]
    assert min(acc) <= lo <= hi <= max(acc)


def test_block_scores_difference_and_interval():
    labels, preds, _ = _case(2)
    out = block_scores(preds, labels, np.ones(labels.shape, bool), reference="good", block=6, n_boot=300)
    common = common_mask(preds, np.ones(labels.shape, bool))
    shy, good = classification(preds["shy"], labels, common), classification(preds["good"], labels, common)
    e = out["methods"]["shy"]
    assert e["accuracy_diff"] == pytest.approx(shy["accuracy"] - good["accuracy"])
    lo, hi = e["accuracy_diff_ci"]
    assert lo <= e["accuracy_diff"] <= hi
    assert out["methods"]["good"]["accuracy_diff_ci"] == (0.0, 0.0)


def test_bad_input():
    labels, preds, folds = _case()
    with pytest.raises(InputError):
        fold_scores(preds, labels, np.ones(labels.shape, bool), folds, reference="nope")
    with pytest.raises(InputError):
        block_scores(preds, labels, np.zeros(labels.shape, bool), reference="good")
    with pytest.raises(InputError):
        common_mask({"a": np.zeros((2, 2))}, np.ones((3, 3), bool))
