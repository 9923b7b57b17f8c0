"""Hard evidence (P exactly 0 or 1 under a link that makes it certain) is exact in every kernel and schedule."""
import numpy as np
import pytest

from crfmap.crf.inference.schedules import Checkerboard
from crfmap.crf.model.evidence import certain_states, UNCERTAIN
from crfstudy.references import exact_marginals
from crfmap.crf.inference.lbp import infer
from crfmap.crf.model.potentials import directional_tables
from crfmap.errors import InputError

RUNS = [("auto", "checkerboard"), ("plain", "checkerboard"), ("plain", "flooding"), ("plain", "sweep"),
        ("plain", "thesis")]
WALLED = np.array([[1.0, 1.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0]])


def _schedule(schedule, kernel):
    """The settings of ``schedule`` on ``kernel`` (a choice of the checkerboard schedule only)."""
    return Checkerboard(kernel=kernel) if schedule == "checkerboard" else schedule


@pytest.mark.parametrize("kernel,schedule", RUNS)
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("grid,table", [
    (WALLED, [[10, 1], [1, 10]]),  # the issue's cases: 0.0099, 0.99 and 0.5 before clamping
    (WALLED, [[100, 1], [1, 100]]),
    (np.array([[1.0, 0.0, 1.0]]), [[1000, 1], [1, 1000]]),
    (np.array([[1.0, 0.4, 0.0, 0.7, 1.0, 0.5]]), [[50, 1], [1, 50]]),
])
def test_issue_cases_match_exact_enumeration(grid, table, kernel, schedule, dtype):
    r = infer(grid, table, schedule=_schedule(schedule, kernel), dtype=dtype, max_iter=2000, tol=1e-12)
    exact = exact_marginals(grid, table)
    certain = (grid == 0) | (grid == 1)
    np.testing.assert_array_equal(r.beliefs.probability[certain], grid[certain])  # exactly, not nearly
    np.testing.assert_allclose(r.beliefs.probability, exact, atol=1e-6 if dtype == np.float64 else 1e-5)


def test_clamped_cell_sends_its_states_message():
    # identity link, P = 1 at x = 0: the message east is the table's occupied column, normalised
    r = infer(np.array([[1.0, 0.5]]), [[10, 1], [2, 10]], pairing="oriented", schedule=Checkerboard(kernel="plain"), tol=1e-12)
    # oriented: a message travelling east uses hidden.T, rows = receiver: column N1 is (10, 1)
    assert r.messages[0, 0, 1] == pytest.approx(10 / 11, abs=1e-12)


def test_link_without_zero_never_makes_a_cell_certain():
    link = [[0.9, 0.2], [0.1, 0.8]]  # P = 1 only says "occupied, 9 to 1"
    grid = WALLED
    r = infer(grid, [[10, 1], [1, 10]], link, tol=1e-12, max_iter=2000)
    assert certain_states(grid, link, directional_tables([[10, 1], [1, 10]])) is None
    assert 0 < r.beliefs.probability[1, 1] < 1
    np.testing.assert_allclose(r.beliefs.probability, exact_marginals(grid, [[10, 1], [1, 10]], link), atol=0.02)


def test_link_with_a_zero_makes_only_that_side_certain():
    link = [[1.0, 0.5], [0.0, 0.5]]  # an observed "occupied" is certain, an observed "empty" is not
    states = certain_states(np.array([[1.0, 0.0, 0.5]]), link, directional_tables([[10, 1], [1, 10]]))
    assert states.tolist() == [[1, UNCERTAIN, UNCERTAIN]]


def test_region_and_warm_start_keep_clamps():
    grid = WALLED.copy()
    grid[0, 0] = 0.5
    region = np.zeros(grid.shape, bool)
    region[:, 1:] = True
    for kernel in ("auto", "plain"):
        first = infer(grid, [[100, 1], [1, 100]], region=region, schedule=Checkerboard(kernel=kernel), max_iter=3)
        again = infer(grid, [[100, 1], [1, 100]], region=region, schedule=Checkerboard(kernel=kernel), messages=first.messages, tol=1e-12)
        for r in (first, again):
            assert r.beliefs.probability[1, 1] == 0.0 and r.beliefs.probability[0, 1] == 1.0


def test_zero_entries_carry_certainty_on():
    # equality table: a certain end fixes the whole chain
    grid = np.array([[1.0, 0.5, 0.3, 0.9]])
    for kernel, schedule in RUNS:
        r = infer(grid, [[1, 0], [0, 1]], schedule=_schedule(schedule, kernel))
        assert r.beliefs.probability.tolist() == [[1.0, 1.0, 1.0, 1.0]]
    np.testing.assert_array_equal(exact_marginals(grid, [[1, 0], [0, 1]]), 1.0)


@pytest.mark.parametrize("grid,table,cell", [
    (np.array([[1.0, 0.5, 0.0]]), [[1, 0], [0, 1]], "(x=0, y=0)"),  # a free cell forced both ways
    (np.array([[0.5, 1.0, 1.0]]), [[0, 1], [1, 1]], "(x=1, y=0)"),  # two adjacent occupied, forbidden
])
@pytest.mark.parametrize("kernel,schedule", RUNS)
def test_contradictory_hard_evidence_is_an_error(grid, table, cell, kernel, schedule):
    with pytest.raises(InputError, match="contradictory hard evidence") as err:
        infer(grid, table, schedule=_schedule(schedule, kernel))
    assert f"at cell {cell}" in str(err.value) and str(err.value).startswith("grid:")
    with pytest.raises(InputError, match="contradictory"):
        exact_marginals(grid, table)


def test_certain_state_with_an_all_zero_column_is_an_error():
    # oriented psi(x_west, x_east) = hidden: an occupied east end has weight 0 whatever its west neighbour
    grid, table = np.array([[0.5, 1.0]]), [[0, 1], [0, 1]]
    for kernel in ("auto", "plain"):
        with pytest.raises(InputError, match=r"\(x=1, y=0\).*impossible next to its neighbours"):
            infer(grid, table, pairing="oriented", schedule=Checkerboard(kernel=kernel))
    with pytest.raises(InputError, match="contradictory"):
        exact_marginals(grid, table, pairing="oriented")
    # the same cell at the west end is possible (it only forces its east neighbour empty)
    r = infer(grid[:, ::-1], table, pairing="oriented")
    assert r.beliefs.probability.tolist() == [[1.0, 0.0]]


@pytest.mark.parametrize("kernel", ["auto", "plain"])
def test_no_iteration_sends_nothing_but_certain_beliefs_are_exact(kernel):
    grid = np.array([[1.0, 0.3, 0.0, 0.6]])
    r = infer(grid, [[10, 1], [1, 10]], max_iter=0, schedule=Checkerboard(kernel=kernel))
    assert r.iterations == 0
    np.testing.assert_allclose(r.beliefs.probability, grid, atol=1e-12)
    assert r.beliefs.probability[0, 0] == 1.0 and r.beliefs.probability[0, 2] == 0.0
    np.testing.assert_array_equal(r.messages, 0.5)


def test_certainty_spreads_past_the_propagation_stack_s_first_size():
    # the stack starts at 1024 cells: 1400 certain senders, each the only one next to its two uncertain
    # neighbours (only senders spread), so a sender lost while the stack grows leaves a neighbour uncertain
    tables = directional_tables(np.array([[1.0, 0.0], [0.0, 1.0]]), "receiver")
    link = [[1.0, 0.0], [0.0, 1.0]]
    row = np.full((1, 3 * 1400), 0.5)
    row[0, ::3] = np.resize([0.0, 1.0], 1400)
    senders = row != 0.5
    spread = certain_states(row, link, tables, senders)
    values = np.resize([0, 1], 1400)
    j = np.arange(row.shape[1])
    nearest = np.where(j % 3 == 2, j // 3 + 1, j // 3)  # the sender beside each cell (west, or east of a 3k + 2)
    expected = np.where(nearest < 1400, values[np.minimum(nearest, 1399)], UNCERTAIN)[None]  # the last has none
    np.testing.assert_array_equal(spread, expected)
