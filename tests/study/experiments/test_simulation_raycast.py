"""crfmap.raycast's kernels, through the study's line_cells and first_hit (crfstudy.experiments.simulation), against a
slow exact reference (tests/naive_raycast.py), and the thesis's Fig. 15 cases."""
import numpy as np
import pytest

from crfmap.errors import InputError
from crfstudy.experiments.simulation import first_hit, line_cells
from naive_raycast import exact_line, is_tie, walk_first_hit

RNG_SEED = 20240611


def random_segments(n, span, seed=RNG_SEED):
    rng = np.random.default_rng(seed)
    return rng.integers(-span, span + 1, size=(n, 4)).tolist()


def test_line_matches_exact_rounding_on_random_segments():
    segments = random_segments(3000, 25)
    ties = 0
    for x0, y0, x1, y1 in segments:
        got = [tuple(c) for c in line_cells(x0, y0, x1, y1).tolist()]
        assert got == exact_line(x0, y0, x1, y1), (x0, y0, x1, y1)
        ties += is_tie(x0, y0, x1, y1)
    assert ties > 100  # the tie-break rule was really exercised


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_line_properties(seed):
    """Connected 8-neighbour path, right ends, every step one closer to the end, within 0.5 cell of the segment."""
    for x0, y0, x1, y1 in random_segments(500, 40, seed):
        cells = line_cells(x0, y0, x1, y1)
        assert tuple(cells[0]) == (x0, y0) and tuple(cells[-1]) == (x1, y1)
        steps = np.diff(cells, axis=0)
        assert np.abs(steps).max(initial=0) <= 1 and (np.abs(steps).sum(axis=1) > 0).all()
        chebyshev = np.abs(cells - [x1, y1]).max(axis=1)
        assert (np.diff(chebyshev) == -1).all()
        d = np.array([x1 - x0, y1 - y0], float)
        if d.any():
            rel = cells - [x0, y0]
            if abs(d[0]) >= abs(d[1]):  # distance along the minor axis to the true line
                off = np.abs(rel[:, 1] - rel[:, 0] * d[1] / d[0])
            else:
                off = np.abs(rel[:, 0] - rel[:, 1] * d[0] / d[1])
            assert off.max() <= 0.5 + 1e-12


def test_first_hit_matches_naive_walk():
    rng = np.random.default_rng(RNG_SEED)
    hits = misses = 0
    for _ in range(300):
        h, w = rng.integers(3, 20, size=2)
        occ = rng.random((h, w)) < rng.uniform(0.02, 0.3)
        start = (int(rng.integers(0, w)), int(rng.integers(0, h)))
        for _ in range(10):
            end = (int(rng.integers(-5, w + 5)), int(rng.integers(-5, h + 5)))  # some leave the grid
            want = walk_first_hit(occ.tolist(), start, end)
            got = first_hit(occ, start, end)
            assert got == want, (occ.shape, start, end)
            hits += want is not None
            misses += want is None
    assert hits > 200 and misses > 200


def test_start_cell_is_not_tested():
    occ = np.ones((1, 4), bool)
    assert first_hit(occ, (0, 0), (3, 0)) == (1, 0)


def test_fig15_tie_makes_visibility_one_sided():
    """Thesis Fig. 15: at a tie the line goes one way; whether a cell blocks depends on the direction cast."""
    a, b = (0, 0), (2, 1)  # the true segment passes the corner between cells (1, 0) and (1, 1)
    block_low = np.zeros((2, 3), bool)
    block_low[0, 1] = True
    block_high = np.zeros((2, 3), bool)
    block_high[1, 1] = True
    assert first_hit(block_low, a, b) == (1, 0)  # cast a -> b passes (1, 0)
    assert first_hit(block_high, a, b) is None  # ... and misses (1, 1)
    assert first_hit(block_high, b, a) == (1, 1)  # cast b -> a passes (1, 1)
    assert first_hit(block_low, b, a) is None
    # So with (1, 1) occupied, b sees a but a does not see b.


def test_fig15_diagonal_gap_is_seen_through():
    """A wall of cells touching only at corners does not stop a diagonal ray (the 'false' case of Fig. 15)."""
    occ = np.zeros((4, 4), bool)
    for x in range(4):
        occ[3 - x, x] = True  # anti-diagonal wall x + y = 3
    assert first_hit(occ, (0, 0), (3, 3)) is None
    assert [tuple(c) for c in line_cells(0, 0, 3, 3).tolist()] == [(0, 0), (1, 1), (2, 2), (3, 3)]
    # a ray that is not exactly diagonal is stopped by the same wall
    assert first_hit(occ, (0, 0), (3, 2)) is not None


def test_bad_input():
    with pytest.raises(InputError):
        line_cells(0, 0, 1.5, 2)
    with pytest.raises(InputError):
        first_hit(np.zeros(3, bool), (0, 0), (1, 0))
