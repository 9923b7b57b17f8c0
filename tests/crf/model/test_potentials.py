import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.crf.model.potentials import check_table, directional_tables, link_unary, message_coefficients


def test_table_parsing_and_scale():
    assert check_table("10,1,1,10").tolist() == [[10, 1], [1, 10]]
    assert check_table([0.9, 0.1, 0.1, 0.9]).shape == (2, 2)


@pytest.mark.parametrize("bad, word", [("1,2,x,4", "numbers"), ([[1, np.inf], [1, 1]], "finite"),
                                       ([[-0.1, 1], [1, 1]], "non-negative"), ([[1, 1], [0, 0]], "C0"),
                                       ([[1, 2, 3]], "2x2"), ("abc", "4 comma")])
def test_bad_tables(bad, word):
    with pytest.raises(InputError, match=word):
        check_table(bad, "hidden")


def test_oriented_pairing_transposes_east_and_north():
    t = np.array([[5.0, 2.0], [1.0, 4.0]])
    d = directional_tables(t, "oriented")
    np.testing.assert_array_equal(d[0], t.T)
    np.testing.assert_array_equal(d[1], t)
    assert all(np.array_equal(x, t) for x in directional_tables(t, "receiver"))


def test_link_unary_and_coefficients():
    assert link_unary(np.array([0.3]), [[1, 0], [0, 1]]).tolist() == pytest.approx([0.3])
    # a link that trusts occupied readings more than empty ones
    u = link_unary(np.array([0.5]), [[2, 0], [0, 1]])
    assert u[0] == pytest.approx(2 / 3)
    # impossible observation under both states -> no information
    assert link_unary(np.array([0.0]), [[1, 0], [1, 0]])[0] == 0.5
    c = message_coefficients(np.array([[[10, 1], [1, 10]]]))
    assert c.tolist() == [[10, 1, 11, 11]]


@pytest.mark.parametrize("link", [[[1, 0], [0, 1]], [[0.9, 0.2], [0.1, 0.8]], [[1, 0], [1, 0]], [[0, 2], [0, 3]]])
def test_link_unary_of_a_grid_is_bit_for_bit_the_elementwise_formula(link):
    p = np.random.default_rng(5).uniform(0.0, 1.0, (67, 41))
    p[0, :3], p[1, :3] = 0.0, 1.0
    t = np.asarray(link, float)
    occ, emp = t[0, 0] * p + t[0, 1] * (1.0 - p), t[1, 0] * p + t[1, 1] * (1.0 - p)
    with np.errstate(invalid="ignore", divide="ignore"):
        expected = np.where(occ + emp > 0, occ / (occ + emp), 0.5)
    grid = link_unary(p, link)
    assert grid.dtype == np.float64 and np.array_equal(grid, expected)
    assert np.array_equal(link_unary(p.ravel(), link), expected.ravel())  # the NumPy path, other shapes
    assert np.array_equal(link_unary(np.asfortranarray(p), link), expected)
