import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.assess.learning import (
    ENTRY_NAMES,
    lbp_mse,
    learn_gradient,
    learn_pseudolikelihood,
    learn_thesis,
    pseudolikelihood,
    rescale,
)
from crfmap.crf.inference.lbp import infer


def toy(seed=0, sigma=0.35):
    rng = np.random.default_rng(seed)
    truth = np.zeros((16, 16))
    truth[3:13, 5:7] = 1
    truth[8:10, 2:14] = 1
    obs = np.clip(truth + rng.normal(0, sigma, truth.shape), 0, 1)
    return obs, truth


def test_thesis_learner_steps_by_alpha_and_never_gets_worse():
    obs, truth = toy()
    r = learn_thesis(obs, truth, [[0.9, 0.1], [0.1, 0.9]], max_rounds=5, progress=False)
    accepted = [t["mse"] for t in r.trace if t["accepted"]]
    assert all(b < a for a, b in zip(accepted, accepted[1:]))
    assert r.mse_after == pytest.approx(accepted[-1]) and r.mse_after < r.mse_before
    # every entry moved by a whole number of alpha steps from the start
    start = np.array([0.9, 0.1, 0.1, 0.9, 1, 0, 0, 1.0])
    moved = np.concatenate([r.hidden.ravel(), r.link.ravel()]) - start
    np.testing.assert_allclose(moved / 0.01, np.round(moved / 0.01), atol=1e-9)
    # the first step tried is +alpha on hidden oo, as in thesis Table 9 (0.9 -> 0.91)
    assert r.trace[1]["entry"] == ENTRY_NAMES[0] and r.trace[1]["value"] == pytest.approx(0.91)
    assert lbp_mse(obs, truth, r.hidden, r.link) == pytest.approx(r.mse_after)


def test_gradient_learner_lowers_the_mse():
    obs, truth = toy(1)
    r = learn_gradient(obs, truth, steps=10, progress=False)
    assert r.mse_after < r.mse_before
    assert r.hidden.max() == pytest.approx(10) and r.link.max() == pytest.approx(1)
    assert lbp_mse(obs, truth, r.hidden, r.link) == pytest.approx(r.mse_after, rel=1e-6)


def test_rescaling_does_not_change_lbp():
    obs, _ = toy(2)
    H, L = np.array([[3.0, 0.5], [0.7, 2.0]]), np.array([[0.8, 0.1], [0.05, 0.6]])
    H2, L2 = rescale(H, L)
    a = infer(obs, H, L, tol=1e-10).beliefs.probability
    b = infer(obs, H2, L2, tol=1e-10).beliefs.probability
    np.testing.assert_allclose(a, b, atol=1e-8)


def test_pseudolikelihood_gradient_matches_finite_differences():
    obs, truth = toy(3)
    H, L = np.array([[3.0, 1.2], [0.7, 2.0]]), np.array([[1.0, 0.2], [0.1, 0.9]])
    _, grad = pseudolikelihood(obs, truth, H, L)
    theta = np.log(np.r_[H.ravel(), L.ravel()])
    for i in range(8):
        e = np.zeros(8)
        e[i] = 1e-6
        up, down = np.exp(theta + e), np.exp(theta - e)
        num = (pseudolikelihood(obs, truth, up[:4].reshape(2, 2), up[4:].reshape(2, 2))[0]
               - pseudolikelihood(obs, truth, down[:4].reshape(2, 2), down[4:].reshape(2, 2))[0]) / 2e-6
        assert grad[i] == pytest.approx(num, abs=1e-7)


def test_pseudolikelihood_learner_increases_its_objective():
    obs, truth = toy(4)
    r = learn_pseudolikelihood(obs, truth, steps=50, progress=False)
    assert r.trace[-1]["objective"] > r.trace[0]["objective"]


def test_shape_mismatch_is_named():
    with pytest.raises(InputError, match="truth"):
        learn_thesis(np.zeros((3, 3)), np.zeros((3, 4)), progress=False)
