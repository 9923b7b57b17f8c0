"""Synthetic recordings for the scan-split tests: a laser inside a walled box, every beam hitting a wall."""
import numpy as np
import pytest

from box_scans import scans_in_a_box


@pytest.fixture
def room():
    """A laser near the centre of a 2 m square room, turning a little: 6 scans of 90 beams."""
    rng = np.random.default_rng(0)
    n_scans = 6
    poses = np.column_stack([1 + 0.05 * rng.standard_normal(n_scans), 1 + 0.05 * rng.standard_normal(n_scans),
                             rng.uniform(-0.1, 0.1, n_scans)])
    return scans_in_a_box(poses, (0.05, 0.05, 1.95, 1.95), 90)
