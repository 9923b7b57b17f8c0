"""Ablations and calibrated independent-cell models, against slow obvious references."""
import math

import numpy as np
import pytest

from crfstudy.analysis import ablations
from crfmap.assess.scansplit import ScanSplit
from crfmap.crf.presets import get_preset
from crfmap.errors import InputError


def _isotonic_minmax(y, w):
    """Isotonic regression by its min-max formula: f_i = max_{j<=i} min_{k>=i} mean(y[j..k]) (weighted)."""
    n = len(y)
    out = np.empty(n)
    for i in range(n):
        out[i] = max(min(np.sum(w[j:k + 1] * y[j:k + 1]) / np.sum(w[j:k + 1]) for k in range(i, n))
                     for j in range(i + 1))
    return out


@pytest.mark.parametrize("seed", range(5))
def test_pav_equals_the_min_max_formula(seed):
    rng = np.random.default_rng(seed)
    x = rng.integers(-6, 7, 80)
    y = (rng.random(80) < 1 / (1 + np.exp(-0.5 * x + rng.normal(0, 1, 80)))).astype(float)
    iso = ablations.IsotonicEvidence.fit(x, y)
    values = np.unique(x)
    means = np.array([y[x == v].mean() for v in values])
    weights = np.array([np.sum(x == v) for v in values], float)
    assert np.array_equal(iso.x, values)
    assert np.allclose(iso.p, _isotonic_minmax(means, weights))
    assert np.all(np.diff(iso.p) >= -1e-15)
    # between and beyond the fitted values: linear, then constant
    assert iso.predict(np.array([values[0] - 5, values[-1] + 5])).tolist() == [iso.p[0], iso.p[-1]]


def test_platt_recovers_the_logistic_it_was_drawn_from():
    rng = np.random.default_rng(0)
    x = rng.integers(-8, 9, 200000).astype(float)
    raw = 0.5 + np.arctan(x) / math.pi
    z = np.log(raw / (1 - raw))
    y = rng.random(z.size) < 1 / (1 + np.exp(-(-0.7 + 1.6 * z)))
    fit = ablations.PlattRaw.fit(raw, y)
    assert fit.alpha == pytest.approx(-0.7, abs=0.03) and fit.beta == pytest.approx(1.6, abs=0.03)


def _split(seed=0, shape=(16, 16)):
    rng = np.random.default_rng(seed)
    walls = rng.random(shape) < 0.25
    counts = [rng.poisson(np.where(walls, a, b)) for a, b in ((2, 0.2), (0.3, 1.5), (2, 0.2), (0.3, 1.5))]
    counts[0][:4, :4] = counts[1][:4, :4] = 0  # a never-seen corner
    return ScanSplit(*counts)


def test_ablations_change_one_thing_and_j0_is_the_observation():
    base = get_preset("certainty")
    presets = ablations.ablation_presets()
    assert presets["no margin"].margin is None and presets["no cap"].limit == math.inf
    assert presets["J = 0"].coupling == 0 and presets["J = 0"].occupied == base.occupied
    sp = _split()
    lbp = presets["J = 0"].refine(hits=sp.first_hits, passes=sp.first_passes).beliefs.probability
    preds, summaries = ablations.ablation_predictions(sp, {"iso": ablations.IsotonicEvidence.fit_split(sp)})
    assert np.allclose(preds["J = 0"], lbp, atol=1e-12)
    assert set(summaries) == {"no margin", "no cap"}
    unseen = sp.first_hits + sp.first_passes == 0
    assert np.all(preds["iso, unseen at 0.5"][unseen] == 0.5)
    assert np.array_equal(preds["iso"][~unseen], preds["iso, unseen at 0.5"][~unseen])


def test_isotonic_fit_on_a_split_uses_the_second_halfs_labels():
    sp = _split(1)
    iso = ablations.IsotonicEvidence.fit_split(sp)
    mask = sp.group("all")
    x = ablations.evidence(sp)[mask]
    y = sp.labels()[mask]
    # the fit minimises the squared error among non-decreasing functions: no worse than the cell means
    assert np.mean((iso.predict(x) - y) ** 2) <= np.mean((np.clip(0.5 + 0.1 * x, 0, 1) - y) ** 2)


@pytest.mark.parametrize("x,y", [([], []), ([1, 2], [0]), ([np.inf], [1]), ([1], [2])])
def test_bad_fit_input(x, y):
    with pytest.raises(InputError):
        ablations.IsotonicEvidence.fit(np.array(x, float), np.array(y, float))
