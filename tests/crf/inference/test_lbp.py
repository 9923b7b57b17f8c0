"""LBP kernels against exact marginals and a naive reference, schedules, bounds, safety."""
import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.crf.inference.schedules import Flooding
from crfstudy.references import exact_marginals
from crfmap.crf.engine.messages import initial_messages
from crfmap.crf.inference.lbp import infer, message
from crfmap.crf.inference.regions import disc_region
from crfmap.crf.inference.schedules import SCHEDULES
from crfmap.grid import OccupancyGrid

from naive import naive_flooding

RNG = np.random.default_rng(12345)


@pytest.mark.parametrize("schedule", SCHEDULES)
@pytest.mark.parametrize("shape", [(1, 9), (9, 1)])
def test_chain_is_exact(schedule, shape):
    """BP is exact on a chain: every schedule's beliefs equal the enumerated marginals."""
    obs = RNG.uniform(0.05, 0.95, shape)
    hidden = [[6.0, 1.0], [1.0, 6.0]]
    link = [[0.9, 0.2], [0.1, 0.8]]
    r = infer(obs, hidden, link, schedule=schedule, tol=1e-13, max_iter=500)
    assert r.converged
    np.testing.assert_allclose(r.beliefs.probability, exact_marginals(obs, hidden, link), atol=1e-10)


@pytest.mark.parametrize("schedule", SCHEDULES)
def test_chain_with_non_symmetric_table_is_exact_when_oriented(schedule):
    obs = RNG.uniform(0.05, 0.95, (1, 10))
    hidden = [[5.0, 2.0], [0.5, 4.0]]
    r = infer(obs, hidden, schedule=schedule, pairing="oriented", tol=1e-13, max_iter=500)
    np.testing.assert_allclose(r.beliefs.probability,
                               exact_marginals(obs, hidden, pairing="oriented"), atol=1e-10)
    # the thesis's receiver pairing is a different (directed) model: it must not match here
    r2 = infer(obs, hidden, schedule=schedule, pairing="receiver", tol=1e-13, max_iter=500)
    assert np.abs(r2.beliefs.probability - r.beliefs.probability).max() > 1e-3


def comb_region(h, w):
    """A tree inside the lattice: the bottom row plus every other column (no cycles)."""
    mask = np.zeros((h, w), bool)
    mask[0, :] = True
    mask[:, ::2] = True
    return mask


@pytest.mark.parametrize("schedule", SCHEDULES)
def test_tree_is_exact(schedule):
    """On a tree (a comb cut out of the lattice with a region mask) LBP equals exact marginals."""
    h, w = 4, 5
    region = comb_region(h, w)
    obs = RNG.uniform(0.05, 0.95, (h, w))
    hidden = [[8.0, 1.0], [1.0, 8.0]]
    exact = exact_marginals(obs, hidden, region=region)
    r = infer(obs, hidden, schedule=schedule, region=region, tol=1e-13, max_iter=500)
    np.testing.assert_allclose(r.beliefs.probability[region], exact[region], atol=1e-10)


def test_lattice_is_not_a_tree_so_lbp_is_approximate():
    """The same data without the region has loops: LBP is close to, but not equal to, exact."""
    obs = RNG.uniform(0.05, 0.95, (4, 5))
    hidden = [[8.0, 1.0], [1.0, 8.0]]
    r = infer(obs, hidden, tol=1e-12)
    err = np.abs(r.beliefs.probability - exact_marginals(obs, hidden)).max()
    assert 1e-6 < err < 0.2


@pytest.mark.parametrize("shape", [(3, 4), (4, 4), (2, 5)])
def test_all_schedules_reach_the_same_fixed_point_close_to_exact(shape):
    obs = RNG.uniform(0.05, 0.95, shape)
    hidden = [[2.0, 1.0], [1.0, 2.0]]  # weak coupling: LBP converges and is accurate
    exact = exact_marginals(obs, hidden)
    beliefs = {}
    for s in SCHEDULES:
        r = infer(obs, hidden, schedule=s, tol=1e-12, max_iter=2000)
        assert r.converged, s
        beliefs[s] = r.beliefs.probability
    for s in SCHEDULES:
        np.testing.assert_allclose(beliefs[s], beliefs["checkerboard"], atol=1e-6)
    assert np.abs(beliefs["checkerboard"] - exact).max() < 0.02


@pytest.mark.parametrize("pairing", ["receiver", "oriented"])
@pytest.mark.parametrize("iterations", [1, 2, 5])
def test_flooding_matches_naive_reference_iteration_by_iteration(pairing, iterations):
    obs = RNG.uniform(0.0, 1.0, (3, 4))
    hidden = [[3.0, 0.7], [1.3, 2.5]]
    link = [[1.1, 0.1], [0.2, 1.3]]
    r = infer(obs, hidden, link, schedule=Flooding(damping=0.3), max_iter=iterations, tol=0.0,
              pairing=pairing)
    ref = naive_flooding(obs, hidden, link, iterations, pairing=pairing, damping=0.3)
    np.testing.assert_allclose(r.beliefs.probability, ref, atol=1e-12)


def test_worked_example_of_the_thesis():
    """Thesis sec. 3.4.2 (Tables 3-6), hidden table 0.9/0.1, identity link, schedule 'thesis'.

    Layout that reproduces it: C1 = cell (x0, y0) (the corner where the pass starts), C4 its east
    neighbour, C2 its north neighbour, C3 diagonal; observation node 4+i belongs to C_i
    (5: 0.6, 6: 0.8, 7: 0.3, 8: 0.4). The pass visits C1 then C4 as the text does.
    """
    grid = np.array([[0.6, 0.4],   # row y0: C1, C4
                     [0.8, 0.3]])  # row y1: C2, C3
    t = [[0.9, 0.1], [0.1, 0.9]]
    r = infer(grid, t, schedule="thesis", max_iter=1, tol=0.0)
    m = r.messages
    assert m[3, 0, 0] == pytest.approx(0.74)   # delta 2->1 (from the north neighbour C2)
    assert m[1, 0, 0] == pytest.approx(0.42)   # delta 4->1 (from the east neighbour C4)
    assert message([[1, 0], [0, 1]], 0.6) == pytest.approx(0.6)  # delta 5->1 through the link
    b1, b4 = r.beliefs.probability[0, 0], r.beliefs.probability[0, 1]
    # The thesis prints delta_2->1(E) = 0.26 and then uses 0.24: B1 ~ 0.77 comes from the slip.
    assert b1 == pytest.approx(0.74 * 0.42 * 0.6 / (0.74 * 0.42 * 0.6 + 0.26 * 0.58 * 0.4))
    assert round(b1, 3) == 0.756
    slip = 0.74 * 0.42 * 0.6 / (0.74 * 0.42 * 0.6 + 0.24 * 0.58 * 0.4)
    assert round(slip, 2) == 0.77
    # B4 ~ 0.505 follows with the correct 0.26
    assert round(b4, 3) == 0.505


def test_message_of_table_1():
    assert message([[0.9, 0.1], [0.1, 0.9]], 0.8) == pytest.approx(0.74)
    assert message([[10, 1], [1, 10]], 0.5) == pytest.approx(0.5)


def test_hard_evidence_and_hard_tables_give_no_nan():
    obs = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 1.0], [0.5, 1.0, 0.0]])
    consistent = np.array([[0.5, 0.9, 0.5], [0.2, 0.5, 1.0], [0.5, 0.7, 0.5]])
    for hidden in ([[1, 0], [0, 1]], [[10, 1], [1, 10]], [[1, 1], [0, 1]]):
        for dtype in (np.float32, np.float64):
            for s in SCHEDULES:
                for grid in (obs, consistent):
                    if grid is obs and hidden[1][0] == 0:  # certain 1 next to certain 0 under a zero entry
                        with pytest.raises(InputError, match="contradictory hard evidence"):
                            infer(grid, hidden, schedule=s, max_iter=50, dtype=dtype)
                        continue
                    b = infer(grid, hidden, schedule=s, max_iter=50, dtype=dtype).beliefs.probability
                    assert np.all(np.isfinite(b)) and b.min() >= 0 and b.max() <= 1


def test_large_grid_no_underflow_and_float32_close_to_float64():
    obs = RNG.uniform(0, 1, (300, 400))
    r64 = infer(obs, max_iter=300, tol=1e-6)
    r32 = infer(obs, max_iter=300, tol=1e-6, dtype=np.float32)
    assert np.all(np.isfinite(r64.beliefs.probability))
    assert np.abs(r64.beliefs.probability - r32.beliefs.probability).max() < 1e-3


def test_diagnostics_are_reported():
    obs = RNG.uniform(0.2, 0.8, (20, 20))
    r = infer(obs, max_iter=3, tol=0.0)
    assert r.iterations == 3 and r.max_change.shape == (3,) and not r.converged
    r = infer(obs, tol=1e-8)
    assert r.converged and r.max_change[-1] < 1e-8 and r.iterations == len(r.max_change)


def test_thesis_two_iterations_is_deterministic_and_differs_from_converged():
    obs = RNG.uniform(0.1, 0.9, (12, 15))
    a = infer(obs, schedule="thesis", max_iter=2)
    b = infer(obs, schedule="thesis", max_iter=2)
    assert a.iterations == 2
    np.testing.assert_array_equal(a.beliefs.probability, b.beliefs.probability)
    c = infer(obs, tol=1e-10)
    assert np.abs(a.beliefs.probability - c.beliefs.probability).max() > 1e-4


def test_warm_start_from_converged_messages_stops_at_once():
    obs = RNG.uniform(0.1, 0.9, (30, 30))
    r = infer(obs, tol=1e-9)
    r2 = infer(obs, tol=1e-9, messages=r.messages)
    assert r2.iterations == 1
    np.testing.assert_allclose(r2.beliefs.probability, r.beliefs.probability, atol=1e-8)


@pytest.mark.parametrize("schedule", SCHEDULES)
def test_bounded_lbp_only_changes_messages_sent_from_inside(schedule):
    grid = OccupancyGrid(RNG.uniform(0.1, 0.9, (20, 30)), resolution=0.5)
    start = infer(grid, max_iter=3, tol=0.0).messages
    region = disc_region(grid, (7.0, 5.0), 2.0)
    r = infer(grid, region=region, messages=start, schedule=schedule, tol=1e-10)
    changed = r.messages != start
    # slot d at a receiver was sent by its neighbour west/east/south/north of it
    senders = np.zeros_like(changed)
    senders[0, :, 1:] = region[:, :-1]
    senders[1, :, :-1] = region[:, 1:]
    senders[2, 1:, :] = region[:-1, :]
    senders[3, :-1, :] = region[1:, :]
    assert changed.any()
    assert not np.any(changed & ~senders)


def test_damped_flooding_converges_to_the_checkerboard_fixed_point():
    # Moderate coupling: one fixed point. (With [[10, 1], [1, 10]] on pure noise LBP has several,
    # and different schedules may settle in different ones.)
    obs = RNG.uniform(0.05, 0.95, (40, 40))
    hidden = [[3.0, 1.0], [1.0, 3.0]]
    a = infer(obs, hidden, schedule="checkerboard", tol=1e-10)
    b = infer(obs, hidden, schedule=Flooding(damping=0.5), tol=1e-10, max_iter=5000)
    assert a.converged and b.converged
    np.testing.assert_allclose(a.beliefs.probability, b.beliefs.probability, atol=1e-6)


@pytest.mark.parametrize("kwargs, word", [
    ({"hidden": [[1, -1], [1, 1]]}, "non-negative"),
    ({"hidden": [[0, 0], [1, 1]]}, "all zero"),
    ({"link": [[1, 0]]}, "2x2"),
    ({"hidden": "1,2,3"}, "4 comma"),
    ({"schedule": "random"}, "schedule"),
    ({"schedule": Flooding}, "schedule"),
    ({"region": np.ones((2, 2), bool)}, "region"),
    ({"messages": np.full((4, 2, 2), 0.5)}, "messages"),
    ({"pairing": "sideways"}, "pairing"),
])
def test_bad_arguments_are_named(kwargs, word):
    with pytest.raises(InputError, match=word):
        infer(np.full((3, 3), 0.5), **kwargs)


@pytest.mark.parametrize("bad, word", [
    (np.zeros((0, 3)), "empty"),
    (np.array([[0.5, np.nan]]), "NaN"),
    (np.array([[0.5, 1.5]]), r"\[0, 1\]"),
    (np.zeros((2, 2, 2)), "2-D"),
    (np.array([["a"]]), "numeric"),
])
def test_bad_grids_are_named(bad, word):
    with pytest.raises(InputError, match=word):
        infer(bad)


def test_initial_messages_are_uniform():
    m = initial_messages((2, 3))
    assert m.shape == (4, 2, 3) and np.all(m == 0.5)


def test_cells_a_hair_from_certain_are_read_at_the_floor_and_said_so():
    """P in (0, MESSAGE_FLOOR) or (1 - MESSAGE_FLOOR, 1) is LBP's on the clipped grid, with one warning naming the
    count; exactly 0 or 1 is hard evidence, and ordinary grids are silent."""
    import warnings

    from crfmap.crf.engine.messages import MESSAGE_FLOOR

    p = np.array([[1.0, 1e-310, 0.5, 0.3], [0.2, 0.5, 1 - 1e-12, 0.0]])
    clipped = np.where((p > 0) & (p < 1), np.clip(p, MESSAGE_FLOOR, 1 - MESSAGE_FLOOR), p)
    with pytest.warns(UserWarning, match=r"grid: 2 cell\(s\) have P within 1e-06 of 0 or 1"):
        got = infer(p, max_iter=200, tol=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # neither the clipped grid nor hard evidence warns
        want = infer(clipped, max_iter=200, tol=1e-12)
        infer(np.array([[0.0, 0.4, 1.0]]), max_iter=5)
    np.testing.assert_allclose(got.beliefs.probability, want.beliefs.probability, rtol=0, atol=1e-12)
