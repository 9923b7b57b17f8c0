import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid


def test_int8_conversion_follows_nav_msgs():
    g = OccupancyGrid(np.array([[0.0, 0.5, 1.0, 0.254]]))
    assert g.to_int8().tolist() == [[0, -1, 100, 25]]
    back = OccupancyGrid.from_int8(np.array([[-1, 0, 100, 65]], dtype=np.int8))
    assert back.probability.tolist() == [[0.5, 0.0, 1.0, 0.65]]
    with pytest.raises(InputError, match="outside"):
        OccupancyGrid.from_int8(np.array([[101]]))


def test_world_and_cell_coordinates_round_trip_with_yaw():
    g = OccupancyGrid(np.full((4, 6), 0.5), resolution=0.05, origin=(1.0, -2.0, 0.3))
    wx, wy = g.cell_to_world(np.array([0, 5]), np.array([0, 3]))
    ix, iy = g.world_to_cell(wx, wy)
    np.testing.assert_allclose(ix, [0.5, 5.5])
    np.testing.assert_allclose(iy, [0.5, 3.5])


def test_row_zero_is_lowest_y():
    g = OccupancyGrid(np.full((3, 2), 0.5), resolution=1.0, origin=(0, 0, 0))
    assert g.cell_to_world(0, 0)[1] < g.cell_to_world(0, 2)[1]


def test_bounds_of_a_grid_at_yaw_zero():
    g = OccupancyGrid(np.full((3, 4), 0.5), resolution=0.25, origin=(-1.0, 2.0, 0.0))
    assert g.bounds() == (-1.0, 2.0, 0.0, 2.75)  # xmin, ymin, xmax, ymax


def test_bounds_of_a_rotated_grid_hold_every_cell_centre():
    g = OccupancyGrid(np.full((4, 6), 0.5), resolution=0.5, origin=(1.0, -2.0, 0.7))
    xmin, ymin, xmax, ymax = g.bounds()
    iy, ix = np.mgrid[0:4, 0:6]
    wx, wy = g.cell_to_world(ix, iy)
    assert xmin < wx.min() and wx.max() < xmax and ymin < wy.min() and wy.max() < ymax
    corners = [g.cell_to_world(x - 0.5, y - 0.5) for x, y in ((0, 0), (6, 0), (0, 4), (6, 4))]
    assert min(c[0] for c in corners) == pytest.approx(xmin) and max(c[1] for c in corners) == pytest.approx(ymax)


@pytest.mark.parametrize("kwargs, word", [({"resolution": 0}, "resolution"), ({"resolution": float("nan")}, "resolution"),
                                          ({"origin": (0, 0, 0, 0)}, "origin")])
def test_bad_metadata(kwargs, word):
    with pytest.raises(InputError, match=word):
        OccupancyGrid(np.full((2, 2), 0.5), **kwargs)
