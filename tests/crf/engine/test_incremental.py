"""The engine's incremental API (what the online mapper drives) against infer on the same grid."""
import numpy as np
import pytest

from crfmap.crf.engine.incremental import IncrementalLBP
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.regions import near_known
from crfmap.errors import InputError

HIDDEN = [[3.0, 1.0], [1.0, 3.0]]


@pytest.mark.parametrize("margin", [None, 1])
def test_observations_set_cell_by_cell_converge_to_infer(margin):
    rng = np.random.default_rng(2)
    grid = np.full((14, 17), 0.5)
    cells = np.argwhere(rng.uniform(size=grid.shape) < 0.4)[:, ::-1].astype(np.int64)  # (x, y)
    grid[cells[:, 1], cells[:, 0]] = rng.uniform(0.05, 0.95, len(cells))
    lbp = IncrementalLBP(*grid.shape, HIDDEN, np.eye(2), dtype=np.float64, margin=margin)
    lbp.set_observations(cells, grid[cells[:, 1], cells[:, 0]])
    changes = lbp.run(2000, 1e-12, threads=1)
    region = None if margin is None else near_known(grid, margin)
    expected = infer(grid, HIDDEN, region=region, tol=1e-12, max_iter=2000)
    assert changes[-1] < 1e-12 and expected.converged
    np.testing.assert_allclose(lbp.beliefs(), expected.beliefs.probability, atol=1e-9)
    np.testing.assert_allclose(lbp.messages(), expected.messages, atol=1e-9)


def test_rows_bound_the_senders_and_bad_margins_are_refused():
    lbp = IncrementalLBP(6, 6, HIDDEN, np.eye(2))
    lbp.set_observations(np.array([[2, 2]], np.int64), np.array([0.9]))
    lbp.run(3, 0.0, threads=1, rows=(2, np.array([2]), np.array([3])))
    assert lbp.senders == 1
    b = lbp.beliefs()
    assert b[2, 2] > 0.5 and b[2, 3] > 0.5 and b[0, 0] == 0.5  # only the cell's neighbours heard it
    with pytest.raises(InputError, match="margin"):
        IncrementalLBP(3, 3, HIDDEN, np.eye(2), margin=-1)
