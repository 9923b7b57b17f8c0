import numpy as np
import pytest

from crfmap.errors import InputError
from crfstudy.references import exact_marginals


def test_two_cells_by_hand():
    p = np.array([[0.7, 0.2]])
    t = np.array([[3.0, 1.0], [1.0, 3.0]])
    # joint over (x0, x1), index 0 = occupied
    u = [np.array([0.7, 0.3]), np.array([0.2, 0.8])]
    joint = np.outer(u[0], u[1]) * t
    joint /= joint.sum()
    np.testing.assert_allclose(exact_marginals(p, t).ravel(), [joint[0].sum(), joint[:, 0].sum()])


def test_no_coupling_returns_observations():
    p = np.array([[0.1, 0.6], [0.9, 0.3]])
    np.testing.assert_allclose(exact_marginals(p, [[1, 1], [1, 1]]), p)


def test_refuses_big_grids_and_asymmetric_receiver_tables():
    with pytest.raises(InputError, match="too many"):
        exact_marginals(np.full((5, 5), 0.5))
    with pytest.raises(InputError, match="oriented"):
        exact_marginals(np.full((2, 2), 0.5), [[2, 1], [0.5, 2]])
