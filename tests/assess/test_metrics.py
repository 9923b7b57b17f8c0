"""Metrics against hand-computed cases."""
import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.assess.metrics import auc, confusion, evaluate, mse, roc_curve


def test_mse_by_hand():
    assert mse([[0.5, 1.0], [0.0, 0.25]], [[1, 1], [0, 0]]) == pytest.approx((0.25 + 0 + 0 + 0.0625) / 4)


def test_confusion_precision_recall_accuracy_by_hand():
    pred = np.array([[0.9, 0.8, 0.7, 0.2, 0.1, 0.5, 0.6]])
    truth = np.array([[1, 1, 0, 1, 0, 1, 1]])
    c = confusion(pred, truth)
    # predicted occupied: 0.9(T) 0.8(T) 0.7(F) 0.6(T); empty: 0.2(T occupied -> FN) 0.1(TN); 0.5 left out
    assert (c.tp, c.fp, c.fn, c.tn, c.unknown) == (3, 1, 1, 1, 1)
    assert c.precision == pytest.approx(3 / 4)  # TP / (TP + FP): the thesis's eq. 13 had it swapped
    assert c.recall == pytest.approx(3 / 4)
    assert c.accuracy == pytest.approx(4 / 6)


def test_precision_and_recall_are_not_swapped():
    pred = np.array([[0.9, 0.9, 0.9, 0.1]])
    truth = np.array([[1, 0, 0, 1]])
    c = confusion(pred, truth)
    assert c.precision == pytest.approx(1 / 3) and c.recall == pytest.approx(1 / 2)


def test_roc_and_auc_by_hand():
    fpr, tpr, thr = roc_curve([[0.9, 0.8, 0.3, 0.1]], [[1, 0, 1, 0]])
    assert fpr.tolist() == [0, 0, 0.5, 0.5, 1] and tpr.tolist() == [0, 0.5, 0.5, 1, 1]
    assert auc([[0.9, 0.8, 0.3, 0.1]], [[1, 0, 1, 0]]) == pytest.approx(0.75)
    assert auc([[0.9, 0.8, 0.2, 0.1]], [[1, 1, 0, 0]]) == pytest.approx(1.0)
    # ties count half
    assert auc([[0.5, 0.5]], [[1, 0]]) == pytest.approx(0.5)


def test_auc_equals_rank_statistic_on_random_data():
    rng = np.random.default_rng(3)
    p = rng.uniform(size=(30, 30)).round(2)  # with ties
    t = rng.uniform(size=(30, 30)) < p
    pos, neg = p[t], p[~t]
    wins = (pos[:, None] > neg[None, :]).sum() + 0.5 * (pos[:, None] == neg[None, :]).sum()
    assert auc(p, t) == pytest.approx(wins / (pos.size * neg.size))


def test_evaluate_and_mask():
    pred = np.array([[0.9, 0.1], [0.8, 0.3]])
    truth = np.array([[1, 0], [0, 0]])
    r = evaluate(pred, truth)
    assert (r.tp, r.fp, r.tn, r.fn) == (1, 1, 2, 0)
    m = np.array([[True, True], [False, True]])
    assert evaluate(pred, truth, mask=m).fp == 0


def test_shape_mismatch_and_one_class_truth():
    with pytest.raises(InputError, match="shape"):
        mse(np.zeros((2, 2)), np.zeros((2, 3)))
    with pytest.raises(InputError, match="both occupied and empty"):
        roc_curve(np.zeros((2, 2)), np.zeros((2, 2)))


def test_roc_and_auc_give_the_hand_written_numbers_bit_for_bit():
    """sklearn.metrics.roc_curve (every threshold kept) and auc in place of the sweep they replaced."""
    import naive_replaced as old

    for seed in range(80):
        rng = np.random.default_rng(seed)
        n = int(rng.integers(2, 80))
        p = rng.uniform(size=n)
        if seed % 2:
            p = rng.choice([0.0, 0.1, 0.3, 0.5, 0.7, 1.0], size=n)  # many ties, exact 0 and 1
        p[rng.uniform(size=n) < 0.2] = 0.5
        t = (rng.uniform(size=n) < rng.uniform(0.1, 0.9)).astype(np.float64)
        t[:2] = (0.0, 1.0)
        got, want = roc_curve(p[None], t[None]), old.roc_curve(p, t)
        for g, w in zip(got, want):
            assert g.dtype == w.dtype
            np.testing.assert_array_equal(g, w)
        assert auc(p[None], t[None]) == old.auc(p, t)
    # unknown cells left out, and a mask: the same cells go to the library
    p, t = np.array([[0.9, 0.5, 0.2, 0.5, 0.7]]), np.array([[1, 0, 0, 1, 0]])
    keep = p[0] != 0.5
    np.testing.assert_array_equal(roc_curve(p, t, include_unknown=False)[1], old.roc_curve(p[0, keep], t[0, keep])[1])
    mask = np.array([[True, True, False, True, True]])
    assert auc(p, t, mask) == old.auc(p[mask], t[mask])
