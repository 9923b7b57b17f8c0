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


# ---- the notebook's helpers: the student network, the chain correlation, Onsager, LBP against exact, figures ---------
from crfstudy.experiments import background  # noqa: E402


def test_student_joint_is_the_chain_rule_and_refuses_a_cpd_that_does_not_sum_to_one():
    p_i, p_d = np.array([0.7, 0.3]), np.array([0.6, 0.4])
    p_g = np.array([[[0.3, 0.4, 0.3], [0.05, 0.25, 0.7]], [[0.9, 0.08, 0.02], [0.5, 0.3, 0.2]]])
    p_s, p_l = np.array([[0.95, 0.05], [0.2, 0.8]]), np.array([[0.1, 0.9], [0.4, 0.6], [0.99, 0.01]])
    joint = background.student_joint(p_i, p_d, p_g, p_s, p_l)
    assert joint[1, 0, 1, 1, 0] == pytest.approx(0.3 * 0.6 * 0.08 * 0.8 * 0.4)  # the thesis's eq. 2 example
    assert joint.sum() == pytest.approx(1.0)
    assert joint.sum(axis=(0, 1, 2, 3))[1] == pytest.approx(0.502, abs=1e-3)  # Koller & Friedman's P(l1)
    with pytest.raises(InputError, match="P\\(S\\|I\\)"):
        background.student_joint(p_i, p_d, p_g, np.array([[0.9, 0.2], [0.2, 0.8]]), p_l)


def test_neighbour_correlation_counts_agreeing_and_disagreeing_bonds():
    chains = np.array([[1, 1, 1], [1, -1, 1]])  # bonds: +1 +1 and -1 -1
    assert background.neighbour_correlation(chains) == 0.0
    assert background.neighbour_correlation(np.ones((3, 5))) == 1.0


def test_onsager_magnetisation_is_zero_below_the_critical_coupling_and_rises_to_one():
    m = background.onsager_magnetisation([0.2, background.CRITICAL_COUPLING, 0.5, 2.0])
    assert m[0] == m[1] == 0.0 and 0.8 < m[2] < 1.0 and m[3] == pytest.approx(1.0, abs=1e-6)


def test_magnetisation_curve_orders_with_the_coupling():
    curve = background.magnetisation_curve([0.1, 1.0], side=8, sweeps=50, chains=8, seed=0)
    assert len(curve) == 2 and curve[0] < 0.5 < 0.95 < curve[1]


def test_lbp_against_exact_is_exact_on_a_tree_and_counts_what_did_not_converge():
    variants = {"converged": dict(tol=1e-12, max_iter=1000, threads=1)}
    pairs, not_converged = background.lbp_against_exact({"weak": [[1.5, 1.0], [1.0, 1.5]]}, [(1, 4)], variants,
                                                        n_grids=3, seed=2)
    (exact, approx), = pairs.values()
    assert len(exact) == len(approx) == 3 and not_converged == {"weak": 0}
    np.testing.assert_allclose(np.concatenate(approx), np.concatenate(exact), atol=1e-9)  # a chain has no loop
    (row,) = background.lbp_exact_errors(pairs)
    assert row[:3] == ["weak", "converged", 3] and row[3] < 1e-9


def test_lbp_against_exact_on_a_loop_differs_from_exact_with_a_strong_table():
    pairs, _ = background.lbp_against_exact({"strong": [[10.0, 1.0], [1.0, 10.0]]}, [(2, 2)],
                                            {"converged": dict(tol=1e-10, max_iter=10000, threads=1)}, 4, seed=0)
    (row,) = background.lbp_exact_errors(pairs)
    assert row[3] > 1e-3  # LBP over-counts evidence around the 4-cycle


def test_the_notebook_figures_have_their_panels():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crfmap import OccupancyGrid

    grid = OccupancyGrid(np.array([[0.2, 0.9], [0.5, 0.1]]), resolution=1.0)
    fig = background.labelled_grid_figure(grid, "t")
    assert [t.get_text() for t in fig.axes[0].texts] == ["0.2", "0.9", "0.5", "0.1"]
    labels = [t.get_text() for t in background.student_network_figure().axes[0].texts]
    assert [t for t in labels if t] == list(background.STUDENT_NODES)  # the arrows are empty annotations
    assert labels.count("") == len(background.STUDENT_EDGES)
    chains = {0.0: np.array([1, -1, 1]), 1.0: np.array([1, 1, 1])}
    assert [ax.get_ylabel() for ax in background.chains_figure(chains).axes] == ["J = 0", "J = 1"]
    lattices = {0.3: np.ones((4, 4)), round(background.CRITICAL_COUPLING, 4): -np.ones((4, 4))}
    fig = background.lattices_figure(lattices, [0.2, 0.8], [0.1, 0.9], 4)
    assert len(fig.axes) == 3 and fig.axes[1].get_title().endswith("(critical)")
    pairs = {("a", "converged"): ([np.zeros(2)], [np.ones(2)]), ("b", "converged"): ([np.zeros(2)], [np.ones(2)])}
    assert len(background.lbp_exact_figure(pairs, 1).axes) == 2
    theta = np.linspace(0, 1, 11)
    assert background.coin_likelihood_figure(theta, theta * (1 - theta), 0.5).axes[0].get_xlabel() == "theta = P(heads)"
    curves = {"x": ([0, 1], [0, 1], 0.5)}
    fig = background.roc_example_figure(grid, grid, grid, curves)
    assert fig.axes[3].get_title() == "Fig. 12: ROC, occupied = positive"
    plt.close("all")
