import numpy as np
import pytest

from crfmap.errors import InputError
from crfmap.recording import ScanSet


def test_head_cuts_every_per_scan_field_alike():
    n = 10
    scans = ScanSet(np.arange(n * 3, dtype=np.float32).reshape(n, 3), -0.5, 0.5, 0.1, 5.0,
                    np.arange(n * 3.0).reshape(n, 3), 0.5 * np.arange(n), frame_id="odom", source="test")
    first = scans.head(4)
    assert len(first) == 4 and first.laser_poses.shape == (4, 3) and first.stamps.tolist() == [0.0, 0.5, 1.0, 1.5]
    np.testing.assert_array_equal(first.ranges, scans.ranges[:4])
    np.testing.assert_array_equal(first.laser_poses, scans.laser_poses[:4])
    assert (first.angle_min, first.range_max, first.frame_id, first.source) == (-0.5, 5.0, "odom", "test")
    assert len(scans.head(99)) == n and len(scans.head(0)) == 0
    with pytest.raises(InputError, match="n: must be >= 0"):
        scans.head(-1)
