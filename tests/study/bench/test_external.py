"""The optional PGMax / PyMaxflow benchmark rows: absent libraries are reported, present ones agree.

The first tests run without either library (as in CI). The ones that need a library skip
without it; run them in a venv that has them (see crfstudy.bench.external's docstring).
"""
import itertools
import sys

import numpy as np
import pytest

from crfmap.assess import mincut as G
from crfstudy.bench import external as E
from crfmap.errors import InputError
from crfstudy.references import crf_energy, exact_marginals
from crfmap.crf.inference.lbp import infer

KEYS = {"method", "size", "dtype", "threads", "seconds_per_iteration", "mcells_per_second"}
NON_SYMMETRIC = np.array([[3.0, 0.7], [1.3, 2.5]])


@pytest.fixture
def nothing_installed(monkeypatch):
    for module in E.LIBRARIES.values():
        monkeypatch.setitem(sys.modules, module, None)  # "import module" now raises ImportError


def naive_energy(occupied, observed, hidden):
    """-log of the unnormalised joint, one cell and one edge at a time (0 = occupied in the table)."""
    u = np.clip(observed, 1e-6, 1 - 1e-6)
    h, w = occupied.shape
    state = lambda y, x: 0 if occupied[y, x] else 1  # noqa: E731
    energy = 0.0
    for y in range(h):
        for x in range(w):
            energy -= np.log(u[y, x] if occupied[y, x] else 1.0 - u[y, x])
            if x + 1 < w:
                energy -= np.log(hidden[state(y, x), state(y, x + 1)])
            if y + 1 < h:
                energy -= np.log(hidden[state(y, x), state(y + 1, x)])
    return energy


# --- without the libraries ------------------------------------------------------------------------------


def test_available_reports_missing_libraries_as_none(nothing_installed):
    assert E.available() == {"pgmax": None, "pymaxflow": None}


def test_available_survives_an_import_that_breaks_otherwise(monkeypatch):
    def broken(name):
        raise RuntimeError(f"{name} found an incompatible jax")

    monkeypatch.setattr(E.importlib, "import_module", broken)
    assert E.available() == {"pgmax": None, "pymaxflow": None}


def test_available_in_this_environment_gives_versions_or_none():
    for name, version in E.available().items():
        assert name in E.LIBRARIES and (version is None or isinstance(version, str) and version)


def test_run_external_without_the_libraries_says_not_installed(nothing_installed):
    records = list(E.run_external((64, 128), 1, quick=True))
    assert [r["method"] for r in records] == ["pgmax-bp", "pymaxflow-map"]
    for r in records:
        assert KEYS <= set(r)
        assert r["note"].startswith("not installed (pip install")
        assert all(r[k] is None for k in KEYS - {"method"})


def test_run_external_skips_large_sizes_and_stops_after_a_failure(monkeypatch):
    monkeypatch.setattr(E, "available", lambda: {"pgmax": "0.6.1", "pymaxflow": "1.3.2"})
    calls = []

    def failing(size, repeats, iterations=E.ITERATIONS, seed=0):
        calls.append(size)
        raise AttributeError("module 'jax.lib' has no attribute 'xla_bridge'")

    monkeypatch.setattr(E, "bench_pgmax", failing)
    monkeypatch.setattr(E, "bench_maxflow", lambda size, repeats: [E.record("pymaxflow-map", size, seconds=1.0)])
    big = E.MAXFLOW_MAX_SIZE * 2
    records = list(E.run_external((64, 128, big), 1))
    pg = [r for r in records if r["method"] == "pgmax-bp"]
    assert calls == [64] and len(pg) == 1 and pg[0]["note"].startswith("failed: AttributeError")
    mf = [r for r in records if r["method"] == "pymaxflow-map"]
    assert [r["size"] for r in mf] == [64, 128, big]
    assert mf[-1]["note"].startswith("skipped") and mf[0]["version"] == "1.3.2"


def test_crf_energy_equals_a_cell_by_cell_sum():
    rng = np.random.default_rng(4)
    observed = rng.uniform(0.0, 1.0, (4, 5))
    observed[0, 0] = 0.0  # floored like crfmap.crf.inference.lbp.infer
    for hidden in (E.DEFAULT_HIDDEN, NON_SYMMETRIC):
        for _ in range(5):
            occupied = rng.uniform(size=(4, 5)) < 0.5
            assert crf_energy(occupied, observed, hidden) == pytest.approx(naive_energy(occupied, observed, hidden),
                                                                               rel=1e-12)
    with pytest.raises(InputError, match="occupied"):
        crf_energy(np.zeros((2, 2), bool), observed)


@pytest.mark.parametrize("hidden", [[[10.0, 1.0], [1.0, 10.0]], [[5.0, 1.0], [1.0, 2.0]], [[0.9, 0.3], [0.3, 0.2]]])
def test_potts_weight_reproduces_every_entry_of_the_table(hidden):
    hidden = np.array(hidden)
    w, shift, constant = G.potts_weight(hidden)
    assert w >= 0
    for xa, xb in itertools.product((0, 1), repeat=2):  # x = 1 occupied = table index 0
        expected = -np.log(hidden[1 - xa, 1 - xb])
        assert constant + shift * (xa + xb) + w * (xa != xb) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("hidden", [NON_SYMMETRIC, [[1.0, 3.0], [3.0, 1.0]], [[1.0, 0.0], [0.0, 1.0]]])
def test_potts_weight_refuses_tables_a_cut_cannot_solve(hidden):
    with pytest.raises(InputError, match="hidden"):
        G.potts_weight(hidden)


# --- PyMaxflow ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("hidden", [[[10.0, 1.0], [1.0, 10.0]], [[5.0, 1.0], [1.0, 2.0]]])
def test_graph_cut_finds_the_brute_force_map(seed, hidden):
    pytest.importorskip("maxflow")
    hidden = np.array(hidden)
    observed = np.random.default_rng(seed).uniform(0.0, 1.0, (3, 3))
    labellings = [np.array(bits, bool).reshape(3, 3) for bits in itertools.product((False, True), repeat=9)]
    energies = np.array([naive_energy(lab, observed, hidden) for lab in labellings])
    labels, flow_energy = G.graph_cut_map(observed, hidden)
    assert naive_energy(labels, observed, hidden) == pytest.approx(energies.min(), abs=1e-9)
    assert flow_energy == pytest.approx(energies.min(), abs=1e-9)  # max-flow value + constants
    if np.sort(energies)[1] - energies.min() > 1e-9:  # a unique minimiser: the labels themselves
        np.testing.assert_array_equal(labels, labellings[int(energies.argmin())])


def test_graph_cut_handles_strips():
    pytest.importorskip("maxflow")
    for shape in ((1, 6), (5, 1)):
        observed = np.random.default_rng(9).uniform(0.0, 1.0, shape)
        labels, flow_energy = G.graph_cut_map(observed)
        assert labels.shape == shape
        assert flow_energy == pytest.approx(crf_energy(labels, observed), abs=1e-9)


def test_maxflow_records_map_energy_at_most_the_lbp_labels():
    pytest.importorskip("maxflow")
    records = E.bench_maxflow(24, 1)
    assert [r["grid"] for r in records] == ["uniform", "office"]
    for r in records:
        assert KEYS <= set(r) and r["method"] == "pymaxflow-map" and r["seconds"] > 0
        assert r["energy_map"] <= r["energy_lbp_labels"] + 1e-9
        assert 0.0 <= r["agreement_with_lbp"] <= 1.0 and r["lbp_converged"]


# --- PGMax ----------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def pgmax_grid():
    pytest.importorskip("pgmax")
    return np.random.default_rng(5).uniform(0.0, 1.0, (8, 8))


@pytest.mark.parametrize("hidden", [E.DEFAULT_HIDDEN, NON_SYMMETRIC])
def test_pgmax_marginals_equal_crfmap_flooding_iteration_for_iteration(pgmax_grid, hidden):
    lattice = E.PgmaxLattice(pgmax_grid, hidden)
    for iterations in (1, 7):
        arrays, _ = lattice.runner(iterations)(lattice.arrays, 0.0)
        ours = infer(pgmax_grid, hidden, schedule="flooding", max_iter=iterations, tol=0.0, pairing="oriented")
        assert np.abs(lattice.marginals(arrays) - ours.beliefs.probability).max() < 1e-4


def test_pgmax_warm_start_carries_crfmap_messages(pgmax_grid):
    lattice = E.PgmaxLattice(pgmax_grid, NON_SYMMETRIC)
    first = infer(pgmax_grid, NON_SYMMETRIC, schedule="flooding", max_iter=3, tol=0.0, pairing="oriented")
    then = infer(pgmax_grid, NON_SYMMETRIC, schedule="flooding", max_iter=4, tol=0.0, pairing="oriented")
    arrays, _ = lattice.runner(1)(lattice.with_messages(first.messages), 0.0)
    assert np.abs(lattice.marginals(arrays) - then.beliefs.probability).max() < 1e-5
    # a wrong slot mapping would not survive this: the third iteration is far from the fourth
    assert np.abs(first.beliefs.probability - then.beliefs.probability).max() > 1e-2


def test_pgmax_temperature_one_is_sum_product(pgmax_grid):
    chain = pgmax_grid[:1, :7]  # a tree: BP is exact there
    lattice = E.PgmaxLattice(chain)
    exact = exact_marginals(chain)
    sum_product, _ = lattice.runner(20, temperature=1.0)(lattice.arrays, 0.0)
    max_product, _ = lattice.runner(20, temperature=0.0)(lattice.arrays, 0.0)
    assert np.abs(lattice.marginals(sum_product) - exact).max() < 1e-5
    assert np.abs(lattice.marginals(max_product) - exact).max() > 1e-2


def test_bench_pgmax_records(pgmax_grid):
    compile_rec, bp = E.bench_pgmax(8, 1, iterations=10)
    assert compile_rec["method"] == "pgmax-compile" and compile_rec["seconds"] > 0
    assert KEYS <= set(bp) and bp["method"] == "pgmax-bp" and bp["dtype"] == "float32" and bp["threads"] is None
    assert bp["seconds_per_iteration"] > 0 and bp["mcells_per_second"] > 0
    assert bp["max_belief_difference"] < 1e-4
    assert bp["fixed_point_crfmap_converged"] and bp["fixed_point_max_belief_difference"] < 1e-4
