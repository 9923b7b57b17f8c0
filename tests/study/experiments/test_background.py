import numpy as np
import pytest

from crfstudy.experiments.background import gibbs_ising, ising_energy, ising_exact
from crfmap.errors import InputError


def two_site_law_by_hand(coupling, field):
    """P(s1, s2) ∝ exp(J s1 s2 + H (s1 + s2)) over (-1,-1), (+1,-1), (-1,+1), (+1,+1)."""
    states = [(-1, -1), (1, -1), (-1, 1), (1, 1)]
    w = np.array([np.exp(coupling * a * b + field * (a + b)) for a, b in states])
    return states, w / w.sum()


def test_exact_law_of_two_sites_matches_the_hand_formula():
    states, p = ising_exact(2, coupling=0.7, field=-0.3)
    hand_states, hand_p = two_site_law_by_hand(0.7, -0.3)
    assert [tuple(s) for s in states.tolist()] == hand_states
    np.testing.assert_allclose(p, hand_p)


@pytest.mark.parametrize("shape", [2, (1, 2), (2, 1)])
def test_gibbs_on_two_sites_matches_the_exact_distribution(shape):
    coupling, field, n = 0.8, 0.3, 40000
    samples = gibbs_ising(shape, coupling, field, sweeps=20, chains=n, seed=3).reshape(n, 2)
    states, p = two_site_law_by_hand(coupling, field)
    freq = np.array([np.mean((samples[:, 0] == a) & (samples[:, 1] == b)) for a, b in states])
    sigma = np.sqrt(p * (1 - p) / n)
    assert np.all(np.abs(freq - p) < 5 * sigma), (freq, p)


def test_gibbs_on_a_3x3_lattice_matches_exact_moments():
    coupling, field, n = 0.4, -0.1, 20000
    samples = gibbs_ising((3, 3), coupling, field, sweeps=30, chains=n, seed=5).astype(float)
    states, p = ising_exact((3, 3), coupling, field)
    s = states.astype(float)
    exact_mean = np.tensordot(p, s, axes=1)
    exact_corner_edge = np.sum(p * s[:, 0, 0] * s[:, 0, 1])
    assert np.abs(samples.mean(axis=0) - exact_mean).max() < 0.04
    assert abs(np.mean(samples[:, 0, 0] * samples[:, 0, 1]) - exact_corner_edge) < 0.04


def test_chain_nearest_neighbour_correlation_is_tanh_of_coupling():
    # free chain, no field: E[s_i s_(i+1)] = tanh(J) exactly (a classic result)
    coupling = 0.6
    s = gibbs_ising(30, coupling, sweeps=50, chains=4000, seed=2).astype(float)
    corr = np.mean(s[:, :-1] * s[:, 1:])
    assert corr == pytest.approx(np.tanh(coupling), abs=0.01)


def test_energy_by_hand_and_consistent_with_exact_law():
    assert ising_energy([[1, -1], [1, 1]], coupling=2.0, field=1.0) == pytest.approx(-2.0 * (-1 + 1 + -1 + 1) - 2.0)
    states, p = ising_exact((2, 2), coupling=0.5, field=0.2)
    energies = np.array([ising_energy(s, 0.5, 0.2) for s in states])
    w = np.exp(-energies)
    np.testing.assert_allclose(p, w / w.sum())


def test_seeded_and_reproducible_and_initial_kept_with_no_sweeps():
    a = gibbs_ising((5, 7), 0.3, sweeps=5, seed=11)
    b = gibbs_ising((5, 7), 0.3, sweeps=5, seed=11)
    np.testing.assert_array_equal(a, b)
    init = np.where(np.arange(35).reshape(5, 7) % 3 == 0, 1, -1)
    np.testing.assert_array_equal(gibbs_ising((5, 7), sweeps=0, initial=init), init)


def test_strong_field_aligns_every_spin():
    s = gibbs_ising((6, 6), coupling=0.0, field=20.0, sweeps=1, seed=0)
    assert np.all(s == 1)


@pytest.mark.parametrize("kwargs, name", [
    ({"shape": (2, 2, 2)}, "shape"),
    ({"shape": 0}, "shape"),
    ({"shape": 3, "coupling": float("nan")}, "coupling"),
    ({"shape": 3, "sweeps": -1}, "sweeps"),
    ({"shape": 3, "chains": 0}, "chains"),
    ({"shape": 3, "initial": [1, 0, 1]}, "initial"),
])
def test_bad_input_names_the_argument(kwargs, name):
    with pytest.raises(InputError, match=f"^{name}:"):
        gibbs_ising(**kwargs)


def test_exact_refuses_big_models_and_energy_refuses_non_spins():
    with pytest.raises(InputError, match="too many"):
        ising_exact((5, 5))
    with pytest.raises(InputError, match="^spins:"):
        ising_energy([0, 1])


def _gibbs_by_hand(shape, coupling, field, sweeps, chains, seed, initial=None):
    """The sampler written out site by site: the same draws (one uniform per site and colour, in C order), the
    conditional P(+1) = e^local / (e^local + e^-local) from the neighbours' current spins."""
    shape = (shape,) if isinstance(shape, int) else shape
    full = shape if chains is None else (chains,) + shape
    rng = np.random.default_rng(seed)
    spins = np.where(rng.random(full) < 0.5, 1, -1).astype(np.int8) if initial is None else \
        np.broadcast_to(initial, full).astype(np.int8)
    lattice = spins.reshape((-1,) + ((1,) if len(shape) == 1 else ()) + shape)
    _, h, w = lattice.shape
    for _ in range(sweeps):
        for colour in (0, 1):
            u = rng.random(full).reshape(lattice.shape)
            for c, y, x in np.ndindex(lattice.shape):
                if (y + x) % 2 != colour:
                    continue
                near = sum(int(lattice[c, yy, xx]) for yy, xx in ((y - 1, x), (y + 1, x), (y, x - 1), (y, x + 1))
                           if 0 <= yy < h and 0 <= xx < w)
                local = coupling * near + field
                lattice[c, y, x] = 1 if u[c, y, x] < np.exp(local) / (np.exp(local) + np.exp(-local)) else -1
    return spins


@pytest.mark.parametrize("shape, chains, initial", [(9, None, None), (6, 3, None), ((4, 5), None, None),
                                                     ((3, 4), 2, np.ones((3, 4), np.int8))])
def test_gibbs_kernel_draws_what_the_site_by_site_sampler_draws(shape, chains, initial):
    kernel = gibbs_ising(shape, coupling=0.7, field=-0.2, sweeps=6, chains=chains, seed=4, initial=initial)
    assert np.array_equal(kernel, _gibbs_by_hand(shape, 0.7, -0.2, 6, chains, 4, initial))
