"""Bayesian Hilbert maps: the closed-form rounds against a direct optimisation and a dense reference."""
import math

import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.mapping.hilbert import CUTOFF, HilbertMap, beam_samples, hilbert_grid
from crfmap.recording import ScanSet


def _log_sigmoid(z):
    return -np.logaddexp(0.0, -z)


def _bound(mu, s2, phi, y, mu0, s0):
    """Jaakkola-Jordan lower bound on the evidence for one weight N(mu, s2), the best xi for each point."""
    second = phi ** 2 * (mu ** 2 + s2)  # E[(w phi)^2]
    xi = np.sqrt(second)
    lam = np.tanh(xi / 2) / (4 * xi)
    data = np.sum(_log_sigmoid(xi) + (y - 0.5) * phi * mu - xi / 2 - lam * (second - xi ** 2))
    kl = 0.5 * (s2 / s0 + (mu - mu0) ** 2 / s0 - 1 - math.log(s2 / s0))
    return data - kl


def test_one_feature_reaches_the_optimum_of_the_bound():
    # one centre at the origin; five points at known distances with labels: the model has one weight, so the
    # diagonal posterior is the full one and the EM rounds must climb to the bound's maximum over (mu, s2)
    points = np.array([[0.0, 0.0], [0.3, 0.0], [0.0, 0.5], [0.6, 0.0], [0.2, 0.2]])
    y = np.array([1.0, 1.0, 0.0, 0.0, 1.0])
    m = HilbertMap((0, 0, 0, 0), feature_spacing=1.0, length_scale=0.5, em_iterations=500, prior_variance=4.0)
    assert m.mu.size == 1
    m.fit_batch(points, y)
    phi = np.exp(-np.sum(points ** 2, axis=1) / (2 * 0.5 ** 2))
    # direct search: a fine grid around the optimum, refined twice
    mu_c, ls_c, width = 0.0, 0.0, 4.0
    for _ in range(4):
        mus = np.linspace(mu_c - width, mu_c + width, 201)
        lss = np.linspace(ls_c - width, ls_c + width, 201)
        values = np.array([[_bound(a, math.exp(b), phi, y, 0.0, 4.0) for b in lss] for a in mus])
        i, j = np.unravel_index(np.argmax(values), values.shape)
        mu_c, ls_c, width = mus[i], lss[j], width / 20
    assert m.mu[0] == pytest.approx(mu_c, abs=2e-3)
    assert math.log(m.sig[0]) == pytest.approx(ls_c, abs=2e-3)
    # the predictive: sigmoid(phi mu / sqrt(1 + pi phi^2 s2 / 8)) by hand at the centre
    expected = 1 / (1 + math.exp(-m.mu[0] / math.sqrt(1 + math.pi * m.sig[0] / 8)))
    assert m.predict(np.array([[0.0, 0.0]]))[0] == pytest.approx(expected, rel=1e-12)


def _dense_reference(model, batches):
    """The authors' update with the dense feature matrix (all centres, no cut-off)."""
    gx = model.origin[0] + model.spacing * np.arange(model.nx)
    gy = model.origin[1] + model.spacing * np.arange(model.ny)
    centres = np.column_stack([np.tile(gx, model.ny), np.repeat(gy, model.nx)])

    def phi(p):
        return np.exp(-model.gamma * ((p[:, None, :] - centres[None]) ** 2).sum(-1))

    mu, sig = np.zeros(len(centres)), np.full(len(centres), model.prior_variance)
    for points, y in batches:
        X = phi(points)
        xi = np.ones(len(points))
        mu0, sig0 = mu, sig
        for _ in range(model.em_iterations):
            lam = np.tanh(xi / 2) / (4 * xi)
            sig = 1 / (1 / sig0 + 2 * (X ** 2 * lam[:, None]).sum(0))
            mu = sig * (mu0 / sig0 + X.T @ (y - 0.5))
            xi = np.sqrt((X ** 2 * sig).sum(1) + (X @ mu) ** 2)
    return mu, sig, phi


def test_sequential_batches_match_the_dense_update():
    rng = np.random.default_rng(0)
    batches = [(rng.uniform(0, 2, (30, 2)), rng.integers(0, 2, 30).astype(float)) for _ in range(4)]
    m = HilbertMap((0, 0, 2, 2), feature_spacing=0.4, length_scale=0.2, prior_variance=3.0)
    for points, y in batches:
        m.fit_batch(points, y)
    mu, sig, phi = _dense_reference(m, batches)
    # the cut-off drops features below exp(-CUTOFF^2 / 2) = 3e-4
    np.testing.assert_allclose(m.mu, mu, atol=2e-3 * np.abs(mu).max())
    np.testing.assert_allclose(m.sig, sig, rtol=2e-3)
    q = rng.uniform(0, 2, (50, 2))
    a, s2 = phi(q) @ mu, phi(q) ** 2 @ sig
    np.testing.assert_allclose(m.predict(q), 1 / (1 + np.exp(-a / np.sqrt(1 + np.pi * s2 / 8))), atol=1e-3)
    assert math.exp(-CUTOFF ** 2 / 2) < 1e-3


def test_beam_samples_and_grid():
    s = ScanSet(np.array([[1.0, np.inf], [0.55, 0.05]], np.float32), 0.0, math.pi / 2, 0.1, 5.0,
                np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), np.zeros(2))
    (p1, l1), (p2, l2) = beam_samples(s, free_spacing=0.25)
    np.testing.assert_allclose(p1, [[1, 0], [0.25, 0], [0.5, 0], [0.75, 0]], atol=1e-12)  # the no-return: nothing
    assert l1.tolist() == [1, 0, 0, 0] and l2.tolist() == [1, 0]  # 0.05 < range_min is dropped
    # settings of this tiny case (the defaults are tuned for 5 cm grids of real logs)
    g = hilbert_grid(s, 0.1, (-0.5, -0.5, 1.5, 1.5), feature_spacing=0.2, length_scale=0.2, free_spacing=0.25)
    assert g.probability.shape == (20, 20) and g.meta["scans"] == 2
    assert g.probability[5, 15] > 0.5 > g.probability[5, 9]  # the wall at x = 1, free space before it
    with pytest.raises(InputError, match="labels"):
        HilbertMap((0, 0, 1, 1)).fit_batch(np.zeros((2, 2)), np.array([0.0, 2.0]))
    with pytest.raises(InputError, match="length_scale"):
        HilbertMap((0, 0, 1, 1), length_scale=0)
