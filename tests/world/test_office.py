"""crfmap.world.office: the procedural office floor is reproducible, walled, and its waypoints reachable."""
import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.world.office import office_floor
from crfmap.world.reachability import reachable


def test_office_floor():
    a, b = office_floor(12.0, 10.0, 0.1, seed=4), office_floor(12.0, 10.0, 0.1, seed=4)
    assert np.array_equal(a.truth.probability, b.truth.probability) and np.array_equal(a.waypoints, b.waypoints)
    assert not np.array_equal(a.truth.probability, office_floor(12.0, 10.0, 0.1, seed=5).truth.probability)
    for w, h, res, seed in ((6.0, 5.0, 0.1, 0), (20.0, 15.0, 0.05, 1), (31.0, 9.0, 0.1, 2), (9.0, 33.0, 0.1, 3)):
        s = office_floor(w, h, res, seed)
        assert s.truth.shape == (round(h / res), round(w / res))
        mask = reachable(s.truth, s.start, s.robot_radius)
        assert len(s.waypoints) >= 1
        for x, y in s.waypoints:
            assert mask[int(y / res), int(x / res)]
        p = s.truth.probability
        assert (p[0] == 1).all() and (p[-1] == 1).all() and (p[:, 0] == 1).all() and (p[:, -1] == 1).all()
        assert mask.sum() > 0.3 * (p == 0).sum()  # most of the floor is reachable
    with pytest.raises(InputError):
        office_floor(2.0, 10.0)
    with pytest.raises(InputError):
        office_floor(10.0, 10.0, resolution=0.0)
